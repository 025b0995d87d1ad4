"""Figures without a display: make one, save it, or get it as SVG text.

matplotlib is the optional ``plot`` extra and is imported inside the functions only, so
that ``import odomkit.plot`` (and ``odomkit --help``) stays light. Figures are made from
:class:`matplotlib.figure.Figure` with the Agg canvas, never through ``pyplot``: no global
state, no window, no backend switch in a user's own session.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["FORMATS", "check_plot_file", "figure_svg", "have_matplotlib", "new_figure",
           "require_matplotlib", "save_figure", "thin"]

#: The file formats :func:`save_figure` writes, by suffix.
FORMATS = (".png", ".svg", ".pdf")
#: Resolution of PNG files [dots per inch].
PNG_DPI = 110
#: Most vertices a drawn line keeps (:func:`thin`): a 100 000-row log drawn in full makes
#: megabytes of SVG and looks the same.
MAX_VERTICES = 4000


def have_matplotlib() -> bool:
    """Whether the optional ``plot`` extra (matplotlib) is installed."""
    import importlib.util

    return importlib.util.find_spec("matplotlib") is not None


def require_matplotlib(flag: str = "--plot") -> None:
    """Raise :class:`~odomkit.errors.InputError` naming the ``plot`` extra when matplotlib
    is missing (the one-line error of every ``--plot``)."""
    if not have_matplotlib():
        raise InputError(f"{flag} needs matplotlib: pip install 'odomkit[plot]'")


def check_plot_file(path: str | Path, flag: str = "--plot") -> Path:
    """Check a figure path before anything is computed: its suffix names a format of
    :data:`FORMATS` and matplotlib is installed. (Whether the file may be written is
    :func:`odomkit.io.files.check_outputs`'s job.)

    >>> check_plot_file("track.jpg")
    Traceback (most recent call last):
    ...
    odomkit.errors.InputError: track.jpg: --plot writes .png, .svg or .pdf (the format comes from the suffix)
    """
    target = Path(path)
    if target.suffix.lower() not in FORMATS:
        raise InputError(f"{flag} writes .png, .svg or .pdf (the format comes from the suffix)",
                         source=str(path))
    require_matplotlib(flag)
    return target


def new_figure(nrows: int = 1, ncols: int = 1, *, mosaic: str | Sequence[Sequence[str]] | None = None,
               size: tuple[float, float] | None = None) -> tuple[Figure, list[Axes] | dict[str, Axes]]:
    """A headless figure (Agg canvas) with a grid of axes, or axes named by a ``mosaic``
    (:meth:`matplotlib.figure.Figure.subplot_mosaic`).

    Parameters
    ----------
    nrows, ncols : int
        The grid, when no ``mosaic`` is given.
    mosaic : str or nested lists of str, optional
        Named panels, e.g. ``"AB;CD"``.
    size : (width, height), optional
        Inches; default 4.5 × 3.6 per panel.

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : list of Axes (row by row), or dict of Axes by name with a mosaic
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if mosaic is not None:
        rows = mosaic.split(";") if isinstance(mosaic, str) else mosaic
        nrows, ncols = len(rows), max(len(r) for r in rows)
    fig = Figure(figsize=size or (4.5 * ncols, 3.6 * nrows), layout="constrained")
    FigureCanvasAgg(fig)
    if mosaic is not None:
        if isinstance(mosaic, str):
            return fig, dict(fig.subplot_mosaic(mosaic))
        return fig, {str(k): v for k, v in fig.subplot_mosaic([list(r) for r in mosaic]).items()}
    grid = fig.subplots(nrows, ncols, squeeze=False)
    return fig, [ax for row in grid for ax in row]


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` in the format its suffix names (.png, .svg, .pdf).

    The caller checks first whether the file may be written
    (:func:`odomkit.io.files.check_outputs`); this writes. SVG and PDF carry no date, so
    the same figure gives the same file.
    """
    target = Path(path)
    fmt = target.suffix.lower().lstrip(".")
    if f".{fmt}" not in FORMATS:
        raise InputError("figures are written as .png, .svg or .pdf (the format comes from the suffix)",
                         source=str(path))
    metadata = {"png": {"Software": None}, "svg": {"Date": None}, "pdf": {"CreationDate": None}}[fmt]
    with _fixed_ids():
        fig.savefig(target, format=fmt, dpi=PNG_DPI, metadata=metadata)
    return target


def _fixed_ids() -> AbstractContextManager[None]:
    """SVG element ids from a fixed salt, not a random one: the same figure, the same file."""
    import matplotlib

    return matplotlib.rc_context({"svg.hashsalt": "odomkit"})


def figure_svg(fig: Figure) -> str:
    """``fig`` as SVG text starting at its ``<svg`` element, ready to be embedded in HTML
    (text is drawn as paths: no font is needed to show it)."""
    buffer = io.StringIO()
    with _fixed_ids():
        fig.savefig(buffer, format="svg", metadata={"Date": None})
    text = buffer.getvalue()
    return text[text.find("<svg"):]


def thin(n: int, most: int = MAX_VERTICES) -> NDArray[np.intp]:
    """Row indices that draw a line of ``n`` points with at most about ``most`` vertices
    (evenly spaced; the first and last row always kept).

    >>> thin(10, 4).tolist()
    [0, 3, 6, 9]
    >>> thin(3).tolist()
    [0, 1, 2]
    """
    if n <= most:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, most).round().astype(np.intp))
