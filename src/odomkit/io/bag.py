"""ROS bags in: ROS 1 ``.bag``, ROS 2 ``.db3`` and ``.mcap`` (a ROS 2 bag is its folder),
read through ``rosbags`` (the ``ros`` extra; no ROS install), imported only when a bag is read.
A ROS 1 bag is also known by its first line (``#ROSBAG V2.0``) and an MCAP file by its magic
bytes, whatever they are called (``run``, ``RUN.BAG``); a gzip-compressed bag is refused in
one line saying to decompress it.

**Messages and the channels they give** (:mod:`odomkit.log`):

==============================  ============================================================
message                         channels
==============================  ============================================================
``sensor_msgs/JointState``      two joints (``--joints left,right``): ``ticks_left``,
                                ``ticks_right``; one joint: ``ticks``. A joint position is the
                                wheel angle [rad], so one "tick" is one radian and the robot
                                file's metres per tick is the wheel radius: ``m_per_tick =
                                0.033``, or ``wheel_radius = 0.033`` with ``encoder_resolution
                                = 6.283185307179586`` (2π "ticks" a turn). Positions are
                                differenced; without positions, velocities [rad/s] are
                                integrated over each step.
``nav_msgs/Odometry``           ``speed`` (twist linear x [m/s]), ``yaw_rate`` (angular z)
``Twist``, ``TwistStamped``     ``speed``, ``yaw_rate`` (``geometry_msgs``; a command. Twist
                                has no header, so its time is always the bag's)
``TwistWithCovarianceStamped``  ``speed``, ``yaw_rate`` (``geometry_msgs``; twist.twist linear
                                x, angular z): wheel odometry without its pose, a measurement
                                read as an Odometry's twist
``ackermann_msgs/``             ``speed`` (drive speed), ``steer`` (drive steering angle, the
``AckermannDriveStamped``       road wheels'), each held from its stamp as a command is: a car
``sensor_msgs/Imu``             ``yaw_rate`` (angular velocity z: a gyro; about another axis
                                with ``imu_up``, ``--imu-up``), and ``heading`` (yaw of the
                                orientation) when the IMU gives one (its
                                ``orientation_covariance[0]`` is not −1) and is level
==============================  ============================================================

A diff robot reads the two joints; a gyro robot (or a unicycle, the body-velocity vehicle)
reads ``speed`` + ``yaw_rate`` (Odometry, Twist, TwistStamped, TwistWithCovarianceStamped,
or one of them with an Imu for the rate); a compass robot ``speed`` + an Imu's ``heading``;
a gyro or tricycle robot one joint as its ``ticks``.

**A twist that moves sideways.** No vehicle of odomkit's has a sideways velocity, so a
twist's linear y is not read; where it is material (:func:`_check_lateral`: its RMS over the
messages that move above 10 % of linear x's and 0.02 m/s), a warning names the topic and
both figures: a holonomic (mecanum, omni) base's track would be wrong without a word.

**Time.** Each message's header stamp (``--bag-time``: the time the bag received it).
Stamps that go backwards are an error naming the message, and so are stamps that never
change (a publisher that does not fill them in). Times are seconds as in the bag (epoch
seconds for a real robot), as a truth file (TUM) has them. Each publisher stamps on its own
clock: topics that share fewer than two of the first one's messages are an error naming each
one's span, how far apart they start and what mends it (:func:`_apart`: ``--bag-time``, or
for the truth topic ``--truth-time-offset``, which moves its stamps before they are
interpolated at the rows).

**Several topics** (``--topic /odom --topic /imu``): the first topic's messages are the
log's rows; every other topic is resampled at those times, and a channel given by two
topics is taken from the one named last (so ``/imu``'s gyro replaces ``/odom``'s yaw
rate). Rows outside another topic's span are left out, with a warning where they are more
than 1 % of the rows or span more than 1 s (a message at either end is no news). A rate is resampled
as the mean of its signal over each step (exact for the signal below), a wheel angle or a
heading by linear interpolation. Where the replaced channel and its replacement disagree
grossly (:func:`_check_replaced`: the one moves more than twice as far as the other, or they
turn opposite ways), a warning names both topics and both figures: a sensor that does not
measure what the robot did (an IMU not mounted level, a skid-steer odometry's yaw gain). An
Imu topic whose mean linear acceleration puts gravity off its z axis (mounted on its side)
warns that its ``angular_velocity.z`` is not the robot's yaw rate.

**Ground truth** (``--truth-topic /mocap``): a pose topic (Odometry, PoseStamped,
PoseWithCovarianceStamped, TransformStamped, as vicon_bridge publishes
``/vicon/NAME/NAME``: its translation x, y and its rotation's yaw, or Pose2D, as
mocap_optitrack publishes ``ground_pose``: x, y, theta at the bag's times, for it has no
header) becomes the log's ground
truth, as a text log's ``gt_*`` columns do (never one of the log's own topics: the odometry
scored against itself is refused): ``track``, ``calibrate``, ``fit-noise`` and ``evaluate``
use it where a truth file is not given. A ``tf2_msgs/TFMessage`` topic (``/tf``) gives the
transforms of one frame pair among it (``--truth-frame world:base_link``: header.frame_id
and child_frame_id, a leading '/' ignored on either; direct transforms only, none chained),
each at its own header stamp; the topic's only pair needs no ``--truth-frame``, several are
an error listing them with their counts (:func:`_tf_poses`), and a pair from the ``odom``
frame warns (the odometry's own, as a rule). A ``tf_static`` topic is no truth: its
transforms do not move. A GPS topic (``sensor_msgs/NavSatFix``, ``--truth-topic /fix``) is position-only
truth on its own clock instead, as a truth file of latitude/longitude is
(:func:`odomkit.io.truth.project_latlon`: east and north of the first fix [m]): kept at its
fixes (``meta["truth"]``, which :func:`odomkit.truth.truth_from_log` returns), not
interpolated at the rows. Messages without a fix (``status.status`` < 0) are left out and
counted in a warning; an altitude that is NaN (not known) makes every height 0. Where every
fix states its position covariance (``position_covariance_type`` > 0), its median
horizontal σ per axis, √((c_ee + c_nn)/2), is kept as ``meta["truth_position_sigma"]``
[m], and a command whose truth σ is not given says so (``--truth-sigma`` takes it; it is
never set from the bag silently).

**Truth in a bag of its own** (``--truth mocap.bag --truth-topic /pose``:
:func:`read_bag_truth`): the same topic types, kept at their own stamps as a TUM file's poses
are (nothing is interpolated at a log's rows), so that a truth recorded apart from the log
reads as its text file would.

**What a rate means over a step** (row k's rate holds from row k to row k+1, as in
:mod:`odomkit.log`): a command (Twist, TwistStamped) holds from its stamp to the next one
(step k uses message k); an Odometry twist (and a TwistWithCovarianceStamped: wheel odometry
without its pose) is the controller's estimate over an interval *ending* at its stamp (ROS 2
``diff_drive_controller``: the wheel motion of each update divided by its period, averaged
over the last ``velocity_rolling_window_size`` updates), so step k uses message k+1. That is
exact for a window of one update (and for odomkit's own ``--bag-out``); a longer window lags
by about half its length, so where the bag has the wheels' JointState, dead-reckon that
instead. An IMU or joint velocity is a sample of a
smooth signal: step k uses the mean of both ends (trapezoid rule, second order).
"""

from __future__ import annotations

import gzip
import math
import tempfile
import warnings
import zlib
from collections.abc import Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import unwrap_angle
from odomkit.errors import InputError, OdomkitError
from odomkit.kinematics import unicycle_moving
from odomkit.log import INCREMENT_CHANNELS, OdometryLog, clock_text
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.truth import BAG_TIME_HINT, Truth, bursts_note

__all__ = ["BagOdometry", "MESSAGE_TYPES", "bag_root", "bag_topics", "is_bag", "parse_truth_frame",
           "read_bag", "read_bag_odometry", "read_bag_truth", "require_rosbags", "TRUTH_TYPES"]

