"""The "How honest is the covariance?" table for the OptiOdom differential robot
(docs/results/honesty.md) stays true: the protocol of ``benchmarks/honesty.py`` run again
on the real data, each coverage within three binomial standard errors of the page's figure
and each NEES mean within three standard errors of its sample. The targets of issue 11
(held out, 95 % in [0.88, 0.99] and 50 % in [0.40, 0.80] at 10 s AND 30 s with one fitted
model) are met at both lengths by fit-noise's defaults (slip, bias and the truth's own
noise, trimmed, fitted on both lengths) and missed at 30 s by one window end without the
truth's noise; the test asserts what the page says, including which window lengths miss
them, so a change that moves a model across a target fails here and the page must be
updated with it.
``tests/test_docs.py`` checks that :data:`README` below is the page's table.
"""

from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest

from odomkit.calibrate.fit_noise import DEFAULT_TRIM, fit_noise, noise_parameters
from odomkit.evaluate import nees
from odomkit.io.robotfile import read_robot
from odomkit.noise import LateralSlipNoise, ParameterUncertainty, SpeedNoise, WheelNoise

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
LEVELS = ("0.5", "0.9", "0.95", "0.99")

#: The differential table of docs/results/honesty.md:
#: (fit) -> {window: (coverage 50/90/95/99, NEES mean, targets met)}
README = {
    "guess": {"10s": ((0.04, 0.13, 0.18, 0.26), 67.3, False), "30s": ((0.09, 0.41, 0.48, 0.67), 10.7, False)},
    "white 10s": {"10s": ((0.75, 0.96, 0.97, 0.99), 1.71, True),
                  "30s": ((0.97, 1.00, 1.00, 1.00), 0.27, False)},
    "white+slip+bias trimmed": {"10s": ((0.51, 0.87, 0.91, 0.95), 3.80, True),
                                "30s": ((0.74, 0.97, 0.99, 1.00), 1.09, False)},
    "defaults": {"10s": ((0.52, 0.88, 0.92, 0.95), 2.88, True),
                 "30s": ((0.61, 0.96, 0.98, 0.99), 1.42, True)},
}


def _benchmark():
    spec = importlib.util.spec_from_file_location("honesty_benchmark", REPO / "benchmarks" / "honesty.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def measured(data_dir):
    """{fit: {window: score}} on the held-out half, as ``benchmarks/honesty.py`` computes it."""
    bench = _benchmark()
    root = data_dir / "optiodom"
    if not (root / "diff").is_dir():
        pytest.skip("OptiOdom data not found")
    fit_folders, held_folders = bench.split(root, "diff")
    fit_runs, held_runs = bench.runs_of(fit_folders), bench.runs_of(held_folders)
    nominal, guess = read_robot(REPO / "src/odomkit/data/optiodom_diff.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = bench.calibrate(fit_runs, nominal)
        guess_models = (*guess, ParameterUncertainty())
        params = noise_parameters(guess_models, robot, ())
        plain = (WheelNoise(0.0, 0.0), ParameterUncertainty())
        slip = (WheelNoise(0.0, 0.0), SpeedNoise(0.0), LateralSlipNoise(0.0), ParameterUncertainty())
        scored = {"guess": (plain, False, np.array([guess_models[p.model].variance_parameters()[p.name]
                                                    for p in params]))}
        fits = (("white 10s", plain, ("white",), None, None, False),
                ("white+slip+bias trimmed", slip, ("white", "bias"), bench.WINDOWS, DEFAULT_TRIM, False),
                ("defaults", slip, ("white", "bias"), bench.WINDOWS, DEFAULT_TRIM, True))
        for name, models, kinds, windows, trim, truth in fits:
            fitted = (bench.merged(fit_runs, robot, models, windows, truth) if windows
                      else bench.bases(fit_runs, robot, models, "10s"))
            fit = fit_noise([b for _, b, _ in fitted], models, robot, kinds=kinds, trim=trim)
            scored[name] = (models, truth, np.array(list(fit.variances.values())))
        held = {(models, truth): {w: bench.bases(held_runs, robot, models, w, truth) for w in ("10s", "30s")}
                for models, truth in {(plain, False), (slip, False), (slip, True)}}
    out = {}
    for name, (models, truth, v) in scored.items():
        out[name] = {}
        for w, bases in held[models, truth].items():
            score = bench.score(bases, v)
            err = np.concatenate([b.error[:, :2] for _, b, _ in bases])
            cov = np.concatenate([b.covariance(v)[:, :2, :2] for _, b, _ in bases])
            score["nees_se"] = float(np.std(nees(err, cov)) / np.sqrt(err.shape[0]))
            score["meets"] = bench.meets(score)
            out[name][w] = score
    return out


@pytest.mark.parametrize("window", ["10s", "30s"])
@pytest.mark.parametrize("fit", list(README))
def test_readme_table_within_sampling_error(measured, fit, window):
    got = measured[fit][window]
    claimed, claimed_nees, claimed_meets = README[fit][window]
    n = got["n"]
    assert n == {"10s": 467, "30s": 145}[window]  # window ends of the held-out half
    for level, p in zip(LEVELS, claimed, strict=True):
        se = np.sqrt(max(p * (1 - p), 1.0 / n) / n)
        assert abs(got["coverage"][level] - p) <= 3 * se + 0.005, (level, got["coverage"][level], p)
    assert abs(got["nees"] - claimed_nees) <= 3 * got["nees_se"] + 0.005 * claimed_nees
    assert got["meets"] is claimed_meets


def test_only_the_default_fit_meets_the_targets_at_both_lengths(measured):
    for fit in ("white 10s", "white+slip+bias trimmed"):
        assert not (measured[fit]["10s"]["meets"] and measured[fit]["30s"]["meets"])
    assert measured["defaults"]["10s"]["meets"] and measured["defaults"]["30s"]["meets"]


def test_trimmed_slip_misses_30_s_by_one_window_end(measured):
    """The page's "144 of 145": the best model's only miss."""
    got = measured["white+slip+bias trimmed"]["30s"]
    assert round(got["coverage"]["0.95"] * got["n"]) == got["n"] - 1
