"""Type stubs of the extension module (python/src/*.rs). Units are SI (m, s, kg, rad,
J); quaternions are (x, y, z, w); arrays are NumPy copies."""

import os
from typing import Any, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Vector = Union[Sequence[float], npt.NDArray[np.float64]]
#: A handle target `world_from_gripper`: (position m, quaternion x y z w), a position
#: alone (the orientation stays the current target's), or 7 numbers [x y z qx qy qz qw].
Target = Union[Tuple[Vector, Vector], Vector]
Targets = Mapping[str, Target]

class SceneError(ValueError):
    """A scene that cannot be loaded or built; `key` is the key path in `--set` syntax
    (None when the error has none), `file` the scene's path."""

    key: Optional[str]
    file: Optional[str]

class SimulationError(RuntimeError):
    """An internal error caught at the boundary (reset the simulation), a save that
    does not replay, or a simulation used after such an error."""

class GraspError(ValueError):
    """A grasp or release the world refused (off the object, out of reach, a sheet
    point off its boundary, a handle that drives a prescribed base); nothing changed."""

class Scene:
    """A scene file with overrides applied, checked and built once."""

    @staticmethod
    def load(
        path: Union[str, os.PathLike[str]], overrides: Optional[Mapping[str, Any]] = None
    ) -> "Scene":
        """Load a scene file; `overrides` maps key paths to values as `--set` does."""
    @staticmethod
    def from_yaml(
        text: str, overrides: Optional[Mapping[str, Any]] = None, name: str = "<string>"
    ) -> "Scene":
        """A scene from YAML text; `name` stands for the file in messages."""
    def with_overrides(self, overrides: Mapping[str, Any]) -> "Scene":
        """The same scene with more overrides, applied after its own."""
    def build(self, seed: Optional[int] = None) -> "Simulation":
        """A simulation at t = 0; `seed` replaces the scene's `seed:`."""
    @property
    def name(self) -> str: ...
    @property
    def duration(self) -> float:
        """Simulated duration of `developable_sim run`, s."""
    @property
    def dt(self) -> float:
        """Time step, s."""
    @property
    def seed(self) -> int: ...
    @property
    def objects(self) -> list[str]: ...
    @property
    def handles(self) -> list[str]: ...
    @property
    def cameras(self) -> list[str]: ...
    @property
    def yaml(self) -> str:
        """The scene text before overrides."""
    @property
    def file(self) -> str: ...
    @property
    def overrides(self) -> list[str]:
        """The overrides as `--set` specs (`key.path=value`), in order."""

class ObjectState:
    """One object's state (copies)."""

    name: str
    kind: str
    time: float
    vertices: npt.NDArray[np.float64]
    """(N, 3) positions in the scene frame, m."""
    triangles: npt.NDArray[np.uint32]
    """(T, 3) vertex indices, counter-clockwise seen from the material +z side."""
    material: npt.NDArray[np.float64]
    """(N, 2) flat-pattern coordinates [u, v], m."""
    rulings: npt.NDArray[np.uint32]
    """(R, 2) vertex index pairs of ruling and crease segments."""
    regions: npt.NDArray[np.uint8]
    """(N,) 0 flat, 1 curved, 2 singular."""
    singular_ids: npt.NDArray[np.uint64]
    singular_positions: npt.NDArray[np.float64]
    """(K, 3) m."""
    singular_material: npt.NDArray[np.float64]
    """(K, 2) [u, v], m."""
    energies: dict[str, float]
    """J: kinetic, elastic, gravity, external, total."""
    isometry_error: float
    coordinates: dict[str, npt.NDArray[np.float64]]
    """Ribbons: crease_direction (dimensionless), bending_angle (rad)."""
    iterations: Optional[int]
    outer_iterations: Optional[int]
    converged: Optional[bool]
    kept_previous_state: Optional[bool]
    constraint_violation: Optional[float]
    """m."""

class CameraFrame:
    """One rendered camera frame (docs/camera.md)."""

    camera: str
    time: float
    index: int
    color: npt.NDArray[np.uint8]
    """(H, W, 3) rgb8."""
    depth: npt.NDArray[np.float32]
    """(H, W) along the optical axis, m; NaN: none."""
    points: npt.NDArray[np.float32]
    """(H, W, 3) optical frame (x right, y down, z forward), m."""
    k: npt.NDArray[np.float64]
    """(3, 3) intrinsics, px."""
    world_from_optical: npt.NDArray[np.float64]
    """(4, 4)."""

class Grasp:
    """What `Simulation.grasp` did."""

    object: str
    material_point: npt.NDArray[np.float64]
    """(2,) [u, v] held, m."""
    distance: float
    """From the point asked for to the point held, m (0 by material point)."""
    changed: bool
    """False when the handle already held exactly this."""

class HandleState:
    """What a handle holds now and what it feels."""

    name: str
    attached: bool
    object: str
    material_point: npt.NDArray[np.float64]
    """(2,) [u, v] held (or held last), m."""
    generation: int
    """0: the scene's own hold; + 1 at each grasp that changed it."""
    grasp_radius: float
    """m."""
    force: Optional[npt.NDArray[np.float64]]
    """(3,) N, scene frame: the object on the gripper, last step; None when open or
    not stepped since the grasp."""
    torque: Optional[npt.NDArray[np.float64]]
    """(3,) N m, scene frame, about the grasp point; None as force."""

class Simulation:
    """One simulated world."""

    def step(self, targets: Optional[Targets] = None) -> None:
        """Advance by dt; handles not named follow their scripted trajectory."""
    def state(self, object: Union[str, int, None] = None) -> ObjectState: ...
    def targets(self) -> dict[str, Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
        """Each handle's current target (position m, quaternion x y z w)."""
    def grasp(
        self,
        handle: str,
        object: Union[str, int, None] = None,
        *,
        point: Optional[Vector] = None,
        near: Optional[Vector] = None,
        max_distance: Optional[float] = None,
        hold: Optional[str] = None,
    ) -> Grasp:
        """Close `handle` on `point` ([u, v], m), or the graspable point nearest `near`
        ([x, y, z], m) within `max_distance` (m, default its grasp_radius), or with
        neither the point nearest its current target; `hold` 'position' | 'normal' |
        'full' (default the scene's). Raises GraspError when refused."""
    def release(self, handle: str) -> bool:
        """Open `handle`; False when it held nothing."""
    def handle_state(self, handle: str) -> HandleState: ...
    def wrench(
        self, handle: str
    ) -> Optional[Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
        """(force N, torque N m about the grasp point), scene frame, the object on the
        gripper in the last step; None when open or not stepped since the grasp."""
    def reset(self, seed: Optional[int] = None) -> None: ...
    def save(self) -> bytes: ...
    @staticmethod
    def load(data: bytes) -> "Simulation": ...
    def copy(self) -> "Simulation": ...
    def render_depth(self, camera: str, pose: Optional[Target] = None) -> CameraFrame: ...
    @property
    def time(self) -> float:
        """s."""
    @property
    def dt(self) -> float:
        """s."""
    @property
    def steps(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def duration(self) -> float:
        """s."""
    @property
    def objects(self) -> list[str]: ...
    @property
    def handles(self) -> list[str]: ...
    @property
    def cameras(self) -> list[str]: ...
    @property
    def last_step_time(self) -> float:
        """Wall time of the last world step alone, s."""

def step_many(
    sims: Iterable[Simulation], targets: Optional[Sequence[Optional[Targets]]] = None
) -> None:
    """One step of every simulation, in parallel, the GIL released once."""

def _panic_for_test() -> None: ...
