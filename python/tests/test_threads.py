"""Many simulations at once: from Python threads (the GIL is released while a world
steps) and with step_many; results bit-identical to stepping them one by one."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import developable_sim as ds
from conftest import same_bits, scene_path

STEPS = 20


@pytest.fixture(scope="module")
def scene() -> ds.Scene:
    return ds.Scene.load(scene_path("ribbon_gripper"), overrides={"ribbon.segments": 30})


def target(i: int, k: int) -> dict:
    """Each simulation its own command sequence."""
    return {"gripper": [1.0 - 0.002 * k, 0.001 * i, 0.002 * k]}


def run_alone(scene: ds.Scene, i: int) -> np.ndarray:
    sim = scene.build(seed=i)
    for k in range(STEPS):
        sim.step(targets=target(i, k))
    return sim.state().vertices


def test_threads_give_the_results_of_sequential_runs(scene):
    alone = [run_alone(scene, i) for i in range(6)]
    sims = [scene.build(seed=i) for i in range(6)]

    def run(i):
        for k in range(STEPS):
            sims[i].step(targets=target(i, k))

    with ThreadPoolExecutor(max_workers=3) as pool:
        list(pool.map(run, range(6)))
    for i in range(6):
        assert same_bits(sims[i].state().vertices, alone[i])
    # and each differs from the others (the check could fail)
    assert not same_bits(alone[0], alone[1])


def test_step_many_gives_the_results_of_sequential_runs(scene):
    alone = [run_alone(scene, i) for i in range(5)]
    sims = [scene.build(seed=i) for i in range(5)]
    for k in range(STEPS):
        ds.step_many(sims, [target(i, k) for i in range(5)])
    for i in range(5):
        assert same_bits(sims[i].state().vertices, alone[i])
        assert sims[i].steps == STEPS
    # without targets, every handle follows its script, as sim.step() does
    a, b = scene.build(), scene.build()
    for _ in range(3):
        ds.step_many([a])
        b.step()
    assert same_bits(a.state().vertices, b.state().vertices)


def test_step_many_refuses_bad_batches(scene):
    a, b = scene.build(), scene.build()
    with pytest.raises(ValueError, match="listed twice"):
        ds.step_many([a, a])
    with pytest.raises(ValueError, match="2 targets for 1 simulations"):
        ds.step_many([a], [None, None])
    with pytest.raises(KeyError, match=r"targets\[1\].*no handle `hand`"):
        ds.step_many([a, b], [None, {"hand": [0, 0, 0]}])
    with pytest.raises(TypeError):
        ds.step_many([a, "b"])
    assert a.steps == 0 and b.steps == 0  # nothing stepped


def borrowed_while(work, probe) -> int:
    """How often `probe()` (a read of a simulation) in the main thread found the
    simulation borrowed while `work` ran in another thread. A method borrows its
    simulation for the whole call; the main thread runs Python only when it holds the
    GIL: a borrowed simulation seen from here means the GIL was released inside a
    method, while it held the borrow."""
    done = threading.Event()

    def run():
        try:
            work()
        finally:
            done.set()

    t = threading.Thread(target=run)
    t.start()
    seen = 0
    while not done.is_set():
        try:
            probe()
        except RuntimeError as e:  # PyO3's "Already mutably borrowed"
            assert "borrowed" in str(e), e
            seen += 1
    t.join()
    return seen


def test_stepping_releases_the_gil(scene):
    sims = [scene.build(seed=i) for i in range(8)]

    def one():
        for _ in range(100):
            sims[0].step()

    def batch():
        for _ in range(20):
            ds.step_many(sims)

    assert borrowed_while(one, lambda: sims[0].steps) > 0
    assert borrowed_while(batch, lambda: sims[3].steps) > 0


def test_the_borrow_probe_sees_nothing_when_the_gil_is_held(scene):
    """Its negative test: `reset` borrows the simulation too but keeps the GIL (it
    only copies the initial world): the main thread never sees the borrow."""
    sim = scene.build()

    def resets():
        for _ in range(3000):
            sim.reset()

    assert borrowed_while(resets, lambda: sim.steps) == 0
