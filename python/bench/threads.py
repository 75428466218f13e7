"""Throughput of many independent simulations stepped from Python threads, and the
binding's per-step overhead against the Rust step (issue 50).

    .venv/bin/python python/bench/threads.py            # 64 ribbon_gripper scenes, 1 s each
    .venv/bin/python python/bench/threads.py --sims 8 --seconds 0.2   # a quick look

For each thread count (default 1 and 2) the same work is done from scratch: `--sims`
simulations of the scene (seeds 0..sims-1) each stepped `--seconds` of simulated time
with a target for the gripper every step, the simulations split evenly between the
threads. Printed: wall time, process CPU time, throughput (steps/s) and its ratio to
one thread; then `step_many` on all simulations at once; then, from the one-thread
run, the binding's overhead: per step, the time of the Python call `sim.step(...)`
minus the time of the world step alone (`sim.last_step_time`, measured in Rust
around `World::step`), as a ratio to the world step (medians over all steps).

The load average is printed before and after: on a shared machine wall-time ratios
mean little (another process takes a core); CPU time per step and the overhead ratio
do not depend on the load as much. On an idle machine (load average < 0.3), run it
with `--repeat 5` and take the median ratio.
"""

from __future__ import annotations

import argparse
import os
import statistics
import threading
import time
from pathlib import Path

import developable_sim as ds

ROOT = Path(__file__).resolve().parents[2]


def load_average() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def target(i: int, k: int, p0):
    """Slow circles of 2 cm around the start, a different phase per simulation."""
    import math

    a = 0.05 * k + i
    return {"gripper": [p0[0] - 0.1 + 0.02 * math.cos(a), p0[1] + 0.02 * math.sin(a), p0[2] + 0.1]}


def run_threads(scene: ds.Scene, sims: int, steps: int, threads: int) -> dict:
    pool = [scene.build(seed=i) for i in range(sims)]
    p0 = pool[0].targets()["gripper"][0]
    call_ns = [[] for _ in range(threads)]
    rust_ns = [[] for _ in range(threads)]

    def work(t: int):
        mine = pool[t::threads]
        calls, rusts = call_ns[t], rust_ns[t]
        for k in range(steps):
            for i, sim in enumerate(mine):
                tg = target(t + threads * i, k, p0)
                start = time.perf_counter_ns()
                sim.step(targets=tg)
                calls.append(time.perf_counter_ns() - start)
                rusts.append(sim.last_step_time * 1e9)

    workers = [threading.Thread(target=work, args=(t,)) for t in range(threads)]
    cpu0, wall0 = time.process_time(), time.perf_counter()
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    calls = [x for c in call_ns for x in c]
    rusts = [x for r in rust_ns for x in r]
    overhead = [c - r for c, r in zip(calls, rusts)]
    return {
        "wall": wall,
        "cpu": cpu,
        "steps": sims * steps,
        "call_us": statistics.median(calls) / 1e3,
        "rust_us": statistics.median(rusts) / 1e3,
        "overhead_us": statistics.median(overhead) / 1e3,
        "rust_total": sum(rusts) / 1e9,
    }


def run_batch(scene: ds.Scene, sims: int, steps: int) -> dict:
    pool = [scene.build(seed=i) for i in range(sims)]
    p0 = pool[0].targets()["gripper"][0]
    cpu0, wall0 = time.process_time(), time.perf_counter()
    for k in range(steps):
        ds.step_many(pool, [target(i, k, p0) for i in range(sims)])
    return {"wall": time.perf_counter() - wall0, "cpu": time.process_time() - cpu0, "steps": sims * steps}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "config/scenes/ribbon_gripper.yaml"))
    ap.add_argument("--sims", type=int, default=64)
    ap.add_argument("--seconds", type=float, default=1.0, help="simulated time per simulation, s")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args()
    scene = ds.Scene.load(a.scene)
    steps = round(a.seconds / scene.dt)
    print(f"{a.sims} x {scene.name}, {steps} steps of {scene.dt} s each; cores: {os.cpu_count()}")
    print(f"load average before: {load_average()}")
    counts = [int(t) for t in a.threads.split(",")]
    for r in range(a.repeat):
        base = None
        for threads in counts:
            m = run_threads(scene, a.sims, steps, threads)
            rate = m["steps"] / m["wall"]
            base = base or rate
            print(
                f"[{r}] threads {threads}: wall {m['wall']:.3f} s, cpu {m['cpu']:.3f} s, "
                f"{rate:.0f} steps/s, x{rate / base:.2f} of one thread; cpu per step "
                f"{1e6 * m['cpu'] / m['steps']:.1f} us"
            )
            if threads == 1:
                one = m
        b = run_batch(scene, a.sims, steps)
        rate = b["steps"] / b["wall"]
        print(
            f"[{r}] step_many: wall {b['wall']:.3f} s, cpu {b['cpu']:.3f} s, {rate:.0f} steps/s, "
            f"x{rate / base:.2f} of one thread"
        )
    if 1 in counts:
        # with one thread, all the time outside the world steps holds the GIL: the
        # binding's work and this script's own Python (the target dicts, the loop)
        s = 1 - one["rust_total"] / one["wall"]
        print(
            f"per step (one thread, medians): Python call {one['call_us']:.1f} us, world step "
            f"{one['rust_us']:.1f} us, binding overhead {one['overhead_us']:.2f} us = "
            f"{one['overhead_us'] / one['rust_us']:.4f} of the world step"
        )
        print(
            f"share of the one-thread run outside the world steps (GIL held): {s:.4f}; two "
            f"threads on two idle cores can reach x{1 / (s + (1 - s) / 2):.3f} (Amdahl)"
        )
    print(f"load average after: {load_average()}")


if __name__ == "__main__":
    main()
