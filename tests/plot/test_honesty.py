"""The coverage diagram and the profile figure (odomkit.plot.honesty): the binomial band
against exact binomial sums (math.comb), the threshold against χ²₁(0.95) to 16 digits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.plot import binomial_band, draw_profile, draw_reliability, new_figure

CHI2_1_95 = 3.841458820694124  # χ²₁(0.95) = 1.959963984540054²


def _axes():
    fig, axes = new_figure()
    return axes[0]


def _quantile(q, n, p):
    """Smallest k with P(K ≤ k) ≥ q for K ~ Binomial(n, p), by exact summation."""
    total = 0.0
    for k in range(n + 1):
        total += math.comb(n, k) * p**k * (1 - p) ** (n - k)
        if total >= q * (1 - 1e-12):
            return k
    return n


@pytest.mark.parametrize("n", [20, 54, 300])
def test_the_band_is_the_binomial_range_of_the_fraction(n):
    levels = np.array([0.5, 0.9, 0.95, 0.99])
    lo, hi = binomial_band(levels, n)
    assert lo.tolist() == [_quantile(0.025, n, p) / n for p in levels]
    assert hi.tolist() == [_quantile(0.975, n, p) / n for p in levels]


def test_the_drawn_band_and_the_series():
    ax = _axes()
    covers = {"white": {"0.5": 0.41, "0.9": 0.8, "0.95": 0.86, "0.99": None},
              "white + bias": {0.5: 0.52, 0.9: 0.88, 0.95: 0.94, 0.99: 0.985}}
    artists = draw_reliability(ax, covers, n_scored=120)
    diagonal, band, white, both = artists
    assert np.array_equal(white.get_xdata(), [0.5, 0.9, 0.95])  # None left out
    assert np.array_equal(both.get_ydata(), [0.52, 0.88, 0.94, 0.985])
    # The band's polygon at p = 0.9 spans the binomial 95 % range of 120 samples.
    verts = band.get_paths()[0].vertices
    near = verts[np.abs(verts[:, 0] - 0.9) < 2e-3, 1]
    assert near.min() == pytest.approx(_quantile(0.025, 120, 0.9) / 120, abs=1 / 120)
    assert near.max() == pytest.approx(_quantile(0.975, 120, 0.9) / 120, abs=1 / 120)
    assert "95 % range of 120 independent samples" in band.get_label()
    assert ax.get_xlabel() == "predicted probability of the ellipse"


def test_without_a_sample_count_there_is_no_band():
    ax = _axes()
    artists = draw_reliability(ax, {"track rows": {"0.5": 0.1, "0.95": 0.6}})
    assert len(artists) == 2  # diagonal and the series: rows of one run are not independent


def test_profile_deviance_threshold_and_interval():
    ax = _axes()
    x = np.linspace(1.0, 3.0, 41)
    ll = -0.5 * ((x - 2.0) / 0.25) ** 2 - 100.0
    curve, line, span, mark = draw_profile(ax, x, ll, interval=(2 - 0.49, 2 + 0.49), name="k_left",
                                           unit="m^½", estimate=2.0)
    assert np.allclose(curve.get_ydata(), ((x - 2.0) / 0.25) ** 2)
    assert line.get_ydata()[0] == pytest.approx(CHI2_1_95, rel=1e-12)
    assert ax.get_xlabel() == "k_left [m^½]"
    assert "95 % interval [1.51, 2.49]" in span.get_label()


def test_an_open_interval_is_said_to_be_open():
    ax = _axes()
    x = np.linspace(0.0, 1.0, 11)
    _, _, span = draw_profile(ax, x, np.zeros(11), interval=(0.0, math.inf), name="sigma_dt")
    assert "∞ (open" in span.get_label()