#: The message types odomkit reads, by their ROS 2 names (rosbags names ROS 1 types alike).
MESSAGE_TYPES = {
    "sensor_msgs/msg/JointState": "JointState",
    "nav_msgs/msg/Odometry": "Odometry",
    "geometry_msgs/msg/Twist": "Twist",
    "geometry_msgs/msg/TwistStamped": "TwistStamped",
    "geometry_msgs/msg/TwistWithCovarianceStamped": "TwistWithCovarianceStamped",
    "sensor_msgs/msg/Imu": "Imu",
    "ackermann_msgs/msg/AckermannDriveStamped": "AckermannDriveStamped",
}
#: ackermann_msgs' definitions (ROS 1 and 2 alike), which rosbags' built-in type stores lack:
#: registered for a ROS 2 bag that carries no definitions of its own (a ROS 1 bag does).
_ACKERMANN = {
    "ackermann_msgs/msg/AckermannDrive": "float32 steering_angle\nfloat32 steering_angle_velocity\n"
                                         "float32 speed\nfloat32 acceleration\nfloat32 jerk\n",
    "ackermann_msgs/msg/AckermannDriveStamped": "std_msgs/Header header\n"
                                                "ackermann_msgs/AckermannDrive drive\n",
}
#: The messages a ground-truth topic may hold (``--truth-topic``): poses (motion capture:
#: vicon_bridge publishes TransformStamped; ``/tf`` transforms of one frame pair,
#: ``--truth-frame``) or GPS fixes (NavSatFix, position-only).
TRUTH_TYPES = {
    "nav_msgs/msg/Odometry": "Odometry",
    "geometry_msgs/msg/PoseStamped": "PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped": "PoseWithCovarianceStamped",
    "sensor_msgs/msg/NavSatFix": "NavSatFix",
    "geometry_msgs/msg/TransformStamped": "TransformStamped",
    "tf2_msgs/msg/TFMessage": "TFMessage",
    "geometry_msgs/msg/Pose2D": "Pose2D",
}
_TF = "tf2_msgs/msg/TFMessage"
_BAG_SUFFIXES = (".bag", ".db3", ".mcap")
#: The first bytes of a ROS 1 bag (its version line) and of an MCAP file (its magic), and the
#: suffix rosbags needs to open each: it picks its reader by the name alone.
_MAGIC = {"ros1": (b"#ROSBAG V2.0", ".bag"), "mcap": (b"\x89MCAP0\r\n", ".mcap")}
_GZIP_MAGIC = b"\x1f\x8b"  # RFC 1952, section 2.3.1
#: Messages between two reports to a ``progress`` (one report per message would cost about as much
#: as decoding the message).
_REPORT_EVERY = 1000


def require_rosbags() -> Any:
    """The ``rosbags`` package, or one line saying how to install it."""
    try:
        import rosbags.highlevel
        import rosbags.rosbag1
        import rosbags.rosbag2
        import rosbags.typesys
    except ImportError:
        raise InputError("ROS bags need the rosbags package: pip install 'odomkit[ros]'") from None
    return rosbags


def is_bag(path: str | Path) -> bool:
    """A ``.bag``, ``.db3`` or ``.mcap`` name, a folder with a ROS 2 ``metadata.yaml``, or a
    file whose first bytes are a ROS 1 bag's or an MCAP file's, whatever it is called. A
    gzip-compressed bag (``.bag.gz``, or gzip whose content is a bag) is one too, so that
    reading it says to decompress it (:func:`read_bag`).

    Examples
    --------
    >>> is_bag("run.bag"), is_bag("rosbag2_2024_05_01/rosbag2_2024_05_01_0.mcap"), is_bag("log.csv")
    (True, True, False)
    """
    path = Path(path)
    if path.suffix.lower() in _BAG_SUFFIXES or _gzip_bag_name(path):
        return True
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return _sniff(path) is not None


def _gzip_bag_name(path: Path) -> bool:
    return path.name.lower().endswith(tuple(s + ".gz" for s in _BAG_SUFFIXES))


def _magic_kind(head: bytes) -> str | None:
    return next((kind for kind, (magic, _) in _MAGIC.items() if head.startswith(magic)), None)


def _sniff(path: Path) -> str | None:
    """What a file's first bytes say it is: ``"ros1"``, ``"mcap"``, ``"gzip"`` (a gzip file
    whose content begins as one of those), or None (anything else, a folder, no such file)."""
    length = max(len(magic) for magic, _ in _MAGIC.values())
    try:
        if not path.is_file():  # a regular file only: reading a pipe's first bytes would eat them
            return None
        with path.open("rb") as file:
            head = file.read(length)
            if not head.startswith(_GZIP_MAGIC):
                return _magic_kind(head)
            file.seek(0)
            with gzip.GzipFile(fileobj=file) as inner:
                return "gzip" if _magic_kind(inner.read(length)) else None
    except (OSError, EOFError, zlib.error):  # a folder, unreadable, a damaged gzip: no bag here
        return None


@contextmanager
def _bag_errors(source: str) -> Iterator[None]:
    """rosbags' own errors (a bad magic, a missing metadata key, a truncated chunk) become
    one line naming the bag."""
    try:
        yield
    except OdomkitError:
        raise
    except FileNotFoundError:
        raise InputError("no such file or folder", source=source) from None
    except Exception as err:  # rosbags raises many kinds; all mean "not a readable bag"
        raise InputError(f"not a readable ROS bag ({type(err).__name__}: {err})", source=source) from None


@contextmanager
def _open(path: Path) -> Iterator[Any]:
    """An open rosbags ``AnyReader`` on ``path`` (a storage file inside a ROS 2 bag folder
    opens the folder; a ROS 1 bag or MCAP file by another name opens through a link named
    as rosbags needs, :func:`_named_as`)."""
    source = str(path)
    if not path.exists():
        raise InputError("no such file or folder", source=source)
    kind = _sniff(path) if path.is_file() else None
    if kind == "gzip" or (path.is_file() and _gzip_bag_name(path)):
        # rosbags reads a bag in place (it seeks through its index): no reading through gzip.
        plain = path.name[:-3] if path.name.lower().endswith(".gz") else "decompressed.bag"
        how = f"gunzip -k {path.name}" if plain != "decompressed.bag" else f"zcat {path.name} > {plain}"
        raise InputError(f"is a gzip-compressed ROS bag; decompress it first ({how}) and give {plain}",
                         source=source)
    rosbags = require_rosbags()
    path = bag_root(path)
    stores = rosbags.typesys
    with ExitStack() as stack:
        # A lone file that its bytes call a bag, by another name (not a ROS 2 bag's folder).
        suffix = _MAGIC[kind][1] if kind in _MAGIC and path.is_file() else None
        if suffix is not None and path.suffix != suffix:
            path = stack.enter_context(_named_as(path, suffix, source))
        with _bag_errors(source):
            # The default types serve a ROS 2 bag without message definitions (db3 before Iron);
            # the messages odomkit reads are the same in every ROS 2 release.
            default = stores.get_typestore(stores.Stores.ROS2_HUMBLE)
            for name, text in _ACKERMANN.items():
                default.register(stores.get_types_from_msg(text, name))
            reader = rosbags.highlevel.AnyReader([path], default_typestore=default)
            reader.open()
        stack.callback(reader.close)
        yield reader


def bag_root(path: str | Path) -> Path:
    """The bag ``path`` belongs to: a ROS 2 storage file (``.db3``, ``.mcap``) beside its
    ``metadata.yaml`` is its folder's bag; anything else is itself. Two paths name one bag
    where their roots resolve alike.

    Examples
    --------
    >>> str(bag_root("run.bag"))
    'run.bag'
    """
    path = Path(path)
    storage_file = path.is_file() and path.suffix.lower() in (".db3", ".mcap")
    return path.parent if storage_file and (path.parent / "metadata.yaml").is_file() else path


@contextmanager
def _named_as(path: Path, suffix: str, source: str) -> Iterator[Path]:
    """A symbolic link to ``path`` ending in ``suffix``, in a temporary folder removed after:
    rosbags chooses its reader by the suffix alone (``AnyReader`` takes any name but ``.bag``
    for ROS 2, whose reader then wants ``.db3`` or ``.mcap``), so ``run`` or ``RUN.BAG``
    would not open though its first bytes say what it is."""
    with tempfile.TemporaryDirectory(prefix="odomkit-bag-") as folder:
        link = Path(folder) / f"bag{suffix}"
        try:
            link.symlink_to(path.resolve())
        except OSError:  # no symbolic links here (Windows without the right): say what to do
            what = "a ROS 1 bag" if suffix == ".bag" else "an MCAP file"
            raise InputError(f"is {what} (by its first bytes), which rosbags opens only by a "
                             f"{suffix} name: rename it to {path.stem}{suffix}", source=source) from None
        yield link


def bag_topics(path: str | Path) -> dict[str, str]:
    """Every topic of a bag and its message type (``{"/odom": "nav_msgs/msg/Odometry"}``)."""
    with _open(Path(path)) as reader:
        return _topics(reader, str(path))


