"""developable_sim: developable ribbons (Pan et al.) and paper (Schreck et al.) from
Python, without ROS.

>>> import developable_sim as ds
>>> sim = ds.Scene.load("config/scenes/ribbon_gripper.yaml").build(seed=0)
>>> p0, q0 = sim.targets()["gripper"]          # m, quaternion (x, y, z, w)
>>> sim.step(targets={"gripper": (p0 + [-0.002, 0.0, 0.003], q0)})
>>> sim.state("ribbon").vertices.shape
(102, 3)

Units are SI (m, s, kg, rad, J, N) as in the scene files; quaternions are
(x, y, z, w). Grippers grasp and release at run time (`sim.grasp`, `sim.release`) and
report the wrench the object exerts on them (`sim.wrench`). The API is in docs/python.md; `developable_sim.gym` has a gymnasium
environment (`pip install developable_sim[gym]`).
"""

from ._native import (
    CameraFrame,
    Grasp,
    GraspError,
    HandleState,
    ObjectState,
    Scene,
    SceneError,
    Simulation,
    SimulationError,
    __version__,
    step_many,
)

__all__ = [
    "CameraFrame",
    "Grasp",
    "GraspError",
    "HandleState",
    "ObjectState",
    "Scene",
    "SceneError",
    "Simulation",
    "SimulationError",
    "__version__",
    "step_many",
]
