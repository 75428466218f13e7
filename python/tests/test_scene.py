"""Scene.load / Scene.from_yaml, overrides, and bad scenes: each raises SceneError
carrying the key path; nothing panics across the boundary."""

from __future__ import annotations

import numpy as np
import pytest

import developable_sim as ds
from conftest import scene_path

GRIPPER = scene_path("ribbon_gripper")


def test_load_reads_the_scene_and_its_names():
    scene = ds.Scene.load(GRIPPER)
    assert scene.name == "ribbon_gripper"
    assert scene.dt == 0.01 and scene.duration == 8.0 and scene.seed == 0
    assert scene.objects == ["ribbon"]
    assert scene.handles == ["gripper"]
    assert scene.cameras == ["camera"]
    assert scene.yaml == GRIPPER.read_text()
    assert scene.overrides == []


def test_overrides_are_written_as_set_specs_and_change_the_scene():
    scene = ds.Scene.load(
        GRIPPER,
        overrides={
            "ribbon.segments": np.int64(20),  # NumPy integers are integers
            "dt": 0.005,
            "solver.kind": "lbfgsb",  # a top-level string is YAML, as with --set
            "ribbon.base.position": np.array([0.0, 0.1, 0.0]),
            "handles.0.point": (1.0, 0.0),
            "name": "renamed",
            "ribbon.settle": np.False_,  # a NumPy boolean is a boolean, not 0
        },
    )
    assert scene.overrides == [
        "ribbon.segments=20",
        "dt=0.005",
        "solver.kind=lbfgsb",
        "ribbon.base.position=[0.0, 0.1, 0.0]",
        "handles.0.point=[1.0, 0.0]",
        "name=renamed",
        "ribbon.settle=false",
    ]
    assert scene.dt == 0.005 and scene.name == "renamed"
    sim = scene.build()
    state = sim.state()
    # 20 elements: 21 rim pairs
    assert state.vertices.shape == (42, 3)
    # the base moved by 0.1 m along y
    assert np.isclose(state.vertices[:, 1].mean(), 0.1, atol=1e-3)


def test_float_overrides_round_trip_bit_exactly():
    x = 0.1 + 0.2  # 0.30000000000000004: needs 17 digits
    scene = ds.Scene.load(GRIPPER, overrides={"dt": x})
    assert scene.dt == x
    tiny = ds.Scene.load(GRIPPER, overrides={"ribbon.initial_shape.imperfection": 1e-7})
    assert tiny.overrides == ["ribbon.initial_shape.imperfection=1e-7"]


def test_from_yaml_and_with_overrides():
    text = GRIPPER.read_text()
    scene = ds.Scene.from_yaml(text, overrides={"ribbon.segments": 10}, name="mine.yaml")
    assert scene.file == "mine.yaml"
    assert scene.build().state().vertices.shape == (22, 3)
    more = scene.with_overrides({"ribbon.segments": 12, "seed": 3})
    assert more.overrides == ["ribbon.segments=10", "ribbon.segments=12", "seed=3"]
    assert more.seed == 3 and more.build().state().vertices.shape == (26, 3)
    assert scene.build().state().vertices.shape == (22, 3)  # unchanged


def scene_error(**kwargs) -> ds.SceneError:
    with pytest.raises(ds.SceneError) as e:
        if "text" in kwargs:
            ds.Scene.from_yaml(kwargs["text"], name="bad.yaml")
        else:
            ds.Scene.load(kwargs.get("path", GRIPPER), overrides=kwargs.get("overrides"))
    return e.value


@pytest.mark.parametrize(
    "overrides, key, words",
    [
        # checked values (the scene's own check): key from the check
        ({"ribbon.width": 5}, "ribbon.width", "must be smaller than ribbon.length"),
        ({"dt": 0}, "dt", "must be > 0"),
        ({"cameras.0.far": 0.01}, "cameras.0.far", "must be > near"),
        # types and unknown keys (serde): key from the parser's path
        ({"ribbon.segments": -3}, "ribbon.segments", "expected usize"),
        ({"ribbon.segments": "many"}, "ribbon.segments", "invalid type"),
        ({"ribbon.colour": 1}, "ribbon.colour", "unknown field `colour`"),
        ({"handles.0.point": [1.0]}, "handles.0.point", "invalid length 1"),
        ({"solver.kind": "magic"}, "solver.kind", "unknown value `magic`"),
        # a bad override path
        ({"handles.7.point": [1.0, 0.0]}, "handles.7.point", "out of range"),
    ],
)
def test_a_bad_scene_raises_scene_error_with_its_key_path(overrides, key, words):
    e = scene_error(overrides=overrides)
    assert isinstance(e, ValueError)
    assert e.key == key, str(e)
    assert words in str(e), str(e)
    assert key.split(".")[-1] in str(e)


def test_a_bad_file_names_the_key_and_the_line():
    e = scene_error(text="name: x\nduration: 1\ndt: 0.01\nribbon:\n  segments: -1\n")
    assert e.key == "ribbon.segments" and e.file == "bad.yaml"
    assert "line 5" in str(e), str(e)


def test_errors_without_a_key_say_so(tmp_path):
    e = scene_error(text="ribbon:\n  length: [1\n")
    assert e.key is None and "line" in str(e)
    missing = tmp_path / "nowhere.yaml"
    e = scene_error(path=missing)
    assert e.key is None and e.file == str(missing) and "cannot read" in str(e)
    e = scene_error(text="")
    assert e.key is None and "empty" in str(e)


def test_bad_override_values_raise_type_errors():
    with pytest.raises(TypeError, match="cannot be written as YAML"):
        ds.Scene.load(GRIPPER, overrides={"dt": object()})
    with pytest.raises(TypeError, match="dict of key paths"):
        ds.Scene.load(GRIPPER, overrides=["dt=0.1"])


def test_the_key_of_a_message_is_only_a_key():
    """The `key` extraction's negative side: a message that starts with words and a
    colon is not a key path."""
    e = scene_error(text="ribbon: [1, 2\n")
    assert e.key is None, str(e)


def test_a_panic_inside_the_library_arrives_as_simulation_error():
    from developable_sim import _native

    with pytest.raises(ds.SimulationError, match="a panic raised on purpose"):
        _native._panic_for_test()
    # the interpreter and the library go on
    assert ds.Scene.load(GRIPPER).name == "ribbon_gripper"
