"""``odomkit umbmark``: Borenstein–Feng calibration from return position errors.

::

    odomkit umbmark ERRORS.csv --side 4 --wheel-base 0.34 [--json]
    odomkit umbmark --runs RUN.csv [RUN.csv ...] --robot ROBOT.toml --side 0.75 [--json]

ERRORS.csv has a header naming the columns ``direction,x,y`` (any order, extra columns
ignored); ``direction`` is ``cw`` or ``ccw``, x and y are the return position errors in
metres, absolute minus calculated (Borenstein–Feng eq. 3.1). Each direction needs at least
two runs (the 3·SEM rule needs a standard deviation; Borenstein–Feng used five).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from numpy.typing import NDArray

from odomkit.cli import app
from odomkit.cli.output import print_json
from odomkit.errors import InputError

REQUIRED_COLUMNS = ("direction", "x", "y")
MIN_RUNS_PER_DIRECTION = 2


def read_errors_csv(path: str | Path) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Read an UMBmark errors CSV -> (errors_cw (n, 2), errors_ccw (m, 2)) [m].

    Raises :class:`~odomkit.errors.InputError` naming the file, line and field for a
    missing file, a header without ``direction``, ``x`` or ``y``, a direction other than
    cw/ccw, a value that is not a finite number, a direction with no runs, or fewer than
    two runs in a direction.
    """
    p = Path(path)
    source = str(p)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError("file not found", source=source) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", source=source) from None
    rows = [(n, r) for n, r in enumerate(csv.reader(text.splitlines()), start=1)
            if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError("empty file; expected a header 'direction,x,y' and one row per run",
                         source=source)
    header_line, header = rows[0]
    names = [c.strip().lower() for c in header]
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise InputError(f"header {','.join(header)!r} lacks column(s) {', '.join(missing)}; "
                         "expected 'direction,x,y'", source=source, line=header_line)
    index = {c: names.index(c) for c in REQUIRED_COLUMNS}
    runs: dict[str, list[tuple[float, float]]] = {"cw": [], "ccw": []}
    for line, row in rows[1:]:
        if len(row) < len(names):
            raise InputError(f"expected {len(names)} fields, got {len(row)}", source=source,
                             line=line)
        direction = row[index["direction"]].strip().lower()
        if direction not in runs:
            raise InputError(f"field 'direction' must be 'cw' or 'ccw', got {direction!r}",
                             source=source, line=line)
        values = []
        for col in ("x", "y"):
            raw = row[index[col]].strip()
            try:
                value = float(raw)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise InputError(f"field {col!r} must be a finite number [m], got {raw!r}",
                                 source=source, line=line)
            values.append(value)
        runs[direction].append((values[0], values[1]))
    for direction, found in runs.items():
        if len(found) < MIN_RUNS_PER_DIRECTION:
            raise InputError(
                f"{len(found)} {direction} run(s); UMBmark needs at least "
                f"{MIN_RUNS_PER_DIRECTION} per direction (Borenstein–Feng used 5)",
                source=source)
    return np.array(runs["cw"]), np.array(runs["ccw"])


def _from_runs(run_paths: list[Path], robot: Path | None, side: float) -> dict[str, Any]:
    """The logs-with-ground-truth form (:mod:`odomkit.workflows.calibration`)."""
    if robot is None:
        raise InputError("--runs needs --robot ROBOT.toml (the parameters the odometry used)")
    from odomkit.workflows.calibration import umbmark_from_files

    return umbmark_from_files(run_paths, robot, side).to_dict()


def _print_text(out: dict[str, Any]) -> None:
    mm = 1000.0
    print(f"centre of gravity CW : x = {out['cg']['cw'][0] * mm:9.2f} mm  "
          f"y = {out['cg']['cw'][1] * mm:9.2f} mm")
    print(f"centre of gravity CCW: x = {out['cg']['ccw'][0] * mm:9.2f} mm  "
          f"y = {out['cg']['ccw'][1] * mm:9.2f} mm")
    print(f"E_max,syst           : {out['e_max_syst'] * mm:9.2f} mm")
    print(f"alpha (Type A)       : {math.degrees(out['alpha']):9.4f} deg  "
          f"(x: {math.degrees(out['alpha_x']):.4f}, y: {math.degrees(out['alpha_y']):.4f})")
    print(f"beta  (Type B)       : {math.degrees(out['beta']):9.4f} deg  "
          f"(x: {math.degrees(out['beta_x']):.4f}, y: {math.degrees(out['beta_y']):.4f})")
    radius = out["radius"]
    print(f"radius R             : {'infinite' if radius is None else f'{radius:.3f} m'}")
    print(f"E_d = D_R/D_L        : {out['E_d']:.6f}")
    print(f"E_b = b_act/b_nom    : {out['E_b']:.6f}")
    print(f"c_left, c_right      : {out['c_left']:.6f}, {out['c_right']:.6f}")
    print(f"corrected wheel base : {out['wheel_base']:.6f} m "
          f"(was {out['wheel_base_nominal']:.6f} m)")
    sem = out["sem"]
    print(f"SEM CW, CCW          : {sem['cw'] * mm:.2f} mm, {sem['ccw'] * mm:.2f} mm")
    advised = out["second_compensation_advised"]
    verdict = {True: "advised", False: "not needed", None: "unknown (< 2 runs)"}[advised]
    print(f"(further) compensation: {verdict} (3·SEM rule)")
    if "e_max_syst_after" in out:
        print(f"E_max,syst corrected : {out['e_max_syst_after'] * mm:9.2f} mm (same runs)")
    ck = out.get("chong_kleeman")
    if ck:
        print(f"Chong–Kleeman c_b    : {ck['c_b']:.6f} (half the needed correction; "
              "use E_b)")


@app.command("umbmark")
def umbmark_command(
    errors_csv: Annotated[list[Path] | None, typer.Argument(
        help="CSV with columns direction,x,y (cw/ccw, return errors in metres).")] = None,
    side: Annotated[float, typer.Option(
        "--side", help="Side L of the square in metres (required).",
        show_default=False)] = math.nan,
    wheel_base: Annotated[float | None, typer.Option(
        "--wheel-base",
        help="Wheel base the odometry used, metres (default: from --robot).")] = None,
    runs: Annotated[list[Path] | None, typer.Option(
        "--runs", help="Logs with ground truth (calibrate from logs).")] = None,
    robot: Annotated[Path | None, typer.Option("--robot", help="Robot file (TOML).")] = None,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """UMBmark (Borenstein–Feng): E_max,syst and the corrections E_d, E_b, c_L, c_R, b."""
    positional = list(errors_csv or [])
    if not (math.isfinite(side) and side > 0):
        raise InputError(f"--side must be a positive length in metres, got {side!r} "
                         "(it is required)")
    if runs:
        # `--runs a.csv b.csv` leaves b.csv as a positional argument: they are all runs.
        out = _from_runs(list(runs) + positional, robot, side)
    else:
        if len(positional) != 1:
            raise InputError(
                "give exactly one ERRORS.csv (or --runs RUN.csv ... --robot ROBOT.toml)")
        if wheel_base is None:
            if robot is None:
                raise InputError("--wheel-base (or --robot ROBOT.toml) is required")
            from odomkit.io.robotfile import read_robot
            from odomkit.robot import DiffDrive

            parsed, _ = read_robot(robot)
            if not isinstance(parsed, DiffDrive):
                raise InputError("UMBmark needs a differential-drive robot (type = \"diff\")",
                                 source=str(robot))
            wheel_base = parsed.effective_wheel_base
        if not (math.isfinite(wheel_base) and wheel_base > 0):
            raise InputError(
                f"--wheel-base must be a positive length in metres, got {wheel_base!r}")
        from odomkit.calibrate.umbmark import umbmark_summary

        errors_cw, errors_ccw = read_errors_csv(positional[0])
        out = umbmark_summary(errors_cw, errors_ccw, side, wheel_base)
    if json_out:
        print_json(out)
    else:
        _print_text(out)
