"""A simulation too large for time or memory is refused before it starts, with the estimate
and the way to allow it; a malformed scheduler address is one line (issue 10, item 8)."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.noise import WheelNoise
from odomkit.path import Arc, Straight
from odomkit.simulate import monte_carlo, simulate_runs
from odomkit.simulate.engine import MAX_WORK, check_size

# A RuntimeWarning anywhere is a failure: outside pytest it would print before the error.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

DIFF = ["--model", "diff", "--wheel-base", "0.4", "--k-left", "0.001", "--k-right", "0.001"]


def _must_not_start(what: str):
    def started(*args, **kwargs):
        raise AssertionError(f"{what} started: the request was not refused before the work")
    return started


@pytest.mark.parametrize("runs, partitions", [(10**9, 1000), (1000, 10**9), (10**9, 1)])
def test_huge_requests_are_refused_at_once(runs, partitions, monkeypatch):
    """Refused before any work: the plan (the first allocation of the simulation) and the
    prediction monte_carlo compares with are never built (tests time nothing)."""
    import odomkit.simulate.engine as engine
    import odomkit.simulate.experiment as experiment

    monkeypatch.setattr(engine, "make_plan", _must_not_start("the simulation's plan"))
    monkeypatch.setattr(experiment, "_predicted", _must_not_start("the prediction"))
    with pytest.raises(ModelError, match="--max-work|memory"):
        simulate_runs([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=runs, partitions=partitions)
    with pytest.raises(ModelError, match="--max-work|memory"):
        monte_carlo([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=runs, partitions=partitions)


def test_the_message_gives_the_estimate_the_limit_and_the_way_out():
    with pytest.raises(ModelError) as info:
        check_size(10**6, 10**5, 3)
    message = str(info.value)
    assert "1e+06 runs × 1e+05 partitions × 3 segments = 3e+11 partition steps" in message
    assert f"limit {MAX_WORK:.3g}" in message and "--max-work" in message


def test_normal_sizes_pass_and_the_limit_can_be_raised():
    # Chong–Kleeman's experiment: 10⁴ runs × 10⁴ partitions (about 1.5 s), on a square path
    check_size(10_000, 10_000, 8)
    with pytest.raises(ModelError):
        check_size(10**6, 10**5, 1)
    check_size(10**6, 10**5, 1, max_work=1e12)


def test_memory_is_bounded_even_with_few_partitions():
    with pytest.raises(ModelError, match="memory"):
        check_size(10**9, 1, 1, max_work=1e30)


def test_a_raised_limit_reaches_the_engine():
    mc = simulate_runs([Straight(1.0)], WheelNoise(1e-3, 1e-3), 0.4, runs=300, partitions=10,
                       seed=1, max_work=3000)
    assert mc.final.shape == (300, 3)
    with pytest.raises(ModelError, match="--max-work"):
        simulate_runs([Straight(1.0)], WheelNoise(1e-3, 1e-3), 0.4, runs=300, partitions=10,
                      seed=1, max_work=2999)


def test_cli_refuses_and_allows(run_cli):
    code, _, err = run_cli("simulate", *DIFF, "--segment", "arc:3,1", "--runs", "1000000000")
    assert code == 2 and "--max-work" in err and len(err.strip().splitlines()) == 1, err
    code, out, err = run_cli("simulate", *DIFF, "--segment", "arc:3,1", "--runs", "300",
                             "--partitions", "10", "--max-work", "3000", "--json")
    assert code == 0, err


@pytest.mark.parametrize("address", ["", " ", "foo", "tcp://", "tcp://localhost", "inproc://x"])
def test_a_malformed_scheduler_address_is_one_line(run_cli, address):
    code, _, err = run_cli("simulate", *DIFF, "--segment", "arc:3,1", "--runs", "10",
                           "--partitions", "10", "--scheduler", address)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "--scheduler" in lines[0] and "host:port" in lines[0], err


def test_runs_whose_spread_overflows_are_an_error_not_nan_statistics():
    # 10³⁰⁸ m: every pose is finite (~1e156 m) but their variance (~1e312 m²) is not
    with pytest.raises(ModelError, match="not finite"):
        with np.errstate(all="ignore"):
            simulate_runs([Straight(1e308)], WheelNoise(1e-3, 1e-3), 0.4, runs=10, partitions=5, seed=1)


@pytest.mark.parametrize("segment", ["straight:1e200", "straight:1e308", "arc:1e200,1"])
def test_cli_overflow_is_one_line(run_cli, segment):
    code, out, err = run_cli("simulate", *DIFF, "--segment", segment, "--runs", "50",
                             "--partitions", "5", "--json")
    assert code == 2, out
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: ") and "encountered" not in err, err


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_predict_refuses_partitions_beyond_memory(run_cli, engine, monkeypatch):
    import odomkit.propagate.predict as predict

    monkeypatch.setattr(predict, "predict", _must_not_start("the prediction"))
    code, _, err = run_cli("predict", *DIFF, "--segment", "arc:3,1", "--engine", engine,
                           "--partitions", "1000000000")
    assert code == 2 and "--partitions" in err and "limit" in err, err
