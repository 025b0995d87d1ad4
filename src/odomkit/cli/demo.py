"""``odomkit demo``: the whole product on the built-in data, in a few lines of headline
numbers and an HTML report (dead reckoning with covariance, a prediction checked by Monte
Carlo, calibration, and how honest the guessed and the fitted noise are)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from odomkit.cli.application import app

__all__ = ["demo"]

# The report has every model; the terminal shows the guess and the best fit.
_NAMES = {"guessed": "guessed (robot file)", "white+bias": "fitted white + bias"}


def _row(label: str, window: str, score: dict[str, Any]) -> str:
    c = score["coverage"]
    lo, hi = score["nees_bounds"]
    inside = " / ".join(f"{c[k]:.2f}" for k in ("0.5", "0.9", "0.95", "0.99"))
    return (f"  {label:<22} {window[:-1]:>3} s {score['windows']:>5}   {inside}   "
            f"{score['nees_position_mean']:>7.3g} ({lo:.2f}..{hi:.2f})")


def _folder(text: str) -> Path:
    """``--out`` as a path; an empty one is refused: ``Path("")`` is the current folder, and
    the demo would fill it (fuzz finding)."""
    if not text:
        raise typer.BadParameter("an empty path; give a folder (. for the current one)")
    return Path(text)


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the outputs.", parser=_folder,
                                      metavar="<path>")] = Path("demo-output"),
    force: Annotated[bool, typer.Option(help="Replace existing outputs.")] = False,
) -> None:
    """Calibrate on the built-in OptiOdom runs, fit the noise on half of the built-in
    experiments, show how honest it is on the other half, and write report.html with it all."""
    from odomkit.workflows.demo import run_demo

    s = run_demo(out, overwrite=force)
    c, h = s["calibration"], s["noise_honesty"]
    print(f"odomkit demo on built-in OptiOdom data (differential robot, MIT licence; "
          f"{len(h['fit']['experiments']) + len(h['held_out']['experiments'])} experiments)")
    print(f"calibrated on {c['experiment']} ({len(s['runs'])} UMBmark runs): E_max,syst "
          f"{1000 * c['e_max_syst_before']:.1f} mm -> {1000 * c['exact']['e_max_syst_after']:.1f} mm "
          f"(E_d {c['exact']['E_d']:.5f}, E_b {c['exact']['E_b']:.5f})")
    mc = s["monte_carlo_one_square"]
    print(f"one square predicted in closed form, against {mc['runs']} Monte Carlo runs: {mc['verdict']}")
    fit, held = h["fit"], h["held_out"]
    print(f"noise fitted on {fit['runs']} runs, scored on {held['runs']} held-out runs, each window "
          "restarted from OptiTrack (honest: inside as predicted):")
    print(f"  {'noise':<22} window  ends   inside 50 / 90 / 95 / 99 %   NEES mean (95 % bounds)")
    for key, label in _NAMES.items():
        for window in held["windows"]:
            print(_row(label, window, h["models"][key][window]))
    print(f"report: {Path(s['report']).resolve()} (every figure and number, explained; open it in a browser)")
    names = [Path(p).name for p in s["outputs"]]
    tracks = sum(n.endswith("_track.csv") for n in names)
    listed = [n for n in names if not n.endswith(("_track.csv", ".tum", ".html"))]
    print(f"outputs in {Path(out).resolve()}: {', '.join(listed)}, and {tracks} tracks "
          "(*_track.csv with covariance, *.tum)")
