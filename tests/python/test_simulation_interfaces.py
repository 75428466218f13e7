"""The ROS 2 standard simulation_interfaces services (release 1.5.1) over Cyclone DDS, as
a test harness written for Gazebo or Isaac Sim calls them: the feature list, the
simulation state round trip (playing, paused, stopped), steps while paused (and refused
while playing), resets by scope, and quitting; the SimulateSteps action as rclpy's
ActionClient calls it (goal, feedback, result, refusal while playing, cancel). The
request and response types are checked first against the vendored .msg/.srv/.action
text, parsed by rosbags."""

from __future__ import annotations

import dataclasses
import uuid

from conftest import ROOT, SCENES, reliable_qos
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

import ros_types as rt

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
VENDORED = ROOT / "src" / "wire" / "interfaces" / "simulation_interfaces"
NODE = "/developable_sim"
STATUS_QOS = reliable_qos(depth=10000)

# SimulationState, Result, SimulatorFeatures constants (the vendored definitions)
STOPPED, PLAYING, PAUSED, QUITTING = 0, 1, 2, 3
FEATURE_UNSUPPORTED, OK, OPERATION_FAILED = 0, 1, 4
ALREADY_IN_TARGET_STATE = 101
SCOPE_DEFAULT, SCOPE_TIME, SCOPE_STATE, SCOPE_ALL = 0, 1, 2, 255


def typestore():
    """rosbags' Jazzy store plus the vendored simulation_interfaces definitions, each
    service split into its request and response as rosidl does."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for p in sorted(VENDORED.glob("*.msg")):
        types.update(get_types_from_msg(p.read_text(), f"simulation_interfaces/msg/{p.stem}"))
    for p in sorted(VENDORED.glob("*.srv")):
        req, resp = p.read_text().split("\n---\n")
        for part, text in (("Request", req), ("Response", resp)):
            types.update(
                get_types_from_msg(text, f"simulation_interfaces/msg/{p.stem}_{part}")
            )
    store.register(types)
    return store


def rosbags_fields(store, name):
    """(field name, type) of a registered type, nested types by their short name."""
    out = []
    for fname, (kind, detail) in store.fielddefs[name][1]:
        if kind.name == "BASE":
            out.append((fname, detail[0]))
        elif kind.name == "NAME":
            out.append((fname, detail.split("/")[-1]))
        else:  # a sequence or array
            (ekind, edetail), _ = detail
            out.append((fname, (edetail[0] if ekind.name == "BASE" else edetail) + "[]"))
    return out


def idl_type(tp) -> str:
    """The ROS type a cyclonedds field type stands for: `uint8`, `string`, `uint16[]`,
    or a nested type's short name (from its DDS name `pkg::msg::dds_::Type_`)."""
    if tp is str:
        return "string"
    meta = getattr(tp, "__metadata__", None)
    if meta is not None:
        m = meta[0]
        if isinstance(m, str):
            return m
        inner = tp.__args__[0].__args__[0]  # Sequence[X]
        return idl_type(inner) + "[]"
    return tp.__idl_typename__.split("::")[-1].rstrip("_")


def dataclass_fields(cls):
    """(field name, ROS type) of a ros_types dataclass, the rmw_cyclonedds request
    header (client_guid, sequence_number) left out."""
    return [
        (f.name, idl_type(f.type))
        for f in dataclasses.fields(cls)
        if f.name not in ("client_guid", "sequence_number")
    ]


