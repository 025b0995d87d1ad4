"""``odomkit demo``: calibration, and how honest the guessed and the fitted noise are, on
the built-in data."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from odomkit.cli.application import app

__all__ = ["demo"]

_NAMES = {"guessed": "guessed (robot file)", "white": "fitted white", "white+bias": "fitted white + bias"}


def _row(label: str, window: str, score: dict[str, Any]) -> str:
    c = score["coverage"]
    lo, hi = score["nees_bounds"]
    inside = " / ".join(f"{c[k]:.2f}" for k in ("0.5", "0.9", "0.95", "0.99"))
    return (f"  {label:<22} {window[:-1]:>3} s {score['windows']:>5}   {inside}   "
            f"{score['nees_position_mean']:>7.3g} ({lo:.2f}..{hi:.2f})")


def _values(parameters: dict[str, float]) -> str:
    return ", ".join(f"{k} {v:.3g}" for k, v in parameters.items())


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the outputs.")] = Path("demo-output"),
    force: Annotated[bool, typer.Option(help="Replace existing outputs.")] = False,
) -> None:
    """Calibrate on the built-in OptiOdom runs, fit the noise on half of the built-in
    experiments and show how honest it is on the other half."""
    from odomkit.workflows.demo import run_demo

    s = run_demo(out, overwrite=force)
    c, h = s["calibration"], s["noise_honesty"]
    print(f"odomkit demo on built-in OptiOdom data (differential robot, MIT licence; "
          f"{len(h['fit']['experiments']) + len(h['held_out']['experiments'])} experiments)")
    print(f"calibrated on {c['experiment']} ({len(s['runs'])} UMBmark runs): E_max,syst "
          f"{1000 * c['e_max_syst_before']:.1f} mm -> {1000 * c['exact']['e_max_syst_after']:.1f} mm "
          f"(E_d {c['exact']['E_d']:.5f}, E_b {c['exact']['E_b']:.5f})")
    fit, held = h["fit"], h["held_out"]
    print(f"noise fitted in {fit['window'][:-1]} s windows of {fit['runs']} runs "
          f"({', '.join(fit['kinds'])}: {', '.join(fit['experiments'])}),")
    print(f"scored on {held['runs']} held-out runs ({', '.join(held['kinds'])}: "
          f"{', '.join(held['experiments'])}), each window restarted from OptiTrack:")
    print(f"  {'noise':<22} window  ends   inside 50 / 90 / 95 / 99 %   NEES mean (95 % bounds)")
    for key, label in _NAMES.items():
        for window in held["windows"]:
            print(_row(label, window, h["models"][key][window]))
    print("  honest: inside 0.50 / 0.90 / 0.95 / 0.99 and the NEES mean within its bounds")
    print(f"guessed: {_values(h['models']['guessed']['parameters'])}; fitted: "
          f"{_values(h['models']['white+bias']['parameters'])} (fitted_robot.toml)")
    names = [Path(p).name for p in s["outputs"]]
    tracks = sum(n.endswith("_track.csv") for n in names)
    listed = [n for n in names if not n.endswith(("_track.csv", ".tum"))]
    print(f"outputs in {Path(out).resolve()}: {', '.join(listed)}, and {tracks} tracks "
          "(*_track.csv with covariance, *.tum)")
