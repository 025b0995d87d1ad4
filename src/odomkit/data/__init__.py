"""Built-in sample data (OptiOdom, MIT licence: see LICENSE-OptiOdom.txt).

Six differential-drive experiments of the OptiOdom dataset (Sousa et al. 2022), copied
unchanged: the UMBmark square 230620202042 in this folder (the files most examples and
tests name), and five more under ``optiodom/<kind>/<id>/`` (the dataset's own sub-paths).
Every metadata file lists the same nominal robot (``optiodom_diff.toml``).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["OPTIODOM_EXPERIMENTS", "builtin_data_path", "builtin_experiment_path"]

#: The built-in OptiOdom experiments: id -> (kind of path, folder inside ``odomkit/data``;
#: "" is the data folder itself). Runs and durations: 230620202042 6 x 90 s (0.75 m
#: UMBmark square), 231220200045 2 x 70 s (1.7 m square), 231220200150 2 x 76 s and
#: 231220200154 2 x 51 s (circles), 030120210001 2 runs and 030120210006 4 runs (free
#: paths, 80-125 s each).
OPTIODOM_EXPERIMENTS: dict[str, tuple[str, str]] = {
    "230620202042": ("square", ""),
    "231220200045": ("square", "optiodom/square/231220200045"),
    "231220200154": ("circular", "optiodom/circular/231220200154"),
    "231220200150": ("circular", "optiodom/circular/231220200150"),
    "030120210001": ("free", "optiodom/free/030120210001"),
    "030120210006": ("free", "optiodom/free/030120210006"),
}


def builtin_data_path(name: str) -> Path:
    """Path of a file shipped in ``odomkit/data`` (``name`` may hold ``/``).

    Examples
    --------
    >>> builtin_data_path("optiodom_diff.toml").name
    'optiodom_diff.toml'
    """
    return Path(str(resources.files("odomkit.data").joinpath(name)))


def builtin_experiment_path(experiment: str) -> Path:
    """The folder of a built-in OptiOdom experiment (its ``<id>_metadata.csv`` and
    ``<id>_run-NN.csv`` files, for :func:`odomkit.io.optiodom.read_experiment`).

    Examples
    --------
    >>> sorted(p.name for p in builtin_experiment_path("231220200154").iterdir())
    ['231220200154_metadata.csv', '231220200154_run-01.csv', '231220200154_run-02.csv']
    """
    try:
        _, folder = OPTIODOM_EXPERIMENTS[experiment]
    except KeyError:
        raise KeyError(f"no built-in experiment {experiment!r}; there are "
                       f"{', '.join(OPTIODOM_EXPERIMENTS)}") from None
    base = Path(str(resources.files("odomkit.data")))
    return base / folder if folder else base
