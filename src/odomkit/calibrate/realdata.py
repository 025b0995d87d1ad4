"""Calibration from logs with ground truth: UMBmark return errors from runs, UMBmark and
exact calibration side by side, and the OptiOdom square-path acceptance table.

Return position error (Borenstein–Feng eq. 3.1): ε = absolute − calculated, i.e. the
ground-truth end position minus the dead-reckoned one, both in the run's start frame (the
odometry starts at the first ground-truth pose; OptiOdom ground truth is already relative
to the start pose). A run's direction is the sign of its ground-truth heading change.

Transferring a calibration between experiments whose metadata list different nominal
parameters (OptiOdom: Li = 0.2 or 0.205 m, Di = 0.084 or 0.085 m for the same robot) is
done in *physical* terms: the calibrated metres per tick and effective wheel base are kept
and re-expressed as corrections of the other experiment's nominal values.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from odomkit import validate
from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.umbmark import UmbmarkResult, apply_corrections, umbmark
from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive
from odomkit.track import dead_reckon_log

__all__ = [
    "e_max_syst_of_runs", "return_errors_from_runs", "run_direction", "square_table", "SquareRow",
    "transfer", "umbmark_from_runs", "UmbmarkFromRuns"
]


def run_direction(log: OdometryLog) -> str:
    """``"ccw"`` or ``"cw"`` from the sign of the ground-truth heading change of a run."""
    if log.ground_truth is None:
        raise InputError("run has no ground truth; its direction cannot be told", source=log.source)
    turn = float(log.ground_truth[-1, 2] - log.ground_truth[0, 2])
    if abs(turn) < 0.5 * np.pi:
        raise InputError(f"ground-truth heading changes by only {turn:.3f} rad; "
                         "not a UMBmark square (expected about ±2π)", source=log.source)
    return "ccw" if turn > 0 else "cw"


def _robots(runs: Sequence[OdometryLog], robot: DiffDrive | Sequence[DiffDrive],
            allow_mixed: bool) -> list[DiffDrive]:
    robots = [robot] * len(runs) if isinstance(robot, DiffDrive) else list(robot)
    if len(robots) != len(runs):
        raise ModelError(f"got {len(robots)} robots for {len(runs)} runs; give one, or one per run")
    for r in robots:
        if not isinstance(r, DiffDrive):
            raise ModelError(f"UMBmark needs a DiffDrive robot, got {type(r).__name__}")
    nominal = {(r.wheel_base, r.m_per_tick_left, r.m_per_tick_right) for r in robots}
    if len(nominal) > 1:
        msg = ("runs come from experiments with different nominal parameters "
               f"(wheel_base, m_per_tick_left, m_per_tick_right) = {sorted(nominal)}")
        if not allow_mixed:
            raise ModelError(msg + "; calibrate each experiment separately or pass allow_mixed=True")
        warnings.warn(msg + "; each run is dead-reckoned with its own robot and UMBmark uses the "
                      "mean wheel base", stacklevel=3)
    return robots


def return_errors_from_runs(
    runs: Sequence[OdometryLog],
    robot: DiffDrive | Sequence[DiffDrive],
    *,
    allow_mixed: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """UMBmark return position errors of logged square runs.

    Parameters
    ----------
    runs : sequence of OdometryLog
        Square runs with ground truth (any order, both directions).
    robot : DiffDrive or sequence of DiffDrive (one per run)
        The parameters the odometry uses.
    allow_mixed : bool
        Accept runs whose robots have different nominal parameters (with a warning).

    Returns
    -------
    errors_cw, errors_ccw : ndarray, shape (n, 2) and (m, 2)
        ε = ground-truth end − odometry end position [m], Borenstein–Feng eq. (3.1).

    Examples
    --------
    >>> from odomkit.integrate import dead_reckon
    >>> a = np.r_[0, np.full(100, np.pi / 200)]           # spin 2π CCW on the spot
    >>> gt = dead_reckon(np.zeros(100), np.full(100, 2 * np.pi / 100))
    >>> gt[-1, :2] = [0.01, -0.02]                         # but truth ends 1 cm, −2 cm away
    >>> log = OdometryLog(np.arange(101.0), {"dist_left": -a, "dist_right": a}, gt)
    >>> cw, ccw = return_errors_from_runs([log], DiffDrive(0.5))
    >>> cw.shape, np.round(ccw, 6).tolist()
    ((0, 2), [[0.01, -0.02]])
    """
    robots = _robots(runs, robot, allow_mixed)
    cw: list[NDArray[np.float64]] = []
    ccw: list[NDArray[np.float64]] = []
    for log, rob in zip(runs, robots, strict=True):
        direction = run_direction(log)
        assert log.ground_truth is not None
        end = dead_reckon_log(log, rob).poses[-1]
        err = log.ground_truth[-1, :2] - end[:2]  # Borenstein–Feng eq. (3.1)
        # Into the start frame (start at the origin heading +x), where UMBmark's eq. 4.17–4.24
        # hold; a no-op for OptiOdom, whose ground truth starts at (0, 0, 0).
        c, s = np.cos(log.ground_truth[0, 2]), np.sin(log.ground_truth[0, 2])
        err = np.array([c * err[0] + s * err[1], -s * err[0] + c * err[1]])
        (ccw if direction == "ccw" else cw).append(err)
    return np.array(cw).reshape(-1, 2), np.array(ccw).reshape(-1, 2)


def e_max_syst_of_runs(runs: Sequence[OdometryLog], robot: DiffDrive | Sequence[DiffDrive], *,
                       allow_mixed: bool = False) -> float:
    """E_max,syst (Borenstein–Feng eq. 3.2–3.4) of logged runs dead-reckoned with ``robot``;
    needs at least one run in each direction [m]."""
    cw, ccw = return_errors_from_runs(runs, robot, allow_mixed=allow_mixed)
    _need_both(cw, ccw)
    return float(max(np.hypot(*cw.mean(axis=0)), np.hypot(*ccw.mean(axis=0))))


def _need_both(cw: NDArray[np.float64], ccw: NDArray[np.float64]) -> None:
    if len(cw) == 0 or len(ccw) == 0:
        missing = "clockwise" if len(cw) == 0 else "counter-clockwise"
        raise InputError(f"UMBmark needs runs in both directions; no {missing} run was given "
                         f"({len(cw)} CW, {len(ccw)} CCW)")


@dataclass(frozen=True)
class UmbmarkFromRuns:
    """:func:`umbmark_from_runs` result: the UMBmark analysis, the corrected robot (one per
    run when the runs had different robots) and E_max,syst before and after [m]."""

    result: UmbmarkResult
    robots: tuple[DiffDrive, ...]
    e_max_syst_before: float
    e_max_syst_after: float

    @property
    def robot(self) -> DiffDrive:
        """The corrected robot (the first one with mixed runs)."""
        return self.robots[0]

    def to_dict(self) -> dict[str, Any]:
        out = self.result.to_dict()
        out.update(e_max_syst_before=self.e_max_syst_before, e_max_syst_after=self.e_max_syst_after)
        return out


def umbmark_from_runs(
    runs: Sequence[OdometryLog],
    robot: DiffDrive | Sequence[DiffDrive],
    side: float,
    *,
    allow_mixed: bool = False,
    **kwargs: Any,
) -> UmbmarkFromRuns:
    """UMBmark (Borenstein–Feng) from logged square runs, and the E_max,syst the corrected
    parameters give on the same runs.

    Parameters
    ----------
    runs : sequence of OdometryLog, both directions
    robot : DiffDrive or one per run
    side : float
        Square side L [m].
    allow_mixed : bool
        See :func:`return_errors_from_runs`.
    **kwargs : passed to :func:`odomkit.calibrate.umbmark.umbmark` (e.g. ``variant``).
    """
    validate.positive(side, "side", unit="m")
    robots = _robots(runs, robot, allow_mixed)
    cw, ccw = return_errors_from_runs(runs, robots, allow_mixed=allow_mixed)
    _need_both(cw, ccw)
    b = float(np.mean([r.effective_wheel_base for r in robots]))
    res = umbmark(cw, ccw, side, b, **kwargs)
    corrected = [apply_corrections(r, res) for r in robots]
    after = e_max_syst_of_runs(runs, corrected, allow_mixed=True)
    before = float(max(np.hypot(*cw.mean(axis=0)), np.hypot(*ccw.mean(axis=0))))
    return UmbmarkFromRuns(res, tuple(corrected), before, after)


def transfer(calibrated: DiffDrive, nominal: DiffDrive) -> DiffDrive:
    """``nominal`` with the physical parameters of ``calibrated`` (metres per tick of each
    wheel, effective wheel base) expressed as its corrections.

    Examples
    --------
    >>> r = transfer(DiffDrive(0.2, 1e-4, 1e-4, 1.01, 0.99, 1.05), DiffDrive(0.21, 1e-4, 1e-4))
    >>> round(r.c_wheel_base, 12), round(r.effective_wheel_base, 12)   # 0.2·1.05 = 0.21·1
    (1.0, 0.21)
    """
    return replace(nominal, c_left=calibrated.scale_left / nominal.m_per_tick_left,
                   c_right=calibrated.scale_right / nominal.m_per_tick_right,
                   c_wheel_base=calibrated.effective_wheel_base / nominal.wheel_base)


@dataclass(frozen=True)
class SquareRow:
    """One experiment of the OptiOdom square table; E_max,syst values in metres.

    ``out_umbmark``/``out_exact`` are means over the calibrations made on every *other*
    experiment with the same square side (NaN when there is none)."""

    experiment: str
    side: float
    n_cw: int
    n_ccw: int
    before: float
    in_umbmark: float
    in_exact: float
    in_trajectory: float
    out_umbmark: float
    out_exact: float
    n_out: int


def square_table(experiments: Sequence[Any], **exact_kwargs: Any) -> list[SquareRow]:
    """E_max,syst of every OptiOdom ``diff/square`` experiment: before calibration, after
    UMBmark and after the exact calibration (endpoints), in sample and out of sample.

    Parameters
    ----------
    experiments : sequence of experiments
        Each with ``.metadata`` (``experiment``, ``side``, ``robot()``) and ``.runs``
        (logs with ground truth), e.g. :class:`odomkit.io.optiodom.OptiOdomExperiment`;
        :func:`odomkit.workflows.calibration.optiodom_square_table` reads them from disk.
    **exact_kwargs : passed to :func:`odomkit.calibrate.exact.calibrate_exact`
        for the endpoint fit (default: positions only).

    Returns
    -------
    list of SquareRow, one per experiment, in the order given.
    """
    exps = list(experiments)
    cal: dict[str, tuple[DiffDrive, DiffDrive]] = {}
    traj: dict[str, DiffDrive] = {}
    for ex in exps:
        nominal = ex.metadata.robot()
        um = umbmark_from_runs(ex.runs, nominal, ex.metadata.side).robot
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exact = cast(DiffDrive, calibrate_exact(ex.runs, nominal, "endpoints", **exact_kwargs).robot)
            traj[ex.metadata.experiment] = cast(
                DiffDrive, calibrate_exact(ex.runs, nominal, "trajectory").robot)
        cal[ex.metadata.experiment] = (um, exact)
    rows = []
    for ex in exps:
        meta = ex.metadata
        nominal = meta.robot()
        cw, ccw = return_errors_from_runs(ex.runs, nominal)
        um, exact = cal[meta.experiment]
        others = [o for o in exps if o.metadata.side == meta.side
                  and o.metadata.experiment != meta.experiment]
        out_u = [e_max_syst_of_runs(ex.runs, transfer(cal[o.metadata.experiment][0], nominal))
                 for o in others]
        out_e = [e_max_syst_of_runs(ex.runs, transfer(cal[o.metadata.experiment][1], nominal))
                 for o in others]
        rows.append(SquareRow(
            experiment=meta.experiment, side=float(meta.side), n_cw=len(cw), n_ccw=len(ccw),
            before=e_max_syst_of_runs(ex.runs, nominal),
            in_umbmark=e_max_syst_of_runs(ex.runs, um), in_exact=e_max_syst_of_runs(ex.runs, exact),
            in_trajectory=e_max_syst_of_runs(ex.runs, traj[meta.experiment]),
            out_umbmark=float(np.mean(out_u)) if out_u else float("nan"),
            out_exact=float(np.mean(out_e)) if out_e else float("nan"), n_out=len(others),
        ))
    return rows
