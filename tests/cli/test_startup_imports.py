"""``odomkit --help`` must not load the heavy stacks (issue 10 item 10).

Start-up time is measured by ``benchmarks/startup.py``; here the cause of a slow start-up
is checked without timing: a fresh interpreter runs the help of every command and
reports which heavy packages ended up in ``sys.modules``. Each of them costs 0.1–2 s to
import and no ``--help`` needs one.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("scipy", "numba", "matplotlib", "polars", "dask", "rosbags")

_PROBE = """
import contextlib, io, json, sys
from odomkit.cli import app, main
with contextlib.redirect_stdout(io.StringIO()):
    codes = {'--help': main(['--help'])}
    import typer.main
    names = sorted(typer.main.get_command(app).commands)
    for name in names:
        codes[name + ' --help'] = main([name, '--help'])
heavy = sorted(m for m in sys.modules if m.split('.')[0] in %r)
numpy = 'numpy' in sys.modules
print(json.dumps({'codes': codes, 'commands': names, 'heavy': heavy, 'numpy': numpy}))
"""


def _probe() -> dict:
    done = subprocess.run([sys.executable, "-c", _PROBE % (HEAVY,)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def probe() -> dict:
    return _probe()


def test_every_help_succeeds(probe):
    assert "track" in probe["commands"]  # the probe saw the real command list
    assert all(code == 0 for code in probe["codes"].values()), probe["codes"]


def test_help_imports_no_heavy_package(probe):
    assert probe["heavy"] == []


def test_help_imports_no_numpy(probe):
    """No --help needs numpy either: the JSON printer imported it at the top of cli.output
    (35 ms of odomkit --help's 117, over the start-up budget; benchmarks/startup.py)."""
    assert probe["numpy"] is False


def test_the_probe_sees_a_heavy_import():
    """The check itself can fail: the same probe after importing scipy reports it."""
    code = "import scipy\n" + _PROBE % (HEAVY,)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert "scipy" in json.loads(done.stdout.strip().splitlines()[-1])["heavy"]


def test_import_odomkit_is_light():
    """``import odomkit`` gives the errors and the version, and loads no numpy at all."""
    roots = ("numpy",) + HEAVY
    code = f"import sys, odomkit; print(sorted(m for m in sys.modules if m.split('.')[0] in {roots!r}))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
