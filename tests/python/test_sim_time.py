"""Time under use_sim_time (issue 45): simulated time starts at the first /clock sample
wherever the clock is (a simulator already running at 100 s, `ros2 bag play --clock` at
epoch times of ~1.7e9 s), stamps follow the clock, a clock that jumps backwards resets
the simulation (counted in SimStatus.clock_resets), a forward gap beyond max_clock_jump
is not simulated; a bag recorded under such a clock replays identical. And real-time
honesty: a node that cannot keep up says so in SimStatus.real_time_factor and on
stderr."""

from __future__ import annotations

import time

import pytest
from conftest import SCENES, _cdr1, reliable_qos
from cyclonedds.core import Policy
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from test_commands_replay import commands, replay, without_one_command

import ros_types as rt

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
DT_NS = 10_000_000  # the gripper scene's dt, 0.01 s
TIME_ORIGIN = 8  # SimCommand kinds (msg/SimCommand.msg)
S = 1_000_000_000
CLOCK_QOS = _cdr1(
    Policy.Reliability.BestEffort, Policy.History.KeepLast(1), Policy.Durability.Volatile
)
# every status of the run, whatever the reader's pace
STATUS_QOS = reliable_qos(depth=10000)


def ns(stamp) -> int:
    return stamp.sec * S + stamp.nanosec


