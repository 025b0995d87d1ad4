"""``odomkit demo``: dead reckoning, calibration and prediction on the built-in data."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from odomkit.cli.application import app

__all__ = ["demo"]


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the outputs.")] = Path("demo-output"),
    force: Annotated[bool, typer.Option(help="Replace existing outputs.")] = False,
) -> None:
    """Dead-reckon, calibrate and predict on the built-in OptiOdom UMBmark runs."""
    from odomkit.workflows.demo import run_demo

    s = run_demo(out, overwrite=force)
    print("Built-in data: OptiOdom experiment 230620202042 (0.75 m UMBmark square, MIT licence)")
    for stem, run in s["runs"].items():
        print(f"  {stem} ({run['direction']:>3}): path {run['path_length']:.2f} m, final error vs "
              f"OptiTrack {1000 * run['final_position_error']:.1f} mm, heading "
              f"{run['final_heading_error']:+.3f} rad, inside 95 % ellipse "
              f"{100 * run['inside_95_fraction']:.0f} % of the time "
              f"({100 * run['calibrated']['inside_95_fraction']:.0f} % once calibrated)")
    c = s["calibration"]
    print(f"E_max,syst {1000 * c['e_max_syst_before']:.1f} mm uncalibrated; "
          f"{1000 * c['umbmark']['e_max_syst_after']:.1f} mm after UMBmark "
          f"(E_d {c['umbmark']['E_d']:.5f}, E_b {c['umbmark']['E_b']:.5f}); "
          f"{1000 * c['exact']['e_max_syst_after']:.1f} mm after the exact fit "
          f"(E_d {c['exact']['E_d']:.5f}, E_b {c['exact']['E_b']:.5f})")
    p = s["prediction_one_square"]
    print(f"predicted end-of-square std (k = 0.001 m^1/2): x {1000 * p['std'][0]:.1f} mm, "
          f"y {1000 * p['std'][1]:.1f} mm, theta {p['std'][2]:.4f} rad")
    print(f"outputs in {Path(out).resolve()}:")
    for path in s["outputs"]:
        print(f"  {path}")
