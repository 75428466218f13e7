"""The rcl_interfaces parameter services over Cyclone DDS, as `ros2 param` with
rmw_cyclonedds calls them: list, get, describe, types, and set, where run-time
parameters take effect (paused, markers_rate, the input policy) and read-only ones are
refused with a reason."""

from __future__ import annotations

import time

from conftest import SCENES, SENSOR_QOS, pose_msg, reliable_qos, set_params

import ros_types as rt

GRIPPER = str(SCENES / "ribbon_gripper.yaml")
NODE = "/developable_sim"
BOOL, INTEGER, DOUBLE, STRING = 1, 2, 3, 4  # rcl_interfaces/ParameterType


def call(ros, service, req, resp, **fields):
    return ros.call(f"{NODE}/{service}", req, resp, **fields)


def test_list_get_describe_and_types(ros, domain_id, start_node):
    start_node(domain_id, GRIPPER, "--ros-args", "-p", "real_time_factor:=0.5")
    r = call(ros, "list_parameters", rt.ListParametersRequest, rt.ListParametersResponse)
    names = set(r.result.names)
    assert {"scene", "paused", "markers_rate", "use_sim_time", "marker.line_width"} <= names
    assert "marker" in r.result.prefixes
    g = call(
        ros, "get_parameters", rt.GetParametersRequest, rt.GetParametersResponse,
        names=["real_time_factor", "scene", "paused", "no_such_parameter"],
    )
    rtf, scene, paused, missing = g.values
    assert (rtf.type, rtf.double_value) == (DOUBLE, 0.5)
    assert scene.type == STRING and scene.string_value.endswith("ribbon_gripper.yaml")
    assert (paused.type, paused.bool_value) == (BOOL, False)
    assert missing.type == 0
    d = call(
        ros, "describe_parameters", rt.DescribeParametersRequest, rt.DescribeParametersResponse,
        names=["scene", "markers_rate"],
    ).descriptors
    assert d[0].read_only and not d[1].read_only and d[1].type == DOUBLE
    assert d[1].floating_point_range and d[1].floating_point_range[0].from_value == 0.0
    types = call(
        ros, "get_parameter_types", rt.GetParameterTypesRequest, rt.GetParameterTypesResponse,
        names=["paused", "foxglove_port", "nope"],
    ).types
    assert list(types) == [BOOL, INTEGER, 0]


def test_set_parameters_take_effect_or_are_refused(ros, domain_id, start_node):
    start_node(domain_id, GRIPPER)
    status = ros.reader("/ribbon/status", rt.SimStatus)
    # (the head of each MarkerArray only: decoding whole meshes in Python on a loaded
    # machine is slower than the node makes them, and the test would count the reader)
    markers = ros.reader("/ribbon/markers", rt.MarkerArrayHead, reliable_qos(1, True))
    ros.wait_matched(status)
    ros.wait_matched(markers)

    # read-only and bad values: refused with a reason, nothing changes
    scene, lead, typed = set_params(ros, scene="other.yaml", max_stamp_lead=-1.0, paused=0.5)
    assert not scene.successful and "read-only" in scene.reason, scene
    assert not lead.successful and "must be > 0" in lead.reason, lead
    assert not typed.successful and "type bool" in typed.reason, typed

    # paused: the simulation stops, and resumes
    (ok,) = set_params(ros, paused=True)
    assert ok.successful, ok.reason
    st = ros.take(status, 5.0, until=lambda s: s.paused)[-1]
    time.sleep(0.5)
    assert all(s.step == st.step for s in ros.take(status, 0.3))
    (ok,) = set_params(ros, paused=False)
    assert ok.successful
    ros.take(status, 5.0, until=lambda s: not s.paused and s.step > st.step + 10)

    # markers_rate: 10 Hz of simulated time at dt = 0.01 s is one mesh per 10 steps
    (ok,) = set_params(ros, markers_rate=10.0)
    assert ok.successful
    time.sleep(0.3)
    markers.take(N=100)
    start = ros.take(status, 5.0, until=lambda s: True)[-1].step
    got = ros.take(markers, 2.0)
    end = ros.take(status, 5.0, until=lambda s: True)[-1].step
    stamps = sorted({(m.header.stamp.sec, m.header.stamp.nanosec) for m in got})
    steps = end - start
    assert steps >= 50, steps
    assert len(stamps) <= steps // 10 + 2, (len(stamps), steps)
    gaps = [(b[0] - a[0]) + (b[1] - a[1]) * 1e-9 for a, b in zip(stamps, stamps[1:])]
    assert gaps and min(gaps) >= 0.1 - 1e-9, gaps
    # back to every tick
    (ok,) = set_params(ros, markers_rate=0.0)
    assert ok.successful
    time.sleep(0.3)
    markers.take(N=100)
    status.take(N=256)
    start = ros.take(status, 5.0, until=lambda s: True)[-1].step
    got = ros.take(markers, 1.0)
    status.take(N=256)
    end = ros.take(status, 5.0, until=lambda s: True)[-1].step
    # more meshes than 10 Hz would give in those steps (a keep-last-1 reader may miss some)
    stamps = {(m.header.stamp.sec, m.header.stamp.nanosec) for m in got}
    assert len(stamps) > (end - start) // 10 + 2, (len(stamps), end - start)

    # the input policy: an empty frame id is rejected, then accepted once allowed
    pose = ros.writer("/handles/gripper", rt.PoseStamped, SENSOR_QOS)
    ros.wait_matched(pose)
    now = int(time.time())
    for _ in range(10):
        pose.write(pose_msg(0.7, 0.0, 0.3, frame="", sec=now))
        time.sleep(0.02)
    h = ros.take(status, 5.0, until=lambda s: s.handles[0].rejected_unknown_frame > 0)[-1].handles[0]
    assert not h.external
    (ok,) = set_params(ros, accept_empty_frame_id=True)
    assert ok.successful
    for _ in range(10):
        pose.write(pose_msg(0.7, 0.0, 0.3, frame="", sec=now + 1))
        time.sleep(0.02)
    h = ros.take(status, 5.0, until=lambda s: s.handles[0].external)[-1].handles[0]
    assert abs(h.target.position.x - 0.7) < 1e-12
    g = call(ros, "get_parameters", rt.GetParametersRequest, rt.GetParametersResponse,
             names=["accept_empty_frame_id", "markers_rate"])
    assert g.values[0].bool_value is True and g.values[1].double_value == 0.0
