"""Simulation: step with and without targets, time and dt, the state's arrays, targets,
reset with and without a seed, copies, bad targets."""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest

import developable_sim as ds
from conftest import same_bits, scene_path

GRIPPER = scene_path("ribbon_gripper")
IDENTITY = [0.0, 0.0, 0.0, 1.0]


@pytest.fixture(scope="module")
def scene() -> ds.Scene:
    return ds.Scene.load(GRIPPER, overrides={"ribbon.segments": 20})


def grasp_vertex(state: ds.ObjectState) -> int:
    """The mesh vertex at the gripper's material point (1, 0): the far end's centre
    is not a vertex, so the two far rim vertices (1, -w/2), (1, w/2) average to it."""
    far = np.flatnonzero(np.isclose(state.material[:, 0], 1.0))
    assert len(far) == 2
    return far


def test_step_advances_time_by_dt(scene):
    sim = scene.build(seed=0)
    assert sim.time == 0.0 and sim.dt == 0.01 and sim.steps == 0
    for k in range(1, 6):
        sim.step()
        assert sim.steps == k
    assert sim.time == pytest.approx(0.05, abs=1e-15)
    assert sim.last_step_time > 0


def test_state_has_every_array_with_its_shape_and_units(scene):
    sim = scene.build()
    s0 = sim.state("ribbon")
    # before any step: no solver report; the flat strip of l = 1 m, w = 0.05 m
    assert s0.iterations is None and s0.converged is None and s0.constraint_violation is None
    assert s0.name == "ribbon" and s0.kind == "ribbon" and s0.time == 0.0
    n = s0.vertices.shape[0]
    assert s0.vertices.shape == (n, 3) and s0.vertices.dtype == np.float64
    assert s0.material.shape == (n, 2) and s0.material.dtype == np.float64
    assert s0.triangles.dtype == np.uint32 and s0.triangles.shape[1] == 3
    assert s0.triangles.max() == n - 1
    assert s0.rulings.dtype == np.uint32 and s0.rulings.shape[1] == 2
    assert s0.regions.shape == (n,) and s0.regions.dtype == np.uint8
    assert s0.material[:, 0].min() == 0.0 and s0.material[:, 0].max() == 1.0
    assert np.allclose(np.abs(s0.material[:, 1]), 0.025)
    for _ in range(30):
        sim.step()
    s = sim.state(0)
    # the pattern's rim points move with the crease directions (x_j = (l j/n - w c_j/2,
    # -w/2), y_j = (l j/n + w c_j/2, w/2): Pan et al. eq. 2); their midpoints do not
    mid0 = (s0.material[0::2] + s0.material[1::2]) / 2
    mid = (s.material[0::2] + s.material[1::2]) / 2
    assert np.allclose(mid, mid0, atol=1e-15, rtol=0)
    assert np.allclose(mid[:, 0], np.linspace(0.0, 1.0, 21), atol=1e-15, rtol=0)
    assert np.all(mid[:, 1] == 0.0)
    assert not same_bits(s.vertices, s0.vertices)
    # one step's report
    assert s.iterations >= 1 and s.outer_iterations >= 1
    assert s.converged is True and s.kept_previous_state is False
    assert 0 <= s.constraint_violation < 1e-3
    # energies in J, total their sum
    e = s.energies
    assert set(e) == {"kinetic", "elastic", "gravity", "external", "total"}
    assert e["total"] == pytest.approx(e["kinetic"] + e["elastic"] + e["gravity"] + e["external"])
    assert e["kinetic"] > 0 and e["elastic"] > 0
    # the ribbon is exactly isometric by construction (round-off)
    assert s.isometry_error < 1e-12
    c = s.coordinates
    assert set(c) == {"crease_direction", "bending_angle"}
    # k = 0..n for n = 20 elements; the ends are no creases: c_0 = c_n = 0 (eq. 1)
    assert c["bending_angle"].shape == (21,) and c["crease_direction"].shape == (21,)
    assert c["crease_direction"][0] == 0.0 == c["crease_direction"][-1]
    # edge lengths against the pattern: what isometry_error reports
    a, b = s.triangles[:, 0], s.triangles[:, 1]
    world = np.linalg.norm(s.vertices[a] - s.vertices[b], axis=1)
    flat = np.linalg.norm(s.material[a] - s.material[b], axis=1)
    assert np.max(np.abs(world - flat) / flat) <= s.isometry_error * (1 + 1e-9) + 1e-15


def test_singular_points_are_reported_with_ids_positions_and_material_points():
    # extreme torsion: creases meet at the rims, where the crease bounds are active
    sim = ds.Scene.load(scene_path("ribbon_extreme_torsion")).build()
    seen = 0
    for _ in range(60):
        sim.step()
        s = sim.state()
        k = len(s.singular_ids)
        assert s.singular_ids.dtype == np.uint64
        assert s.singular_positions.shape == (k, 3) and s.singular_material.shape == (k, 2)
        seen = max(seen, k)
        if k:
            # a singular point lies on a rim: |v| = w / 2 in the pattern
            assert np.allclose(np.abs(s.singular_material[:, 1]), 0.025, atol=1e-12)
    assert seen > 0


