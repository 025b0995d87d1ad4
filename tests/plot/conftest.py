"""Figures need the optional ``plot`` extra: these tests skip without matplotlib."""

from __future__ import annotations

import pytest

pytest.importorskip("matplotlib")


@pytest.fixture()
def png_is_drawn():
    """The check below, as a fixture (test modules do not import each other)."""
    return _png_is_drawn


def _png_is_drawn(path) -> bool:
    """A PNG that decodes and is not blank: more than 1 % of its pixels differ from the
    most common colour (the background)."""
    import numpy as np
    from matplotlib.image import imread

    img = imread(path)
    flat = img.reshape(-1, img.shape[-1])
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    return img.shape[0] > 50 and img.shape[1] > 50 and 1.0 - counts.max() / flat.shape[0] > 0.01
