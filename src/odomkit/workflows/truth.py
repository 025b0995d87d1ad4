"""The truth options every truth-taking command shares (``track``, ``evaluate``, ``fit-noise``):
a truth file, or the log's own ``gt_*`` columns."""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.truth import Truth
    from odomkit.workflows.logs import LogOptions

__all__ = ["applied_clock", "clock_from_robot", "load_truth", "resolved_truth", "TruthOptions",
           "truth_options_per_log", "warn_of_truth", "with_truth_topic", "without_spikes"]


@dataclass(frozen=True)
class TruthOptions:
    """How to read the truth (see ``odomkit evaluate --help``).

    ``path`` None means the log's own ground truth. ``sigma`` [m] is the truth's own position
    noise per axis, ``heading_sigma`` [rad] its heading noise and ``time_sigma`` [s] its fixes'
    time against the log's clock. None means not given: zero, or the robot file's ``[truth]``
    (what ``fit-noise`` fitted) where a command scores a robot file's covariance
    (:meth:`resolved`); ``fit-noise`` fits it. ``max_gap`` [s] is the longest gap between fixes
    to interpolate across (None: no limit). ``time_offset`` [s] is how late the truth's clock
    runs against the log's: a fix stamped t is the pose at log time t − ``time_offset``
    (``--truth-time-offset``; None: not given, the robot file's ``[truth] time_offset`` or
    zero, and ``calibrate --truth`` fits it). ``record`` reads only the lines of a file of
    tagged records that this word leads, the tag dropped (``--truth-record``;
    :func:`odomkit.io.text.select_record`). ``up`` is the axis of a TUM or KITTI file's frame
    that points up (``--truth-up``; :func:`odomkit.frames.planar_poses`). A ``path`` that is a
    ROS bag is read by :func:`odomkit.io.bag.read_bag_truth`: ``topic`` names its truth topic
    (``--truth-topic`` given with ``--truth``; None: the bag's only one), ``frame`` the ``/tf``
    transforms of a TFMessage truth topic (``--truth-frame PARENT:CHILD``; None: its only frame
    pair) and ``bag_time`` times its messages by when the bag received them (``--bag-time``).
    ``file_clock`` [s] is the robot file's ``[truth] time_offset`` kept for the log's own truth
    where ``time_offset`` was not given (:meth:`clock` gives zero there): it moves a truth on
    its own clock (a bag's GPS topic), never a log's gt_* columns, which :func:`load_truth`
    alone can tell apart.
    """

    path: Path | None = None
    format: str = "auto"
    columns: str | None = None
    time_unit: str = "s"
    sigma: float | None = None
    max_gap: float | None = 0.5
    heading_sigma: float | None = None
    time_sigma: float | None = None
    time_offset: float | None = None
    record: str | None = None
    up: str = "+z"
    topic: str | None = None
    bag_time: bool = False
    file_clock: float = 0.0
    frame: str | None = None

    def resolved(self, defaults: Mapping[str, float] | None = None) -> TruthOptions:
        """These options with each truth noise and the clock offset not given taken from
        ``defaults`` (a robot file's ``[truth]``: ``sigma``, ``heading_sigma``, ``time_sigma``,
        ``time_offset``), else zero."""
        found = defaults or {}

        def pick(given: float | None, key: str) -> float:
            return found.get(key, 0.0) if given is None else given

        return replace(self, sigma=pick(self.sigma, "sigma"),
                       heading_sigma=pick(self.heading_sigma, "heading_sigma"),
                       time_sigma=pick(self.time_sigma, "time_sigma"), time_offset=self.clock(found),
                       file_clock=self._file_clock(found))

    def _file_clock(self, table: Mapping[str, float]) -> float:
        """The robot file's offset for the log's own truth, where none was given (``file_clock``).
        Kept once found: resolving again sees the zero :meth:`clock` put in ``time_offset``."""
        if self.file_clock:
            return self.file_clock
        return float(table.get("time_offset", 0.0)) if self.path is None and self.time_offset is None else 0.0

    def clock(self, table: Mapping[str, float]) -> float:
        """The truth's clock offset [s]: as given, else a robot file's ``[truth]``
        ``time_offset`` (``table``) for a truth file, else zero. The robot file's offset
        belongs to the truth files it was fitted against, not to a log's own gt_* columns
        (on the log's clock by construction); a flag is applied to either."""
        if self.time_offset is not None:
            return self.time_offset
        return float(table.get("time_offset", 0.0)) if self.path is not None else 0.0

    @property
    def held(self) -> dict[str, float]:
        """The truth noise the user gave, by :func:`odomkit.calibrate.fit_noise.fit_noise`'s
        names (``truth_sigma``, ``truth_heading_sigma``, ``truth_time_sigma``): ``fit-noise``
        holds these and fits the others."""
        given = {"truth_sigma": self.sigma, "truth_heading_sigma": self.heading_sigma,
                 "truth_time_sigma": self.time_sigma}
        return {k: float(v) for k, v in given.items() if v is not None}


