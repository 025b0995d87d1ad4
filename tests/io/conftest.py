"""ROS bags for the tests, written with rosbags' own writers (ROS 1, ROS 2 SQLite, ROS 2 MCAP), and
the ``parser`` fixture that runs a reader test through both table parsers."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

BAG_FORMATS = ("ros1", "db3", "mcap")


@pytest.fixture(params=["polars", "numpy"])
def parser(request, monkeypatch):
    """Run a test through both table parsers: polars (fast extra) and numpy."""
    import odomkit.io.table as table

    if request.param == "polars":
        pytest.importorskip("polars")
    else:
        monkeypatch.setattr(table, "polars_module", lambda: None)
    return request.param


def _build(store: Any, msgtype: str, values: dict[str, Any]) -> Any:
    """A message of ``msgtype`` with ``values`` (nested dicts) and zeros/empties elsewhere."""
    from rosbags.interfaces import Nodetype

    _, fields = store.fielddefs[msgtype]
    kwargs: dict[str, Any] = {}
    for name, (node, desc) in fields:
        given = values.get(name)
        if node == Nodetype.NAME:
            kwargs[name] = _build(store, desc, given or {})
        elif node == Nodetype.BASE:
            base = desc[0]
            default: Any = "" if base == "string" else 0.0 if base.startswith("float") else 0
            kwargs[name] = default if given is None else given
        else:  # ARRAY (fixed length) or SEQUENCE
            (sub_node, sub_desc), length = desc
            if sub_node == Nodetype.BASE and sub_desc[0] == "string":
                kwargs[name] = list(given or [])
            elif sub_node == Nodetype.NAME:  # messages (tf2_msgs/TFMessage's transforms)
                kwargs[name] = [_build(store, sub_desc, item) for item in given or []]
            else:
                default_array = np.zeros(length) if node == Nodetype.ARRAY else np.zeros(0)
                kwargs[name] = default_array if given is None else np.asarray(given, dtype=float)
    return store.types[msgtype](**kwargs)


#: ackermann_msgs' definitions (the ROS interface, as its package declares it).
ACKERMANN_MSGS = {
    "ackermann_msgs/msg/AckermannDrive": "float32 steering_angle\nfloat32 steering_angle_velocity\n"
                                         "float32 speed\nfloat32 acceleration\nfloat32 jerk\n",
    "ackermann_msgs/msg/AckermannDriveStamped": "std_msgs/Header header\n"
                                                "ackermann_msgs/AckermannDrive drive\n",
}


#: tf2_msgs' definition, which rosbags' ROS 1 type store lacks (a ROS 1 bag carries it).
TF2_MSGS = {"tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n"}


def write_bag(path: Path, fmt: str, messages: Iterable[tuple[str, str, int, dict[str, Any]]]) -> Path:
    """Write ``(topic, msgtype, bag time [ns], fields)`` messages; returns the bag's path
    (a ``.bag`` file for ros1, a folder for db3 and mcap)."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ros1 = fmt == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    for name, text in ACKERMANN_MSGS.items():  # a car's drive command: not in rosbags' stores
        store.register(get_types_from_msg(text, name))
    for name, text in TF2_MSGS.items():
        if name not in store.types:  # /tf: in the ROS 2 stores, not in ROS 1's
            store.register(get_types_from_msg(text, name))
    path = path.with_suffix(".bag") if ros1 else path
    plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
    writer = Writer1(path) if ros1 else Writer2(path, version=9, storage_plugin=plugin)
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    conns: dict[str, Any] = {}
    with writer:
        for topic, msgtype, ns, values in sorted(messages, key=lambda m: m[2]):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(conns[topic], ns, serialize(_build(store, msgtype, values), msgtype))
    return path


def header(t_ns: int, frame_id: str = "") -> dict[str, Any]:
    """A header stamped at ``t_ns`` nanoseconds."""
    return {"stamp": {"sec": t_ns // 10**9, "nanosec": t_ns % 10**9}, "frame_id": frame_id}


@pytest.fixture(scope="session")
def bag_writer() -> Callable[..., Path]:
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    return write_bag


@pytest.fixture(scope="session")
def stamp() -> Callable[..., dict[str, Any]]:
    return header


#: An OptiOdom run's wheel: encoder resolution × gear ratio (optiodom_diff.toml) ticks a turn.
_TICKS_PER_TURN = 64 * 43.7
#: The same robot with wheel angles in radians as its "ticks" (a JointState's positions):
#: metres per tick = the wheel radius.
_RAD_ROBOT = """[robot]
type = "diff"
wheel_base = 0.2
wheel_radius = 0.042
encoder_resolution = 6.283185307179586
[noise]
k_left = 0.001
k_right = 0.001
"""


@pytest.fixture(scope="session")
def rad_robot() -> str:
    """The robot file's text for a bag whose JointState wheel angles came from an OptiOdom run
    (:func:`wheel_angles`)."""
    return _RAD_ROBOT


def _wheel_angles(log: Any) -> tuple[np.ndarray, np.ndarray]:
    """An OptiOdom run's left and right wheel angles [rad] at its rows, from 0: its ticks per
    cycle summed (row 0's are motion before the log) and turned into radians."""
    turn = 2 * np.pi / _TICKS_PER_TURN
    left = np.cumsum(np.r_[0, log.channels["ticks_left"][1:]]) * turn
    right = np.cumsum(np.r_[0, log.channels["ticks_right"][1:]]) * turn
    return left, right


@pytest.fixture(scope="session")
def wheel_angles() -> Callable[[Any], tuple[np.ndarray, np.ndarray]]:
    """``wheel_angles(log)``: an OptiOdom run's wheel angles [rad], what a JointState carries."""
    return _wheel_angles


def _one_line_error(call: Callable[[], object]) -> str:
    """The message of the InputError ``call()`` raises, checked to be one line."""
    from odomkit.errors import InputError

    with pytest.raises(InputError) as info:
        call()
    text = str(info.value)
    assert "\n" not in text
    return text


@pytest.fixture(scope="session")
def errors() -> Callable[[Callable[[], object]], str]:
    """``errors(call)``: the one-line InputError message ``call()`` raises."""
    return _one_line_error