def test_state_rejects_unknown_objects(scene):
    sim = scene.build()
    with pytest.raises(KeyError, match="no object `rope`"):
        sim.state("rope")
    with pytest.raises(IndexError):
        sim.state(3)


def test_targets_drive_the_gripper(scene):
    sim = scene.build()
    p0, q0 = sim.targets()["gripper"]
    # the far end's centre, up to the seeded imperfection of the shape (1e-6 rad)
    assert np.allclose(p0, [1.0, 0.0, 0.0], atol=1e-5) and np.allclose(q0, IDENTITY, atol=1e-5)
    goal = np.array([0.9, 0.05, 0.2])
    for k in range(100):
        # move the target in a straight line over 0.5 s, then hold it
        s = min(1.0, (k + 1) / 50)
        sim.step(targets={"gripper": (p0 + s * (goal - p0), IDENTITY)})
    p, q = sim.targets()["gripper"]
    assert same_bits(p, p0 + 1.0 * (goal - p0)) and same_bits(q, np.array(IDENTITY))
    state = sim.state()
    held = state.vertices[grasp_vertex(state)].mean(axis=0)
    # the grasp point is held at the target; the solver reports its violation as the
    # largest coordinate error (m), round-off apart the one measured on the mesh
    assert np.abs(held - goal).max() == pytest.approx(state.constraint_violation, abs=1e-14)
    assert state.constraint_violation < 1e-6


def test_target_forms_are_equivalent(scene):
    theta = 0.3
    q = [math.sin(theta / 2), 0.0, 0.0, math.cos(theta / 2)]  # about x, (x, y, z, w)
    p = [0.95, 0.0, 0.05]
    runs = []
    for form in [(p, q), p + q, (np.array(p), np.array(q) * 2.0)]:  # normalized
        sim = scene.build()
        for _ in range(5):
            sim.step(targets={"gripper": form})
        runs.append(sim.state().vertices)
    assert same_bits(runs[0], runs[1])
    assert np.allclose(runs[0], runs[2], atol=1e-12, rtol=0)
    # a position alone keeps the current target's orientation
    sim = scene.build()
    sim.step(targets={"gripper": (p, q)})
    sim.step(targets={"gripper": [0.9, 0.0, 0.05]})
    assert np.allclose(sim.targets()["gripper"][1], q, atol=1e-15)


@pytest.mark.parametrize(
    "targets, error, words",
    [
        ({"hand": [1.0, 0.0, 0.0]}, KeyError, "no handle `hand`"),
        ({"gripper": [1.0, np.nan, 0.0]}, ValueError, "not finite"),
        ({"gripper": ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])}, ValueError, "no rotation"),
        ({"gripper": ([1.0, 0.0, 0.0], [0.0, 0.0, np.inf, 1.0])}, ValueError, "not finite"),
        ({"gripper": [1.0, 0.0]}, ValueError, "position must be 3 numbers"),
        ({"gripper": [1.0, 0.0, 0.0, 1.0]}, ValueError, "got 4 items"),
        ({"gripper": "up"}, ValueError, "got a string"),
        ([1.0, 0.0, 0.0], TypeError, "targets must be a dict"),
    ],
)
def test_bad_targets_raise_and_do_not_step(scene, targets, error, words):
    sim = scene.build()
    with pytest.raises(error, match=words):
        sim.step(targets=targets)
    assert sim.steps == 0


def test_reset_returns_to_the_start_and_reseeds(scene):
    sim = scene.build(seed=0)
    start = sim.state().vertices
    for _ in range(10):
        sim.step()
    after = sim.state().vertices
    sim.reset()
    assert sim.time == 0.0 and sim.steps == 0
    assert same_bits(sim.state().vertices, start)
    for _ in range(10):
        sim.step()
    assert same_bits(sim.state().vertices, after)  # the same run again
    # another seed: another imperfection of the initial shape (rad 1e-6)
    sim.reset(seed=5)
    assert sim.seed == 5
    other = sim.state().vertices
    assert not same_bits(other, start) and np.allclose(other, start, atol=1e-5)
    assert same_bits(other, scene.build(seed=5).state().vertices)


def test_copies_are_independent_and_pickle_round_trips(scene):
    sim = scene.build()
    for _ in range(3):
        sim.step()
    twin = sim.copy()
    deep = copy.deepcopy(sim)
    for s in (sim, twin, deep):
        for _ in range(4):
            s.step()
    assert same_bits(twin.state().vertices, sim.state().vertices)
    assert same_bits(deep.state().vertices, sim.state().vertices)
    twin.step()
    assert twin.steps == sim.steps + 1
    back = pickle.loads(pickle.dumps(sim))
    assert back.steps == sim.steps and same_bits(back.state().vertices, sim.state().vertices)
