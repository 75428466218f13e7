"""A gymnasium environment over a developable_sim scene, in the style of SoftGym's
pickers (Lin et al. 2020): each picker is a handle of the scene, moved by a bounded
displacement each step; the observation is the object's vertices or a point cloud
from the scene's camera; the reward is a function you pass.

Needs gymnasium (`pip install developable_sim[gym]`).

    import developable_sim as ds
    from developable_sim.gym import PickerEnv

    env = PickerEnv("config/scenes/ribbon_gripper.yaml", max_displacement=0.01)
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Grasp and release: each picker's fourth action component is SoftGym's pick flag. Above
0.5 an open picker closes on the graspable point nearest its target within the
handle's `grasp_radius` (nothing there: it stays open), a closed one keeps its hold; at
0.5 or below a closed picker lets go. Then the pickers move. `grasping=False` drops the
fourth component: the handles hold what the scene says for the whole episode.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError(
        "developable_sim.gym needs gymnasium: pip install developable_sim[gym]"
    ) from e

from ._native import GraspError, Scene, Simulation

#: reward(sim, action) -> float, called after each step with the simulation and the
#: action as given, clipped to [-1, 1] (each row a picker's displacement, then its pick
#: flag when grasping).
RewardFn = Callable[[Simulation, np.ndarray], float]


def relaxed(sim: Simulation, action: np.ndarray) -> float:
    """The default reward: minus the elastic energy of every object, J (prefer an
    unbent object). A placeholder: pass your task's reward."""
    return -sum(sim.state(o).energies["elastic"] for o in sim.objects)