def _topics(reader: Any, source: str) -> dict[str, str]:
    """The open bag's topics and their message types."""
    with _bag_errors(source):
        return {name: str(info.msgtype) for name, info in reader.topics.items()}


def _the_one(available: dict[str, str], types: dict[str, str], flag: str, source: str) -> str:
    """The bag's only topic of ``types``; else an error asking for ``flag``, listing them."""
    found = sorted(n for n, t in available.items() if t in types and not _static_tf(n, t))
    if len(found) != 1:
        raise InputError(f"name the topic with {flag}; {_topic_list(available, types)}", source=source)
    return found[0]


#: The other topics an error names, with their types (a bag may hold hundreds).
_OTHERS_NAMED = 10


def _topic_list(topics: dict[str, str], types: dict[str, str] = MESSAGE_TYPES) -> str:
    """The topics of ``types`` there are, then the others with their types (the first
    :data:`_OTHERS_NAMED`): a topic read under a name odomkit does not expect is seen at once."""
    def listed(name: str, msgtype: str) -> bool:
        return msgtype in types and not (types is TRUTH_TYPES and _static_tf(name, msgtype))

    readable = [f"{n} ({types[t]})" for n, t in sorted(topics.items()) if listed(n, t)]
    others = [f"{n} ({t})" for n, t in sorted(topics.items()) if not listed(n, t)]
    what = ("topics odomkit reads" if types is MESSAGE_TYPES else "truth topics" if types is TRUTH_TYPES
            else f"{'/'.join(types.values())} topics")
    text = f"{what}: " + (", ".join(readable) if readable else "none")
    if not others:
        return text
    more = len(others) - _OTHERS_NAMED
    return (text + "; other topics: " + ", ".join(others[:_OTHERS_NAMED])
            + (f" and {more} more" if more > 0 else ""))


def _static_tf(name: str, msgtype: str) -> bool:
    """A ``tf_static`` topic (``/tf_static``, ``/robot1/tf_static``): transforms that do not move."""
    return msgtype == _TF and name.rstrip("/").rsplit("/", 1)[-1] == "tf_static"


def _find_topic(topics: dict[str, str], wanted: str, source: str,
                types: dict[str, str] = MESSAGE_TYPES) -> str:
    for name in (wanted, "/" + wanted.lstrip("/")):
        if name in topics:
            if topics[name] not in types:
                raise InputError(f"topic {name} is {topics[name]}; odomkit reads "
                                 f"{', '.join(types.values())} ({_topic_list(topics, types)})",
                                 source=source)
            if types is TRUTH_TYPES and _static_tf(name, topics[name]):
                raise InputError(f"topic {name} holds static transforms, which do not move: it is no "
                                 f"ground truth (/tf with --truth-frame PARENT:CHILD may be; "
                                 f"{_topic_list(topics, types)})", source=source)
            return name
    raise InputError(f"no topic {wanted} in the bag; {_topic_list(topics, types)}", source=source)


def _choose_topics(topics: dict[str, str], wanted: Sequence[str], source: str,
                   truth_topic: str | None = None) -> list[str]:
    """The log's topics: those ``wanted`` (``--topic``), else the bag's one readable topic
    other than ``truth_topic`` (the name as found in the bag). The truth topic is never one
    of them: the odometry would be scored against itself (a user study's final error of
    0.16 m, with no warning, was the odometry's own pose against its own twist)."""
    rest = {n: t for n, t in topics.items() if n != truth_topic}
    itself = (f"the odometry would be scored against itself; the truth must come from another "
              f"source (motion capture, GPS): {_topic_list(rest, TRUTH_TYPES)}")
    if wanted:
        chosen = [_find_topic(topics, w, source) for w in wanted]
        if len(set(chosen)) != len(chosen):
            raise InputError(f"--topic names a topic twice: {', '.join(wanted)}", source=source)
        if truth_topic in chosen:
            raise InputError(f"--truth-topic {truth_topic} is also a --topic: {itself}", source=source)
        return chosen
    readable = sorted(n for n, t in topics.items() if t in MESSAGE_TYPES and n != truth_topic)
    if len(readable) == 1:
        return readable
    if not readable and topics.get(truth_topic or "") in MESSAGE_TYPES:
        raise InputError(f"the bag's one topic odomkit reads as a log, {truth_topic}, is the --truth-topic: "
                         f"{itself}", source=source)
    raise InputError(f"a bag log needs --topic; {_topic_list(topics)}", source=source)


@dataclass
class _Stream:
    """One topic's samples: times (M,) [ns] and its signals (channel, kind, values (M,)); kind is
    ``angle`` (cumulative, interpolated), ``absolute`` (an angle, interpolated unwrapped) or
    a rate signal: ``forward``, ``backward`` or ``linear`` (see the module docstring)."""

    topic: str
    ns: NDArray[np.int64]
    signals: list[tuple[str, str, NDArray[np.float64]]] = field(default_factory=list)


