"""The Rust message structs match the .msg files byte for byte: every message the binary
writes decodes with `rosbags` using only the .msg text (ours from msg/, the standard ones
from rosbags' ROS 2 Jazzy store) and re-encodes to the identical bytes; the bag's schemas
and type hashes are what rosbag2 and rosbags compute."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from conftest import BIN, ROOT, SCENES

MSG_DIR = ROOT / "msg"
SEPARATOR = "=" * 80


@pytest.fixture(scope="module")
def typestore():
    """ROS 2 Jazzy types plus ours, registered from the .msg text alone."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for p in sorted(MSG_DIR.glob("*.msg")):
        types.update(get_types_from_msg(p.read_text(), f"developable_sim/msg/{p.stem}"))
    store.register(types)
    return store


# Two recordings: the torsion scene (singular points appear: every sequence type is
# non-empty) and the pushed ribbon with its camera's images and cloud and the ground
# truth (sensor_msgs, a capture command; a small image keeps it quick).
RUNS = {
    "torsion": ["ribbon_extreme_torsion.yaml"],
    "camera": [
        "ribbon_gripper_push.yaml",
        "--duration",
        "0.1",
        "--record-cameras",
        "--set",
        "outputs.points=true",
        "--set",
        "cameras.0.width=160",
        "--set",
        "cameras.0.height=120",
    ],
}
TYPES = {
    "torsion": {
        "developable_sim/msg/SimStatus",
        "developable_sim/msg/SingularPoints",
        "visualization_msgs/msg/MarkerArray",
        "rosgraph_msgs/msg/Clock",
        "developable_sim/msg/SimCommand",
        "developable_sim/msg/GraspState",
        "geometry_msgs/msg/WrenchStamped",
    },
    # (its gripper carries the finger: no wrench on the ribbon)
    "camera": {
        "developable_sim/msg/SimStatus",
        "developable_sim/msg/SingularPoints",
        "visualization_msgs/msg/MarkerArray",
        "rosgraph_msgs/msg/Clock",
        "developable_sim/msg/SimCommand",
        "developable_sim/msg/GraspState",
        "tf2_msgs/msg/TFMessage",
        "sensor_msgs/msg/Image",
        "sensor_msgs/msg/CameraInfo",
        "sensor_msgs/msg/PointCloud2",
    },
}


@pytest.fixture(scope="module", params=sorted(RUNS))
def recorded(request, tmp_path_factory):
    """A headless run recorded the way the node records: (run name, bag)."""
    scene, *args = RUNS[request.param]
    bag = tmp_path_factory.mktemp("interfaces") / "bag"
    r = subprocess.run(
        [str(BIN), "run", str(SCENES / scene), "--record", str(bag), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    return request.param, bag


def messages(bag: Path):
    for f in sorted(bag.glob("*.mcap")):
        with open(f, "rb") as fh:
            reader = make_reader(fh)
            yield from reader.iter_messages()


def test_every_recorded_message_round_trips_through_the_msg_definitions(recorded, typestore):
    run, bag = recorded
    seen = set()
    nonempty_points = captures = 0
    for schema, channel, message in messages(bag):
        typ = schema.name
        msg = typestore.deserialize_cdr(message.data, typ)
        again = bytes(typestore.serialize_cdr(msg, typ))
        assert again == bytes(message.data), f"{channel.topic} ({typ}) differs after a round trip"
        seen.add(typ)
        if typ == "developable_sim/msg/SingularPoints" and msg.points:
            nonempty_points += 1
        if typ == "developable_sim/msg/SimCommand" and msg.kind == msg.CAPTURE:
            assert msg.camera == "camera", msg
            captures += 1
    assert seen == TYPES[run]
    if run == "torsion":
        assert nonempty_points > 0
    else:
        assert captures == 2  # 0.1 s at 15 Hz: ticks 0 and 1


def test_schemas_carry_every_dependency_in_rosbag2_form(recorded, typestore):
    _, recorded = recorded
    with open(next(recorded.glob("*.mcap")), "rb") as fh:
        reader = make_reader(fh)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
    for schema in summary.schemas.values():
        assert schema.encoding == "ros2msg"
        text = schema.data.decode()
        parts = text.split(SEPARATOR + "\n")
        deps = [p.split("\n", 1)[0] for p in parts[1:]]
        assert all(d.startswith("MSG: ") for d in deps)
        assert len(deps) == len(set(deps)), "a dependency is listed twice"
        if schema.name.startswith("developable_sim/"):
            root = (MSG_DIR / (schema.name.split("/")[-1] + ".msg")).read_text()
            assert parts[0] == root
        else:
            # standard types: exactly what rosbags generates for ROS 2 Jazzy
            expected, _ = typestore.generate_msgdef(schema.name, ros_version=2)
            assert text == expected
        # and rosbags parses the whole schema back into the same fields
        parsed = get_types_from_msg(text, schema.name)
        assert parsed[schema.name] == typestore.fielddefs[schema.name]


def test_channel_metadata_and_metadata_yaml(recorded, typestore):
    _, recorded = recorded
    with open(next(recorded.glob("*.mcap")), "rb") as fh:
        summary = make_reader(fh).get_summary()
    schemas = summary.schemas
    for ch in summary.channels.values():
        typ = schemas[ch.schema_id].name
        assert ch.message_encoding == "cdr"
        assert ch.metadata["topic_type_hash"] == typestore.hash_rihs01(typ)
        qos = yaml.safe_load(ch.metadata["offered_qos_profiles"])
        assert qos[0]["history"] == "keep_last" and qos[0]["depth"] >= 1
    info = yaml.safe_load((recorded / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9
    assert info["storage_identifier"] == "mcap"
    assert info["relative_file_paths"] == [p.name for p in recorded.glob("*.mcap")]
    counts = {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}
    assert sum(counts.values()) == info["message_count"] == summary.statistics.message_count
    for t in info["topics_with_message_count"]:
        md = t["topic_metadata"]
        assert md["serialization_format"] == "cdr"
        assert md["type_description_hash"] == typestore.hash_rihs01(md["type"])
        assert md["offered_qos_profiles"][0]["reliability"] in ("reliable", "best_effort")
