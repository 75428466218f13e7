"""Commands as data: every external action the node applies (handle poses, parameter
changes, pauses, single steps, resets) is recorded in order, and `developable_sim
replay` applies the same commands through the same function, so the replay of a session
driven by all of them is identical bit for bit; a bag with one recorded command removed
replays DIFFERENT."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

from conftest import BIN, ROOT, SCENES, SENSOR_QOS, pose_msg, set_params
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from mcap_ros2.decoder import DecoderFactory

import ros_types as rt

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
COMMANDS = "/developable_sim/commands"
STEP, RESET, SET_PAUSED, SET_PARAMETER = 1, 2, 3, 4


def replay(bag: Path, out: Path) -> tuple[int, dict]:
    r = subprocess.run(
        [str(BIN), "replay", str(bag), "--stats", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert r.returncode in (0, 1), r.stdout + r.stderr
    return r.returncode, json.loads(out.read_text())


def drive_ahead(ros, seconds: float, x: float) -> None:
    """Gripper poses stamped 2 s ahead of the wall clock (a clock offset between two
    machines), moving: accepted while max_stamp_lead > 2 s, rejected below."""
    w = ros.writer("/handles/gripper", rt.PoseStamped, SENSOR_QOS)
    ros.wait_matched(w)
    end = time.monotonic() + seconds
    k = 0
    while time.monotonic() < end:
        ahead = time.time_ns() + 2_000_000_000
        sec, nanosec = divmod(ahead, 1_000_000_000)
        w.write(pose_msg(x, 0.02 * (k % 5), 0.3, sec=sec, nanosec=nanosec))
        k += 1
        time.sleep(0.01)


def commands(bag: Path) -> list[tuple[int, str]]:
    """(kind, parameter name) of every recorded command, decoded by mcap-ros2-support."""
    out = []
    for f in sorted(bag.glob("*.mcap")):
        with open(f, "rb") as fh:
            reader = make_reader(fh, decoder_factories=[DecoderFactory()])
            for _s, channel, _m, msg in reader.iter_decoded_messages(topics=[COMMANDS]):
                assert channel.topic == COMMANDS
                out.append((msg.kind, msg.parameter_name))
    return out


def without_one_command(bag: Path, dst: Path, drop) -> None:
    """Copy `bag` into `dst` with the python `mcap` writer, leaving out the first command
    for which `drop(decoded)` is true."""
    dst.mkdir()
    (f,) = sorted(bag.glob("*.mcap"))
    dropped = False
    with open(f, "rb") as fh, open(dst / f.name, "wb") as out:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        w = Writer(out, compression=CompressionType.NONE)
        header = reader.get_header()
        w.start(profile=header.profile, library=header.library)
        for m in reader.iter_metadata():
            w.add_metadata(m.name, m.metadata)
        summary = reader.get_summary()
        schema_ids = {
            s.id: w.register_schema(s.name, s.encoding, s.data) for s in summary.schemas.values()
        }
        channel_ids = {
            c.id: w.register_channel(c.topic, c.message_encoding, schema_ids[c.schema_id], c.metadata)
            for c in summary.channels.values()
        }
        for _s, channel, message, decoded in reader.iter_decoded_messages():
            if not dropped and channel.topic == COMMANDS and drop(decoded):
                dropped = True
                continue
            w.add_message(
                channel_ids[channel.id],
                log_time=message.log_time,
                data=message.data,
                publish_time=message.publish_time,
                sequence=message.sequence,
            )
        w.finish()
    assert dropped, "the command to drop is in the bag"


def test_runtime_changes_pauses_steps_and_resets_replay_identical(
    start_node, ros, domain_id, tmp_path
):
    bag = tmp_path / "bag"
    node = start_node(domain_id, GRIPPER, "--record", str(bag))
    drive_ahead(ros, 0.4, 0.75)
    assert all(r.successful for r in set_params(ros, max_stamp_lead=1.0))
    drive_ahead(ros, 0.4, 0.70)  # rejected now: the gripper stays where it was
    results = set_params(ros, max_stamp_lead=10.0, marker__line_width=0.004, accept_empty_frame_id=True)
    assert all(r.successful for r in results)
    drive_ahead(ros, 0.3, 0.65)
    assert all(r.successful for r in set_params(ros, paused=True))
    drive_ahead(ros, 0.2, 0.60)  # taken while paused: they land in the next step
    for _ in range(2):
        assert ros.call("/developable_sim/step", rt.TriggerRequest, rt.TriggerResponse).success
    r = ros.call("/developable_sim/set_paused", rt.SetBoolRequest, rt.SetBoolResponse, data=False)
    assert r.success
    assert all(r.successful for r in set_params(ros, markers_rate=20.0, real_time_factor=2.0))
    drive_ahead(ros, 0.3, 0.72)
    assert ros.call("/developable_sim/reset", rt.TriggerRequest, rt.TriggerResponse).success
    drive_ahead(ros, 0.3, 0.68)
    assert node.stop() == 0, node.log()

    recorded = commands(bag)
    kinds = [k for k, _ in recorded]
    assert kinds.count(RESET) == 1 and kinds.count(SET_PAUSED) == 2, recorded
    params = [p for k, p in recorded if k == SET_PARAMETER]
    assert params == [
        "max_stamp_lead",
        "max_stamp_lead",
        "marker.line_width",
        "accept_empty_frame_id",
        "markers_rate",
        "real_time_factor",
    ], recorded
    assert kinds.count(STEP) > 20

    code, rep = replay(bag, tmp_path / "replay.json")
    assert code == 0 and rep["identical"], rep
    assert rep["resets"] == 1 and rep["steps"] == kinds.count(STEP), rep
    statuses = next(t for t in rep["topics"] if t["topic"] == "/ribbon/status")
    assert statuses["compared"] > rep["steps"], "statuses of pause changes compared too"

    # the negative: without the command that lowered max_stamp_lead, the replay accepts
    # the poses the node rejected, and says so
    tampered = tmp_path / "tampered"
    without_one_command(
        bag,
        tampered,
        lambda m: m.kind == SET_PARAMETER and m.parameter_name == "max_stamp_lead" and m.double_value == 1.0,
    )
    code, rep = replay(tampered, tmp_path / "tampered.json")
    assert code == 1 and not rep["identical"], rep
    differing = {t["topic"] for t in rep["topics"] if t["differing"] > 0}
    assert "/ribbon/status" in differing and "/ribbon/markers" in differing, rep


GRASP, RELEASE = 5, 6


def test_grasps_and_releases_with_every_runtime_change_replay_identical(
    start_node, ros, domain_id, tmp_path
):
    """A session that releases, grasps (by [u, v], by the nearest point, by the
    open / close shortcut), pauses, steps, resets and changes every run-time parameter
    replays IDENTICAL; without one recorded grasp, DIFFERENT."""
    bag = tmp_path / "bag"
    node = start_node(domain_id, GRIPPER, "--record", str(bag))
    grasp = lambda **f: ros.call(  # noqa: E731
        "/developable_sim/grasp", rt.GraspRequest, rt.GraspResponse, handle="gripper", **f
    )
    close = lambda data: ros.call(  # noqa: E731
        "/handles/gripper/grasp", rt.SetBoolRequest, rt.SetBoolResponse, data=data
    )
    time.sleep(0.5)
    assert ros.call(
        "/developable_sim/release", rt.ReleaseRequest, rt.ReleaseResponse, handle="gripper"
    ).success
    time.sleep(0.4)
    assert grasp(by_material_point=True, material_point=[0.8, 0.01], hold="full").success
    assert all(r.successful for r in set_params(ros, max_stamp_lead=5.0, tf_max_lag=0.5))
    time.sleep(0.3)
    assert close(False).success
    assert all(r.successful for r in set_params(ros, paused=True))
    assert grasp(world_point=rt.Point(x=0.5, y=0.0, z=0.0), max_distance=2.0).success
    for _ in range(3):
        assert ros.call("/developable_sim/step", rt.TriggerRequest, rt.TriggerResponse).success
    results = set_params(
        ros,
        paused=False,
        marker__line_width=0.004,
        marker__sphere_diameter=0.02,
        accept_empty_frame_id=True,
        markers_rate=20.0,
        real_time_factor=2.0,
    )
    assert all(r.successful for r in results)
    time.sleep(0.4)
    assert close(False).success
    assert ros.call("/developable_sim/reset", rt.TriggerRequest, rt.TriggerResponse).success
    time.sleep(0.3)
    # paused, the released end is still within the grasp radius when it closes again
    assert all(r.successful for r in set_params(ros, paused=True))
    assert close(False).success and close(True).success
    assert all(r.successful for r in set_params(ros, paused=False))
    time.sleep(0.3)
    assert node.stop() == 0, node.log()

    kinds = [k for k, _ in commands(bag)]
    assert kinds.count(GRASP) == 3 and kinds.count(RELEASE) == 4, kinds
    assert kinds.count(SET_PAUSED) == 4, kinds
    code, rep = replay(bag, tmp_path / "replay.json")
    assert code == 0 and rep["identical"], rep
    assert rep["resets"] == 1, rep
    states = next(t for t in rep["topics"] if t["topic"] == "/handles/gripper/state")
    assert states["compared"] >= 8, states  # the start, 7 changes, the reset's

    # the negative: without the grasp at [0.8, 0.01] the end stays open, and replay says so
    tampered = tmp_path / "tampered"
    without_one_command(bag, tampered, lambda m: m.kind == GRASP)
    code, rep = replay(tampered, tmp_path / "tampered.json")
    assert code == 1 and not rep["identical"], rep
    differing = {t["topic"] for t in rep["topics"] if t["differing"] > 0}
    assert {"/ribbon/status", "/ribbon/markers", "/handles/gripper/state"} <= differing, rep


def test_simulate_steps_goal_replays_identical(start_node, ros, domain_id, tmp_path):
    """A SimulateSteps goal's steps are the node's own step commands: recorded one per
    step (exactly N from a node started paused) and replayed IDENTICAL; without one of
    them, DIFFERENT."""
    from test_simulation_interfaces import OK, SUCCEEDED, get_result, goal_uuid, send_goal

    bag = tmp_path / "bag"
    node = start_node(domain_id, GRIPPER, "--paused", "--record", str(bag))
    n = 30
    g = goal_uuid()
    assert send_goal(ros, g, n).accepted
    r = get_result(ros, g)
    assert r.status == SUCCEEDED and r.result.result.result == OK, r
    assert node.stop() == 0, node.log()

    kinds = [k for k, _ in commands(bag)]
    assert kinds.count(STEP) == n, kinds
    code, rep = replay(bag, tmp_path / "replay.json")
    assert code == 0 and rep["identical"] and rep["steps"] == n, rep

    tampered = tmp_path / "tampered"
    without_one_command(bag, tampered, lambda m: m.kind == STEP)
    code, rep = replay(tampered, tmp_path / "tampered.json")
    assert code == 1 and not rep["identical"], rep