def _seconds(ns: NDArray[np.int64]) -> NDArray[np.float64]:
    """Seconds plus a correctly rounded fraction: a stamp written from a float epoch time t
    (odomkit's own bags) reads back as exactly t."""
    return (ns // 1_000_000_000).astype(float) + (ns % 1_000_000_000) / 1e9


def _stamps(reader: Any, conns: list[Any], receive_time: bool, topic: str,
            source: str, progress: Progress = NO_PROGRESS) -> tuple[list[Any], NDArray[np.int64]]:
    """The topic's messages and their times [ns] (header stamp, or the bag's time);
    ``progress`` is advanced every :data:`_REPORT_EVERY` messages and at the end."""
    messages, stamps = [], []
    for bag_ns, msg in _messages(reader, conns, source, progress):
        header = getattr(msg, "header", None)
        stamps.append(bag_ns if receive_time or header is None else _stamp_ns(header))
        messages.append(msg)
    if len(messages) < 2:
        raise InputError(f"topic {topic} has {len(messages)} message(s); a log needs two or more",
                         source=source)
    return messages, _ordered(np.array(stamps, dtype=np.int64), receive_time, topic, source)


def _messages(reader: Any, conns: list[Any], source: str, progress: Progress) -> Iterator[tuple[int, Any]]:
    """Each message of ``conns`` decoded, with the time the bag received it [ns]; ``progress``
    is advanced every :data:`_REPORT_EVERY` messages and at the end."""
    count = 0
    with _bag_errors(source):
        for conn, bag_ns, raw in reader.messages(connections=conns):
            yield int(bag_ns), reader.deserialize(raw, conn.msgtype)
            count += 1
            if count % _REPORT_EVERY == 0:
                progress.advance(_REPORT_EVERY)
    if count % _REPORT_EVERY:
        progress.advance(count % _REPORT_EVERY)


def _stamp_ns(header: Any) -> int:
    """A header's stamp [ns]."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _ordered(ns: NDArray[np.int64], receive_time: bool, topic: str, source: str,
             what: str = "message") -> NDArray[np.int64]:
    """``ns`` (M,), M ≥ 2, checked: times that go backwards, or never change (a publisher that
    does not fill its stamps in), are an error naming the ``what`` (message, transform)."""
    t = _seconds(ns)
    back = np.flatnonzero(np.diff(ns) < 0)
    hint = "pass --bag-time to use the time the bag received each message"
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"{topic}: header stamps go backwards at {what} {i + 1} ({t[i]:.9f} s after "
                         f"{t[i - 1]:.9f} s); {hint}", source=source)
    if ns[-1] == ns[0]:
        raise InputError(f"{topic}: every {what} was received at {t[0]:.9f} s" if receive_time else
                         f"{topic}: every header stamp is {t[0]:.9f} s (never filled in?); {hint}",
                         source=source)
    return ns


def _finite(values: NDArray[np.float64], what: str, topic: str, source: str) -> NDArray[np.float64]:
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputError(f"{topic}: message {bad[0] + 1} has a {what} that is not a finite number",
                         source=source)
    return values


def _joint_signals(messages: list[Any], ns: NDArray[np.int64], joints: Sequence[str], topic: str,
                   source: str) -> _Stream:
    names: dict[str, None] = {}
    for msg in messages:
        names.update(dict.fromkeys(msg.name))
    if not joints:
        left = [n for n in names if "left" in n.lower()]
        right = [n for n in names if "right" in n.lower()]
        if len(left) == 1 and len(right) == 1:
            joints = (left[0], right[0])
        elif len(names) == 1:
            joints = tuple(names)
        else:
            raise InputError(f"{topic}: name the wheel joints with --joints LEFT,RIGHT (or one joint); "
                             f"its joints are {', '.join(names) or 'none'}", source=source)
    missing = [j for j in joints if j not in names]
    if missing:
        raise InputError(f"{topic}: no joint named {missing[0]!r}; its joints are {', '.join(names)}",
                         source=source)
    keep, positions, velocities = [], [], []
    for k, msg in enumerate(messages):
        index = {n: i for i, n in enumerate(msg.name)}
        if not all(j in index for j in joints):
            continue  # a message for other joints (drivers may publish joint groups apart)
        keep.append(k)
        pos, vel = np.asarray(msg.position, dtype=float), np.asarray(msg.velocity, dtype=float)
        positions.append([pos[index[j]] for j in joints] if pos.size == len(msg.name) else None)
        velocities.append([vel[index[j]] for j in joints] if vel.size == len(msg.name) else None)
    if len(keep) < 2:
        raise InputError(f"{topic}: fewer than two messages carry joints {', '.join(joints)}", source=source)
    if all(p is not None for p in positions):
        kind, values = "angle", np.array(positions, dtype=float)
        what = "joint position"
    elif all(v is not None for v in velocities):
        kind, values = "linear", np.array(velocities, dtype=float)
        what = "joint velocity"
    else:
        raise InputError(f"{topic}: the messages carry neither a position nor a velocity for every "
                         f"one of {', '.join(joints)}", source=source)
    _finite(values, what, topic, source)
    if kind == "angle" and np.any(np.abs(np.diff(values, axis=0)) > math.pi):
        warnings.warn(f"{source}: {topic}: a joint position jumps by more than π rad between two "
                      "messages; odomkit reads positions as a continuous wheel angle, not wrapped",
                      stacklevel=2)
    channels = ("ticks_left", "ticks_right") if len(joints) == 2 else ("ticks",)
    stream = _Stream(topic, ns[keep])
    stream.signals = [(c, kind, values[:, i]) for i, c in enumerate(channels)]
    return stream


def _yaw(q: Any) -> float:
    """Yaw of a quaternion (rotation about z of a Z-Y-X Euler decomposition), REP 103."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


#: The kinds of twist message whose twist is a measurement over an interval *ending* at its
#: stamp (module docstring): Odometry's, and wheel odometry published without its pose as a
#: twist with covariance (a covariance says it is an estimate, never a command).
_MEASURED_TWISTS = ("Odometry", "TwistWithCovarianceStamped")


def _twist_signals(messages: list[Any], ns: NDArray[np.int64], kind: str, topic: str,
                   source: str) -> _Stream:
    if kind in _MEASURED_TWISTS:  # twist.twist: Odometry's and TwistWithCovarianceStamped's
        twists = [m.twist.twist for m in messages]
    elif kind == "TwistStamped":
        twists = [m.twist for m in messages]
    else:
        twists = messages
    speed = _finite(np.array([w.linear.x for w in twists], dtype=float), "linear x", topic, source)
    rate = _finite(np.array([w.angular.z for w in twists], dtype=float), "angular z", topic, source)
    _check_lateral(speed, np.array([w.linear.y for w in twists], dtype=float), rate, topic, source)
    signal = "backward" if kind in _MEASURED_TWISTS else "forward"
    return _Stream(topic, ns, [("speed", signal, speed), ("yaw_rate", signal, rate)])


#: A twist's lateral velocity (linear.y) is material, and warned about, where its RMS over the
#: moving messages exceeds this share of linear.x's: a diff-drive or skid-steer base reports
#: 0 (diff_drive_controller) or, filtered (robot_localization), a few % from slip in turns;
#: 10 % missed is 10 m sideways per 100 m travelled, as large an error as any calibration fits.
_LATERAL_SHARE = 0.1
#: ... and this much [m/s]: below it, noise about zero in an estimated twist (of order
#: 0.01 m/s) of a robot that crawls, whose 10 % would be less.
_LATERAL_FLOOR = 0.02


def _check_lateral(vx: NDArray[np.float64], vy: NDArray[np.float64], wz: NDArray[np.float64], topic: str,
                   source: str) -> None:
    """Warn where a twist's lateral velocity ``vy`` (M,) [m/s] is material against its forward
    velocity ``vx`` (M,) [m/s] (:data:`_LATERAL_SHARE`, :data:`_LATERAL_FLOOR`) over the
    messages that move (:func:`odomkit.kinematics.unicycle_moving`, yaw rate ``wz`` (M,)):
    odomkit's vehicles have no sideways velocity, so a holonomic (mecanum, omni) base's
    track would be wrong without a word."""
    ok = np.isfinite(vy)
    moving = ok & unicycle_moving(np.hypot(vx, np.where(ok, vy, 0.0)), wz)
    if not moving.any():
        return
    rms_x = float(np.sqrt(np.mean(vx[moving] ** 2)))
    rms_y = float(np.sqrt(np.mean(vy[moving] ** 2)))
    if rms_y > _LATERAL_SHARE * rms_x and rms_y > _LATERAL_FLOOR:
        warnings.warn(f"{source}: {topic}: the twist moves sideways: linear.y has RMS {rms_y:.3g} m/s "
                      f"against linear.x's {rms_x:.3g} m/s over the {int(moving.sum())} messages that move; "
                      "odomkit's vehicles have no sideways velocity (a holonomic base, mecanum or omni, "
                      "is not modelled), so the track ignores linear.y", stacklevel=4)


def _imu_signals(messages: list[Any], ns: NDArray[np.int64], topic: str, source: str,
                 up: str = "+z") -> _Stream:
    """An Imu topic's yaw rate (its angular velocity about the axis ``up``, sign included) and,
    mounted level (``up`` "+z") with an orientation, its heading."""
    sign, axis = (1.0 if up[0] == "+" else -1.0), up[1]
    rate = sign * _finite(np.array([getattr(m.angular_velocity, axis) for m in messages], dtype=float),
                          f"angular velocity {axis}", topic, source)
    stream = _Stream(topic, ns, [("yaw_rate", "linear", rate)])
    # sensor_msgs/Imu: orientation_covariance[0] = -1 means "no orientation estimate". The yaw of
    # the orientation is the heading only for an IMU mounted level.
    oriented = all(float(m.orientation_covariance[0]) != -1.0 for m in messages)
    if oriented and up == "+z":
        heading = _finite(np.array([_yaw(m.orientation) for m in messages]), "orientation", topic, source)
        stream.signals.append(("heading", "absolute", unwrap_angle(heading)))
    accel = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                      for m in messages], dtype=float)
    _check_level(accel, oriented and up == "+z", topic, source, up)
    return stream


#: An Imu's mean linear acceleration is gravity (the robot's own accelerations average out)
#: where its size lies in this range [m/s²]; outside it (0: an IMU that does not fill it in,
#: or reports it without gravity) nothing is said.
_GRAVITY_RANGE = (5.0, 15.0)
#: Gravity "mostly along z": the mean's z part at least this fraction of its size (a tilt
#: of up to 37°; a level robot on a slope of 20° keeps 0.94).
_LEVEL = 0.8


def _check_level(accel: NDArray[np.float64], oriented: bool, topic: str, source: str,
                 up: str = "+z") -> None:
    """Warn where an IMU's gravity is not along the axis read as up (``up``, ``--imu-up``;
    its sign is not judged): mounted otherwise, the angular velocity read is a rotation about
    a horizontal axis, not the robot's yaw rate.

    ``accel`` (M, 3) [m/s²]: the messages' linear acceleration (x, y, z). Gravity on the
    negative side is not warned about: some drivers report a level IMU's specific force with
    that sign."""
    finite = accel[np.isfinite(accel).all(axis=1)]
    if not finite.size:
        return
    mean = finite.mean(axis=0)
    size = float(np.linalg.norm(mean))
    read = "xyz".index(up[1])
    if not (_GRAVITY_RANGE[0] <= size <= _GRAVITY_RANGE[1]) or abs(mean[read]) >= _LEVEL * size:
        return
    axis = int(np.argmax(np.abs(mean)))
    sign = "+" if mean[axis] > 0 else "-"
    name = "xyz"[axis]
    heading = ", nor its orientation's yaw the heading" if oriented else ""
    warnings.warn(f"{source}: {topic}: gravity is along its {sign}{name} axis (mean linear acceleration "
                  f"({mean[0]:.2f}, {mean[1]:.2f}, {mean[2]:.2f}) m/s²), not {up[1]}: the IMU is not "
                  f"mounted as read, so its angular_velocity.{up[1]} is not the robot's yaw rate{heading}; "
                  f"--imu-up {sign}{name} reads the rate about {sign}{name}", stacklevel=4)