def test_python_types_are_the_vendored_definitions():
    store = typestore()
    pairs = {
        "simulation_interfaces/msg/Result": rt.SimResult,
        "simulation_interfaces/msg/SimulationState": rt.SimulationState,
        "simulation_interfaces/msg/SimulatorFeatures": rt.SimulatorFeatures,
        "simulation_interfaces/msg/GetSimulatorFeatures_Response": rt.GetSimulatorFeaturesResponse,
        "simulation_interfaces/msg/ResetSimulation_Request": rt.ResetSimulationRequest,
        "simulation_interfaces/msg/ResetSimulation_Response": rt.ResetSimulationResponse,
        "simulation_interfaces/msg/StepSimulation_Request": rt.StepSimulationRequest,
        "simulation_interfaces/msg/StepSimulation_Response": rt.StepSimulationResponse,
        "simulation_interfaces/msg/GetSimulationState_Response": rt.GetSimulationStateResponse,
        "simulation_interfaces/msg/SetSimulationState_Request": rt.SetSimulationStateRequest,
        "simulation_interfaces/msg/SetSimulationState_Response": rt.SetSimulationStateResponse,
    }
    for name, cls in pairs.items():
        assert dataclass_fields(cls) == rosbags_fields(store, name), name
    # empty requests: rosidl's placeholder member
    # the SimulateSteps action's goal, result and feedback (the .action's three parts)
    goal, result, feedback = (VENDORED / "SimulateSteps.action").read_text().split("\n---\n")
    for text, part, cls in (
        (goal, "Goal", rt.SimulateStepsGoal),
        (result, "Result", rt.SimulateStepsResult),
        (feedback, "Feedback", rt.SimulateStepsFeedback),
    ):
        name = f"simulation_interfaces/msg/SimulateSteps_{part}"
        store.register(get_types_from_msg(text, name))
        assert dataclass_fields(cls) == rosbags_fields(store, name), name
    for cls in (rt.GetSimulatorFeaturesRequest, rt.GetSimulationStateRequest):
        assert [n for n, _ in dataclass_fields(cls)] == ["structure_needs_at_least_one_member"]
    # the checker itself: a swapped field order is caught
    swapped = [("error_message", "string"), ("result", "uint8")]
    assert swapped != rosbags_fields(store, "simulation_interfaces/msg/Result")


def call(ros, service, req, resp, **fields):
    return ros.call(f"{NODE}/{service}", req, resp, **fields)


def get_state(ros):
    r = call(ros, "get_simulation_state", rt.GetSimulationStateRequest, rt.GetSimulationStateResponse)
    assert r.result.result == OK, r.result
    return r.state.state


def set_state(ros, state):
    return call(
        ros, "set_simulation_state", rt.SetSimulationStateRequest, rt.SetSimulationStateResponse,
        state=rt.SimulationState(state=state),
    ).result


def step(ros, steps):
    return call(
        ros, "step_simulation", rt.StepSimulationRequest, rt.StepSimulationResponse, steps=steps
    ).result


def reset(ros, scope):
    return call(
        ros, "reset_simulation", rt.ResetSimulationRequest, rt.ResetSimulationResponse,
        scope=scope,
    ).result


def newest(ros, status, until=None, timeout=10.0):
    if until is None:
        got = ros.take(status, 0.3)
        assert got, "no status"
        return got[-1]
    return ros.take(status, timeout, until=until)[-1]


