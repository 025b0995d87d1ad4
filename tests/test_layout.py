"""Tests mirror ``src/`` (issue 9): every public module has a test module of its own.

A public module is ``src/odomkit/**/X.py`` whose name does not start with ``_`` (so not
``__init__`` and not private kernels such as ``_numba``), outside ``cli/`` (CLI modules
are tested through the command line, in ``test_cli_*`` modules and ``tests/cli/``).
Its test module is ``tests/**/test_X.py``, matched by basename. Where two public modules
share a basename (``propagate/plan.py`` and ``simulate/plan.py``) the basename says
nothing, so the test must mirror the path: ``tests/propagate/test_plan.py``.

A module may go without a test module only if it is listed below with its reason:
:data:`EXEMPT` for good, :data:`PENDING` until issue 9's refactor settles. A pending
entry must be removed once its test module exists (the test says so), and every entry
must name a module that exists.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping
from pathlib import Path, PurePosixPath

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "src" / "odomkit"
TESTS = REPO / "tests"

#: Modules (paths relative to src/odomkit) that need no test module of their own.
EXEMPT: Mapping[str, str] = {
    "workflows/predict.py": "thin file-in/file-out wrapper; its --json output is frozen by "
                            "tests/test_golden.py and its maths tested in tests/propagate/",
    "workflows/simulate.py": "thin wrapper; --json frozen by tests/test_golden.py, engine "
                             "tested in tests/simulate/",
    "workflows/track.py": "thin wrapper; --json frozen by tests/test_golden.py, dead "
                          "reckoning tested in tests/test_track.py",
    "workflows/umbmark.py": "thin wrapper; --json frozen by tests/test_golden.py, UMBmark "
                            "tested in tests/calibrate/test_umbmark*.py",
}

#: Modules that still lack a test module while issue 9's refactor moves code around; the
#: lead closes each gap (then the entry must go).
PENDING: Mapping[str, str] = {
    "calibrate/residuals.py": "issue 9: tested through tests/calibrate/test_exact.py for now",
    "calibrate/virtual.py": "issue 9: tested in tests/calibrate/test_virtual_umbmark.py "
                            "(rename it test_virtual.py)",
    "io/csvlog.py": "issue 9: tested in tests/io/test_readers.py for now",
    "io/halmstad.py": "issue 9: tested in tests/io/test_readers.py for now",
    "io/jsonfile.py": "issue 9: new module; test module after the refactor",
    "io/trackio.py": "issue 9: tested in tests/test_cli_track.py for now",
    "io/umbmark_errors.py": "issue 9: new module; tested through the umbmark CLI for now",
    "simulate/blocks.py": "issue 9: new module; tested through tests/simulate/test_engine.py",
    "simulate/distributed.py": "issue 9: tested in tests/simulate/test_dask.py",
    "simulate/experiment.py": "issue 9: tested in tests/simulate/test_against_predict.py for now",
    "simulate/plan.py": "issue 9: tested through tests/simulate/test_engine.py for now",
}


def public_modules(package: Path = PACKAGE) -> list[PurePosixPath]:
    """Public modules as paths relative to the package, e.g. ``io/table.py``."""
    found = []
    for path in sorted(package.rglob("*.py")):
        rel = PurePosixPath(path.relative_to(package).as_posix())
        if rel.name.startswith("_") or rel.parts[0] == "cli" or "__pycache__" in rel.parts:
            continue
        found.append(rel)
    return found


def existing_test_modules(tests: Path = TESTS) -> list[PurePosixPath]:
    """Test modules as paths relative to tests/, e.g. ``io/test_readers.py``."""
    return [PurePosixPath(p.relative_to(tests).as_posix()) for p in sorted(tests.rglob("test_*.py"))]


def modules_without_tests(modules: Iterable[PurePosixPath],
                          tests: Iterable[PurePosixPath]) -> list[str]:
    """The modules that have no ``test_<name>.py`` (see the module docstring)."""
    modules = list(modules)
    tests = set(tests)
    test_names = {t.name for t in tests}
    shared = {n for n, count in Counter(m.name for m in modules).items() if count > 1}
    missing = []
    for m in modules:
        wanted = f"test_{m.name}"
        if m.name in shared:
            ok = m.parent / wanted in tests
        else:
            ok = wanted in test_names
        if not ok:
            missing.append(m.as_posix())
    return missing


def test_the_rule_can_fire():
    """The matching rule on a synthetic tree: it finds what is missing, matches by basename,
    and insists on the mirrored path for a shared basename."""
    P = PurePosixPath
    modules = [P("robot.py"), P("io/table.py"), P("propagate/plan.py"), P("simulate/plan.py"),
               P("evaluate.py")]
    tests = [P("test_robot.py"), P("somewhere/test_table.py"), P("propagate/test_plan.py"),
             P("test_plan.py")]
    assert modules_without_tests(modules, tests) == ["simulate/plan.py", "evaluate.py"]


def test_discovery_sees_public_modules_only():
    modules = {m.as_posix() for m in public_modules()}
    assert {"robot.py", "validate.py", "track.py"} <= modules
    assert not {m for m in modules if m.startswith("cli/") or PurePosixPath(m).name.startswith("_")}
    assert "test_layout.py" in {t.name for t in existing_test_modules()}


def test_every_public_module_has_a_test_module():
    missing = set(modules_without_tests(public_modules(), existing_test_modules()))
    unexplained = sorted(missing - set(EXEMPT) - set(PENDING))
    assert not unexplained, (
        "these modules have no tests/**/test_<name>.py; write one (or, with a reason, list "
        f"the module in EXEMPT): {unexplained}")


def test_exempt_and_pending_entries_are_current():
    modules = {m.as_posix() for m in public_modules()}
    missing = set(modules_without_tests(public_modules(), existing_test_modules()))
    gone = sorted((set(EXEMPT) | set(PENDING)) - modules)
    assert not gone, f"EXEMPT/PENDING name modules that no longer exist: {gone}"
    done = sorted(set(PENDING) - missing)
    assert not done, f"these PENDING modules now have a test module; remove them from PENDING: {done}"
    assert not set(EXEMPT) & set(PENDING)
    assert all(reason.strip() for reason in [*EXEMPT.values(), *PENDING.values()])
