"""The OptiOdom UMBmark acceptance table: E_max,syst before and after UMBmark and after the
exact (endpoint least-squares) calibration, in sample and out of sample.

    .venv/bin/python benchmarks/calibration_table.py [DATA_DIR]

DATA_DIR defaults to $ODOMKIT_DATA or ../shared/data beside the repository. Prints the
markdown table of docs/results/real-data.md (the acceptance table) and, as the ratio line, the mean
out-of-sample E_max,syst of the exact calibration over that of UMBmark (below 1 = better).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from odomkit.calibrate.realdata import SquareRow
from odomkit.workflows.calibration import optiodom_square_table


def square_table_markdown(rows: Sequence[SquareRow]) -> str:
    """The table as markdown, E_max,syst in millimetres, with a mean row per square side."""
    head = ("| experiment | side [m] | runs CW/CCW | before | UMBmark (in) | exact (in) "
            "| trajectory fit (in) | UMBmark (out) | exact (out) |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        lines.append(f"| {r.experiment} | {r.side:g} | {r.n_cw}/{r.n_ccw} | {1e3 * r.before:.1f} "
                     f"| {1e3 * r.in_umbmark:.1f} | {1e3 * r.in_exact:.1f} | {1e3 * r.in_trajectory:.1f} "
                     f"| {1e3 * r.out_umbmark:.1f} | {1e3 * r.out_exact:.1f} |")
    for side in sorted({r.side for r in rows}):
        sel = [r for r in rows if r.side == side]
        m = {k: 1e3 * float(np.mean([getattr(r, k) for r in sel]))
             for k in ("before", "in_umbmark", "in_exact", "in_trajectory", "out_umbmark",
                  "out_exact")}
        lines.append(f"| **mean** | {side:g} | | {m['before']:.1f} | {m['in_umbmark']:.1f} "
                     f"| {m['in_exact']:.1f} | {m['in_trajectory']:.1f} | {m['out_umbmark']:.1f} "
                     f"| {m['out_exact']:.1f} |")
    return head + "\n".join(lines) + "\n"


def main() -> None:
    default = os.environ.get("ODOMKIT_DATA") or str(Path(__file__).resolve().parents[2] / "shared" / "data")
    data_dir = Path(sys.argv[1] if len(sys.argv) > 1 else default)
    start = time.perf_counter()
    rows = optiodom_square_table(data_dir)
    seconds = time.perf_counter() - start
    print(square_table_markdown(rows))
    for side in sorted({r.side for r in rows}):
        sel = [r for r in rows if r.side == side]
        ratio = np.mean([r.out_exact for r in sel]) / np.mean([r.out_umbmark for r in sel])
        print(f"side {side:g} m: out-of-sample E_max,syst exact/UMBmark = {ratio:.3f}")
    print(f"({len(rows)} experiments in {seconds:.1f} s)")


if __name__ == "__main__":
    main()
