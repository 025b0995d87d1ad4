"""Saving figures (odomkit.plot.figure): the format follows the suffix, a PNG is drawn,
SVG text embeds, a wrong suffix or a missing matplotlib is one clear error."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.plot import check_plot_file, figure_svg, new_figure, save_figure
from odomkit.plot.figure import thin

MAGIC = {".png": b"\x89PNG\r\n\x1a\n", ".svg": b"<?xml", ".pdf": b"%PDF-"}


def _figure():
    fig, axes = new_figure()
    axes[0].plot([0, 1, 2], [0, 1, 0])
    return fig


@pytest.mark.parametrize("suffix", sorted(MAGIC))
def test_the_suffix_names_the_format(tmp_path, suffix):
    path = save_figure(_figure(), tmp_path / f"f{suffix}")
    assert path.read_bytes().startswith(MAGIC[suffix])


def test_a_png_is_not_blank_and_a_blank_one_is_seen(tmp_path, png_is_drawn):
    assert png_is_drawn(save_figure(_figure(), tmp_path / "f.png"))
    fig, axes = new_figure()
    axes[0].set_axis_off()
    assert not png_is_drawn(save_figure(fig, tmp_path / "blank.png"))


def test_the_same_figure_gives_the_same_svg_and_pdf(tmp_path):
    for suffix in (".svg", ".pdf"):
        a = save_figure(_figure(), tmp_path / f"a{suffix}").read_bytes()
        b = save_figure(_figure(), tmp_path / f"b{suffix}").read_bytes()
        assert a == b


def test_figure_svg_is_an_svg_element():
    text = figure_svg(_figure())
    assert text.startswith("<svg") and text.rstrip().endswith("</svg>")


@pytest.mark.parametrize("name", ["f.jpg", "f", "f.PNG.txt"])
def test_an_unknown_suffix_is_refused(name, tmp_path):
    with pytest.raises(InputError, match=r"--plot writes \.png, \.svg or \.pdf"):
        check_plot_file(tmp_path / name)
    with pytest.raises(InputError):
        save_figure(_figure(), tmp_path / name)


def test_a_missing_matplotlib_names_the_plot_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(InputError, match=r"--plot needs matplotlib: pip install 'odomkit\[plot\]'"):
        check_plot_file("f.png")


def test_thin_keeps_the_ends_and_bounds_the_count():
    rows = thin(100_001, 4000)
    assert rows[0] == 0 and rows[-1] == 100_000 and len(rows) <= 4000
    assert np.all(np.diff(rows) > 0)


def test_importing_the_package_loads_no_matplotlib():
    import subprocess

    code = "import sys, odomkit.plot; print(any(m.startswith('matplotlib') for m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "False", done.stderr
