"""How honest is the covariance? The README's tables (issue 11's measured targets), one command.

    .venv/bin/python benchmarks/honesty.py [--data ../shared/data] [--part optiodom snowhite speed]

(a) OptiOdom, differential and tricycle. The experiments of each kind (diff: square,
    circular, ivanjko, free; tricycle: square, circular, free) are sorted by name; every
    other one (the 1st, 3rd, ...) is the *fit half*, the rest is *held out*. On the fit half
    the robot is calibrated (exact least squares on the whole OptiTrack trajectory; one
    robot per platform: every diff metadata file describes the same physical robot, README
    "Results on OptiOdom") and the noise is fitted by maximum likelihood (``fit-noise``'s
    machinery) in windows of one length. That ONE fitted model is scored on the held-out
    half in windows of 10 s and of 30 s, each restarted from the OptiTrack pose: the fraction
    of window ends inside the predicted 50/90/95/99 % position ellipses and the mean
    position NEES with its 95 % chi-square bounds. Target (issue 11): 95 % coverage in
    [0.88, 0.99] and 50 % in [0.40, 0.80] at both window lengths.
(b) Snowhite (Halmstad, no licence: read from --data, numbers only): calibrated and fitted
    on the first half of the log (101 s), scored on the second.
(c) Speed: ``odomkit fit-noise`` on all 203 OptiOdom runs (two robot files), wall time.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from odomkit.calibrate.exact import calibrate_exact
from odomkit.calibrate.fit_noise import fit_noise, noise_parameters
from odomkit.evaluate import coverage, nees, nees_summary
from odomkit.io.halmstad import read_snowhite
from odomkit.io.optiodom import read_experiment
from odomkit.io.robotfile import read_robot
from odomkit.kinematics import body_steps
from odomkit.log import OdometryLog
from odomkit.noise import ParameterUncertainty, SpeedNoise, TricycleNoise, WheelNoise
from odomkit.truth import truth_at, truth_from_log
from odomkit.windows import cumulative_travel, parse_window, split_windows, window_covariance_basis

REPO = Path(__file__).resolve().parents[1]
LEVELS = ("0.5", "0.9", "0.95", "0.99")
KINDS = {"diff": ("square", "circular", "ivanjko", "free"), "tricyc": ("square", "circular", "free")}
WINDOWS = ("10s", "30s")
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


def bases(runs, robot, models, window):
    """(kind, WindowBasis) of every run with at least one window (its name in ``source``)."""
    spec = parse_window(window)
    out = []
    for kind, log in runs:
        truth = truth_from_log(log)
        samples = truth_at(truth, log.t)
        travel = cumulative_travel(body_steps(robot, log))
        windows, _ = split_windows(log.t, travel, spec, valid=samples.valid)
        if windows:
            basis = window_covariance_basis(log, robot, models, samples.poses, samples.valid, windows,
                                            truth=truth)
            out.append((kind, basis, Path(log.source).stem))
    return out


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
    return (f"{s['n']} | " + " / ".join(f"{c[k]:.2f}" for k in LEVELS) + f" | {s['nees']:.2f} "
            f"({s['bounds'][0]:.2f}–{s['bounds'][1]:.2f})")


def values(parameters):
    return ", ".join(f"{k} {v:.3g}" for k, v in parameters.items())


def table(title, variants, fit_runs, held_runs, robot, breakdown=True):
    """Fit every variant in every fit window, score it held out; print a Markdown table."""
    print(f"\n{title}\n")
    print("| model | fitted on | fitted values | 10 s ends | 10 s: inside 50 / 90 / 95 / 99 % "
          "| NEES (bounds) | 30 s ends | 30 s: inside 50 / 90 / 95 / 99 % | NEES (bounds) "
          "| targets met at 10 s / 30 s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    found, warned = {}, []
    for name, models, kinds, fixed, fit_windows in variants:
        held = {w: bases(held_runs, robot, models, w) for w in WINDOWS}
        for fw in fit_windows:
            if kinds is None:  # the robot file's guess, not fitted
                params = noise_parameters(models, robot, ())
                v = np.array([models[p.model].variance_parameters()[p.name] for p in params])
                shown, notes, seconds = values({p.key: p.to_value(x) for p, x in zip(params, v, strict=True)
                                                if x > 0}), [], 0.0
            else:
                fb = bases(fit_runs, robot, models, fw)
                started = time.perf_counter()
                fit = fit_noise([b for _, b, _ in fb], models, robot, kinds=kinds, fixed=fixed,
                                log_names=[n for _, _, n in fb])
                seconds = time.perf_counter() - started
                v = np.array(list(fit.variances.values()))
                shown, notes = values(fit.parameters), fit.warnings
            s = {w: score(held[w], v) for w in WINDOWS}
            found[name, fw] = (s, held, v)
            print(f"| {name} | {fw[:-1] + ' s windows' if kinds else '—'} | {shown} | {cell(s['10s'])} | "
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
        bias = ParameterUncertainty()
        variants = []
        if guess:
            variants.append(("guessed k (robot file)", (*guess, bias), None, (), ("10s",)))
        variants += [("white", (white, bias), ("white",), {"sigma_dt"}, WINDOWS),
                     ("white + bias", (white, bias), ("white", "bias"), {"sigma_dt"}, WINDOWS)]
        if platform == "diff":  # common-mode distance noise beside the per-wheel noise
            variants.append(("white + speed noise", (white, SpeedNoise(0.0), bias), ("white",), {"sigma_dt"},
                             ("10s",)))
        if platform == "tricyc":  # the speed noise driven by travel, not time (see README)
            variants.append(("white, travel-driven speed", (white, SpeedNoise(0.0), bias), ("white",),
                             {"sigma_dt", "sigma_speed"}, WINDOWS))
        table(f"### {platform}", variants, fit_runs, held_runs, robot)


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
    white, bias = TricycleNoise(0.0, 0.0), ParameterUncertainty()
    table("### Snowhite", [("guessed (examples/snowhite.toml)", (*guess, bias), None, (), ("10s",)),
                           ("white", (white, bias), ("white",), {"sigma_dt"}, WINDOWS),
                           ("white + bias", (white, bias), ("white", "bias"), {"sigma_dt"}, WINDOWS)],
          first, second, robot, breakdown=False)


def speed(root: Path) -> None:
    print("\n## Speed: odomkit fit-noise on every OptiOdom run, 10 s windows, white + bias\n")
    odomkit = str(Path(sys.executable).with_name("odomkit"))
    for platform, robot in (("diff", REPO / "src/odomkit/data/optiodom_diff.toml"),
                            ("tricyc", REPO / "examples/optiodom_tricycle.toml")):
        logs = sorted((root / platform).glob("*/*/*_run-*.csv"))
        out = Path(os.environ.get("TMPDIR", "/tmp")) / f"odomkit-honesty-{platform}.toml"
        cmd = [odomkit, "fit-noise", "--robot", str(robot), "--window", "10s", "--kinds", "white,bias",
               "--out", str(out), "--force"] + [a for p in logs for a in ("--log", str(p))]
        started = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        seconds = time.perf_counter() - started
        first = done.stdout.splitlines()[0] if done.stdout else done.stderr.strip()
        print(f"{platform}: {len(logs)} runs, {seconds:.1f} s wall (exit {done.returncode}): {first}")


def main() -> None:
    default = Path(os.environ.get("ODOMKIT_DATA", REPO.parent / "shared" / "data"))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--part", nargs="*", default=["optiodom", "snowhite", "speed"])
    args = parser.parse_args()
    import warnings

    warnings.simplefilter("ignore")  # the fits' warnings are printed in the tables
    for name in args.part:
        {"optiodom": lambda: optiodom(args.data / "optiodom"), "snowhite": lambda: snowhite(args.data),
         "speed": lambda: speed(args.data / "optiodom")}[name]()


if __name__ == "__main__":
    main()
