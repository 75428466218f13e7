#!/usr/bin/env python3
"""Latency and endurance benchmark of the developable_sim node over real DDS (a
benchmark, not a test: it prints numbers, it does not assert them).

    .venv/bin/python tools/bench_node.py                 # all four measurements
    .venv/bin/python tools/bench_node.py --only stream --stream-seconds 60

1. tick: real-time 100 Hz ticks, nobody publishing: tick start -> markers published
   (node clock, `node --stats`).
2. realtime: a pose every 47 ms (phase drifting against the ticks): pose taken from DDS
   -> markers of the first step using it published (node clock), and the round trip
   seen by the publisher (pose written -> status reporting its stamp received).
3. lockstep: `--lockstep gripper`, one pose at a time: the same two figures.
4. stream: 1 kHz poses on each of two handles for --stream-seconds (default 60):
   per-10-s windows of resident memory and latency (growth check).
5. camera: tick start -> markers of the default scene with its 15 Hz camera against the
   same scene with `--set cameras=[]`, in --camera-pairs pairs of --camera-seconds runs
   (the two in turn, the ratio pair by pair), without and then with a subscriber to the
   camera's images and cloud (which makes DDS send 7 MB a frame; the subscriber reads
   the headers only, so it costs little CPU of its own); the camera's frames drawn,
   skipped and its drawing time.

The node binary: $DEVELOPABLE_SIM_BIN or target/release/developable_sim.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))

import ros_types as rt  # noqa: E402
from conftest import SENSOR_QOS, Ros, pose_msg, reliable_qos  # noqa: E402

BIN = Path(os.environ.get("DEVELOPABLE_SIM_BIN", ROOT / "target" / "release" / "developable_sim"))
GRIPPER = ROOT / "config" / "scenes" / "ribbon_gripper.yaml"
TWO = ROOT / "config" / "scenes" / "ribbon_two_grippers.yaml"


def pct(values, p):
    if not values:
        return float("nan")
    v = sorted(values)
    return v[min(len(v) - 1, round(p * (len(v) - 1)))]


class Node:
    def __init__(self, domain, args, workdir):
        self.stats = Path(workdir) / f"stats_{domain}.json"
        self.log = open(Path(workdir) / f"node_{domain}.log", "w")
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
        self.proc = subprocess.Popen(
            [str(BIN), "node", *args, "--stats", str(self.stats)],
            cwd=ROOT,
            env=env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            if "[developable_sim] ready" in Path(self.log.name).read_text():
                return
            time.sleep(0.05)
        raise RuntimeError(Path(self.log.name).read_text())

    def finish(self):
        self.proc.send_signal(signal.SIGINT)
        self.proc.wait(timeout=30)
        return json.loads(self.stats.read_text())


def fmt(lat):
    return f"median {lat['median_ms']:.3f} ms, p99 {lat['p99_ms']:.3f} ms, max {lat['max_ms']:.3f} ms (n={lat['samples']})"


def bench_tick(work, seconds):
    d = random.randint(1, 200)
    node = Node(d, [str(GRIPPER)], work)
    time.sleep(seconds)
    s = node.finish()
    print(f"[tick] real-time 100 Hz, {s['steps']} steps, overruns {s['overrun_ticks']}")
    print(f"  step:                   {fmt(s['step'])}")
    print(f"  tick start -> markers:  {fmt(s['tick_to_markers'])}")
    print(f"  beyond the tick's step: {fmt(s['tick_beyond_step'])}")
    return s


def round_trips(ros, writer, status, n, spacing):
    rtt = []
    for i in range(n):
        stamp = 1000 + i
        t0 = time.perf_counter()
        writer.write(pose_msg(0.7, 0.05 * (i % 5), 0.3, sec=stamp))
        got = False
        deadline = t0 + 1.0
        while time.perf_counter() < deadline and not got:
            for st in status.take(N=64):
                if hasattr(st, "handles") and st.handles and st.handles[0].last_stamp.sec == stamp:
                    rtt.append((time.perf_counter() - t0) * 1e3)
                    got = True
            if not got:
                time.sleep(0.0002)
        time.sleep(spacing)
    return rtt


def bench_input(work, n, lockstep):
    d = random.randint(1, 200)
    args = [str(GRIPPER)] + (["--lockstep", "gripper"] if lockstep else [])
    node = Node(d, args, work)
    ros = Ros(d)
    status = ros.reader("/ribbon/status", rt.SimStatus, reliable_qos(50))
    writer = ros.writer("/handles/gripper", rt.PoseStamped, SENSOR_QOS)
    Ros.wait_matched(writer)
    Ros.wait_matched(status)
    time.sleep(0.5)
    rtt = round_trips(ros, writer, status, n, 0.0 if lockstep else 0.047)
    s = node.finish()
    name = "lockstep" if lockstep else "realtime"
    print(f"[{name}] {len(rtt)} poses")
    print(f"  step:                          {fmt(s['step'])}")
    print(f"  pose taken -> markers (node):  {fmt(s['input_to_markers'])}")
    print(
        f"  pose written -> status received (Python, incl. 2 DDS hops): median {statistics.median(rtt):.3f} ms, p99 {pct(rtt, 0.99):.3f} ms"
    )
    return s, rtt


def bench_stream(work, seconds):
    d = random.randint(1, 200)
    node = Node(d, [str(TWO)], work)
    ros = Ros(d)
    a = ros.writer("/handles/left", rt.PoseStamped, SENSOR_QOS)
    b = ros.writer("/handles/right", rt.PoseStamped, SENSOR_QOS)
    Ros.wait_matched(a)
    Ros.wait_matched(b)
    start = time.perf_counter()
    n = 0
    period = 1e-3
    while True:
        now = time.perf_counter()
        if now - start >= seconds:
            break
        k = n
        a.write(pose_msg(0.0, 0.0, 0.3, sec=1 + k // 1000, nanosec=(k % 1000) * 10**6))
        b.write(pose_msg(0.6, 0.05 * ((k // 500) % 3), 0.3, sec=1 + k // 1000, nanosec=(k % 1000) * 10**6))
        n += 1
        # keep the 1 kHz schedule (catch up after a late wake-up)
        sleep = start + n * period - time.perf_counter()
        if sleep > 0:
            time.sleep(sleep)
    rate = n / (time.perf_counter() - start)
    s = node.finish()
    print(f"[stream] {n} poses per handle at {rate:.0f} Hz for {seconds} s; node received {s['inputs_received']}")
    print("  window_end_s  rss_MiB  steps  inputs  tick->markers median/p99 ms  pose->markers median/p99 ms")
    for w in s["windows"]:
        print(
            f"  {w['end_s']:10.1f}  {w['rss_kib'] / 1024:7.1f}  {w['steps']:5d}  {w['inputs']:6d}"
            f"  {w['tick_to_markers']['median_ms']:8.3f} / {w['tick_to_markers']['p99_ms']:7.3f}"
            f"  {w['input_to_markers']['median_ms']:8.3f} / {w['input_to_markers']['p99_ms']:7.3f}"
        )
    return s


def camera_subscriber(domain):
    """A participant reading the camera's images and cloud (headers only), with a
    socket receive buffer for 4.9 MB clouds; returns (ros, readers)."""
    buf = '<CycloneDDS><Domain><Internal><SocketReceiveBufferSize min="4MB"/></Internal></Domain></CycloneDDS>'
    uri = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = f"{uri},{buf}" if uri else buf
    try:
        ros = Ros(domain)
    finally:
        if uri is None:
            del os.environ["CYCLONEDDS_URI"]
        else:
            os.environ["CYCLONEDDS_URI"] = uri
    from conftest import _cdr1
    from cyclonedds.core import Policy

    qos = _cdr1(Policy.Reliability.BestEffort, Policy.History.KeepLast(1), Policy.Durability.Volatile)
    readers = [
        ros.reader("/camera/color/image_raw", rt.ImageHead, qos),
        ros.reader("/camera/aligned_depth_to_color/image_raw", rt.ImageHead, qos),
        ros.reader("/camera/depth/color/points", rt.PointCloud2Head, qos),
    ]
    return ros, readers


def camera_run(work, seconds, camera, subscribe):
    d = random.randint(1, 200)
    args = [str(GRIPPER)] + ([] if camera else ["--set", "cameras=[]"])
    node = Node(d, args, work)
    ros, readers, got = None, [], 0
    if subscribe:
        ros, readers = camera_subscriber(d)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for r in readers:
            got += sum(1 for x in r.take(N=8) if hasattr(x, "header"))
        time.sleep(0.01)
    s = node.finish()
    if ros is not None:
        ros.close()
    s["_received"] = got
    return s


def bench_camera(work, seconds, pairs):
    for subscribe in (False, True):
        print(f"[camera] {pairs} pairs of {seconds} s runs, camera on / off, "
              f"{'a subscriber to the images and cloud' if subscribe else 'no subscriber'}; "
              f"load average {os.getloadavg()[0]:.2f}")
        medians, p99s = [], []
        for k in range(pairs):
            runs = {}
            for camera in ((True, False) if k % 2 == 0 else (False, True)):
                runs[camera] = camera_run(work, seconds, camera, subscribe)
            on, off = runs[True], runs[False]
            m = on["tick_to_markers"]["median_ms"] / off["tick_to_markers"]["median_ms"]
            p = on["tick_to_markers"]["p99_ms"] / off["tick_to_markers"]["p99_ms"]
            medians.append(m)
            p99s.append(p)
            print(
                f"  pair {k + 1}: tick -> markers median {on['tick_to_markers']['median_ms']:.3f} / "
                f"{off['tick_to_markers']['median_ms']:.3f} ms (x{m:.3f}), p99 "
                f"{on['tick_to_markers']['p99_ms']:.3f} / {off['tick_to_markers']['p99_ms']:.3f} ms "
                f"(x{p:.3f}); overruns {on['overrun_ticks']} / {off['overrun_ticks']}; camera "
                f"{on['camera_frames']} drawn, {on['camera_frames_skipped']} skipped, drawing "
                f"{fmt(on['camera_draw'])}; received {on['_received']}"
            )
        print(
            f"  ratio camera on / off, median of the pairs: tick -> markers median "
            f"x{statistics.median(medians):.3f}, p99 x{statistics.median(p99s):.3f}; "
            f"load average {os.getloadavg()[0]:.2f}"
        )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", choices=["tick", "realtime", "lockstep", "stream", "camera"])
    ap.add_argument("--tick-seconds", type=float, default=20.0)
    ap.add_argument("--poses", type=int, default=300)
    ap.add_argument("--stream-seconds", type=float, default=60.0)
    ap.add_argument("--camera-seconds", type=float, default=10.0)
    ap.add_argument("--camera-pairs", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        if a.only in (None, "tick"):
            bench_tick(work, a.tick_seconds)
        if a.only in (None, "realtime"):
            bench_input(work, a.poses, lockstep=False)
        if a.only in (None, "lockstep"):
            bench_input(work, a.poses, lockstep=True)
        if a.only in (None, "stream"):
            bench_stream(work, a.stream_seconds)
        if a.only in (None, "camera"):
            bench_camera(work, a.camera_seconds, a.camera_pairs)


if __name__ == "__main__":
    main()
