"""Figures: each a function that draws on a matplotlib Axes and returns its artists.

matplotlib is the optional ``plot`` extra (``pip install 'odomkit[plot]'``); it is imported
inside the functions only, so importing this package costs nothing. Inputs are numpy
arrays with documented shapes in SI units (metres, radians, seconds).

=================================  ====================================================
function                           draws
=================================  ====================================================
:func:`draw_track`                 a track with χ²₂-scaled confidence ellipses, against truth
:func:`draw_umbmark`               UMBmark return errors, centres of gravity, E_max,syst
:func:`draw_covariance_elements`   the six covariance elements over time or distance
:func:`draw_error_band`            the true error inside the ±2σ band, fraction inside
:func:`draw_monte_carlo`           Monte Carlo end points and the predicted ellipse
:func:`draw_method_differences`    how far integration methods drift apart
:func:`draw_nees`                  NEES over time with its χ² band
:func:`draw_reliability`           predicted probability against observed coverage
:func:`draw_profile`               a profile likelihood with its χ²₁ interval
=================================  ====================================================

:func:`new_figure` makes a headless figure, :func:`save_figure` writes it (.png, .svg,
.pdf from the suffix) and :func:`figure_svg` returns it as SVG text for HTML.
"""

from __future__ import annotations

from odomkit.plot.figure import (
    FORMATS,
    check_plot_file,
    figure_svg,
    have_matplotlib,
    new_figure,
    require_matplotlib,
    save_figure,
)
from odomkit.plot.honesty import binomial_band, draw_profile, draw_reliability
from odomkit.plot.series import (
    band_fraction,
    draw_covariance_elements,
    draw_error_band,
    draw_method_differences,
    draw_nees,
    nees_band,
)
from odomkit.plot.spatial import draw_monte_carlo, draw_track, draw_umbmark, plot_noise_fit, plot_tracks

__all__ = [
    "FORMATS", "band_fraction", "binomial_band", "check_plot_file", "draw_covariance_elements",
    "draw_error_band", "draw_method_differences", "draw_monte_carlo", "draw_nees", "draw_profile",
    "draw_reliability", "draw_track", "draw_umbmark", "figure_svg", "have_matplotlib", "nees_band",
    "new_figure", "plot_noise_fit", "plot_tracks", "require_matplotlib", "save_figure",
]