#: A (parent, child) pair of frames, each without a leading '/'.
_Pair = tuple[str, str]


def _frame(name: str) -> str:
    """A frame id as compared: without a leading '/' (ROS 1's tf wrote ``/world``)."""
    return name.lstrip("/")


def parse_truth_frame(text: str) -> tuple[str, str]:
    """``--truth-frame PARENT:CHILD``: the frames of the ``/tf`` transforms that are the truth
    (header.frame_id, child_frame_id), each without a leading '/'.

    Examples
    --------
    >>> parse_truth_frame("/world:base_link")
    ('world', 'base_link')
    """
    parts = [_frame(part.strip()) for part in text.split(":")] if isinstance(text, str) else []
    if len(parts) != 2 or not all(parts):
        raise InputError("--truth-frame takes PARENT:CHILD, the frames of the /tf transforms that are the "
                         f"truth (world:base_link, map:base_footprint); got {text!r}")
    return parts[0], parts[1]


def _check_frame(available: dict[str, str], truth: str | None, frame: _Pair | None, source: str) -> None:
    """``--truth-frame`` picks transforms of a TFMessage truth topic: refused for any other."""
    if frame is None:
        return
    what = "--truth-frame picks the transforms of a tf2_msgs/TFMessage truth topic (/tf)"
    if truth is None:
        raise InputError(f"{what}; no --truth-topic is given", source=source)
    if available[truth] != _TF:
        raise InputError(f"{what}; {truth} is {available[truth]}", source=source)


def _pose_truth(reader: Any, topic: str, msgtype: str, receive_time: bool, source: str,
                progress: Progress = NO_PROGRESS,
                frame: _Pair | None = None) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """A pose topic's times [ns] (M,) and poses (M, 3): x, y [m] and the unwrapped yaw [rad]
    (a TFMessage topic's: the transforms of ``frame``, :func:`_tf_poses`)."""
    kind = TRUTH_TYPES[msgtype]
    if kind == "TFMessage":
        ns, xyt = _tf_poses(reader, topic, frame, receive_time, source, progress)
    else:
        messages, ns = _stamps(reader, [c for c in reader.connections if c.topic == topic], receive_time,
                               topic, source, progress)
        xyt = np.array([_planar(m, kind) for m in messages], dtype=float)
    _finite(xyt, "pose", topic, source)
    xyt[:, 2] = unwrap_angle(xyt[:, 2])
    return ns, xyt


def _planar(msg: Any, kind: str) -> tuple[float, float, float]:
    """A pose message's x, y [m] and yaw [rad]; a transform's translation and rotation are a
    pose of the child frame in the parent's."""
    if kind == "Pose2D":  # mocap_optitrack's ground_pose: the planar pose itself, no header
        return float(msg.x), float(msg.y), float(msg.theta)
    if kind == "TransformStamped":
        position, rotation = msg.transform.translation, msg.transform.rotation
    else:
        pose = msg.pose if kind == "PoseStamped" else msg.pose.pose
        position, rotation = pose.position, pose.orientation
    return float(position.x), float(position.y), _yaw(rotation)