def load_truth(options: TruthOptions, log: OdometryLog | None = None, *,
               heading_warning: bool = True) -> Truth | None:
    """The truth file of ``options``, else the log's own ground truth, else None; its clock
    moved onto the log's by ``options.time_offset`` (t − offset); what it is asked
    (:func:`warn_of_truth`) said as warnings; its heading not (``heading_warning`` False) where
    the caller judges that itself (``odomkit check``'s ``truth_heading``: said once, not twice)."""
    from odomkit.io.bag import is_bag
    from odomkit.io.truth import read_truth
    from odomkit.truth import truth_from_log

    sigma, heading_sigma = options.sigma or 0.0, options.heading_sigma or 0.0
    time_sigma = options.time_sigma or 0.0
    stated: object = None
    found: Truth | None
    if options.path is not None and is_bag(options.path):
        found, stated = _bag_truth(options, log)
    elif options.path is not None:
        for given, what in ((options.topic, "--truth-topic names a topic of a ROS bag"),
                            (options.frame, "--truth-frame picks transforms of a ROS bag's /tf topic")):
            if given is not None:
                raise InputError(f"{what}; the --truth file {options.path} is not a bag (.bag, .db3, .mcap "
                                 "or a ROS 2 bag folder)")
        found = read_truth(options.path, options.format, options.columns, options.time_unit, sigma,
                           record=options.record, up=options.up)
    else:
        if flags := _file_flags(options):
            raise InputError(f"{', '.join(flags)} reads a --truth file, and none is given (the log's own "
                             "truth is read as it is): give the file with --truth, or leave the flag out")
        found = None if log is None else truth_from_log(log)
        stated = None if log is None else log.meta.get("truth_position_sigma")
    if found is None:
        return None
    truth: Truth = found
    if isinstance(stated, float) and not sigma:  # a bag's GPS fixes state their σ (io/bag.py)
        warnings.warn(f"{truth.source}: the fixes state their position covariance, median horizontal "
                      f"sigma {stated:.3g} m per axis, which odomkit fits and scores with only when given: "
                      f"--truth-sigma {stated:.3g} takes it",
                      stacklevel=2)
        # Kept apart from sigma: no fit uses it unasked, but a check judges against it (a GPS's
        # error is correlated in time, which its fixes' scatter about a smooth path misses).
        truth = replace(truth, stated_sigma=stated)
    truth = without_spikes(truth)  # before the clock moves: the spikes' times as the file has them
    offset = applied_clock(options, log)
    if offset:
        truth = replace(truth, t=truth.t - offset)
    warn_of_truth(truth, log, heading=heading_warning)
    if (sigma, heading_sigma, time_sigma) == (truth.sigma, truth.heading_sigma, truth.time_sigma):
        return truth
    return replace(truth, sigma=sigma, heading_sigma=heading_sigma, time_sigma=time_sigma)