class PickerEnv(gym.Env):
    """Pickers (the scene's handles) moving a developable object.

    - action: `(P * 4,)` float32 in [-1, 1] (`(P * 3,)` with `grasping=False`): picker
      p first grasps or releases by its pick flag `action[4p+3]` (above 0.5: close on
      the graspable point nearest its target within its `grasp_radius`, or keep
      holding; otherwise open), then moves its target position by
      `max_displacement * action[4p:4p+3]` m (scene frame), its orientation kept; the
      new position is clipped to `workspace` (low, high corners, m) when given.
      Handles that are not pickers follow their scripted trajectories and scripted
      grasps.
    - observation `"vertices"`: `(N, 3)` float64 vertex positions of `object`, m (the
      vertex count must not change: ribbons; a paper sheet remeshes, use
      `"point_cloud"`); `"point_cloud"`: `(num_points, 3)` float64 points in the scene
      frame, m, from `camera`'s depth, `num_points` of the valid pixels drawn with the
      environment's random generator (zeros when the camera sees nothing).
    - reward: `reward(sim, action)`, default [`relaxed`].
    - seeds: `reset(seed=s)` seeds the environment's generator, which draws the scene
      seed of every episode (the initial imperfection, the paper's singular points,
      camera noise) and the point-cloud samples: the same seed gives the same
      episodes. `options={"scene_seed": k}` pins the scene seed of one episode.
    - an episode is truncated after `horizon` steps (default: the scene's duration);
      it never terminates by itself.
    """

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(
        self,
        scene: Union[Scene, str, os.PathLike],
        *,
        pickers: Optional[Sequence[str]] = None,
        observation: str = "vertices",
        reward: Optional[RewardFn] = None,
        max_displacement: float = 0.01,
        workspace: Optional[Tuple[Sequence[float], Sequence[float]]] = None,
        horizon: Optional[int] = None,
        object: Union[str, int, None] = None,
        camera: Optional[str] = None,
        num_points: int = 1024,
        render_mode: Optional[str] = None,
        grasping: bool = True,
    ) -> None:
        self.scene = scene if isinstance(scene, Scene) else Scene.load(scene)
        self.sim = self.scene.build()
        self.pickers = list(pickers) if pickers is not None else self.sim.handles
        unknown = [p for p in self.pickers if p not in self.sim.handles]
        if not self.pickers or unknown:
            raise ValueError(
                f"pickers must be handles of the scene ({self.sim.handles}), got {self.pickers}"
            )
        if observation not in ("vertices", "point_cloud"):
            raise ValueError(f"observation must be 'vertices' or 'point_cloud', got {observation!r}")
        if not max_displacement > 0:
            raise ValueError(f"max_displacement must be > 0 m, got {max_displacement}")
        self.observation = observation
        self.reward_fn: RewardFn = reward if reward is not None else relaxed
        self.max_displacement = float(max_displacement)
        self.workspace = (
            None
            if workspace is None
            else (np.asarray(workspace[0], float), np.asarray(workspace[1], float))
        )
        self.horizon = (
            int(horizon) if horizon is not None else max(1, round(self.sim.duration / self.sim.dt))
        )
        self.object = object
        self.camera = camera if camera is not None else (self.sim.cameras or [None])[0]
        if (observation == "point_cloud" or render_mode == "rgb_array") and self.camera is None:
            raise ValueError("a point cloud or rgb_array rendering needs a camera in the scene")
        self.num_points = int(num_points)
        self.render_mode = render_mode
        self.grasping = bool(grasping)
        self._width = 4 if self.grasping else 3
        self.action_space = spaces.Box(
            -1.0, 1.0, shape=(self._width * len(self.pickers),), dtype=np.float32
        )
        if observation == "vertices":
            n = self.sim.state(object).vertices.shape[0]
            shape: Tuple[int, ...] = (n, 3)
        else:
            shape = (self.num_points, 3)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=shape, dtype=np.float64)
        self._steps = 0

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        super().reset(seed=seed)
        scene_seed = (options or {}).get("scene_seed")
        if scene_seed is None:
            scene_seed = int(self.np_random.integers(0, 2**63 - 1))
        self.sim.reset(seed=int(scene_seed))
        self._steps = 0
        return self._observe(), self._info()

    def step(self, action: np.ndarray) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        a = np.asarray(action, dtype=np.float64).reshape(len(self.pickers), self._width)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {action}")
        a = np.clip(a, -1.0, 1.0)
        if self.grasping:
            self._pick_or_drop(a[:, 3] > 0.5)
        current = self.sim.targets()
        targets = {}
        for p, name in enumerate(self.pickers):
            position = current[name][0] + self.max_displacement * a[p, :3]
            if self.workspace is not None:
                position = np.clip(position, self.workspace[0], self.workspace[1])
            targets[name] = position
        self.sim.step(targets=targets)
        self._steps += 1
        reward = float(self.reward_fn(self.sim, a))
        truncated = self._steps >= self.horizon
        return self._observe(), reward, False, truncated, self._info()

    def _pick_or_drop(self, pick: np.ndarray) -> None:
        """SoftGym's pick flag: an open picker that picks closes on the nearest point in
        reach (none: it stays open); a closed one that does not pick opens."""
        for name, wants in zip(self.pickers, pick):
            attached = self.sim.handle_state(name).attached
            try:
                if wants and not attached:
                    self.sim.grasp(name)
                elif not wants and attached:
                    self.sim.release(name)
            except GraspError:
                # nothing within grasp_radius, or a handle that drives a ribbon's
                # prescribed base (it cannot let go): the hold stays as it was
                pass

    def render(self) -> Optional[np.ndarray]:
        if self.render_mode != "rgb_array":
            return None
        return self.sim.render_depth(self.camera).color

    def _observe(self) -> np.ndarray:
        if self.observation == "vertices":
            v = self.sim.state(self.object).vertices
            if v.shape != self.observation_space.shape:
                raise RuntimeError(
                    f"the object now has {v.shape[0]} vertices, not {self.observation_space.shape[0]}: "
                    "use observation='point_cloud' for an object that remeshes"
                )
            return v
        return self._point_cloud()

    def _point_cloud(self) -> np.ndarray:
        frame = self.sim.render_depth(self.camera)
        p = frame.points.reshape(-1, 3).astype(np.float64)
        p = p[np.isfinite(p).all(axis=1)]
        out = np.zeros((self.num_points, 3))
        if len(p) == 0:
            return out
        pick = self.np_random.choice(len(p), size=self.num_points, replace=len(p) < self.num_points)
        m = frame.world_from_optical
        out[:] = p[pick] @ m[:3, :3].T + m[:3, 3]
        return out

    def _info(self) -> Dict[str, Any]:
        states = [self.sim.state(o) for o in self.sim.objects]
        return {
            "time": self.sim.time,
            "scene_seed": self.sim.seed,
            "converged": all(s.converged is not False for s in states),
            "attached": {p: self.sim.handle_state(p).attached for p in self.pickers},
        }
