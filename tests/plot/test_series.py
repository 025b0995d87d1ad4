"""Figures over time (odomkit.plot.series): the printed ±2σ fraction against a direct
count, the NEES band against its closed form, the drawn data against the inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.plot import (
    band_fraction,
    draw_covariance_elements,
    draw_error_band,
    draw_method_differences,
    draw_nees,
    nees_band,
    new_figure,
)


def _axes(n):
    fig, axes = new_figure(1, n)
    return axes


def test_the_printed_band_fraction_is_the_count_of_errors_inside():
    rng = np.random.default_rng(7)
    n = 997
    sigma = np.abs(rng.normal(1.0, 0.3, (n, 3))) * [0.01, 0.02, 0.003]
    error = rng.standard_t(4, (n, 3)) * sigma  # heavier tails than the band assumes
    error[:10, 2] = np.nan  # no truth heading there
    error[20, 2] += 2 * np.pi  # a whole turn: wrapped before it is scored
    axes = _axes(3)
    draw_error_band(axes, np.arange(n) * 0.1, error, sigma)
    for c, ax in enumerate(axes):
        e = error[:, c].copy()
        if c == 2:
            e[20] -= 2 * np.pi
        count, total = 0, 0
        for value, s in zip(e, sigma[:, c], strict=True):
            if not math.isnan(value):
                total += 1
                count += abs(value) <= 2 * s
        label = [t.get_text() for t in ax.get_legend().get_texts() if "inside" in t.get_text()][0]
        assert label == f"±2σ predicted: {count / total:.3f} of {total} inside"
    assert [ax.get_ylabel() for ax in axes] == ["error in x [m]", "error in y [m]", "error in θ [rad]"]


def test_band_fraction_of_gaussian_errors_is_95_45_percent():
    rng = np.random.default_rng(1)
    frac = band_fraction(rng.standard_normal(200_000), np.ones(200_000))
    assert frac == pytest.approx(math.erf(2 / math.sqrt(2)), abs=3 * math.sqrt(0.0455 * 0.9545 / 200_000))


def test_nees_band_of_two_dof_is_the_closed_form():
    lo, hi = nees_band(2, 0.95)
    assert lo == pytest.approx(-2 * math.log(1 - 0.025), rel=1e-12)
    assert hi == pytest.approx(-2 * math.log(0.025), rel=1e-12)


def test_draw_nees_prints_the_fraction_inside_the_band_and_the_mean():
    rng = np.random.default_rng(5)
    values = rng.chisquare(2, 500) * 1.5
    values[3] = np.nan
    ax = _axes(1)[0]
    line, band, expected = draw_nees(ax, np.arange(500.0), values)
    ok = values[~np.isnan(values)]
    lo, hi = -2 * math.log(0.975), -2 * math.log(0.025)
    inside = np.mean((ok >= lo) & (ok <= hi))
    assert f"{inside:.3f} inside" in band.get_label()
    assert f"mean {ok.mean():.3g} over 499" in line.get_label()
    assert expected.get_ydata()[0] == 2


def test_covariance_elements_are_drawn_in_kellys_order():
    rng = np.random.default_rng(2)
    A = rng.normal(size=(50, 3, 3))
    cov = A @ A.transpose(0, 2, 1)
    axes = _axes(6)
    lines = draw_covariance_elements(axes, np.linspace(0, 5, 50), cov, s_label="s [m]")
    for line, (i, j) in zip(lines, [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)], strict=True):
        assert np.array_equal(line.get_ydata(), cov[:, i, j])
    assert axes[4].get_ylabel() == "σ_xθ [m·rad]" and axes[0].get_xlabel() == "s [m]"
    with pytest.raises(InputError, match="6 axes"):
        draw_covariance_elements(axes[:3], np.zeros(50), cov)


def test_method_differences_are_position_distances_from_the_reference():
    s = np.linspace(0, 10, 11)
    ref = np.column_stack([s, np.zeros(11), np.zeros(11)])
    other = ref + np.column_stack([np.full(11, 3e-3), np.full(11, 4e-3), np.ones(11)])
    far = ref + np.column_stack([np.full(11, 0.6), np.full(11, 0.8), np.zeros(11)])
    ax = _axes(1)[0]
    lines = draw_method_differences(ax, s, {"exact": ref, "midpoint": other, "euler": far}, reference="exact")
    assert np.allclose(lines[0].get_ydata(), 5e-3) and np.allclose(lines[1].get_ydata(), 1.0)
    assert ax.get_yscale() == "log"  # more than two decades apart
    with pytest.raises(InputError, match="reference"):
        draw_method_differences(ax, s, {"a": ref}, reference="b")
