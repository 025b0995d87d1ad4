"""Dask: the same blocks on a cluster give the same numbers as the local thread pool."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from odomkit.cli import main
from odomkit.errors import ModelError
from odomkit.noise import WheelNoise
from odomkit.path import Arc, Straight
from odomkit.simulate import monte_carlo, simulate_runs, simulate_sweep

distributed = pytest.importorskip("dask.distributed")

PATH = [Arc(3, 1), Straight(0.5)]


@pytest.fixture(scope="module")
def cluster():
    """Two single-threaded workers on loopback (no processes: fast to start)."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp", host="127.0.0.1", dashboard_address=None) as lc:
        yield lc


def test_cluster_results_are_bit_identical_to_local(cluster):
    kw = dict(runs=700, partitions=300, seed=9, pose0=(0, 0, 0.3), cov0=[1e-4, 1e-4, 1e-5],
              segment_ends=True)
    local = simulate_runs(PATH, WheelNoise(0.01, 0.02), 0.4, workers=1, **kw)
    with distributed.Client(cluster) as client:
        remote = simulate_runs(PATH, WheelNoise(0.01, 0.02), 0.4, scheduler=client,
                               chunk_runs=256, **kw)
    assert np.array_equal(local.final, remote.final)
    assert np.array_equal(local.segment_ends, remote.segment_ends)
    # by address, as the CLI does
    by_address = simulate_runs(PATH, WheelNoise(0.01, 0.02), 0.4,
                               scheduler=cluster.scheduler_address, chunk_runs=512, **kw)
    assert np.array_equal(local.final, by_address.final)


def test_sweep_on_cluster_equals_local_runs(cluster):
    grid = [{"noise": WheelNoise(k, k)} for k in (0.001, 0.01)] + [{"path": [Arc(15, 10)]}]
    common = dict(path=PATH, noise=WheelNoise(0.002, 0.002), wheel_base=0.4, runs=400,
                  partitions=100, seed=4)
    remote = simulate_sweep(grid, scheduler=cluster.scheduler_address, **common)
    for setting, result in zip(grid, remote, strict=True):
        local = monte_carlo(**{**common, **setting})
        assert result["setting"] == setting
        np.testing.assert_array_equal(result["simulation"]["cov"], local["simulation"]["cov"])
        assert result["verdict"] == local["verdict"]


def test_cli_scheduler_option(cluster, capsys):
    args = ["simulate", "--wheel-base", "0.4", "--k-left", "0.003", "--k-right", "0.002",
            "--segment", "arc:3,1", "--runs", "300", "--partitions", "200", "--seed", "5",
            "--json"]
    assert main(args) == 0
    local = json.loads(capsys.readouterr().out)
    assert main(args + ["--scheduler", cluster.scheduler_address]) == 0
    remote = json.loads(capsys.readouterr().out)
    assert remote["simulation"] == local["simulation"]


def test_unreachable_scheduler_is_a_user_error(monkeypatch):
    monkeypatch.setattr("odomkit.simulate.distributed.CONNECT_TIMEOUT", "1s")
    with pytest.raises(ModelError, match="Dask scheduler"):
        simulate_runs(PATH, WheelNoise(0.001, 0.001), 0.4, runs=10, partitions=5,
                      scheduler="tcp://127.0.0.1:9")


def test_local_run_does_not_import_dask():
    code = ("import sys; from odomkit.simulate import monte_carlo; "
            "from odomkit.noise import WheelNoise; from odomkit.path import Arc; "
            "monte_carlo([Arc(3, 1)], WheelNoise(1e-3, 1e-3), 0.4, runs=300, partitions=10); "
            "print(any(m == 'dask' or m.startswith('dask.') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