def test_simulation_interfaces_services(ros, domain_id, start_node):
    node = start_node(domain_id, GRIPPER)
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    ros.wait_matched(status)
    # the start-up banner names them (the node prints it before "ready")
    banner = [l for l in node.log().splitlines() if "(simulation_interfaces 1.5.1)" in l]
    assert len(banner) == 1 and "/developable_sim/set_simulation_state" in banner[0], banner
    assert "action: /developable_sim/simulate_steps" in banner[0], banner

    f = call(
        ros, "get_simulator_features", rt.GetSimulatorFeaturesRequest,
        rt.GetSimulatorFeaturesResponse,
    ).features
    # SIMULATION_RESET(_TIME, _STATE), SIMULATION_STATE_GETTING, _SETTING, _PAUSE,
    # STEP_SIMULATION_SINGLE, _MULTIPLE, _ACTION; no spawning, no worlds
    assert sorted(f.features) == [20, 21, 22, 24, 25, 26, 31, 32, 33], f.features
    assert f.spawn_formats == [] and "simulation_interfaces 1.5.1" in f.custom_info

    assert get_state(ros) == PLAYING
    # stepping while playing is refused
    r = step(ros, 5)
    assert r.result == OPERATION_FAILED and "pause it first" in r.error_message, r
    assert set_state(ros, PLAYING).result == ALREADY_IN_TARGET_STATE

    # pause, then step exactly N steps while paused
    assert set_state(ros, PAUSED).result == OK
    assert get_state(ros) == PAUSED
    paused = newest(ros, status, until=lambda s: s.paused)
    ros.take(status, 0.3)  # nothing else comes while paused
    r = step(ros, 25)
    assert r.result == OK, r
    stepped = newest(ros, status)
    assert stepped.paused and stepped.step == paused.step + 25, (paused.step, stepped.step)
    assert step(ros, 0).result == OPERATION_FAILED
    assert step(ros, 1).result == OK
    assert newest(ros, status).step == stepped.step + 1
    assert get_state(ros) == PAUSED

    # resets: time and state together; one scope alone is not supported
    for scope in (SCOPE_TIME, SCOPE_STATE):
        r = reset(ros, scope)
        assert r.result == FEATURE_UNSUPPORTED and "together" in r.error_message, r
    assert reset(ros, SCOPE_DEFAULT).result == OK
    s = newest(ros, status, until=lambda s: s.step == 0)
    assert s.episode == 1 and s.sim_time == 0.0
    assert step(ros, 3).result == OK
    assert reset(ros, SCOPE_ALL).result == OK
    assert newest(ros, status, until=lambda s: s.step == 0).episode == 2

    # stopped: paused and reset; played from there it runs
    assert step(ros, 4).result == OK
    assert set_state(ros, STOPPED).result == OK
    assert get_state(ros) == STOPPED
    s = newest(ros, status, until=lambda s: s.step == 0)
    assert s.paused and s.episode == 3
    assert set_state(ros, STOPPED).result == ALREADY_IN_TARGET_STATE
    assert set_state(ros, PLAYING).result == OK
    assert get_state(ros) == PLAYING
    running = newest(ros, status, until=lambda s: s.step >= 20)
    assert not running.paused

    # quitting: the reply, then the node exits cleanly
    assert set_state(ros, QUITTING).result == OK
    assert node.wait_exit(15.0) == 0, node.log()
    assert "STATE_QUITTING" in node.log()


# The SimulateSteps action, called as rclpy's ActionClient does on rmw_cyclonedds: the
# services <action>/_action/send_goal, get_result, cancel_goal (rq/...Request,
# rr/...Reply) and the topics <action>/_action/feedback and status.
ACTION = f"{NODE}/simulate_steps/_action"
# action_msgs/msg/GoalStatus, action_msgs/srv/CancelGoal
UNKNOWN, SUCCEEDED, CANCELED, ABORTED = 0, 4, 5, 6
CANCEL_NONE, CANCEL_UNKNOWN_GOAL, CANCEL_GOAL_TERMINATED = 0, 2, 3


def goal_uuid():
    return rt.UUID(uuid=list(uuid.uuid4().bytes))


def send_goal(ros, goal_id, steps):
    return ros.call(
        f"{ACTION}/send_goal", rt.SimulateStepsSendGoalRequest, rt.SimulateStepsSendGoalResponse,
        goal_id=goal_id, goal=rt.SimulateStepsGoal(steps=steps),
    )


def get_result(ros, goal_id, fresh=False):
    return ros.call(
        f"{ACTION}/get_result", rt.SimulateStepsGetResultRequest,
        rt.SimulateStepsGetResultResponse, timeout=60.0, fresh=fresh, goal_id=goal_id,
    )


def cancel(ros, goal_id):
    return ros.call(
        f"{ACTION}/cancel_goal", rt.CancelGoalRequest, rt.CancelGoalResponse,
        goal_info=rt.GoalInfo(goal_id=goal_id),
    )


def feedback_of(samples, goal_id):
    return [s.feedback for s in samples if list(s.goal_id.uuid) == list(goal_id.uuid)]


def increasing(values) -> bool:
    return all(b > a for a, b in zip(values, values[1:]))


