"""save() / Simulation.load(bytes): a saved simulation continues bit for bit as the
original does, from any working directory; bad bytes are refused."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import developable_sim as ds
from conftest import same_bits, scene_path


def drive(sim: ds.Simulation, k0: int, k1: int) -> None:
    """Steps k0..k1 of a fixed command sequence for the scene's first handle, relative
    to its start pose: targets on even steps (some with a quaternion, some a position
    alone), the script on odd ones."""
    name = sim.handles[0]
    x, y, z = START[sim.name]
    for k in range(k0, k1):
        p = [x - 0.002 * k, y + 0.001 * k, z + 0.003 * k]
        if k % 2:
            sim.step()
        elif k % 4:
            sim.step(targets={name: p})
        else:
            a = 0.01 * k
            sim.step(targets={name: (p, [math.sin(a), 0, 0, math.cos(a)])})


# the first handle's start position in each scene, m
START = {"ribbon_gripper": (1.0, 0.0, 0.0), "ribbon_gripper_push": (0.85, -0.08, 0.1)}


def all_bits(sim: ds.Simulation) -> list:
    out = [np.float64(sim.time), np.asarray(sim.steps)]
    for o in sim.objects:
        s = sim.state(o)
        out += [s.vertices, s.singular_positions, np.array(list(s.energies.values()))]
        out += list(s.coordinates.values())
    for p, q in sim.targets().values():
        out += [p, q]
    return out


def assert_identical(a: ds.Simulation, b: ds.Simulation) -> None:
    xa, xb = all_bits(a), all_bits(b)
    assert len(xa) == len(xb)
    for u, v in zip(xa, xb):
        assert same_bits(np.asarray(u), np.asarray(v))


@pytest.mark.parametrize("name", ["ribbon_gripper", "ribbon_gripper_push"])
def test_a_loaded_simulation_continues_bit_for_bit(name):
    # ribbon_gripper_push: the ribbon rests on the table (the contact stage's state)
    scene = ds.Scene.load(scene_path(name), overrides={"ribbon.segments": 24})
    original = scene.build(seed=3)
    drive(original, 0, 30)
    data = original.save()
    assert isinstance(data, bytes)
    loaded = ds.Simulation.load(data)
    assert loaded.seed == 3 and loaded.steps == 30
    assert_identical(original, loaded)
    drive(original, 30, 60)
    drive(loaded, 30, 60)
    assert_identical(original, loaded)
    # and the uninterrupted run is the same run
    straight = scene.build(seed=3)
    drive(straight, 0, 60)
    assert_identical(original, straight)


def test_the_comparison_sees_another_command():
    """The negative test of the continuation check: a single different target in the
    continuation gives a different state."""
    scene = ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 24})
    a = scene.build()
    drive(a, 0, 10)
    b = ds.Simulation.load(a.save())
    a.step(targets={"gripper": [0.98, 0.0, 0.03]})
    b.step(targets={"gripper": [0.98, 0.0, np.nextafter(0.03, 1.0)]})
    with pytest.raises(AssertionError):
        assert_identical(a, b)


def test_a_save_loads_from_another_directory(tmp_path):
    # ribbon_gripper_push has no mesh files; a scene path is stored absolute anyway
    scene = ds.Scene.load(os.path.relpath(scene_path("ribbon_gripper"), os.getcwd()))
    sim = scene.build()
    drive(sim, 0, 4)
    data = sim.save()
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert_identical(ds.Simulation.load(data), sim)
    finally:
        os.chdir(cwd)


def test_reset_clears_what_is_saved():
    sim = ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 12}).build()
    drive(sim, 0, 6)
    sim.reset(seed=9)
    drive(sim, 0, 3)
    loaded = ds.Simulation.load(sim.save())
    assert loaded.steps == 3 and loaded.seed == 9
    assert_identical(loaded, sim)


def test_bad_bytes_are_refused():
    sim = ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 12}).build()
    drive(sim, 0, 5)
    data = bytearray(sim.save())
    with pytest.raises(ds.SimulationError, match="DSIMSAVE"):
        ds.Simulation.load(b"not a save")
    with pytest.raises(ds.SimulationError, match="truncated"):
        ds.Simulation.load(bytes(data[:-9]))
    with pytest.raises(ds.SimulationError, match="after the end"):
        ds.Simulation.load(bytes(data) + b"x")
    # a changed target bit: the replay does not reach the recorded state
    tampered = bytearray(data)
    # the last step (k = 4) is a pose: 7 f64 before the 8-byte fingerprint; byte 6 of
    # its x holds mantissa bits 48..51 and 44..47: x moves by about 2^-8 of itself
    tampered[-8 - 56 + 6] ^= 0x10
    with pytest.raises(ds.SimulationError):
        ds.Simulation.load(bytes(tampered))
    # a changed fingerprint
    tampered = bytearray(data)
    tampered[-1] ^= 0x80
    with pytest.raises(ds.SimulationError, match="did not reach the saved state"):
        ds.Simulation.load(bytes(tampered))
