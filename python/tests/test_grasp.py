"""Grasp, release and the handle wrench from Python (World::grasp, World::release,
World::handle_wrench; docs/grasp.md): a Python grasp and release reproduce a scene's
scripted ones bit for bit; the wrench balances gravity exactly on a quasi-static
hanging ribbon (force = weight, torque = the weight's moment about the grasp point);
refusals raise and change nothing; saves, copies and resets carry the holds."""

from __future__ import annotations

import numpy as np
import pytest

import developable_sim as ds
from conftest import ROOT, same_bits, scene_path

PICK = scene_path("ribbon_pick_and_place")
# the scene's scripted grasp (grasp_at 1.0 s) and release (release_at 4.6 s) act at the
# start of the steps ending at 1.0 s and 4.6 s (within half a step): after 99 and 459
# steps of 0.01 s
GRASP_AFTER, RELEASE_AFTER = 99, 459


def run_pick_and_place(grasp_after=None, release_after=None) -> ds.Simulation:
    """The pick-and-place scene; with step counts, its scripted grasp and release are
    removed and done from Python (sim.grasp with no point: the nearest point to the
    gripper's target within its grasp_radius, as the script closes) after those steps."""
    if grasp_after is None:
        sim = ds.Scene.load(PICK).build()
    else:
        off = {"handles.0.grasp_at": None, "handles.0.release_at": None}
        sim = ds.Scene.load(PICK, overrides=off).build()
    for k in range(round(sim.duration / sim.dt)):
        if k == grasp_after:
            g = sim.grasp("picker")
            assert g.changed and g.object == "ribbon"
        if k == release_after:
            assert sim.release("picker")
        sim.step()
    return sim


def final_bits(sim: ds.Simulation) -> list:
    s = sim.state()
    h = sim.handle_state("picker")
    return [s.vertices, s.material, np.array([sim.time]), h.material_point, np.array([h.generation])]


def test_a_python_grasp_and_release_reproduce_the_scripted_ones_bit_for_bit():
    scripted = run_pick_and_place()
    python = run_pick_and_place(GRASP_AFTER, RELEASE_AFTER)
    assert all(same_bits(a, b) for a, b in zip(final_bits(scripted), final_bits(python)))
    h = python.handle_state("picker")
    assert (h.attached, h.generation) == (False, 1)
    # the ribbon was carried: its grasped end (u = l, at y = 0 on the table at first)
    # went across the box (the gripper moves +0.55 m in y; the box spans y 0.2-0.4 m)
    v, m = python.state().vertices, python.state().material
    assert v[np.argmax(m[:, 0]), 1] > 0.5
    # the check's negative test: the same grasp one step later is another run
    late = run_pick_and_place(GRASP_AFTER + 1, RELEASE_AFTER)
    assert not same_bits(late.state().vertices, python.state().vertices)


def hanging(attached: bool = False) -> ds.Simulation:
    """tests/python/scenes/ribbon_hanging.yaml (a 5 g ribbon, 1 m x 0.05 m, quasi-static,
    a gripper at u = 0 that turns it down in 1 s and lifts it), its gripper open."""
    text = (ROOT / "tests" / "python" / "scenes" / "ribbon_hanging.yaml").read_text()
    return ds.Scene.from_yaml(
        text, overrides={"handles.0.attached": attached}, name="ribbon_hanging"
    ).build()


WEIGHT = 0.1 * 1.0 * 0.05 * 9.81  # N: density kg/m^2 x area m^2 x g


def centroid(state: ds.ObjectState) -> np.ndarray:
    """The ribbon's centre of mass: triangle centroids weighted by their flat-pattern
    areas (uniform density; the mesh is isometric to its pattern)."""
    m, t = state.material, state.triangles
    e1, e2 = m[t[:, 1]] - m[t[:, 0]], m[t[:, 2]] - m[t[:, 0]]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return (area[:, None] * state.vertices[t].mean(axis=1)).sum(axis=0) / area.sum()


