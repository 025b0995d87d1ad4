"""How honest is the covariance? The tables of docs/results/honesty.md (issue 11's targets), one command.

    .venv/bin/python benchmarks/honesty.py [--data ../shared/data] [--mrclam DIR] [--victoria DIR]
        [--part optiodom snowhite gps speed car mrclam victoria]

(a) OptiOdom, differential and tricycle. The experiments of each kind (diff: square,
    circular, ivanjko, free; tricycle: square, circular, free) are sorted by name; every
    other one (the 1st, 3rd, ...) is the *fit half*, the rest is *held out*. On the fit half
    the robot is calibrated (exact least squares on the whole OptiTrack trajectory; one
    robot per platform: every diff metadata file describes the same physical robot, docs/results/
    real-data.md) and the noise is fitted as ``odomkit fit-noise --window 10s
    --window 30s`` does: maximum likelihood on the windows of both lengths at once,
    trimmed (window ends outside the fit's 99.9 % ellipse left out and counted). That ONE
    fitted model is scored on the held-out half in windows of 10 s and of 30 s, each
    restarted from the OptiTrack pose: the fraction of window ends inside the predicted
    50/90/95/99 % position ellipses (with the 95 % Clopper–Pearson interval of the 95 %
    figure: a fraction of n ends is itself uncertain) and the mean position NEES with its
    95 % chi-square bounds. Target (issue 11): 95 % coverage in [0.88, 0.99] and 50 % in
    [0.40, 0.80] at both window lengths.
(b) Snowhite (Halmstad, no licence: read from --data, numbers only): calibrated and fitted
    on the first half of the log (101 s), scored on the second.
(c) GPS-like truth: Snowhite calibrated on its first half from position-only fixes (1 Hz,
    own clock, noise σ = 5, 20, 50 cm), scored on the second half against the full truth.
(d) Speed: ``odomkit fit-noise`` on all 203 OptiOdom runs (two robot files), wall time.
(e) A simulated car against a late, noisy 1 Hz GPS (``--part car``; no data needed):
    calibrate, fit-noise and evaluate through the CLI over six seeds.
(f) Five commanded-velocity robots of one type against motion capture (``--part mrclam
    --mrclam DIR``; the UTIAS MRCLAM datasets, not shipped: DIR holds MRCLAM_Dataset6/,
    MRCLAM_Dataset7/, ... each with Robot1..5_Odometry.dat and Robot1..5_Groundtruth.dat):
    ``odomkit fit-noise --window 10s --window 30s`` on robots 1 and 2, ``odomkit evaluate
    --window`` on robots 3, 4 and 5 with that one fitted robot file, through the CLI.
(g) A real car against its GPS (``--part victoria --victoria DIR``; the Victoria Park
    drive of Guivant and Nebot, not shipped: DIR holds aa3_gpsx.mat and aa3_dr.mat, or
    the VictoriaParkSinSincronizar.mat of github.com/ezamorag/EKFSLAM_for_Victoria_Park_Benchmark):
    25 min of rear-left wheel speed and steering angle at 40 Hz against a 5 Hz GPS with
    gaps and jumps. Calibrated (``--window 60s``) and noise-fitted (10 s and 30 s windows)
    on the first half, scored on the second: its whole track's error with the nominal and
    the calibrated robot, and the windows' coverage.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import beta, chi2

from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.fit_noise import DEFAULT_TRIM, fit_noise, noise_parameters
from odomkit.evaluate import coverage, nees, nees_summary
from odomkit.io.halmstad import read_snowhite
from odomkit.io.optiodom import read_experiment
from odomkit.io.robotfile import read_robot
from odomkit.log import OdometryLog
from odomkit.noise import LateralSlipNoise, ParameterUncertainty, SpeedNoise, TricycleNoise, WheelNoise
from odomkit.truth import truth_from_log
from odomkit.window_errors import log_window_basis
from odomkit.windows import parse_window

REPO = Path(__file__).resolve().parents[1]
LEVELS = ("0.5", "0.9", "0.95", "0.99")
KINDS = {"diff": ("square", "circular", "ivanjko", "free"), "tricyc": ("square", "circular", "free")}
WINDOWS = ("10s", "30s")
BOTH = "10s+30s"  # one fit on the windows of both lengths
TAIL = float(chi2.ppf(0.999, 2))  # NEES beyond the 99.9 % ellipse


def split(root: Path, platform: str) -> tuple[list[tuple[str, Path]], list[tuple[str, Path]]]:
    """(kind, folder) of the fit half and of the held-out half."""
    fit, held = [], []
    for kind in KINDS[platform]:
        for i, folder in enumerate(sorted((root / platform / kind).iterdir())):
            (fit if i % 2 == 0 else held).append((kind, folder))
    return fit, held


def runs_of(folders):
    return [(kind, log) for kind, folder in folders for log in read_experiment(folder).runs]


def bases(runs, robot, models, window, truth_noise=False):
    """(kind, WindowBasis, name) of every run with at least one window of length ``window``."""
    return merged(runs, robot, models, (window,), truth_noise)


def merged(runs, robot, models, windows, truth_noise=False):
    """(kind, one WindowBasis of every length, name) per run: ``fit-noise --window A --window B``
    (``truth_noise``: with the truth's own noise as parameters, as fit-noise fits it)."""
    specs = [parse_window(w) for w in windows]
    out = []
    for kind, log in runs:
        basis, _ = log_window_basis(log, robot, models, truth_from_log(log), specs, truth_columns=truth_noise)
        if basis is not None:
            out.append((kind, basis, Path(log.source).stem))
    return out


def clopper_pearson(inside, n, level=0.95):
    """Exact binomial interval of a coverage fraction."""
    a = (1 - level) / 2
    lo = 0.0 if inside == 0 else float(beta.ppf(a, inside, n - inside + 1))
    hi = 1.0 if inside == n else float(beta.ppf(1 - a, inside + 1, n - inside))
    return lo, hi


def score(kind_bases, v, kinds=None):
    sel = [b for k, b, _ in kind_bases if kinds is None or k in kinds]
    err = np.concatenate([b.error[:, :2] for b in sel])
    cov = np.concatenate([b.covariance(v)[:, :2, :2] for b in sel])
    n = nees_summary(err, cov)
    q = nees(err, cov)
    # Observed RMS over predicted RMS (1 if the size is right) of the position and heading.
    th = np.concatenate([b.error[:, 2] for b in sel])
    var_th = np.concatenate([b.covariance(v)[:, 2, 2] for b in sel])
    # The ellipse's shape: mean squared error along its long and its short axis, each over
    # the variance predicted there (1 and 1 if honest).
    lam, vec = np.linalg.eigh(cov)
    along = np.einsum("wa,wab->wb", err, vec) ** 2 / lam
    return {"n": err.shape[0], "coverage": coverage(err, cov), "nees": n["mean"], "bounds": n["bounds"],
            "long": float(along[:, 1].mean()), "short": float(along[:, 0].mean()),
            "median": n["median"], "tail": float(np.mean(q > TAIL)),
            "position_ratio": float(np.sqrt(np.sum(err**2) / np.sum(np.trace(cov, axis1=1, axis2=2)))),
            "heading_ratio": float(np.sqrt(np.nansum(th**2) / np.sum(var_th[np.isfinite(th)])))}


def meets(s):
    """Issue 11's targets at one window length."""
    return 0.88 <= s["coverage"]["0.95"] <= 0.99 and 0.40 <= s["coverage"]["0.5"] <= 0.80


def cell(s):
    c = s["coverage"]
    lo, hi = clopper_pearson(round(c["0.95"] * s["n"]), s["n"])
    return (f"{s['n']} | " + " / ".join(f"{c[k]:.2f}" for k in LEVELS) + f" ({lo:.2f}–{hi:.2f}) | "
            f"{s['nees']:.2f} ({s['bounds'][0]:.2f}–{s['bounds'][1]:.2f})")


def values(parameters):
    return ", ".join(f"{k} {v:.3g}" for k, v in parameters.items())


def table(title, variants, fit_runs, held_runs, robot, breakdown=True):
    """Fit every variant in every fit window, score it held out; print a Markdown table."""
    print(f"\n{title}\n")
    print("| model | fitted on | fitted values | 10 s ends | 10 s: inside 50 / 90 / 95 / 99 % (95 % CI "
          "of the 95 % figure) | NEES (bounds) | 30 s ends | 30 s: inside 50 / 90 / 95 / 99 % (CI) "
          "| NEES (bounds) | targets met at 10 s / 30 s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    found, warned = {}, []
    for name, models, kinds, fixed, fit_windows, trim, truth_noise in variants:
        held = {w: bases(held_runs, robot, models, w, truth_noise) for w in WINDOWS}
        for fw in fit_windows:
            if kinds is None:  # the robot file's guess, not fitted
                params = noise_parameters(models, robot, ())
                v = np.array([models[p.model].variance_parameters()[p.name] for p in params])
                shown, notes, seconds = values({p.key: p.to_value(x) for p, x in zip(params, v, strict=True)
                                                if x > 0}), [], 0.0
            else:
                fb = (merged(fit_runs, robot, models, WINDOWS, truth_noise) if fw == BOTH
                      else bases(fit_runs, robot, models, fw, truth_noise))
                started = time.perf_counter()
                fit = fit_noise([b for _, b, _ in fb], models, robot, kinds=kinds, fixed=fixed,
                                log_names=[n for _, _, n in fb], trim=trim)
                seconds = time.perf_counter() - started
                v = np.array(list(fit.variances.values()))
                shown, notes = values(fit.parameters), fit.warnings
            s = {w: score(held[w], v) for w in WINDOWS}
            found[name, fw] = (s, held, v)
            label = ("10 s and 30 s windows" if fw == BOTH else fw[:-1] + " s windows") if kinds else "—"
            print(f"| {name} | {label} | {shown} | {cell(s['10s'])} | "
                  f"{cell(s['30s'])} | {' / '.join('yes' if meets(s[w]) else 'no' for w in WINDOWS)} |")
            warned += [f"- {name}, {fw} ({seconds:.1f} s): {note}" for note in notes]
    if warned:
        print("\nWarnings of the fits:\n")
        print("\n".join(warned))
    if breakdown:
        print("\nThe held-out errors themselves (no model): RMS over the window ends\n")
        print("| window | kind | ends | median travel [m] | RMS position error [mm] "
              "| RMS heading error [mrad] |")
        print("|---|---|---|---|---|---|")
        _, held, _ = next(iter(found.values()))
        for w in WINDOWS:
            for kind in sorted({k for k, _, _ in held[w]}):
                sel = [b for k, b, _ in held[w] if k == kind]
                e = np.concatenate([b.error for b in sel])
                travel = np.median([x.travel for b in sel for x in b.windows])
                print(f"| {w} | {kind} | {e.shape[0]} | {travel:.2f} | "
                      f"{1000 * np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1))):.1f} | "
                      f"{1000 * np.sqrt(np.mean(e[:, 2] ** 2)):.1f} |")
        print("\nHeld out, by kind of path, and the tails (NEES beyond the 99.9 % ellipse: 0.1 % if "
              "honest; median NEES 1.39 if honest):\n")
        print("| model, fitted on | window | kind | ends | 50 / 90 / 95 / 99 % | NEES mean | median | "
              "beyond 99.9 % | RMS observed / predicted: position, heading | e²/σ² long, short axis |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for (name, fw), (_, held, v) in found.items():
            for w in WINDOWS:
                for kind in sorted({k for k, _, _ in held[w]}):
                    t = score(held[w], v, {kind})
                    c = " / ".join(f"{t['coverage'][k]:.2f}" for k in LEVELS)
                    print(f"| {name}, {fw} | {w} | {kind} | {t['n']} | {c} | {t['nees']:.2f} | "
                          f"{t['median']:.2f} | {100 * t['tail']:.1f} % | {t['position_ratio']:.2f}, "
                          f"{t['heading_ratio']:.2f} | {t['long']:.2f}, {t['short']:.2f} |")
            for w in WINDOWS:
                t = score(held[w], v)
                print(f"| {name}, {fw} | {w} | **all** | {t['n']} | | {t['nees']:.2f} | {t['median']:.2f} | "
                      f"{100 * t['tail']:.1f} % | {t['position_ratio']:.2f}, {t['heading_ratio']:.2f} | "
                      f"{t['long']:.2f}, {t['short']:.2f} |")
    return found


def calibrate(fit_runs, nominal):
    started = time.perf_counter()
    cal = calibrate_exact([log for _, log in fit_runs], nominal, "trajectory")
    print(f"calibrated on {len(fit_runs)} runs (trajectory fit, {time.perf_counter() - started:.1f} s): "
          + ", ".join(f"{n} {v:.5g} ± {e:.2g}" for n, v, e in zip(cal.names, cal.values, cal.std_errors,
                                                                   strict=True)))
    return cal.robot


def standing(runs):
    """Fraction of the steps in which the wheels do not turn."""
    still = [np.mean(sum(np.abs(v[1:]) for k, v in log.channels.items() if k.startswith("ticks")) == 0)
             for _, log in runs]
    return float(np.mean(still))


def optiodom(root: Path) -> None:
    for platform in ("diff", "tricyc"):
        fit_folders, held_folders = split(root, platform)
        fit_runs, held_runs = runs_of(fit_folders), runs_of(held_folders)
        print(f"\n## OptiOdom {platform}: fit half {len(fit_folders)} experiments / {len(fit_runs)} runs, "
              f"held out {len(held_folders)} / {len(held_runs)}")
        if platform == "diff":
            nominal, guess = read_robot(REPO / "src/odomkit/data/optiodom_diff.toml")
            white = WheelNoise(0.0, 0.0)
        else:
            nominal, guess = read_experiment(fit_folders[0][1]).metadata.robot(), ()
            white = TricycleNoise(0.0, 0.0)
            for kind in KINDS[platform]:
                share = standing([r for r in fit_runs + held_runs if r[0] == kind])
                print(f"standing still: {100 * share:.0f} % of the {kind} steps")
        robot = calibrate(fit_runs, nominal)
        variants = []
        if guess:
            variants.append(("guessed k (robot file)", (*guess, ParameterUncertainty()), None, (), ("10s",),
                             None, False))
        variants += model_variants(white, platform)
        table(f"### {platform}", variants, fit_runs, held_runs, robot)
        # The other way round: a split is one draw; experiments differ (the fit half's squares
        # err twice as much as the held-out ones), so the same model may pass one way only.
        robot = calibrate(held_runs, nominal)
        table(f"### {platform}, the other way round: fitted on the held-out half, scored on the fit half",
              model_variants(white, platform)[-3:], held_runs, fit_runs, robot, breakdown=False)


def model_variants(white, platform="diff"):
    """The fitted variants of a table: the vehicle's own white noise alone (fitted on each
    window length, and on both), then with fit-noise's default slip (along and across the
    track for a differential drive, across for a steered one), untrimmed and trimmed, then
    with bias, then with the truth's own noise fitted too (fit-noise's defaults)."""
    bias = ParameterUncertainty()
    slip = (SpeedNoise(0.0), LateralSlipNoise(0.0)) if platform == "diff" else (LateralSlipNoise(0.0),)
    both = ("white", "bias")
    return [("white (vehicle's own)", (white, bias), ("white",), {"sigma_dt"}, (*WINDOWS, BOTH), None, False),
            ("white + slip", (white, *slip, bias), ("white",), {"sigma_dt"}, (BOTH,), None, False),
            ("white + slip, trimmed", (white, *slip, bias), ("white",), {"sigma_dt"}, (BOTH,), DEFAULT_TRIM,
             False),
            ("white + slip + bias, trimmed", (white, *slip, bias), both, {"sigma_dt"}, (BOTH,), DEFAULT_TRIM,
             False),
            ("white + slip + bias + truth noise, trimmed (fit-noise's defaults)", (white, *slip, bias), both,
             {"sigma_dt"}, (BOTH,), DEFAULT_TRIM, True)]


def snowhite(root: Path) -> None:
    log = read_snowhite(root / "halmstad-khepera-snowhite" / "snowhite.txt")
    half = len(log) // 2

    def part(a, b):
        return OdometryLog(log.t[a:b], {k: v[a:b] for k, v in log.channels.items()},
                           log.ground_truth[a:b], f"{log.source}[{a}:{b}]", log.meta)

    first, second = [("free", part(0, half + 1))], [("free", part(half, len(log)))]
    robot, guess = read_robot(REPO / "examples" / "snowhite.toml")
    print(f"\n## Snowhite: fit on rows 0–{half} ({log.t[half]:.1f} s), scored on rows {half}–{len(log) - 1}")
    robot = calibrate(first, robot)
    table("### Snowhite", [("guessed (examples/snowhite.toml)", (*guess, ParameterUncertainty()), None, (),
                            ("10s",), None, False), *model_variants(TricycleNoise(0.0, 0.0), "tricyc")],
          first, second, robot, breakdown=False)


def gps(root: Path) -> None:
    """Calibration from position-only, noisy truth on its own clock, on a real drive: Snowhite's
    motion capture degraded to a GPS (1 fix/s, clock 0.37 s off, no heading, noise σ)."""
    from odomkit.calibrate.positions import calibrate_positions
    from odomkit.track import dead_reckon_log
    from odomkit.truth import Truth

    log = read_snowhite(root / "halmstad-khepera-snowhite" / "snowhite.txt")
    half = len(log) // 2

    def part(a, b):
        return OdometryLog(log.t[a:b], {k: v[a:b] for k, v in log.channels.items()},
                           log.ground_truth[a:b], f"{log.source}[{a}:{b}]", log.meta)

    first, second = part(0, half + 1), part(half, len(log))
    nominal, _ = read_robot(REPO / "examples" / "snowhite.toml")

    def errors(robot):
        track = dead_reckon_log(second, robot, "exact", pose0=second.ground_truth[0])
        e = np.hypot(*(track.poses[:, :2] - second.ground_truth[:, :2]).T)
        return e[-1], float(np.sqrt(np.mean(e**2)))

    final0, rms0 = errors(nominal)
    print("\n## GPS-like truth: Snowhite calibrated on its first half from 1 Hz position fixes on a "
          "clock 0.37 s off, no heading; second half dead-reckoned from its true start\n")
    print(f"nominal robot: second half final error {final0:.3f} m, RMS {rms0:.3f} m\n")
    print("| truth noise σ | fitted c_scale, steering offset [rad], L [m] | final error [m] | RMS error [m] "
          "| cut (final, RMS) |")
    print("|---|---|---|---|---|")
    mocap = truth_from_log(first)
    t_gps = np.arange(mocap.t[0] + 0.37, mocap.t[-1], 1.0)
    xy = np.column_stack([np.interp(t_gps, mocap.t, mocap.xy[:, i]) for i in (0, 1)])
    for sigma in (0.05, 0.2, 0.5):
        noisy = xy + np.random.default_rng(0).normal(0.0, sigma, xy.shape)
        cal = calibrate_positions([first], [Truth(t_gps, noisy, None, sigma=sigma)], nominal)
        final, rms = errors(cal.robot)
        fitted = ", ".join(f"{v:.4g} ± {e:.2g}" for v, e in zip(cal.values, cal.std_errors, strict=True))
        cut = f"{final0 / final:.1f}×, {rms0 / rms:.1f}×"
        print(f"| {sigma:g} m | {fitted} | {final:.3f} | {rms:.3f} | {cut} |")


def speed(root: Path) -> None:
    print("\n## Speed: odomkit fit-noise on every OptiOdom run, 10 s and 30 s windows, white + bias\n")
    odomkit = str(Path(sys.executable).with_name("odomkit"))
    for platform, robot in (("diff", REPO / "src/odomkit/data/optiodom_diff.toml"),
                            ("tricyc", REPO / "examples/optiodom_tricycle.toml")):
        logs = sorted((root / platform).glob("*/*/*_run-*.csv"))
        out = Path(os.environ.get("TMPDIR", "/tmp")) / f"odomkit-honesty-{platform}.toml"
        cmd = [odomkit, "fit-noise", "--robot", str(robot), "--window", "10s", "--window", "30s",
               "--kinds", "white,bias",
               "--out", str(out), "--force"] + [a for p in logs for a in ("--log", str(p))]
        started = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        seconds = time.perf_counter() - started
        first = done.stdout.splitlines()[0] if done.stdout else done.stderr.strip()
        print(f"{platform}: {len(logs)} runs, {seconds:.1f} s wall (exit {done.returncode}): {first}")


def _odomkit_json(*args) -> dict:
    """``odomkit ARGS --json`` in a subprocess, as a user runs it: its JSON object."""
    import json

    odomkit = str(Path(sys.executable).with_name("odomkit"))
    done = subprocess.run([odomkit, *map(str, args), "--json"], capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def car(_root: Path) -> None:
    """A simulated car against a 1 Hz, 1 m GPS on a clock 0.2 s late (the drive of
    tests/workflows/test_car_gps.py, six seeds): calibrate from the first half (scale,
    steering offset, wheel base and the GPS's clock offset), fit-noise there, evaluate the
    second half in 30 s windows, all through the CLI as a user would."""
    import tempfile

    sys.path.insert(0, str(REPO / "tests" / "workflows"))
    from test_car_gps import _drive  # the test's own simulation: one drive, two places use it

    print("\n## A simulated car against GPS (1 Hz, 1 m, 0.2 s late; 20 min, fit on the first half)\n")
    print("| seed | clock offset fitted [s] | c_scale fitted (1.015) | held-out 30 s ends | "
          "inside 95 % / 50 % | NEES mean (bounds) |\n|---|---|---|---|---|---|")
    common = ("--columns", "t=t,speed=speed,steer=steer", "--truth-sigma", "1")
    for seed in range(1, 7):
        with tempfile.TemporaryDirectory() as name:
            folder = Path(name)
            robot, files = _drive(folder, seed=seed)
            (log, gps_file), (held, held_gps) = files["first"], files["second"]
            cal = _odomkit_json("calibrate", log, "--robot", robot, "--truth", gps_file,
                                "--out-robot", folder / "cal.toml", *common)
            _odomkit_json("fit-noise", "--robot", folder / "cal.toml", "--log", log, "--truth", gps_file,
                          "--window", "30s", "--window", "60s", "--kinds", "white,bias",
                          "--out", folder / "fit.toml", *common)
            ev = _odomkit_json("evaluate", held, "--robot", folder / "fit.toml", "--truth", held_gps,
                               "--window", "30s", *common)
            lo, hi = ev["nees_bounds"]
            offset, scale = cal["truth_time_offset"]["value"], cal["parameters"]["c_scale"]
            print(f"| {seed} | {offset:.3f} | {scale:.4f} | {ev['windows']} | "
                  f"{ev['coverage']['0.95']:.2f} / {ev['coverage']['0.5']:.2f} | "
                  f"{ev['nees_position_mean']:.2f} ({lo:.2f}–{hi:.2f}) |")


#: The noise families compared on MRCLAM: the robot file's [noise] for each (a unicycle:
#: commanded speed and yaw rate), and fit-noise's --kinds.
MRCLAM_VARIANTS = (
    ("white (speed, yaw rate, slip)", "alpha_ss = 0.001\npsd_gyro = 1e-5\nalpha_lateral = 0\n", "white"),
    ("white + bias", "alpha_ss = 0.001\npsd_gyro = 1e-5\nalpha_lateral = 0\n", "white,bias"),
    ("fit-noise's defaults: white + turn + bias", "alpha_ss = 0.001\npsd_gyro = 1e-5\nalpha_lateral = 0\n"
     "alpha_turn = 0\nalpha_turn_travel = 0\n", "white,bias"),
)


def mrclam(root: Path | None) -> None:
    """Fit on robots 1–2 of each MRCLAM dataset, score robots 3–5 (issue 11's outside study:
    five robots of one type, commanded v and ω against Vicon)."""
    import tempfile

    if root is None or not root.is_dir():
        print("\n## MRCLAM: skipped (give --mrclam DIR or ODOMKIT_MRCLAM: the UTIAS MRCLAM datasets, "
              "asrl.utias.utoronto.ca/datasets/mrclam, not shipped)")
        return
    folders = sorted(f for f in root.iterdir() if (f / "Robot5_Groundtruth.dat").is_file())
    print("\n## MRCLAM: fitted on robots 1–2 (10 s and 30 s windows), scored on robots 3–5\n")
    print("| dataset | noise | fitted | 10 s: inside 95 % / 50 %, NEES (bounds) | 30 s | 60 s |\n"
          "|---|---|---|---|---|---|")
    common = ("--columns", "t,speed,yaw_rate")
    for folder in folders:
        logs = {r: (folder / f"Robot{r}_Odometry.dat", folder / f"Robot{r}_Groundtruth.dat")
                for r in range(1, 6)}
        for name, noise, kinds in MRCLAM_VARIANTS:
            with tempfile.TemporaryDirectory() as tmp:
                robot = Path(tmp) / "unicycle.toml"
                robot.write_text('[robot]\ntype = "unicycle"\n\n[noise]\n' + noise
                                 + "\n[noise.parameters]\nsigma_scale_left = 0.01\n"
                                 "sigma_yaw_rate_offset = 0.001\nsigma_yaw_rate_scale = 0.01\n")
                fit_args = [a for r in (1, 2) for a in ("--log", logs[r][0], "--truth", logs[r][1])]
                fit = _odomkit_json("fit-noise", "--robot", robot, *fit_args, "--window", "10s", "--window",
                                    "30s", "--kinds", kinds, "--out", Path(tmp) / "fit.toml", *common)
                fitted = ", ".join(f"{k} {v:.2g}" for k, v in fit["parameters"].items()
                                   if not k.startswith("truth") and v > 0)
                cells = []
                for window in ("10s", "30s", "60s"):
                    held = [a for r in (3, 4, 5) for a in ("--truth", logs[r][1])]
                    ev = _odomkit_json("evaluate", *(logs[r][0] for r in (3, 4, 5)), *held, "--robot",
                                       Path(tmp) / "fit.toml", "--window", window, *common)
                    lo, hi = ev["nees_bounds"]
                    cells.append(f"{ev['coverage']['0.95']:.3f} / {ev['coverage']['0.5']:.3f}, "
                                 f"{ev['nees_position_mean']:.2f} ({lo:.2f}–{hi:.2f}), {ev['windows']} ends")
                print(f"| {folder.name} | {name} | {fitted} | {' | '.join(cells)} |")


#: The Victoria Park car as its authors give it: wheel base L = 2.83 m, the speed measured
#: at the rear-left wheel, H = 0.76 m left of the rear axle's centre.
VICTORIA_ROBOT = '[robot]\ntype = "car"\nwheel_base = 2.83\nencoder_offset = 0.76\nencoder_at = "rear"\n'


def _victoria_files(root: Path, folder: Path) -> tuple[Path, Path]:
    """The drive (t [s], speed [m/s], steer [rad]) and GPS (t [s], x, y [m]) of the Victoria
    Park .mat files in ``root`` as text files in ``folder`` (odomkit reads text, not .mat)."""
    from scipy.io import loadmat

    gps = loadmat(root / "aa3_gpsx.mat")
    if (root / "aa3_dr.mat").is_file():
        dr = loadmat(root / "aa3_dr.mat")
        drive = np.column_stack([dr["time"].ravel() / 1000.0, dr["speed"].ravel(), dr["steering"].ravel()])
    else:
        dr = loadmat(root / "VictoriaParkSinSincronizar.mat")
        drive = np.column_stack([dr["time"].ravel(), dr["u"][0], dr["u"][1]])
    log, fixes = folder / "drive.csv", folder / "gps.csv"
    np.savetxt(log, drive, delimiter=",", header="t,speed,steer", comments="", fmt="%.9g")
    east_north = np.column_stack([gps["timeGps"].ravel() / 1000.0, gps["Lo_m"].ravel(), gps["La_m"].ravel()])
    np.savetxt(fixes, east_north, delimiter=",", header="t,x,y", comments="", fmt="%.9g")
    return log, fixes


def victoria(root: Path | None) -> None:
    """Calibrate and fit-noise on the first half of the Victoria Park drive, score the second."""
    import tempfile

    if root is None or not (root / "aa3_gpsx.mat").is_file():
        print("\n## Victoria Park: skipped (give --victoria DIR or ODOMKIT_VICTORIA: aa3_gpsx.mat and "
              "aa3_dr.mat of the Victoria Park dataset, not shipped)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        log, gps = _victoria_files(root, folder)
        nominal = folder / "car.toml"
        nominal.write_text(VICTORIA_ROBOT)
        truth = ("--truth", gps, "--columns", "t,speed,steer")
        print("\n## Victoria Park: a car against its GPS, calibrated and fitted on the first half\n")
        print("| robot file | c_scale | steering offset [rad] | wheel base [m] | steering cubic | "
              "second half: ATE / final error [m] |\n|---|---|---|---|---|---|")
        rows = [("nominal", nominal, {})]
        # The clock the speeds give (calibrate warns where its fitted one differs: a lag in the
        # turning taken for the truth's clock).
        from odomkit.calibrate.check_ratios import speed_clock
        from odomkit.workflows.logs import LogOptions, load_log
        from odomkit.workflows.truth import TruthOptions, load_truth

        car, _ = read_robot(nominal)
        half = load_log(log, car, LogOptions(columns="t,speed,steer", span=":50%"))
        clock = speed_clock([half], car, [load_truth(TruthOptions(gps), half)])
        assert clock is not None
        speeds = f"{clock[0]:.2f}"
        for name, extra in (("calibrated (--window 60s)", ()),
                            ("calibrated (--window 60s --fit-steering-cubic)", ("--fit-steering-cubic",)),
                            (f"calibrated (--fit-steering-cubic, the speeds' clock {speeds} s)",
                             ("--fit-steering-cubic", "--truth-time-offset", speeds))):
            out = folder / f"cal{len(rows)}.toml"
            cal = _odomkit_json("calibrate", log, "--robot", nominal, *truth, "--span", ":50%", "--window",
                                "60s", *extra, "--out-robot", out)
            rows.append((name, out, cal["parameters"]))
        for name, robot, fitted in rows:
            ev = _odomkit_json("evaluate", log, "--robot", robot, *truth, "--span", "50%:")
            print(f"| {name} | {fitted.get('c_scale', 1.0):.4f} | {fitted.get('steering_offset', 0.0):.4f} | "
                  f"{fitted.get('wheel_base', 2.83):.3f} | {fitted.get('steering_cubic', 0.0):.3f} | "
                  f"{ev['ate_rmse']:.1f} / {ev['final_position_error']:.1f} |")
        print("\n| calibration | noise fitted (first half, 10 s + 30 s windows) | second half: 10 s | 30 s | "
              "60 s (inside 95 % / 50 %, NEES mean (bounds), ends) |\n|---|---|---|---|---|")
        for name, robot, _ in rows[1:]:
            fitted_file = folder / f"fit-{robot.stem}.toml"
            fit = _odomkit_json("fit-noise", "--robot", robot, "--log", log, *truth, "--span", ":50%",
                                "--window", "10s", "--window", "30s", "--out", fitted_file)
            noise = ", ".join(f"{k} {v:.2g}" for k, v in fit["parameters"].items() if v > 0)
            cells = []
            for window in ("10s", "30s", "60s"):
                ev = _odomkit_json("evaluate", log, "--robot", fitted_file, *truth, "--span", "50%:",
                                   "--window", window)
                lo, hi = ev["nees_bounds"]
                cells.append(f"{ev['coverage']['0.95']:.2f} / {ev['coverage']['0.5']:.2f}, "
                             f"{ev['nees_position_mean']:.2f} ({lo:.2f}–{hi:.2f}), {ev['windows']}")
            print(f"| {name} | {noise} | {' | '.join(cells)} |")


def main() -> None:
    default = Path(os.environ.get("ODOMKIT_DATA", REPO.parent / "shared" / "data"))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--part", nargs="*",
                        default=["optiodom", "snowhite", "gps", "speed", "car", "mrclam", "victoria"])
    mrclam_dir = os.environ.get("ODOMKIT_MRCLAM")
    parser.add_argument("--mrclam", type=Path, default=Path(mrclam_dir) if mrclam_dir else None,
                        help="folder of UTIAS MRCLAM datasets (MRCLAM_DatasetN/RobotK_*.dat)")
    victoria_dir = os.environ.get("ODOMKIT_VICTORIA")
    parser.add_argument("--victoria", type=Path, default=Path(victoria_dir) if victoria_dir else None,
                        help="folder of the Victoria Park dataset's aa3_gpsx.mat and aa3_dr.mat")
    args = parser.parse_args()
    import warnings

    warnings.simplefilter("ignore")  # the fits' warnings are printed in the tables
    for name in args.part:
        {"optiodom": lambda: optiodom(args.data / "optiodom"), "snowhite": lambda: snowhite(args.data),
         "gps": lambda: gps(args.data), "car": lambda: car(args.data),
         "speed": lambda: speed(args.data / "optiodom"), "mrclam": lambda: mrclam(args.mrclam),
         "victoria": lambda: victoria(args.victoria)}[name]()


if __name__ == "__main__":
    main()