def without_spikes(truth: Truth) -> Truth:
    """The truth without the fixes that jump off its path and back
    (:func:`odomkit.truth_spikes.spike_fixes`: a GPS's multipath jumps, a motion capture's
    marker swaps), said in one warning; the truth itself where it has none. Every truth a
    command reads (:func:`load_truth`) and every one handed to a workflow in memory
    (:func:`odomkit.workflows.results.truths_given`) is screened: a spike is the truth's
    error, and scored as a window's end, or in a start heading fitted around it, it reads as
    the odometry's. A truth whose stamps come in bursts (:func:`odomkit.truth.stamp_bursts`)
    is not screened: its times are not when its fixes were measured (a user study's motion
    capture lost 5.8 % of its fixes as "spikes")."""
    import numpy as np

    from odomkit.log import clock_text
    from odomkit.truth import stamp_bursts
    from odomkit.truth_spikes import MAX_ACCELERATION, SPIKE_SIGMAS, spike_fixes

    if stamp_bursts(truth.t) is not None:
        return truth  # its times are not the fixes': no line in time tells a spike (warn_of_truth says so)
    found = spike_fixes(truth.t, truth.xy)
    if not len(found):
        return truth
    keep = np.ones(len(truth), dtype=bool)
    keep[found.index] = False
    lo, hi = f"{found.off.min():.3g}", f"{found.off.max():.3g}"
    times = ", ".join(f"{clock_text(float(t))} s" for t in found.t[:3]) + (", ..." if len(found) > 3 else "")
    warnings.warn(f"{truth.source}: {len(found)} of {len(truth)} truth fixes left out as spikes, each "
                  f"{lo if lo == hi else f'{lo}..{hi}'} m off the line through its neighbours (more "
                  f"than {SPIKE_SIGMAS:g}x the fixes' scatter about those lines, {found.scatter:.3g} m, and "
                  f"than a vehicle accelerating at {MAX_ACCELERATION:g} m/s^2 could be), at {times}: a "
                  "GPS's multipath jumps or a motion capture's marker swaps are the truth's errors, not the "
                  "odometry's; rows between the fixes kept are interpolated as usual (--max-gap)",
                  stacklevel=3)
    return replace(truth, t=truth.t[keep], xy=truth.xy[keep],
                   theta=None if truth.theta is None else truth.theta[keep])


def warn_of_truth(truth: Truth, log: OdometryLog | None = None, *, heading: bool = True) -> None:
    """Warn, once per truth, of a truth that is not what it claims: a heading that does not
    follow its own motion (unless ``heading`` is False), positions or times in another unit.
    Every truth a command reads (:func:`load_truth`) and every one handed to a workflow in
    memory (:func:`odomkit.workflows.results.truths_given`) is asked."""
    if heading and truth.theta is not None:
        _warn_if_heading_off_motion(truth)
    _warn_if_units_off(truth, log)
    _warn_if_bursty(truth)


def _warn_if_bursty(truth: Truth) -> None:
    """Warn where the truth's fixes come in bursts (:func:`odomkit.truth.bursts_note`):
    stamped when they arrived, every comparison in time is off by up to the bursts' period,
    and nothing else says so."""
    from odomkit.truth import bursts_note

    if note := bursts_note(truth.t):
        warnings.warn(f"{truth.source}: {note}", stacklevel=3)


def _warn_if_heading_off_motion(truth: Truth) -> None:
    """Warn where the truth's heading does not follow the direction its positions move in
    (:func:`odomkit.truth.heading_off_motion`): every window restarted from it, and every
    start aligned to it, starts off the robot's heading. A heading in degrees read as
    radians, or a TUM quaternion written w first, scored a circle's windows at heading NEES
    243 and 18.5, silently."""
    from odomkit.truth import HEADING_OFF_CAUSES, heading_backwards, heading_off_motion

    if note := heading_off_motion(truth):
        warnings.warn(f"{truth.source}: {note}: every window or start taken from it starts off the robot's "
                      f"heading. Likely {HEADING_OFF_CAUSES}; odomkit check compares the two", stacklevel=3)
    elif note := heading_backwards(truth):
        warnings.warn(f"{truth.source}: {note}", stacklevel=3)