def test_the_wrench_balances_gravity_on_a_hanging_ribbon():
    """Quasi-static: the gripper carries the whole ribbon, so the force the ribbon
    exerts on it is its weight, straight down, and the torque about the grasp point is
    the weight's moment, (centre of mass - grasp point) x force: exact statics. The
    ribbon starts horizontal (a cantilever: a large torque about +y) and turns down
    (none). Measured (this scene, solver tolerances 1e-10): force within 1.0e-6 of the
    weight at the first step after the grasp (its multipliers start at zero), 6.2e-8
    after; torque within 2.6e-11 of W L / 2 of the moment."""
    sim = hanging()
    assert sim.wrench("gripper") is None and not sim.handle_state("gripper").attached
    before = sim.state().vertices
    g = sim.grasp("gripper", point=(0.0, 0.0), hold="full")
    assert (g.changed, g.distance, g.object) == (True, 0.0, "ribbon")
    assert same_bits(g.material_point, np.array([0.0, 0.0]))
    # a grasp moves nothing (no snap) and feels nothing before a step
    assert same_bits(sim.state().vertices, before) and sim.wrench("gripper") is None
    largest_torque = 0.0
    for _ in range(110):
        sim.step()
        force, torque = sim.wrench("gripper")
        s = sim.state()
        grasp_point = s.vertices[s.material[:, 0] == 0.0].mean(axis=0)  # the rim pair at u = 0
        moment = np.cross(centroid(s) - grasp_point, force)
        assert np.linalg.norm(force - [0.0, 0.0, -WEIGHT]) < 2e-6 * WEIGHT
        assert np.linalg.norm(torque - moment) < 1e-10 * WEIGHT * 0.5
        largest_torque = max(largest_torque, np.linalg.norm(torque))
        # the same through handle_state
        h = sim.handle_state("gripper")
        assert same_bits(h.force, force) and same_bits(h.torque, torque)
    # the checks could fail: the torque was large (the cantilever) and a wrong sign
    # convention (the gripper on the ribbon) would be far off
    assert largest_torque > 0.2 * WEIGHT * 0.5
    assert np.linalg.norm(-force - [0.0, 0.0, -WEIGHT]) > 1.9 * WEIGHT
    # hanging straight down (the turn ended at 1 s): no moment left
    assert np.linalg.norm(torque) < 1e-9 * WEIGHT
    # released: no wrench
    assert sim.release("gripper") and sim.wrench("gripper") is None
    assert not sim.handle_state("gripper").attached


def test_grasps_are_idempotent_and_move_the_hold_elsewhere():
    sim = hanging()
    sim.grasp("gripper", point=(0.0, 0.0), hold="full")
    sim.step()
    again = sim.grasp("gripper", point=(0.0, 0.0), hold="full")
    assert not again.changed and sim.handle_state("gripper").generation == 1
    assert sim.wrench("gripper") is not None  # nothing changed: the last step's wrench stays
    moved = sim.grasp("gripper", point=(0.0, 0.01), hold="full")
    assert moved.changed and sim.handle_state("gripper").generation == 2
    assert same_bits(sim.handle_state("gripper").material_point, np.array([0.0, 0.01]))
    # by nearest point: the distance to the point asked for is reported
    target = sim.targets()["gripper"][0]
    near = sim.grasp("gripper", near=target + [0.0, 0.0, 0.005], max_distance=0.05)
    assert near.changed and 0.0 < near.distance <= 0.05
    assert sim.release("gripper") is True  # it held
    assert sim.release("gripper") is False  # open already: nothing changed