class Clock:
    """A /clock publisher at the wall rate, as a simulator or `ros2 bag play --clock`."""

    def __init__(self, ros):
        self.w = ros.writer("/clock", rt.Clock, qos=CLOCK_QOS)
        ros.wait_matched(self.w)
        self.now = None
        self.sent_max = None

    def say(self, t_ns: int, times: int = 3) -> None:
        """Publish t_ns (a few times: best effort)."""
        self.now = t_ns
        self.sent_max = t_ns if self.sent_max is None else max(self.sent_max, t_ns)
        c = rt.Clock(clock=rt.Time(sec=t_ns // S, nanosec=t_ns % S))
        for _ in range(times):
            self.w.write(c)
            time.sleep(0.002)

    def run(self, seconds: float, on_tick=None) -> None:
        """Advance from the current time at the wall rate for `seconds`, in 10 ms
        samples (100 Hz, as Gazebo publishes)."""
        start_wall = time.monotonic()
        start = self.now
        while True:
            elapsed = time.monotonic() - start_wall
            if elapsed >= seconds:
                break
            self.say(start + int(elapsed * S), times=1)
            if on_tick is not None:
                on_tick()
            time.sleep(0.01)
        self.say(start + int(seconds * S))


def statuses(ros, reader, timeout=0.5):
    return ros.take(reader, timeout)


def settle(ros, reader, clock_ns: int, timeout=10.0):
    """Statuses until one is stamped within half a dt of clock_ns (the node caught up)."""
    return ros.take(reader, timeout, until=lambda s: abs(ns(s.header.stamp) - clock_ns) <= DT_NS // 2)


def start_sim_time_node(start_node, domain_id, *flags, params=()):
    ros_params = [a for p in params for a in ("-p", p)]
    return start_node(
        domain_id, GRIPPER, *flags, "--ros-args", "-p", "use_sim_time:=true", *ros_params
    )


@pytest.mark.parametrize("start_s", [100, 1_700_000_000])
def test_time_starts_at_the_first_clock_sample_and_follows_the_clock(
    ros, domain_id, start_node, start_s
):
    node = start_sim_time_node(start_node, domain_id)
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    clock = Clock(ros)
    # nothing is published before the clock exists
    assert statuses(ros, status, 0.5) == []
    start = start_s * S
    clock.say(start)
    first = ros.take(status, 10.0, until=lambda s: True)[-1]
    # the initial state, stamped at the clock's start (not at 0, not caught up from 0)
    assert ns(first.header.stamp) == start, first.header.stamp
    assert first.step == 0 and first.sim_time == 0.0 and first.clock_resets == 0
    seen = [first]
    ahead = []

    def check_not_ahead():
        # a status is never stamped after the newest clock sent (dt/2 rule)
        for s in statuses(ros, status, 0.0):
            seen.append(s)
            if ns(s.header.stamp) > clock.sent_max + DT_NS // 2:
                ahead.append((ns(s.header.stamp), clock.sent_max))

    clock.run(2.0, on_tick=check_not_ahead)
    end = clock.now
    seen += settle(ros, status, end)
    assert ahead == [], ahead[:3]
    last = seen[-1]
    # the last state is within one dt of the clock, and every stamp is the clock's start
    # plus the state's simulated time, exactly (ns)
    assert abs(ns(last.header.stamp) - end) <= DT_NS // 2, (ns(last.header.stamp), end)
    for s in seen:
        assert ns(s.header.stamp) == start + s.step * DT_NS, (s.step, s.header.stamp)
    # followed at the clock's rate: 2 s of clock is 200 steps of 0.01 s (not 100 s / dt)
    assert abs(last.step - 200) <= 1, last.step
    assert "simulated time starts at" in node.log()
    assert node.stop() == 0


def test_a_clock_that_jumps_back_resets_and_is_counted(ros, domain_id, start_node):
    node = start_sim_time_node(start_node, domain_id)
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    clock = Clock(ros)
    clock.say(100 * S)
    clock.run(1.0)
    before = settle(ros, status, clock.now)[-1]
    assert before.step >= 99 and before.clock_resets == 0 and before.episode == 0
    # a bag played in a loop: back to its start
    clock.say(100 * S + S // 4)
    reset = ros.take(status, 10.0, until=lambda s: s.clock_resets == 1)[-1]
    assert reset.step == 0 and reset.episode == 1, (reset.step, reset.episode)
    assert ns(reset.header.stamp) == 100 * S + S // 4
    # and it follows the clock again from there
    clock.run(0.5)
    after = settle(ros, status, clock.now)[-1]
    assert after.clock_resets == 1 and abs(after.step - 50) <= 1, after.step
    assert ns(after.header.stamp) == 100 * S + S // 4 + after.step * DT_NS
    # once again: counted twice
    clock.say(100 * S)
    again = ros.take(status, 10.0, until=lambda s: s.clock_resets == 2)[-1]
    assert again.episode == 2 and again.step == 0
    log = node.log()
    assert log.count("/clock jumped back") == 2, log
    assert node.stop() == 0


def test_a_forward_gap_beyond_max_clock_jump_is_not_simulated(ros, domain_id, start_node):
    node = start_sim_time_node(start_node, domain_id)
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    clock = Clock(ros)
    clock.say(100 * S)
    clock.run(0.5)
    before = settle(ros, status, clock.now)[-1]
    steps_before = before.step
    # 5 s of clock in one sample: a paused simulator resumed, a gap in a bag
    clock.say(clock.now + 5 * S)
    clock.run(0.5)
    got = settle(ros, status, clock.now)
    after = got[-1]
    # about 0.5 s more simulated (50 steps), not 5.5 s (550)
    assert abs(after.step - steps_before - 50) <= 2, (steps_before, after.step)
    assert abs(ns(after.header.stamp) - clock.now) <= DT_NS // 2
    assert after.clock_resets == 0 and after.episode == 0
    # no status was stamped inside the gap
    gap = [s for s in got if before.header.stamp.sec + 1 < s.header.stamp.sec < 105]
    assert gap == [], [ns(s.header.stamp) for s in gap][:3]
    log = node.log()
    assert log.count("/clock jumped ahead") == 1, log
    assert node.stop() == 0


def test_a_gap_within_max_clock_jump_is_simulated(ros, domain_id, start_node):
    """The negative of the rule above: max_clock_jump 10 s lets a 5 s gap be simulated
    (caught up in dt steps)."""
    node = start_sim_time_node(start_node, domain_id, params=["max_clock_jump:=10.0"])
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    clock = Clock(ros)
    clock.say(100 * S)
    clock.run(0.3)
    clock.say(clock.now + 5 * S)
    after = settle(ros, status, clock.now, timeout=60.0)[-1]
    assert abs(after.step - 530) <= 2, after.step
    assert "/clock jumped ahead" not in node.log()
    assert node.stop() == 0


def header_stamps(bag) -> dict[str, list[int]]:
    """The header stamps (ns) of every recorded message that has a header, per topic
    (decoded by mcap-ros2-support)."""
    out: dict[str, list[int]] = {}
    for f in sorted(bag.glob("*.mcap")):
        with open(f, "rb") as fh:
            reader = make_reader(fh, decoder_factories=[DecoderFactory()])
            for _s, channel, _m, msg in reader.iter_decoded_messages():
                header = getattr(msg, "header", None)
                if header is not None:
                    stamp = header.stamp.sec * S + header.stamp.nanosec
                    out.setdefault(channel.topic, []).append(stamp)
    return out


def test_a_bag_recorded_under_a_jumping_clock_replays_identical(ros, domain_id, start_node, tmp_path):
    bag = tmp_path / "bag"
    node = start_sim_time_node(start_node, domain_id, "--record", str(bag))
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    clock = Clock(ros)
    clock.say(1_700_000_000 * S)
    clock.run(0.5)
    clock.say(clock.now + 3 * S)  # forward jump: the origin moves
    clock.run(0.3)
    clock.say(1_700_000_000 * S + S // 10)  # backwards: a reset
    clock.run(0.3)
    settle(ros, status, clock.now)
    assert node.stop() == 0
    code, report = replay(bag, tmp_path / "replay.json")
    assert code == 0 and report["identical"], report
    assert report["resets"] == 1 and report["steps"] > 80, report
    # every stamped output is on the clock's time base, the camera's five messages too
    # (their stamp is taken at the capture, beside the simulation loop)
    stamps = header_stamps(bag)
    assert {"/ribbon/status", "/camera/color/camera_info"} <= set(stamps), set(stamps)
    low = {t: min(v) for t, v in stamps.items() if min(v) < 1_700_000_000 * S}
    assert not low, low
    log = node.log()
    assert "/clock jumped ahead" in log and "/clock jumped back" in log
    # the jumps are recorded commands: without the forward jump's TIME_ORIGIN (the
    # second one; the first is the first sample) every later stamp differs
    origins = [k for k, _ in commands(bag) if k == TIME_ORIGIN]
    assert len(origins) == 2, commands(bag)
    seen = []

    def second_origin(m):
        if m.kind == TIME_ORIGIN:
            seen.append(m)
        return len(seen) == 2

    cut = tmp_path / "cut"
    without_one_command(bag, cut, second_origin)
    code, report = replay(cut, tmp_path / "cut.json")
    assert code == 1 and not report["identical"], report
    status = next(t for t in report["topics"] if t["topic"] == "/ribbon/status")
    assert status["differing"] > 0 and "header.stamp" in status["first_difference"], status


def test_a_node_that_cannot_keep_up_says_so(ros, domain_id, start_node):
    """A long ribbon (800 segments) ticking at 1 kHz (dt 1 ms): a step and its markers
    take several ms (measured 6.1 ms a step, 0.11x, at load 11 on 2 cores; a step alone
    is about 4 ms on this machine), so the real-time factor falls well below 1;
    SimStatus says how far and stderr says it once, naming the step time and the tick
    period."""
    node = start_node(domain_id, GRIPPER, "--set", "ribbon.segments=800", "--set", "dt=0.001")
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    got = ros.take(status, 30.0, until=lambda s: s.sim_time > 0.2 and 0 < s.real_time_factor < 0.95)
    slow = got[-1]
    # the factor is simulated over wall time: the node measured it from its steps
    assert 0.0 < slow.real_time_factor < 0.95, slow.real_time_factor
    deadline = time.monotonic() + 10.0
    while "slower than real time" not in node.log() and time.monotonic() < deadline:
        time.sleep(0.1)
    log = node.log()
    line = next(ln for ln in log.splitlines() if "slower than real time" in ln)
    assert "tick period is 1.0 ms" in line and "a step takes" in line, line
    # said once, not once per step (it never keeps up here)
    assert log.count("slower than real time") == 1, log
    assert "keeping up again" not in log, log
    assert node.stop() == 0