def _warn_if_units_off(truth: Truth, log: OdometryLog | None) -> None:
    """Warn where the truth moves faster than a wheeled vehicle
    (:func:`odomkit.truth.implausible_speed`), or where its span and the log's differ by a
    time unit's factor (within 2x of 1000, 1e6, 1e9: :func:`odomkit.truth.clock_unit_hint`)
    while both start together: a truth stamped in ms read as s spans 1000 times the log's
    seconds and overlaps it only in its first thousandth, which evaluate reported as "no
    window travels --min-travel", not as a unit."""
    from odomkit.truth import clock_unit_hint, implausible_speed, latlon_as_metres

    for note in (implausible_speed(truth), latlon_as_metres(truth)):
        if note:
            warnings.warn(f"{truth.source}: {note}", stacklevel=3)
    if log is None or len(log.t) < 2 or len(truth) < 2:
        return
    uncut = log.meta.get("uncut_clock")  # the log's clock before --span cut it
    start, end = uncut if isinstance(uncut, tuple) else (float(log.t[0]), float(log.t[-1]))
    ours, theirs = float(end - start), float(truth.t[-1] - truth.t[0])
    # Both clocks start together (relative times from 0, as a recorder writes them); a truth
    # that merely runs far longer (a GPS logging the whole day) starts elsewhere as a rule.
    if not (ours > 0 and theirs > 0) or abs(float(truth.t[0] - start)) > 0.01 * max(ours, theirs):
        return
    if (hint := clock_unit_hint(ours, theirs)) is not None:
        warnings.warn(f"{truth.source}: {hint}", stacklevel=3)


def applied_clock(options: TruthOptions, log: OdometryLog | None) -> float:
    """The clock offset [s] :func:`load_truth` moves the truth by: ``time_offset``, and for the
    log's own truth on its own clock (a bag's GPS topic, ``meta["truth"]``) the robot file's
    offset too where none was given (``file_clock``; calibrate fitted it against those fixes,
    and a user study's calibrated Husky scored 20.7 m ATE without it, 19.2 m with it). Zero
    for a bag's own truth topic that :func:`odomkit.io.bag.read_bag` moved when it read it
    (``meta["truth_time_offset"]``, :func:`with_truth_topic`); another ``time_offset`` beside
    that one is an :class:`InputError`."""
    from odomkit.truth import Truth

    offset = options.time_offset or 0.0
    moved = None if options.path is not None or log is None else log.meta.get("truth_time_offset")
    if isinstance(moved, float) and log is not None:  # the bag's truth topic, moved when read
        if options.time_offset not in (None, moved):
            raise InputError(f"the log's truth topic was moved by {moved:g} s when it was read "
                             f"(LogOptions.truth_time_offset); a time_offset of {options.time_offset:g} s "
                             "would move it again: give the offset once", source=log.source)
        return 0.0
    if options.path is None and log is not None and isinstance(log.meta.get("truth"), Truth):
        offset += options.file_clock
    return offset


def _file_flags(options: TruthOptions) -> list[str]:
    """The flags given that read a truth file (its format, columns, time unit, records, up
    axis): a bag's truth topic or a log's own truth has none of these to read."""
    return [flag for flag, given in (("--truth-format", options.format != "auto"),
                                     ("--truth-columns", options.columns is not None),
                                     ("--truth-time-unit", options.time_unit != "s"),
                                     ("--truth-record", options.record is not None),
                                     ("--truth-up", options.up != "+z")) if given]