def advanced_by(before, after, n) -> bool:
    """Whether `after` is exactly n steps of dt past `before`: the step counter exactly,
    sim time within 1e-9 s (n additions of dt round to ~1e-14 s; one dt is 1e-2 s)."""
    dt = before.dt
    return (
        after.step == before.step + n
        and abs(after.sim_time - before.sim_time - n * dt) <= 1e-9
    )


def test_simulate_steps_action(ros, domain_id, start_node):
    start_node(domain_id, GRIPPER)
    status = ros.reader("/ribbon/status", rt.SimStatus, STATUS_QOS)
    feedback = ros.reader(
        f"{ACTION}/feedback", rt.SimulateStepsFeedbackMessage, reliable_qos(depth=100000)
    )
    goals = ros.reader(
        f"{ACTION}/status", rt.GoalStatusArray, reliable_qos(depth=1, transient_local=True)
    )
    for r in (status, feedback, goals):
        ros.wait_matched(r)

    # while playing: accepted, then aborted with OPERATION_FAILED and the reason
    g = goal_uuid()
    assert send_goal(ros, g, 5).accepted
    r = get_result(ros, g)
    assert r.status == ABORTED and r.result.result.result == OPERATION_FAILED, r
    assert "pause it first" in r.result.result.error_message, r
    # a goal id already in use is refused; an unknown goal's result is UNKNOWN
    assert not send_goal(ros, g, 5).accepted
    assert get_result(ros, goal_uuid()).status == UNKNOWN

    # paused: N steps, feedback after each, the result when done (asked for at once, so
    # the result request waits for the end), sim time advanced by exactly N dt
    assert set_state(ros, PAUSED).result == OK
    before = newest(ros, status, until=lambda s: s.paused)
    ros.take(status, 0.3)  # nothing else comes while paused
    n = 40
    g = goal_uuid()
    assert send_goal(ros, g, n).accepted
    r = get_result(ros, g, fresh=True)  # a new client: its reply waits for its reader
    assert r.status == SUCCEEDED and r.result.result.result == OK, r
    after = newest(ros, status)
    assert after.paused and advanced_by(before, after, n), (before, after)
    # the checker itself: one step more or less is caught
    assert not advanced_by(before, after, n + 1) and not advanced_by(before, after, n - 1)
    fb = feedback_of(ros.take(feedback, 1.0), g)
    done = [f.completed_steps for f in fb]
    assert increasing(done) and done[-1] == n, done
    assert all(f.remaining_steps == n - f.completed_steps for f in fb), fb
    assert not increasing([1, 3, 2])  # the checker itself
    ended = newest(ros, goals, until=lambda a: any(
        list(s.goal_info.goal_id.uuid) == list(g.uuid) and s.status == SUCCEEDED
        for s in a.status_list
    ))
    assert ended.status_list
    assert get_state(ros) == PAUSED

    # cancel mid-goal: it stops between steps, with the steps done so far
    before = after
    big = 1_000_000
    g = goal_uuid()
    assert send_goal(ros, g, big).accepted
    seen = feedback_of(ros.take(feedback, 30.0, until=lambda s: s.feedback.completed_steps >= 5
                                and list(s.goal_id.uuid) == list(g.uuid)), g)
    c = cancel(ros, g)
    assert c.return_code == CANCEL_NONE, c
    assert [list(i.goal_id.uuid) for i in c.goals_canceling] == [list(g.uuid)], c
    r = get_result(ros, g)
    assert r.status == CANCELED and r.result.result.result == OPERATION_FAILED, r
    msg = r.result.result.error_message
    assert msg.startswith("canceled after ") and msg.endswith(f" of {big} steps"), msg
    k = int(msg.split()[2])
    assert seen[-1].completed_steps <= k < big, (seen[-1], msg)
    after = newest(ros, status)
    assert advanced_by(before, after, k), (before, after, k)
    assert not ros.take(status, 0.5), "steps went on after the cancel"
    assert cancel(ros, g).return_code == CANCEL_GOAL_TERMINATED
    assert cancel(ros, goal_uuid()).return_code == CANCEL_UNKNOWN_GOAL
    assert get_state(ros) == PAUSED
