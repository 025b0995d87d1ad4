"""The optional numba kernels (extra ``odomkit[fast]``): one lazy loader, one njit setup.

Three hot loops have a compiled kernel module: dead reckoning
(``odomkit._integrate_numba``), the covariance recursion (``odomkit.propagate._numba``)
and the Monte Carlo engine (``odomkit.simulate._numba``). Each has a numpy fallback, so
numba stays optional and is not imported until a kernel is wanted: importing it costs
about half a second. Their users call :func:`load` with the module's name; the kernel
modules themselves decorate with :func:`njit`, so every kernel shares one configuration.

numba caches compiled kernels on disk keyed by the kernel module's own source file. It
does not notice edits to the plain functions a kernel inlines from
:mod:`odomkit.angles`: after changing those, delete the ``__pycache__/*.nbi``/``*.nbc``
files of the kernel modules (or touch the modules) so they recompile.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable
from types import ModuleType
from typing import Any

__all__ = ["NJIT_OPTIONS", "load", "njit"]

NJIT_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True}
"""Options of every odomkit kernel: compiled code cached on disk (no recompilation in
each process); the GIL released (threads may run kernels side by side). No fastmath by
default: without it LLVM keeps the operation order, so the numbers do not depend on
vectorisation or chunking. A kernel may add or override options (``njit(fastmath=True)``)."""

_cache: dict[str, ModuleType | None] = {}
_jitted: dict[tuple[Any, ...], Any] = {}


def load(name: str, stacklevel: int = 3) -> ModuleType | None:
    """The kernel module ``odomkit.<name>``, imported on first use and cached.

    Parameters
    ----------
    name : str
        Module path below ``odomkit``, e.g. ``"propagate._numba"``.
    stacklevel : int
        Passed to :func:`warnings.warn` (the default points at the caller's caller).

    Returns
    -------
    module or None
        None when the import fails (numba is not installed): then one warning, naming
        the ``odomkit[fast]`` extra, is given per module and the caller falls back to
        numpy. The outcome is cached either way.

    Examples
    --------
    >>> load("propagate._numba") is load("propagate._numba")
    True
    """
    if name not in _cache:
        try:
            module: ModuleType | None = importlib.import_module(f"odomkit.{name}")
        except ImportError as exc:  # numba is the optional extra odomkit[fast]
            warnings.warn(f"numba is not installed (importing odomkit.{name} failed: {exc}); "
                          "falling back to numpy, which is much slower. Install the extra: "
                          "pip install 'odomkit[fast]'", stacklevel=stacklevel)
            module = None
        _cache[name] = module
    return _cache[name]


def njit(func: Callable[..., Any] | None = None, **options: Any) -> Any:
    """:func:`numba.njit` with :data:`NJIT_OPTIONS`, updated by ``options``.

    Use as ``@njit``, ``@njit(parallel=True)`` or ``njit(f, inline="always")``; the last
    form compiles a plain function defined elsewhere (e.g. the scalar functions of
    :mod:`odomkit.angles`), once per set of options. Imports numba, so only kernel
    modules call it.
    """
    import numba

    merged = {**NJIT_OPTIONS, **options}
    if func is None:
        return numba.njit(**merged)
    key = (func, tuple(sorted(merged.items())))
    if key not in _jitted:
        _jitted[key] = numba.njit(**merged)(func)
    return _jitted[key]