def _bag_truth(options: TruthOptions, log: OdometryLog | None) -> tuple[Truth, float | None]:
    """The truth topic of the ``--truth`` bag and the σ its GPS fixes state; the options of a
    text truth file are refused by name, and so is a topic the log itself was read from
    (the same bag named twice: the odometry would be scored against itself)."""
    from odomkit.io.bag import bag_root, read_bag_truth

    assert options.path is not None
    if text_only := _file_flags(options):
        raise InputError(f"{', '.join(text_only)} applies to a text truth file; {options.path} is a "
                         "ROS bag (name its truth topic with --truth-topic)")
    found = read_bag_truth(options.path, options.topic, options.bag_time, options.frame)
    topic = found[0].source.rsplit(":", 1)[-1]
    own = log.meta.get("topics", ()) if log is not None and log.meta.get("format") == "bag" else ()
    if (log is not None and isinstance(own, list | tuple) and topic in own
            and bag_root(log.source).resolve() == bag_root(options.path).resolve()):
        raise InputError(f"--truth {options.path} --truth-topic {topic} is the log's own topic {topic}: "
                         "the odometry would be scored against itself; the truth must come from another "
                         "source (motion capture, GPS)")
    return found


def with_truth_topic(log: LogOptions, truth: TruthOptions,
                     truth_given: bool) -> tuple[LogOptions, TruthOptions]:
    """Where ``--truth-topic`` (and ``--truth-frame``) belong: to the ``--truth`` bag where a
    truth file is given (``truth_given``), else to the log bag (its own ground truth).
    ``--bag-time`` times both.

    Returns the log and truth options with ``truth_topic`` and ``truth_frame`` moved to
    ``TruthOptions.topic`` and ``TruthOptions.frame`` in the first case; in the second,
    ``--truth-time-offset`` (``truth.time_offset``) given with a truth topic is copied to
    ``LogOptions.truth_time_offset`` as well, which moves the topic's stamps before they are
    interpolated at the log's rows (:func:`odomkit.io.bag.read_bag`: a motion capture on
    another clock than the odometry in the same bag overlaps it only so). ``truth.time_offset``
    stays, for what reports it (calibrate); :func:`applied_clock` does not move that truth again.
    """
    if not truth_given:
        if log.truth_topic is not None and truth.time_offset:
            return replace(log, truth_time_offset=truth.time_offset), truth
        return log, truth
    return (replace(log, truth_topic=None, truth_frame=None),
            replace(truth, topic=log.truth_topic, frame=log.truth_frame, bag_time=log.bag_time))


def resolved_truth(robot_path: str | Path, options: Sequence[TruthOptions]) -> list[TruthOptions]:
    """``options`` with each truth noise not given taken from the robot file's ``[truth]``
    (the noise of the truth its noise was fitted against), else zero: for scoring that
    robot's covariance against a truth (:meth:`TruthOptions.resolved`)."""
    from odomkit.io.robotfile import read_truth_table

    defaults = read_truth_table(robot_path)
    return [o.resolved(defaults) for o in options]


def clock_from_robot(robot_path: str | Path, options: Sequence[TruthOptions]) -> list[TruthOptions]:
    """``options`` with the truth's clock offset, where not given, taken from the robot
    file's ``[truth] time_offset`` (what ``calibrate --truth`` fitted) for a truth file, else
    zero (a log's own gt_* columns share its clock); the truth's noise is left as given (for
    ``fit-noise``, which fits what is not given, ``track``, ``check`` and ``fit-amcl``)."""
    from odomkit.io.robotfile import read_truth_table

    table = read_truth_table(robot_path)
    return [replace(o, time_offset=o.clock(table), file_clock=o._file_clock(table)) for o in options]


def truth_options_per_log(options: TruthOptions, paths: list[Path], logs: int) -> list[TruthOptions]:
    """One :class:`TruthOptions` per log: the i-th ``--truth`` for the i-th log.

    No ``--truth`` gives every log its own ``gt_*`` columns; otherwise the counts must match.
    """
    if not paths:
        return [options] * logs
    if len(paths) != logs:
        raise InputError(f"give one --truth per log: {logs} log(s) but {len(paths)} --truth file(s)")
    return [replace(options, path=Path(p)) for p in paths]