def test_refusals_raise_and_change_nothing():
    sim = hanging()
    sim.step()
    saved = sim.save()
    state = sim.handle_state("gripper")
    far = sim.targets()["gripper"][0] + [0.0, 0.0, 1.0]
    with pytest.raises(ds.GraspError, match="farther than"):
        sim.grasp("gripper", near=far, max_distance=0.1)
    with pytest.raises(ds.GraspError, match="off the ribbon"):
        sim.grasp("gripper", point=(1.5, 0.0))
    with pytest.raises(KeyError, match="no handle `hand`"):
        sim.grasp("hand", point=(0.0, 0.0))
    with pytest.raises(KeyError, match="no object `sheet`"):
        sim.grasp("gripper", "sheet", point=(0.0, 0.0))
    with pytest.raises(TypeError, match="not both"):
        sim.grasp("gripper", point=(0.0, 0.0), near=(0.0, 0.0, 0.0))
    with pytest.raises(TypeError, match="max_distance goes with near"):
        sim.grasp("gripper", point=(0.0, 0.0), max_distance=0.1)
    with pytest.raises(ValueError, match="not finite"):
        sim.grasp("gripper", point=(np.nan, 0.0))
    with pytest.raises(ValueError, match="must be 3 numbers"):
        sim.grasp("gripper", near=(0.0, 0.0))
    with pytest.raises(ValueError, match="max_distance must be >= 0"):
        sim.grasp("gripper", near=(0.0, 0.0, 0.0), max_distance=-1.0)
    with pytest.raises(ValueError, match="unknown hold `clamp`"):
        sim.grasp("gripper", point=(0.0, 0.0), hold="clamp")
    with pytest.raises(KeyError):
        sim.release("hand")
    # nothing changed: the same hold, the same save
    after = sim.handle_state("gripper")
    assert (after.attached, after.generation) == (state.attached, state.generation)
    assert sim.save() == saved


def test_a_sheet_is_grasped_on_its_boundary_only():
    sim = ds.Scene.load(scene_path("paper_first_singularity")).build()
    with pytest.raises(ds.GraspError, match="boundary"):
        sim.grasp("pusher", point=(0.05, 0.05))
    g = sim.grasp("pusher", point=(0.0, 0.05))
    assert g.changed and g.object == "paper"


def test_a_handle_that_drives_the_base_cannot_let_go():
    sim = ds.Scene.load(
        scene_path("ribbon_gripper"),
        overrides={"ribbon.segments": 10, "ribbon.base.mode": "driven", "ribbon.base.handle": "gripper"},
    ).build()
    with pytest.raises(ds.GraspError, match="cannot let go"):
        sim.release("gripper")
    assert sim.handle_state("gripper").attached


def test_saves_copies_and_resets_carry_the_holds():
    # the gripper scene (dynamic, its base fixed): let go of the free end, catch it again
    sim = ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 20}).build()
    for _ in range(5):
        sim.step()
    sim.release("gripper")
    for _ in range(5):
        sim.step()
    sim.grasp("gripper", hold="position", near=sim.targets()["gripper"][0], max_distance=1.0)
    for _ in range(3):
        sim.step()
    sim.grasp("gripper", point=(1.0, 0.01), hold="full")
    for _ in range(3):
        sim.step()
    copy = sim.copy()
    loaded = ds.Simulation.load(sim.save())
    for s in (copy, loaded):
        assert s.handle_state("gripper").generation == 2
        assert same_bits(s.state().vertices, sim.state().vertices)
    for s in (sim, copy, loaded):
        for _ in range(5):
            s.step()
    for s in (copy, loaded):
        assert same_bits(s.state().vertices, sim.state().vertices)
        assert all(same_bits(a, b) for a, b in zip(s.wrench("gripper"), sim.wrench("gripper")))
    # a save whose grasp differs in one bit does not replay to the saved state
    data = bytearray(sim.save())
    i = data.rfind(np.float64(0.01).tobytes())  # the second grasp's v, 0.01 m
    assert i > 0
    data[i] ^= 1  # its last bit
    with pytest.raises(ds.SimulationError, match="did not reach the saved state"):
        ds.Simulation.load(bytes(data))
    # a reset restores the scene's own hold
    sim.reset()
    h = sim.handle_state("gripper")
    assert (h.attached, h.generation) == (True, 0)
