"""developable_sim.gym.PickerEnv: gymnasium's own checker, the action's effect on the
handle targets, SoftGym's pick flag (grasp and release), a pluggable reward, seeds
honoured, point-cloud observations."""

from __future__ import annotations

import numpy as np
import pytest

# gymnasium is a test requirement (python/requirements-test.txt): no skip without it
import gymnasium
from gymnasium.utils.env_checker import check_env

import developable_sim as ds
from conftest import same_bits, scene_path
from developable_sim.gym import PickerEnv, relaxed


@pytest.fixture(scope="module")
def scene() -> ds.Scene:
    return ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 16})


def test_gymnasium_accepts_the_environment(scene):
    env = PickerEnv(scene, horizon=5)
    check_env(env, skip_render_check=True)
    assert isinstance(env, gymnasium.Env)
    assert env.action_space.shape == (4,)  # the displacement and the pick flag
    assert env.observation_space.shape == (34, 3)
    assert PickerEnv(scene, grasping=False).action_space.shape == (3,)


def test_an_action_moves_the_picker_target_by_the_scaled_displacement(scene):
    env = PickerEnv(scene, max_displacement=0.02, horizon=3)
    env.reset(seed=1)
    before = env.sim.targets()["gripper"]
    # inwards (-x): the straight ribbon cannot be pulled beyond its length (+x)
    action = np.array([-0.5, -1.0, 0.25, 1.0], dtype=np.float32)  # and keep holding
    obs, reward, terminated, truncated, info = env.step(action)
    after = env.sim.targets()["gripper"]
    assert same_bits(after[0], before[0] + 0.02 * action[:3].astype(np.float64))
    assert same_bits(after[1], before[1])  # orientation kept
    assert not terminated and not truncated and info["converged"]
    assert info["attached"] == {"gripper": True}
    assert obs.shape == (34, 3) and same_bits(obs, env.sim.state().vertices)
    assert reward == relaxed(env.sim, action) < 0
    # actions beyond [-1, 1] are clipped; the workspace clips positions
    env = PickerEnv(scene, max_displacement=0.5, workspace=([0.0, -0.1, 0.0], [1.0, 0.1, 0.2]))
    env.reset(seed=1)
    env.step(np.array([3.0, 3.0, 3.0, 1.0]))
    assert same_bits(env.sim.targets()["gripper"][0], np.array([1.0, 0.1, 0.2]))
    env.step(np.array([0.0, 0.0, 0.0, 1.0]))
    _, _, _, truncated, _ = env.step(np.array([0.0, 0.0, 0.0, 1.0]))
    assert not truncated
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0, 0.0, 1.0]))
    # without grasping the action is the displacement alone
    env = PickerEnv(scene, grasping=False, max_displacement=0.02)
    env.reset(seed=1)
    env.step(action[:3])
    assert same_bits(env.sim.targets()["gripper"][0], after[0])


def test_the_pick_flag_releases_and_grasps_again(scene):
    env = PickerEnv(scene, max_displacement=0.01, horizon=50)
    env.reset(seed=0)
    # a flag at 0.5 or below opens the gripper; the ribbon's free end drops away
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.0, 0.5]))
    assert info["attached"] == {"gripper": False}
    assert env.sim.handle_state("gripper").generation == 0
    # above 0.5 it closes again on the nearest point in reach (its grasp_radius, 0.02 m)
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.0, 0.6]))
    h = env.sim.handle_state("gripper")
    assert info["attached"] == {"gripper": True} and h.generation == 1
    # and keeps that hold while the flag stays up (no new attachment every step)
    env.step(np.array([0.0, 0.0, 0.0, 1.0]))
    assert env.sim.handle_state("gripper").generation == 1
    # out of reach a pick does nothing: open, lift the picker 0.1 m, pick
    env.step(np.array([0.0, 0.0, 0.0, -1.0]))
    for _ in range(10):
        env.step(np.array([0.0, 0.0, 1.0, -1.0]))
    _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.0, 1.0]))
    assert info["attached"] == {"gripper": False}
    assert env.sim.handle_state("gripper").generation == 1


def test_the_reward_is_pluggable_and_episodes_truncate(scene):
    calls = []

    def height(sim, action):
        calls.append((sim.time, action.copy()))
        return float(sim.state().vertices[:, 2].mean())

    env = PickerEnv(scene, reward=height, horizon=2)
    env.reset(seed=0)
    _, r1, _, t1, _ = env.step(np.array([0.0, 0.0, 1.0, 1.0]))
    _, r2, _, t2, _ = env.step(np.array([0.0, 0.0, 1.0, 1.0]))
    assert [round(t, 9) for t, _ in calls] == [0.01, 0.02]
    assert same_bits(calls[0][1], np.array([[0.0, 0.0, 1.0, 1.0]]))
    assert r2 > r1 > 0 and (t1, t2) == (False, True)


def rollout(env, seed, actions):
    obs, info = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        out.append(env.step(a)[0])
    return np.array(out), info["scene_seed"]


def test_seeds_are_honoured(scene):
    # with pick flags at random: grasps and releases are part of what must repeat
    actions = np.random.default_rng(0).uniform(-1, 1, size=(6, 4))
    env = PickerEnv(scene)
    a, sa = rollout(env, 7, actions)
    b, sb = rollout(PickerEnv(scene), 7, actions)
    c, sc = rollout(env, 8, actions)
    assert sa == sb != sc
    assert same_bits(a, b) and not same_bits(a, c)
    # an unseeded reset draws the next scene seed from the environment's generator
    env.reset(seed=7)
    _, info = env.reset()
    env2 = PickerEnv(scene)
    env2.reset(seed=7)
    assert env2.reset()[1]["scene_seed"] == info["scene_seed"] != sa
    # options pin the scene seed
    assert env.reset(options={"scene_seed": 42})[1]["scene_seed"] == 42


def test_point_cloud_observations_come_from_the_camera(scene):
    env = PickerEnv(scene, observation="point_cloud", num_points=256, horizon=2)
    obs, _ = env.reset(seed=3)
    assert obs.shape == (256, 3) and env.observation_space.contains(obs)
    # the points lie on the ribbon: within half the width (+ the gripper's lift) of it
    v = env.sim.state().vertices
    d = np.min(np.linalg.norm(obs[:, None, :] - v[None], axis=2), axis=1)
    assert d.max() < 0.04
    again, _ = env.reset(seed=3)
    assert same_bits(obs, again)


def test_bad_arguments_are_refused(scene):
    with pytest.raises(ValueError, match="pickers must be handles"):
        PickerEnv(scene, pickers=["hand"])
    with pytest.raises(ValueError, match="observation must be"):
        PickerEnv(scene, observation="pixels")
    with pytest.raises(ValueError, match="max_displacement"):
        PickerEnv(scene, max_displacement=0.0)
