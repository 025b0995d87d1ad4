"""Start-up time of the command line against ``python -c "import numpy, typer"``.

Every command of ``odomkit`` pays its start-up before it does anything; ``--help`` pays
nothing else. The reference is the least any numpy + typer program can cost, so the ratio
says how much odomkit adds. Each run is a fresh interpreter (``subprocess``), so the
import cache of one run never helps the next; the median of ``--repeat`` runs is robust
to the odd slow run of a shared machine. The commands take turns, and the first round is
discarded (it warms the OS file cache and writes the ``.pyc`` files).

Issue 10 item 10 sets the budget: ``odomkit --help`` and ``odomkit track --help`` cost at
most 1.5 × the reference. The script exits with status 1 when one of those two ratios is
above ``--limit``. Two floors are printed beside them, a two-command typer app that imports
numpy and nothing of odomkit: what typer itself costs for ``--help`` and for
``<command> --help``, which no import discipline in odomkit can remove.

    .venv/bin/python benchmarks/startup.py [--repeat 15] [--limit 1.5]
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

REFERENCE = "import numpy, typer"
#: The least any typer program pays for ``--help`` and ``<command> --help``: two commands of
#: one option each, nothing of odomkit. typer 0.29 (measured here) coerces even the group's
#: unset help flag through pydantic once a command is named, so ``<command> --help`` imports
#: pydantic in every typer program; this floor shows which part of a ratio is typer's.
EMPTY_APP = """
import sys
import numpy, typer
app = typer.Typer(add_completion=False)
@app.command()
def a(x: int = 1) -> None:
    \"\"\"A.\"\"\"
@app.command()
def b(y: int = 1) -> None:
    \"\"\"B.\"\"\"
app(sys.argv[1:])
"""


def odomkit_command() -> list[str]:
    """The installed console script beside this interpreter, else an equivalent ``-c``."""
    script = Path(sys.executable).with_name("odomkit")
    if script.is_file():
        return [str(script)]
    return [sys.executable, "-c", "import sys; from odomkit.cli import main; sys.exit(main(sys.argv[1:]))"]


def seconds(argv: list[str]) -> tuple[float, float]:
    """Wall-clock and CPU (user + system) seconds of one fresh run of ``argv``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}):\n{done.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return elapsed, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15, help="timed runs per command")
    parser.add_argument("--limit", type=float, default=1.5, help="largest allowed ratio")
    args = parser.parse_args()

    commands = {"reference": [sys.executable, "-c", REFERENCE],
                "odomkit --help": odomkit_command() + ["--help"],
                "odomkit track --help": odomkit_command() + ["track", "--help"],
                "floor: typer app --help": [sys.executable, "-c", EMPTY_APP, "--help"],
                "floor: typer app a --help": [sys.executable, "-c", EMPTY_APP, "a", "--help"]}
    checked = ("odomkit --help", "odomkit track --help")
    wall: dict[str, list[float]] = {name: [] for name in commands}
    cpu: dict[str, list[float]] = {name: [] for name in commands}
    # Round robin, so that a burst of load on a shared machine hits every command alike.
    for i in range(args.repeat + 1):
        for name, argv in commands.items():
            w, c = seconds(argv)
            if i:  # the first round warms the file cache and the .pyc files
                wall[name].append(w)
                cpu[name].append(c)
    ref_wall, ref_cpu = statistics.median(wall["reference"]), statistics.median(cpu["reference"])
    print(f"{args.repeat} runs each; medians of wall-clock time (the budget) and of CPU time "
          "(steadier on a loaded machine)")
    print(f"{'python -c ' + repr(REFERENCE):30s}: wall {1e3 * ref_wall:7.1f} ms            "
          f"cpu {1e3 * ref_cpu:7.1f} ms")
    worst = 0.0
    for name in list(commands)[1:]:
        w, c = statistics.median(wall[name]), statistics.median(cpu[name])
        if name in checked:
            worst = max(worst, w / ref_wall)
        print(f"{name:30s}: wall {1e3 * w:7.1f} ms, ratio {w / ref_wall:.2f}; "
              f"cpu {1e3 * c:7.1f} ms, ratio {c / ref_cpu:.2f}")
    verdict = "ok" if worst <= args.limit else "TOO SLOW"
    print(f"worst wall-clock ratio of odomkit {worst:.2f} (limit {args.limit}): {verdict}")
    return 0 if worst <= args.limit else 1


if __name__ == "__main__":
    sys.exit(main())
