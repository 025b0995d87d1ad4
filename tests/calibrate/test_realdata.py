"""UMBmark from logs, and the OptiOdom square-path acceptance comparison."""

from __future__ import annotations

import importlib.util
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from odomkit.calibrate.realdata import (
    e_max_syst_of_runs,
    return_errors_from_runs,
    run_direction,
    transfer,
    umbmark_from_runs,
)
from odomkit.calibrate.umbmark import umbmark
from odomkit.calibrate.virtual import (
    SystematicErrors,
    run_virtual_umbmark,
    square_wheel_steps,
    true_robot,
)
from odomkit.errors import InputError, ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_steps
from odomkit.log import OdometryLog
from odomkit.robot import DiffDrive
from odomkit.workflows.calibration import optiodom_square_table

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def square_table_markdown(rows):
    """The markdown table of ``benchmarks/calibration_table.py`` (its only printer)."""
    spec = importlib.util.spec_from_file_location("calibration_table",
                                                  BENCHMARKS / "calibration_table.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.square_table_markdown(rows)


NOMINAL = DiffDrive(wheel_base=0.34, m_per_tick_left=1e-4, m_per_tick_right=1e-4)


def square_logs(errors: SystematicErrors, believed: DiffDrive, side: float, n: int):
    """Noise-free logs of the virtual UMBmark robot (see test_exact.square_logs)."""
    truth = true_robot(errors, believed)
    logs = []
    for direction in ("cw", "ccw"):
        bel_l, bel_r = square_wheel_steps(believed, side, direction, 0.05)
        ticks_l, ticks_r = bel_l / believed.scale_left, bel_r / believed.scale_right
        gt = dead_reckon(*diff_body_steps(ticks_l * truth.m_per_tick_left,
                                          ticks_r * truth.m_per_tick_right, truth.wheel_base))
        ch = {"ticks_left": np.r_[0.0, ticks_l], "ticks_right": np.r_[0.0, ticks_r]}
        logs += [OdometryLog(0.05 * np.arange(gt.shape[0]), ch, gt)] * n
    return logs


def test_return_errors_match_the_virtual_umbmark():
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    logs = square_logs(errors, NOMINAL, 4.0, 2)
    cw, ccw = return_errors_from_runs(logs[::-1], NOMINAL)  # order must not matter
    virt = run_virtual_umbmark(errors, NOMINAL, 4.0, 2, step=0.05)
    np.testing.assert_allclose(cw, virt.errors_cw, atol=1e-12)
    np.testing.assert_allclose(ccw, virt.errors_ccw, atol=1e-12)
    assert [run_direction(log) for log in logs] == ["cw", "cw", "ccw", "ccw"]


def test_return_errors_are_in_the_start_frame():
    # The same runs started elsewhere, heading 2 rad: the errors must not change.
    from odomkit.track import dead_reckon_log

    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    logs = square_logs(errors, NOMINAL, 4.0, 1)
    pose0 = np.array([3.0, -1.0, 2.0])
    moved = []
    for log in logs:
        # Ground truth of the true robot started at pose0 (rigid motion of the track).
        c, s = np.cos(pose0[2]), np.sin(pose0[2])
        gt = log.ground_truth
        g = np.column_stack([pose0[0] + c * gt[:, 0] - s * gt[:, 1],
                             pose0[1] + s * gt[:, 0] + c * gt[:, 1], gt[:, 2] + pose0[2]])
        moved.append(replace(log, ground_truth=g))
    assert dead_reckon_log(moved[0], NOMINAL).poses[0] == pytest.approx(pose0)
    for a, b in zip(return_errors_from_runs(logs, NOMINAL), return_errors_from_runs(moved, NOMINAL),
                    strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_umbmark_from_runs_equals_umbmark_on_the_errors_and_reports_after():
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    logs = square_logs(errors, NOMINAL, 4.0, 1)
    res = umbmark_from_runs(logs, NOMINAL, 4.0)
    virt = run_virtual_umbmark(errors, NOMINAL, 4.0, 1, step=0.05)
    ref = umbmark(virt.errors_cw, virt.errors_ccw, 4.0, NOMINAL.wheel_base)
    assert res.result.E_d == pytest.approx(ref.E_d, rel=1e-12)
    assert res.result.E_b == pytest.approx(ref.E_b, rel=1e-12)
    assert res.e_max_syst_before == pytest.approx(ref.e_max_syst, rel=1e-12)
    # "after" re-dead-reckons the same logs with the corrected robot (an independent check
    # of the correction: the virtual robot re-driven gives its own number).
    assert res.e_max_syst_after < 0.02 * res.e_max_syst_before
    assert res.to_dict()["e_max_syst_after"] == res.e_max_syst_after


def test_bad_input_is_refused_or_warned():
    errors = SystematicErrors(E_d=1.002, E_b=1.01)
    logs = square_logs(errors, NOMINAL, 4.0, 1)
    with pytest.raises(ModelError, match="side"):
        umbmark_from_runs(logs, NOMINAL, 0.0)
    with pytest.raises(InputError, match="both directions"):
        umbmark_from_runs(logs[:1], NOMINAL, 4.0)
    other = replace(NOMINAL, wheel_base=0.35)
    with pytest.raises(ModelError, match="different nominal"):
        umbmark_from_runs(logs, [NOMINAL, other], 4.0)
    with pytest.warns(UserWarning, match="different nominal"):
        umbmark_from_runs(logs, [NOMINAL, other], 4.0, allow_mixed=True)
    straight = replace(logs[0], ground_truth=np.zeros_like(logs[0].ground_truth))
    with pytest.raises(InputError, match="not a UMBmark square"):
        return_errors_from_runs([straight], NOMINAL)
    # Different corrections on the same nominal robot are not "mixed".
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return_errors_from_runs(logs, [NOMINAL, replace(NOMINAL, c_left=1.01)])


def test_transfer_keeps_the_physical_parameters():
    cal = DiffDrive(0.2, 9.43e-5, 9.43e-5, 0.998, 1.001, 1.004)
    other = DiffDrive(0.205, 9.55e-5, 9.55e-5)
    moved = transfer(cal, other)
    assert moved.effective_wheel_base == pytest.approx(cal.effective_wheel_base, rel=1e-15)
    assert moved.scale_left == pytest.approx(cal.scale_left, rel=1e-15)
    assert moved.scale_right == pytest.approx(cal.scale_right, rel=1e-15)


def _independent_e_max(folder) -> float:
    """E_max,syst of one OptiOdom experiment from the raw CSV with a plain loop (midpoint
    arcs), as a check on the library's reader + dead reckoning + eq. (3.1)-(3.4)."""
    meta = {}
    for line in next(folder.glob("*_metadata.csv")).read_text().splitlines():
        cells = [c for c in line.split(",") if c]
        if cells:
            meta[cells[0]] = cells[1:]
    b = float(meta["Li"][0])
    tick = np.pi * float(meta["Di"][0]) / (float(meta["ngear"][0]) * float(meta["encRes"][0]))
    ends = {"cw": [], "ccw": []}
    for path in sorted(folder.glob("*_run-*.csv")):
        data = np.loadtxt(path, delimiter=",")
        x = y = th = 0.0
        for n_right, n_left in data[1:, 4:6]:
            dr, dl = n_right * tick, n_left * tick
            d, dth = 0.5 * (dr + dl), (dr - dl) / b
            c = 1.0 if dth == 0 else np.sin(dth / 2) / (dth / 2)
            x += d * c * np.cos(th + dth / 2)
            y += d * c * np.sin(th + dth / 2)
            th += dth
        ends["ccw" if data[-1, 3] > 0 else "cw"].append(data[-1, 1:3] - [x, y])
    return max(np.hypot(*np.mean(ends[k], axis=0)) for k in ends)


@pytest.mark.slow
def test_optiodom_square_table_exact_beats_umbmark_out_of_sample(data_dir):
    folder = data_dir / "optiodom" / "diff" / "square"
    if not folder.is_dir():
        pytest.skip(f"no OptiOdom square experiments under {data_dir}")
    rows = optiodom_square_table(data_dir)
    assert len(rows) == 8
    first = rows[0]
    assert first.before == pytest.approx(_independent_e_max(folder / first.experiment), rel=1e-9)
    for r in rows:
        # Every calibration improves the experiment it was made on by far.
        assert r.in_umbmark < 0.2 * r.before and r.in_exact < 0.2 * r.before
        assert r.out_umbmark < 0.3 * r.before and r.out_exact < 0.3 * r.before
    for side in (0.75, 1.7):
        sel = [r for r in rows if r.side == side]
        # The acceptance criterion: the exact calibration does at least as well as UMBmark
        # out of sample (mean over experiments of the same robot and square size). In
        # sample, the endpoint least squares minimises what E_max,syst measures.
        assert np.mean([r.out_exact for r in sel]) <= np.mean([r.out_umbmark for r in sel])
        assert np.mean([r.in_exact for r in sel]) <= np.mean([r.in_umbmark for r in sel])
    md = square_table_markdown(rows)
    assert md.count("\n") == 2 + len(rows) + 2


@pytest.mark.slow
def test_trajectory_fit_finds_the_same_physical_robot_in_every_experiment(data_dir):
    # The 0.75 m experiments list different nominal values (Li 0.2 or 0.205 m, Di 0.084 or
    # 0.085 m) for one physical robot. The trajectory fit, which observes the scale, must
    # find the same effective wheel base and metres per tick whatever the metadata say.
    from odomkit.calibrate.exact import calibrate_exact
    from odomkit.io.optiodom import read_experiment

    folder = data_dir / "optiodom" / "diff" / "square"
    if not folder.is_dir():
        pytest.skip(f"no OptiOdom square experiments under {data_dir}")
    fits = []
    for name in ("230620202042", "230620202144", "230620202258", "230620202317"):
        ex = read_experiment(folder / name)
        fits.append(calibrate_exact(ex.runs, ex.metadata.robot(), "trajectory", every=2).robot)
    bases = np.array([r.effective_wheel_base for r in fits])
    ticks = np.array([[r.scale_left, r.scale_right] for r in fits])
    assert np.ptp(bases) / bases.mean() < 2e-3  # vs 2.5 % spread of the metadata
    assert np.all(np.ptp(ticks, axis=0) / ticks.mean(axis=0) < 3e-3)  # vs 1.2 % of the Di
    # Consistency with the square endpoints: E_max,syst of each experiment with the
    # trajectory fit stays well below the uncalibrated one.
    for name, robot in zip(("230620202042", "230620202144"), fits, strict=False):
        ex = read_experiment(folder / name)
        assert e_max_syst_of_runs(ex.runs, robot) < 0.5 * e_max_syst_of_runs(ex.runs, ex.metadata.robot())


@pytest.mark.slow
def test_tricycle_trajectory_fit_is_consistent_across_experiments(data_dir):
    # OptiOdom tricycle squares (7 experiments, CW + CCW each): the fitted steering offset
    # and L describe one vehicle, so they must agree between experiments, and a
    # calibration made on one experiment must cut the end-position error of the others.
    from odomkit.calibrate.exact import calibrate_exact
    from odomkit.io.optiodom import read_experiment
    from odomkit.track import dead_reckon_log

    folder = data_dir / "optiodom" / "tricyc" / "square"
    if not folder.is_dir():
        pytest.skip(f"no OptiOdom tricycle squares under {data_dir}")
    exps = [read_experiment(p) for p in sorted(folder.iterdir()) if p.is_dir()]
    fits = [calibrate_exact(ex.runs, ex.metadata.robot(), "trajectory", every=2) for ex in exps]
    values = np.array([f.values for f in fits])  # c_scale, steering_offset, wheel_to_axle
    assert np.ptp(values[:, 1]) < 0.004  # rad
    assert np.ptp(values[:, 2]) < 0.005  # m

    def end_error(runs, robot):
        return np.mean([np.hypot(*(r.ground_truth[-1, :2] - dead_reckon_log(r, robot).poses[-1, :2]))
                        for r in runs])

    before = np.mean([end_error(ex.runs, ex.metadata.robot()) for ex in exps])
    after = np.mean([end_error(ex.runs, fits[(i + 1) % len(exps)].robot) for i, ex in enumerate(exps)])
    assert after < 0.3 * before
