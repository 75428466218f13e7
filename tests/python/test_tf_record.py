"""A TF-driven run recorded and replayed: the bag holds the poses the node looked up
and the lookups that failed (`<handle topic>/tf_lookup_failed`), so `replay`
reproduces every status, the `rejected_tf_lookup` counter included; and lock-step on a
TF-driven handle is refused."""

from __future__ import annotations

import threading
import time

import ros_types as rt
from conftest import SCENES
from test_bags import metadata_counts, replay
from test_ros_graph import TF_QOS, TF_STATIC_QOS, handle_status, tf

GRIPPER = str(SCENES / "ribbon_gripper.yaml")


def test_a_tf_driven_run_with_failed_lookups_replays_identically(
    start_node, ros, domain_id, tmp_path
):
    bag = tmp_path / "bag"
    node = start_node(
        domain_id, GRIPPER, "--set", "handles.0.tf_frame=tool0", "--record", str(bag)
    )
    status = ros.reader("/ribbon/status", rt.SimStatus)
    static = ros.writer("/tf_static", rt.TFMessage, qos=TF_STATIC_QOS)
    dynamic = ros.writer("/tf", rt.TFMessage, qos=TF_QOS)
    for e in (status, static, dynamic):
        ros.wait_matched(e)
    static.write(rt.TFMessage(transforms=[tf("world", "base_link", (0.0, 0.0, 0.1), 0.0, 0)]))
    running = threading.Event()
    running.set()

    def broadcast():
        k = 0
        while running.is_set():
            x = 0.7 + 0.002 * (k % 50)
            dynamic.write(rt.TFMessage(transforms=[tf("base_link", "tool0", (x, 0.05, 0.2))]))
            k += 1
            time.sleep(0.02)

    sender = threading.Thread(target=broadcast, daemon=True)
    sender.start()
    try:
        handle_status(ros, status, 5.0, lambda h: h.external)
        time.sleep(0.5)
    finally:
        running.clear()
        sender.join()
    # TF stops: every tick after tf_max_lag (0.25 s) is a failed, counted lookup
    last = handle_status(ros, status, 5.0, lambda h: h.rejected_tf_lookup >= 20)
    assert node.stop() == 0, node.log()

    counts = metadata_counts(bag)
    failures = counts.get("/handles/gripper/tf_lookup_failed", 0)
    assert failures >= last.rejected_tf_lookup, (failures, last)
    assert counts["/handles/gripper"] > 10  # the poses looked up while TF flowed
    r = replay(bag, tmp_path)
    # statuses carry rejected_tf_lookup: identical only if each failure came back
    assert r["identical"], r
    assert r["max_abs_difference"] == 0.0
    assert r["inputs"] == counts["/handles/gripper"] + failures


def test_lockstep_on_a_tf_driven_handle_is_refused_clearly(start_node, domain_id):
    node = start_node(
        domain_id,
        GRIPPER,
        "--set",
        "handles.0.tf_frame=tool0",
        "--lockstep",
        "gripper",
        wait=False,
    )
    assert node.wait_exit(30) != 0
    log = node.log()
    assert "--lockstep gripper: handle `gripper` follows TF frame `tool0`" in log, log
    assert "--lockstep service" in log
    assert "[developable_sim] ready" not in log