def _tf_poses(reader: Any, topic: str, frame: _Pair | None, receive_time: bool, source: str,
              progress: Progress = NO_PROGRESS) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The transforms of one (parent, child) pair of a TFMessage topic, direct ones only (no
    chaining): times [ns] (M,) (each transform's header stamp, or its message's bag time) and
    x, y [m], yaw [rad] (M, 3). ``frame`` None: the topic's only pair; several are an error
    listing them with their counts, as is a ``frame`` the topic does not carry."""
    counts: dict[_Pair, int] = {}
    chosen: _Pair | None = frame
    stamps: list[int] = []
    poses: list[tuple[float, float, float]] = []
    for bag_ns, msg in _messages(reader, [c for c in reader.connections if c.topic == topic], source,
                                 progress):
        for tf in msg.transforms:
            pair = (_frame(tf.header.frame_id), _frame(tf.child_frame_id))
            counts[pair] = counts.get(pair, 0) + 1
            chosen = pair if chosen is None else chosen
            if pair == chosen:  # without a frame, only the first pair is kept: another is an error
                stamps.append(bag_ns if receive_time else _stamp_ns(tf.header))
                poses.append(_planar(tf, "TransformStamped"))
    pairs = ", ".join(f"{p}:{c} ({n})" for (p, c), n in sorted(counts.items()))
    if not counts:
        raise InputError(f"{topic} holds no transforms", source=source)
    if frame is None and len(counts) > 1:
        raise InputError(f"{topic} carries transforms of {len(counts)} frame pairs; name the truth's with "
                         f"--truth-frame PARENT:CHILD: {pairs} (transforms of each)", source=source)
    assert chosen is not None
    label = f"{topic} {chosen[0]}:{chosen[1]}"
    if frame is not None and frame not in counts:
        raise InputError(f"{topic} has no transform {chosen[0]}:{chosen[1]} (--truth-frame); its frame "
                         f"pairs: {pairs} (transforms of each)", source=source)
    if len(stamps) < 2:
        raise InputError(f"{label}: {len(stamps)} transform(s); truth needs two or more", source=source)
    if chosen[0].rsplit("/", 1)[-1] == "odom":
        warnings.warn(f"{source}: {label}: a transform from the odom frame is, as a rule, the odometry's "
                      "own (its controller or an EKF publishes it): the odometry would be scored against "
                      "itself; ground truth comes from elsewhere (motion capture, GPS)", stacklevel=4)
    ns = _ordered(np.array(stamps, dtype=np.int64), receive_time, label, source, "transform")
    return ns, np.array(poses, dtype=float)


def _truth_stream(reader: Any, topic: str, msgtype: str, receive_time: bool, source: str,
                  progress: Progress = NO_PROGRESS, frame: _Pair | None = None) -> _Stream:
    """Ground truth as three signals ``gt_x``, ``gt_y``, ``gt_theta`` (unwrapped), interpolated;
    fixes stamped in bursts (a Pose2D's or ``--bag-time``'s arrival times) are warned of here,
    where the log's rows hide them (a truth bag of its own is, as any truth file, by
    :func:`odomkit.workflows.truth.load_truth`)."""
    ns, xyt = _pose_truth(reader, topic, msgtype, receive_time, source, progress, frame)
    if note := bursts_note(_seconds(ns)):
        warnings.warn(f"{source}: {topic}: {note}", stacklevel=4)
    return _Stream(topic, ns, [("gt_x", "absolute", xyt[:, 0]), ("gt_y", "absolute", xyt[:, 1]),
                               ("gt_theta", "absolute", xyt[:, 2])])


def _first_at_each_time(ns: NDArray[np.int64], topic: str, source: str) -> NDArray[np.bool_]:
    """Which messages to keep: the first at each stamp (a truth's clock must increase), with
    a warning counting the others."""
    repeat = np.concatenate(([False], np.diff(ns) == 0))
    if repeat.any():
        warnings.warn(f"{source}: {topic}: {int(repeat.sum())} fixes repeat an earlier stamp and were "
                      "dropped (the first fix at each time is kept)", stacklevel=4)
    return ~repeat


def read_bag_truth(path: str | Path, topic: str | None = None, receive_time: bool = False,
                   frame: str | None = None) -> tuple[Truth, float | None]:
    """A bag's ground-truth topic as truth on its own clock (``--truth BAG``, a truth that was
    recorded apart from the log, e.g. a motion capture's own bag).

    Unlike a log bag's ``--truth-topic`` pose topic, which is interpolated at the log's rows,
    the poses are kept at their own stamps, as a TUM file's are, and ``evaluate`` and the
    windows interpolate them. A NavSatFix topic is read as in :func:`read_bag` (east and
    north of the first fix).

    Parameters
    ----------
    path : a ROS 1 ``.bag``, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file
    topic : a :data:`TRUTH_TYPES` topic; None: the bag's only one (``tf_static`` aside)
    receive_time : use the time the bag received each message instead of header stamps
    frame : ``"PARENT:CHILD"``, the transforms of a TFMessage topic that are the truth
        (``--truth-frame``, :func:`parse_truth_frame`); None: the topic's only frame pair

    Returns
    -------
    truth : Truth
        Times [s] strictly increasing (a message repeating a stamp is dropped, with a
        warning); the heading (unwrapped yaw) for a pose topic, None for GPS fixes.
    stated_sigma : float or None
        The median horizontal σ per axis [m] that every GPS fix states, else None.

    Raises
    ------
    InputError
        Not a bag, no such topic (listing the truth topics there are), several truth topics
        and none named, fewer than two messages, stamps that go backwards; ``frame`` as
        :func:`read_bag`'s ``truth_frame``.
    """
    path = Path(path)
    source = str(path)
    pair = None if frame is None else parse_truth_frame(frame)
    with _open(path) as reader:
        available = _topics(reader, source)
        if topic is None:
            topic = _the_one(available, TRUTH_TYPES, "--truth-topic", source)
        name = _find_topic(available, topic, source, TRUTH_TYPES)
        _check_frame(available, name, pair, source)
        if TRUTH_TYPES[available[name]] == "NavSatFix":
            return _fix_truth(reader, name, receive_time, source)
        ns, xyt = _pose_truth(reader, name, available[name], receive_time, source, frame=pair)
    keep = _first_at_each_time(ns, name, source)
    return Truth(_seconds(ns[keep]), xyt[keep, :2], xyt[keep, 2], 0.0, f"{source}:{name}"), None


def _fix_truth(reader: Any, topic: str, receive_time: bool, source: str,
               progress: Progress = NO_PROGRESS) -> tuple[Truth, float | None]:
    """A NavSatFix topic as position-only truth on its own clock (module docstring), and the
    median horizontal σ per axis [m] its fixes state (None unless every fix states one)."""
    from odomkit.io.truth import project_latlon

    messages, ns = _stamps(reader, [c for c in reader.connections if c.topic == topic], receive_time,
                           topic, source, progress)
    fixed = np.flatnonzero([int(m.status.status) >= 0 for m in messages])
    lost = len(messages) - fixed.size
    if lost:
        warnings.warn(f"{source}: {topic}: {lost} of {len(messages)} NavSatFix messages have no fix "
                      "(status < 0) and are left out", stacklevel=3)
    if fixed.size < 2:
        raise InputError(f"{topic}: {fixed.size} of {len(messages)} NavSatFix messages have a fix "
                         "(status >= 0); truth needs two or more", source=source)
    kept = [messages[i] for i in fixed]
    geo = np.array([[m.latitude, m.longitude] for m in kept], dtype=float)
    for col, limit, what in ((0, 90.0, "latitude"), (1, 180.0, "longitude")):
        bad = np.flatnonzero(~(np.abs(geo[:, col]) <= limit))  # NaN too
        if bad.size:
            raise InputError(f"{topic}: message {fixed[bad[0]] + 1} has {what} {geo[bad[0], col]}; "
                             f"expected degrees within ±{limit:g}", source=source)
    alt = np.array([m.altitude for m in kept], dtype=float)
    ns = ns[fixed]
    first = _first_at_each_time(ns, topic, source)
    if not first.all():
        kept = [m for m, k in zip(kept, first, strict=True) if k]
        geo, alt, ns = geo[first], alt[first], ns[first]
    name = f"{source}:{topic}"
    # NaN altitude: "not known" (sensor_msgs/NavSatFix); then no fix's height is used.
    xy, _ = project_latlon(geo[:, 0], geo[:, 1], alt if np.all(np.isfinite(alt)) else None, source=name)
    sigma = None
    if all(int(m.position_covariance_type) > 0 for m in kept):
        cov = np.array([m.position_covariance for m in kept], dtype=float)  # row-major, east-north-up
        per_fix = np.sqrt(0.5 * (cov[:, 0] + cov[:, 4]))
        stated = float(np.median(per_fix))
        sigma = stated if math.isfinite(stated) and stated > 0 else None
    return Truth(_seconds(ns), xy, None, 0.0, name), sigma


def _read_stream(reader: Any, topic: str, msgtype: str, joints: Sequence[str], receive_time: bool,
                 source: str, progress: Progress = NO_PROGRESS, imu_up: str = "+z") -> _Stream:
    conns = [c for c in reader.connections if c.topic == topic]
    messages, ns = _stamps(reader, conns, receive_time, topic, source, progress)
    kind = MESSAGE_TYPES[msgtype]
    if kind == "JointState":
        return _joint_signals(messages, ns, joints, topic, source)
    if kind == "Imu":
        return _imu_signals(messages, ns, topic, source, imu_up)
    if kind == "AckermannDriveStamped":
        return _ackermann_signals(messages, ns, topic, source)
    return _twist_signals(messages, ns, kind, topic, source)


def _ackermann_signals(messages: list[Any], ns: NDArray[np.int64], topic: str, source: str) -> _Stream:
    """A car's drive command (``ackermann_msgs/AckermannDriveStamped``): ``speed`` [m/s] and the
    road wheels' ``steer`` [rad], each held from its stamp to the next, as a command is."""
    speed = _finite(np.array([m.drive.speed for m in messages], dtype=float), "drive speed", topic, source)
    steer = _finite(np.array([m.drive.steering_angle for m in messages], dtype=float), "steering angle",
                    topic, source)
    return _Stream(topic, ns, [("speed", "forward", speed), ("steer", "forward", steer)])


def _integral_at(s: NDArray[np.float64], v: NDArray[np.float64], kind: str,
                 times: NDArray[np.float64]) -> NDArray[np.float64]:
    """∫ from s[0] to each time of the rate signal of samples (s, v) (times inside [s0, s_end])."""
    h = np.diff(s)
    seg = {"forward": v[:-1], "backward": v[1:], "linear": 0.5 * (v[:-1] + v[1:])}[kind] * h
    cum = np.concatenate(([0.0], np.cumsum(seg)))
    j = np.clip(np.searchsorted(s, times, side="right") - 1, 0, s.size - 2)
    tau = times - s[j]
    if kind == "forward":
        part = v[j] * tau
    elif kind == "backward":
        part = v[j + 1] * tau
    else:
        slope = np.divide(v[j + 1] - v[j], h[j], out=np.zeros_like(tau), where=h[j] > 0)
        part = v[j] * tau + 0.5 * slope * tau**2
    return cum[j] + part


def _value_at(s: NDArray[np.float64], v: NDArray[np.float64], kind: str,
              times: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rate signal just after each time (for zero-length steps and the last row)."""
    j = np.clip(np.searchsorted(s, times, side="right") - 1, 0, s.size - 1)
    if kind == "forward":
        return v[j]
    if kind == "backward":
        return v[np.minimum(j + 1, s.size - 1)]
    return np.interp(times, s, v)


def _step_means(v: NDArray[np.float64], kind: str) -> NDArray[np.float64]:
    """Rows = the samples: the mean of the signal over each step, exactly (no division)."""
    out = v.astype(float).copy()
    if kind == "backward":
        out[:-1] = v[1:]
    elif kind == "linear":
        out[:-1] = 0.5 * (v[:-1] + v[1:])
    return out


def _channel(s: NDArray[np.float64], name: str, kind: str, v: NDArray[np.float64], rows: NDArray[np.float64],
             own: bool) -> NDArray[np.float64]:
    """Channel ``name`` at the log's ``rows`` from a stream's samples (``s``, ``v``); ``own``:
    the rows are the samples. Times [s] from one origin near them (exact differences)."""
    if kind == "angle":
        cum = v if own else np.interp(rows, s, v)
        return np.concatenate(([0.0], np.diff(cum)))
    if kind == "absolute":
        return v if own else np.interp(rows, s, v)
    if name in INCREMENT_CHANNELS:  # a joint velocity integrated over each step
        if own:
            return np.concatenate(([0.0], _step_means(v, kind)[:-1] * np.diff(rows)))
        return np.concatenate(([0.0], np.diff(_integral_at(s, v, kind, rows))))
    if own:
        return _step_means(v, kind)
    dt = np.diff(rows)
    mean = np.divide(np.diff(_integral_at(s, v, kind, rows)), dt, out=np.zeros_like(dt), where=dt > 0)
    out = _value_at(s, v, kind, rows)
    out[:-1] = np.where(dt > 0, mean, out[:-1])
    return out


#: Rows left out at the ends of another topic's span are warned about beyond this share of
#: them or this many seconds (:func:`_merge`).
_LOST_SHARE = 0.01
_LOST_SECONDS = 1.0


def _merge(streams: list[_Stream], source: str, truth: str | None = None, receive_time: bool = False,
           offset: float = 0.0) -> tuple[NDArray[np.float64], dict[str, NDArray[np.float64]]]:
    """The log's times and channels: the first stream's rows that every other one spans, the
    others resampled there (module docstring); ``truth``, ``receive_time`` and ``offset`` (the
    truth topic, ``--bag-time``, ``--truth-time-offset``) for the error where they share fewer
    than two rows (:func:`_apart`)."""
    primary = streams[0]
    spans = [(other, (primary.ns >= other.ns[0]) & (primary.ns <= other.ns[-1])) for other in streams[1:]]
    keep = np.ones(primary.ns.size, dtype=bool)
    for _, inside in spans:
        keep &= inside
    if keep.sum() < 2:
        raise _apart(streams, source, truth, receive_time, offset)
    for other, inside in spans:
        lost = int((~inside).sum())
        # Topics seldom start and stop in the same instant: a message or so at either end is
        # no news (a Husky bag's 1 of 3952, 0.1 s); more than 1 % of them, or of a second, is.
        lost_s = (float(primary.ns[-1] - primary.ns[0]) - float(np.ptp(primary.ns[inside]) if inside.any()
                                                                else 0.0)) / 1e9
        if lost > _LOST_SHARE * inside.size or lost_s > _LOST_SECONDS:
            span = _seconds(other.ns[[0, -1]])
            warnings.warn(f"{source}: {lost} of {inside.size} {primary.topic} messages fall "
                          f"outside {other.topic}'s time span ({span[0]:.9f}..{span[1]:.9f} s) and "
                          "are left out", stacklevel=3)
    first, last = np.flatnonzero(keep)[[0, -1]]
    origin = primary.ns[first]
    # Resampled on times from one origin: epoch seconds as floats are only good to 0.24 µs.
    rows = (primary.ns[first:last + 1] - origin) / 1e9
    channels: dict[str, NDArray[np.float64]] = {}
    given_by: dict[str, str] = {}
    for stream in streams:  # later topics replace earlier ones' channels
        own = stream is primary
        s = rows if own else (stream.ns - origin) / 1e9
        for name, kind, values in stream.signals:
            v = values[first:last + 1] if own else values
            channel = _channel(s, name, kind, v, rows, own)
            if name in channels:
                _check_replaced(name, kind, rows, (given_by[name], channels[name]),
                                (stream.topic, channel), source)
            channels[name], given_by[name] = channel, stream.topic
    return _seconds(primary.ns[first:last + 1]), channels


def _apart(streams: list[_Stream], source: str, truth: str | None, receive_time: bool,
           offset: float) -> InputError:
    """The error of topics that share fewer than two of the first one's messages: each one's
    span (clock text, as :func:`odomkit.truth.no_overlap` says a truth file's) and, where one
    misses the first's span altogether, how far apart the two start and what mends it:
    ``--bag-time`` (header stamps on two clocks: a user study's F1TENTH car stamped its
    odometry on its own clock and its motion capture 8328 s earlier, in one bag), and for
    the truth topic (``truth``) the ``--truth-time-offset`` their first stamps suggest, on
    top of the ``offset`` it was moved by already."""
    primary = streams[0]

    def span(stream: _Stream) -> str:
        start, end = _seconds(stream.ns[[0, -1]])
        return f"{stream.topic} ({clock_text(start)}..{clock_text(end)} s)"

    moved = f"; {truth} moved by --truth-time-offset {offset:g}" if offset and truth else ""
    spans = f"topics {', '.join(span(s) for s in streams)}{moved}"
    missed = [s for s in streams[1:] if s.ns[0] > primary.ns[-1] or s.ns[-1] < primary.ns[0]]
    if not missed:
        return InputError(f"{spans} overlap in fewer than two {primary.topic} messages", source=source)
    far = max(missed, key=lambda s: abs(int(s.ns[0]) - int(primary.ns[0])))
    apart = (int(far.ns[0]) - int(primary.ns[0])) / 1e9
    said = (f"{spans} do not overlap in time: {far.topic} starts {abs(apart):.3f} s "
            f"{'after' if apart > 0 else 'before'} {primary.topic}, its stamps on another clock")
    hints = [] if receive_time else [BAG_TIME_HINT]
    if far.topic == truth:
        hints.append(f"--truth-time-offset {offset + apart:.3f}, which puts {truth}'s fixes on "
                     f"{primary.topic}'s clock (a fix stamped t is the pose at t − offset; this is their "
                     "first stamps' difference, the clocks' offset give or take how far apart the topics "
                     "began)")
    return InputError(said + (f"; try {', or '.join(hints)}" if hints else ""), source=source)


#: The windows [s] over which a replaced channel and its replacement are summed before the
#: absolute values are taken: a gyro's white noise averages out within each (0.02 rad/s at
#: 100 Hz: 0.002 rad a window), and a turn lasts longer than one.
_WINDOW = 1.0
#: Where the one moves more than this many times as far as the other, one of them is wrong:
#: an honest pair differs by a skid-steer odometry's yaw gain (10–20 %) or a wheel scale.
_FACTOR = 2.0
#: Besides, the difference must exceed this much plus :data:`_DRIFT` per second [rad, or m
#: for speed]: a robot going straight ahead, whose odometry turns 0 rad, and a gyro's
#: uncorrected bias up to 0.01 rad/s (0.6°/s, a cheap MEMS gyro; the robot file's
#: ``gyro_bias`` corrects it later) must not warn.
_SLACK = 1.0
_DRIFT = 0.01


def _check_replaced(name: str, kind: str, rows: NDArray[np.float64], old: tuple[str, NDArray[np.float64]],
                    new: tuple[str, NDArray[np.float64]], source: str) -> None:
    """Warn where channel ``name`` of topic ``new`` (which replaces it) and of topic ``old``
    disagree grossly over the rows they share (``rows`` (N,) [s] from the first).

    Both are summed over :data:`_WINDOW` windows into the motion of each (Δθ [rad], or the
    distance [m] for ``speed``); a warning where Σ|Δ| of the one exceeds :data:`_FACTOR`
    times the other's by more than :data:`_SLACK` + :data:`_DRIFT`·duration, or where both
    move that much and their windows go opposite ways (correlation below −½: a gyro upside
    down). A user study's Jackal bag: the odometry's twist turns 47 rad in 61 s, its level IMU 9."""
    if rows.size < 2 or rows[-1] <= rows[0]:
        return
    dt = np.diff(rows)

    def motion(values: NDArray[np.float64]) -> NDArray[np.float64]:
        if name in INCREMENT_CHANNELS:
            steps = values[1:]
        elif kind == "absolute":
            steps = np.diff(values)
        else:
            steps = values[:-1] * dt
        window = np.floor(rows[:-1] / _WINDOW).astype(np.int64)
        return np.bincount(window, weights=steps).astype(float)  # weighted: float64 already

    def net(steps: NDArray[np.float64]) -> str:
        return f"{round(float(steps.sum()), 3) + 0.0:+.3g}"  # +0, not -0 or +1e-16

    (old_topic, old_values), (new_topic, new_values) = old, new
    a, b = motion(old_values), motion(new_values)
    total_a, total_b = float(np.abs(a).sum()), float(np.abs(b).sum())
    duration = float(rows[-1] - rows[0])
    slack = _SLACK + _DRIFT * duration
    low, high = sorted((total_a, total_b))
    turning = name in ("yaw_rate", "heading")  # else travel: a speed, a wheel's distance or ticks
    unit, verb = ("rad", "turns") if turning else ("ticks" if name.startswith("ticks") else "m", "travels")
    figures = (f"over the {duration:.4g} s they share, {old_topic} {verb} {total_a:.3g} {unit} in all "
               f"(Σ|Δ| over {_WINDOW:g} s windows; net {net(a)}) and {new_topic} {total_b:.3g} {unit} "
               f"(net {net(b)})")
    said = (f"{source}: {name} from {new_topic} replaces {old_topic}'s (the topic named last is used), "
            "but they disagree")
    causes = ("an IMU not mounted level, a wrong wheel separation or yaw gain, a topic of another frame"
              if turning else
              "a command the robot did not follow, a wrong wheel radius, a topic of another robot")
    hint = f"one of them is not the robot's motion ({causes})"
    if high - low > slack and high > _FACTOR * low:
        ratio = f"{high / low:.1f}" if low > 0 else "∞"
        warnings.warn(f"{said} by a factor {ratio}: {figures}; {hint}", stacklevel=4)
    elif low > slack and float(a @ b) < -0.5 * math.sqrt(float(a @ a) * float(b @ b)):
        warnings.warn(f"{said}: they move opposite ways ({figures}); {hint}", stacklevel=4)


def read_bag(path: str | Path, topics: Sequence[str] = (), joints: Sequence[str] = (),
             receive_time: bool = False, truth_topic: str | None = None, *,
             progress: Progress = NO_PROGRESS, imu_up: str = "+z",
             truth_frame: str | None = None, truth_time_offset: float = 0.0) -> OdometryLog:
    """Read a ROS bag's odometry topics as a log (module docstring: messages, time, topics).

    Parameters
    ----------
    path : a ROS 1 ``.bag``, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file (a ROS 1
        bag or MCAP file by another name too: known by its first bytes)
    topics : topic names, the first giving the rows; empty: the bag's one readable topic
        (other than ``truth_topic``)
    joints : JointState joint names, ``(left, right)`` or one; empty: the joints whose
        names contain "left" and "right", or the only joint
    receive_time : use the time the bag received each message instead of header stamps
    truth_topic : a pose topic (:data:`TRUTH_TYPES`, e.g. motion capture) that becomes the
        log's ground truth, interpolated at the rows (θ on the unwrapped yaw); rows outside
        its span are left out, with a warning. A NavSatFix topic is kept as position-only
        truth at its fixes instead: ``meta["truth"]`` (and ``meta["truth_position_sigma"]``)
    progress : Progress
        One stage, ``"reading NAME"`` of the messages of the topics read (their count in the
        bag's index), advanced every 1000 messages (:mod:`odomkit.progress`)
    imu_up : the Imu axis that points up (``"+z"``, ``"-z"``, ``"+x"``, ...): the yaw rate is
        the angular velocity about it, sign included; the orientation's yaw is read as a
        heading only for ``"+z"``
    truth_frame : ``"PARENT:CHILD"`` (``--truth-frame``): the ``/tf`` transforms that are the
        truth, where ``truth_topic`` is a TFMessage topic (:func:`parse_truth_frame`); None:
        the topic's only frame pair
    truth_time_offset : how late ``truth_topic``'s clock runs against the log's [s]
        (``--truth-time-offset``): a fix stamped t is the pose at log time t − offset. A pose
        topic's stamps are moved so before they are interpolated at the rows (a motion capture
        stamped on another clock than the odometry, in one bag: a user study's was 8328 s
        ahead), GPS fixes (kept at their own times) likewise; ``meta["truth_time_offset"]``
        then records it, and :func:`odomkit.workflows.truth.load_truth` does not move the
        log's own truth again

    Returns
    -------
    OdometryLog
        ``t`` [s], the channels and the ground truth; ``meta`` names the topics and the
        time source.

    Raises
    ------
    InputError
        Not a bag (or a gzip-compressed one), no such topic or joint (listing the ones there
        are), a truth topic that is one of the log's topics, stamps that go backwards or are
        zero, values that are not finite, rosbags not installed; a ``truth_frame`` without a
        TFMessage truth topic, or not on it, or a TFMessage truth topic of several frame pairs
        without one; a ``tf_static`` truth topic; a ``truth_time_offset`` that is not a finite
        number or comes without a truth topic; topics that share fewer than two of the first
        one's messages (each one's span, and where they miss each other altogether, how far
        apart they start and the ``--bag-time`` or ``--truth-time-offset`` that mends it).

    Warns
    -----
    UserWarning
        Rows left out (outside another topic's span); an Imu whose gravity is not along its
        z axis; a channel given by two topics whose two versions disagree grossly
        (:func:`_check_replaced`); a twist that moves sideways (:func:`_check_lateral`); a
        truth transform from the odom frame (the odometry's own, as a rule).
    """
    path = Path(path)
    source = str(path)
    frame = None if truth_frame is None else parse_truth_frame(truth_frame)
    if not isinstance(truth_time_offset, int | float) or not math.isfinite(truth_time_offset):
        raise InputError(f"--truth-time-offset must be a finite number of seconds, got {truth_time_offset!r}")
    if truth_time_offset and not truth_topic:
        raise InputError("--truth-time-offset moves a bag's truth topic here: give it with --truth-topic")
    shift = round(truth_time_offset * 1e9)  # [ns]: a fix stamped t is the pose at log time t − offset
    with _open(path) as reader:
        available = _topics(reader, source)
        truth = None if not truth_topic else _find_topic(available, truth_topic, source, TRUTH_TYPES)
        _check_frame(available, truth, frame, source)
        chosen = _choose_topics(available, topics, source, truth)
        if joints and not any(MESSAGE_TYPES[available[c]] == "JointState" for c in chosen):
            raise InputError("--joints applies to a JointState topic; none is read", source=source)
        read = [*chosen, *([truth] if truth is not None else [])]
        total = sum(int(c.msgcount) for c in reader.connections if c.topic in read)
        fixes = truth is not None and TRUTH_TYPES[available[truth]] == "NavSatFix"
        gps: Truth | None = None
        stated: float | None = None
        with stage(progress, total, f"reading {path.name}"):
            streams = [_read_stream(reader, c, available[c], joints, receive_time, source, progress, imu_up)
                       for c in chosen]
            if truth is not None and fixes:
                gps, stated = _fix_truth(reader, truth, receive_time, source, progress)
                if shift:
                    gps = replace(gps, t=gps.t - truth_time_offset)
            elif truth is not None:
                stream = _truth_stream(reader, truth, available[truth], receive_time, source, progress, frame)
                streams.append(replace(stream, ns=stream.ns - shift) if shift else stream)
    t, channels = _merge(streams, source, truth, receive_time, truth_time_offset)
    poses = None
    if truth is not None and not fixes:
        poses = np.column_stack([channels.pop(c) for c in ("gt_x", "gt_y", "gt_theta")])
    meta: dict[str, object] = {"format": "bag", "topics": chosen, "time": "bag" if receive_time else "header"}
    if shift:
        meta["truth_time_offset"] = float(truth_time_offset)
    if gps is not None:
        meta["truth"] = gps
        if stated is not None:
            meta["truth_position_sigma"] = stated
    return OdometryLog(t, channels, poses, source, meta)


@dataclass(frozen=True)
class BagOdometry:
    """A ``nav_msgs/Odometry`` topic read back (e.g. ``odomkit track --bag-out``).

    Parameters
    ----------
    t : ndarray, shape (N,)
        Header stamps [s].
    poses : ndarray, shape (N, 3)
        ``[x, y, θ]`` [m, m, rad]; θ is the yaw of the orientation, unwrapped.
    pose_covariance, twist_covariance : ndarray, shape (N, 36)
        The messages' row-major 6×6 covariances, as stored (:mod:`odomkit.io.ros`).
    twist : ndarray, shape (N, 2)
        Linear x [m/s] and angular z [rad/s] of the twist.
    frame_id, child_frame_id : str
        Of the first message.
    """

    t: NDArray[np.float64]
    poses: NDArray[np.float64]
    pose_covariance: NDArray[np.float64]
    twist: NDArray[np.float64]
    twist_covariance: NDArray[np.float64]
    frame_id: str
    child_frame_id: str

    @property
    def cov(self) -> NDArray[np.float64]:
        """The planar pose covariance (N, 3, 3) over (x, y, yaw): ROS indices 0, 1, 5."""
        index = np.array([0, 1, 5])
        return self.pose_covariance.reshape(-1, 6, 6)[:, index[:, None], index]


def read_bag_odometry(path: str | Path, topic: str | None = None, receive_time: bool = False) -> BagOdometry:
    """Read a ``nav_msgs/Odometry`` topic: poses, twists and their covariances.

    ``topic`` None takes the bag's one Odometry topic.
    """
    path = Path(path)
    source = str(path)
    with _open(path) as reader:
        available = _topics(reader, source)
        if topic is None:
            topic = _the_one(available, {"nav_msgs/msg/Odometry": "Odometry"}, "--topic", source)
        name = _find_topic(available, topic, source)
        if available[name] != "nav_msgs/msg/Odometry":
            raise InputError(f"topic {name} is {available[name]}, not nav_msgs/msg/Odometry", source=source)
        messages, ns = _stamps(reader, [c for c in reader.connections if c.topic == name], receive_time,
                               name, source)
    poses = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, _yaw(m.pose.pose.orientation)]
                      for m in messages], dtype=float)
    poses[:, 2] = unwrap_angle(poses[:, 2])
    return BagOdometry(
        _seconds(ns), poses,
        np.array([m.pose.covariance for m in messages], dtype=float),
        np.array([[m.twist.twist.linear.x, m.twist.twist.angular.z] for m in messages], dtype=float),
        np.array([m.twist.covariance for m in messages], dtype=float),
        str(messages[0].header.frame_id), str(messages[0].child_frame_id))
