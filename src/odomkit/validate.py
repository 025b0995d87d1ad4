"""Validators for numbers, arrays and covariances, written once (issue 9).

Each validator returns its argument in canonical form (``float``, ``int`` or a float
array) or raises one error whose one-line message names the field and says what was
expected (docs/reference/commands/index.md, "What every command shares"), e.g.
``DiffDrive.wheel_base must be a positive finite number, got -0.4``. The error is
:class:`~odomkit.errors.ModelError` unless the caller passes ``error=``: any callable that
takes the message, such as :class:`~odomkit.errors.InputError` or
``functools.partial(InputError, source=path)``.

What counts as what
-------------------
real number
    ``int``, ``float`` or a numpy integer or floating scalar. ``bool`` is not a number
    here (``DiffDrive(True)`` is a bug, not a wheel base of 1 m), nor is a string:
    text is parsed at the edges (``io/``, ``cli/``), never here.
integer
    ``int`` or a numpy integer, never ``bool``. A float is rejected *even when it is
    integral* (``1e9``, ``3.0``): one rule for every count (runs, partitions, seeds,
    decimation), no silent rounding of ``2.5``, and a count that arrives as a float is a
    mistake upstream that is better named than hidden.
covariance
    A finite, symmetric, positive semi-definite matrix. Asymmetry up to 1e-9 of the
    largest entry and negative eigenvalues down to −1e-12 of it are rounding (a matrix
    computed as J·P·Jᵀ, or typed with 17 digits), not errors: the matrix is accepted and
    returned symmetrised.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from odomkit.errors import ModelError, OdomkitError

__all__ = [
    "ErrorFactory",
    "covariance",
    "finite",
    "finite_array",
    "non_negative",
    "non_negative_int",
    "pose",
    "positive",
    "positive_int",
    "shape",
]

ErrorFactory = Callable[[str], OdomkitError]
"""What raises: called with the message, returns the exception to raise."""

# Asymmetry a covariance may have and still be symmetric, relative to its largest entry:
# far above the ~1e-16 of rounding, far below any hand-typed asymmetry.
_SYMMETRY_RTOL = 1e-9
# Negative eigenvalue a PSD matrix may show from rounding, relative to its largest entry
# (eigvalsh of a 3x3 is accurate to a few ulps of the largest eigenvalue).
_PSD_RTOL = 1e-12


def _unit(unit: str | None) -> str:
    return f" [{unit}]" if unit else ""


def _as_real(value: object) -> float | None:
    """``value`` as a float if it is a real number (see module docstring), else None."""
    if isinstance(value, bool | np.bool_) or not isinstance(
        value, int | float | np.integer | np.floating
    ):
        return None
    try:
        return float(value)
    except OverflowError:  # an int beyond float range: not a finite number
        return math.inf


def finite(value: object, name: str, *, unit: str | None = None,
           error: ErrorFactory = ModelError) -> float:
    """A finite real number.

    Parameters
    ----------
    value : object
        The number to check.
    name : str
        Field name for the message, e.g. ``"Tricycle.steering_offset"``.
    unit : str, optional
        Unit shown in the message, e.g. ``"m"`` gives ``... finite number [m], got ...``.
    error : callable, optional
        Exception factory (default :class:`~odomkit.errors.ModelError`).

    Returns
    -------
    float

    Examples
    --------
    >>> finite(-2, "gyro_bias")
    -2.0
    >>> finite(float("nan"), "gyro_bias", unit="rad/s")
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: gyro_bias must be a finite number [rad/s], got nan
    """
    x = _as_real(value)
    if x is None or not math.isfinite(x):
        raise error(f"{name} must be a finite number{_unit(unit)}, got {value!r}")
    return x


def positive(value: object, name: str, *, unit: str | None = None,
             error: ErrorFactory = ModelError) -> float:
    """A finite real number > 0 (parameters as in :func:`finite`).

    Examples
    --------
    >>> positive(0.4, "wheel_base", unit="m")
    0.4
    >>> positive(0, "wheel_base", unit="m")
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: wheel_base must be a positive finite number [m], got 0
    """
    x = _as_real(value)
    if x is None or not (math.isfinite(x) and x > 0):
        raise error(f"{name} must be a positive finite number{_unit(unit)}, got {value!r}")
    return x


def non_negative(value: object, name: str, *, unit: str | None = None,
                 error: ErrorFactory = ModelError) -> float:
    """A finite real number >= 0 (parameters as in :func:`finite`); −0.0 is zero.

    Examples
    --------
    >>> non_negative(0, "k_left", unit="m^½")
    0.0
    """
    x = _as_real(value)
    if x is None or not (math.isfinite(x) and x >= 0):
        raise error(f"{name} must be a non-negative finite number{_unit(unit)}, got {value!r}")
    return x


def _as_int(value: object) -> int | None:
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        return None
    return int(value)


def positive_int(value: object, name: str, *, error: ErrorFactory = ModelError) -> int:
    """An integer >= 1; bool and floats (even ``3.0``) are rejected.

    Examples
    --------
    >>> positive_int(np.int64(3), "runs")
    3
    >>> positive_int(1e3, "runs")
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: runs must be a positive integer, got 1000.0
    """
    n = _as_int(value)
    if n is None or n < 1:
        raise error(f"{name} must be a positive integer, got {value!r}")
    return n


def non_negative_int(value: object, name: str, *, error: ErrorFactory = ModelError) -> int:
    """An integer >= 0; bool and floats are rejected.

    Examples
    --------
    >>> non_negative_int(0, "seed")
    0
    """
    n = _as_int(value)
    if n is None or n < 0:
        raise error(f"{name} must be a non-negative integer, got {value!r}")
    return n


def _shape_text(spec: Sequence[int | str]) -> str:
    return "(" + ", ".join(str(s) for s in spec) + ("," if len(spec) == 1 else "") + ")"


def _as_float_array(values: ArrayLike, name: str, error: ErrorFactory) -> NDArray[np.float64]:
    try:
        return np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{name} must be an array of numbers, got {values!r}") from None


def shape(values: ArrayLike, name: str, spec: Sequence[int | str], *,
          error: ErrorFactory = ModelError) -> NDArray[np.float64]:
    """A float array whose shape matches ``spec``.

    Parameters
    ----------
    values : array_like
    name : str
        Field name for the message.
    spec : sequence of int or str
        The expected shape; a str entry (``"N"``) matches any length and names it in the
        message.
    error : callable, optional
        Exception factory (default :class:`~odomkit.errors.ModelError`).

    Returns
    -------
    ndarray of float, shape matching ``spec``

    Examples
    --------
    >>> shape(np.zeros((5, 3)), "poses", ("N", 3)).shape
    (5, 3)
    >>> shape(np.zeros((5, 2)), "poses", ("N", 3))
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: poses must have shape (N, 3), got (5, 2)
    """
    arr = _as_float_array(values, name, error)
    ok = arr.ndim == len(spec) and all(
        isinstance(want, str) or got == want for got, want in zip(arr.shape, spec, strict=True)
    )
    if not ok:
        raise error(f"{name} must have shape {_shape_text(spec)}, got {arr.shape}")
    return arr


def finite_array(values: ArrayLike, name: str, spec: Sequence[int | str] | None = None, *,
                 error: ErrorFactory = ModelError) -> NDArray[np.float64]:
    """A float array of finite numbers (and of shape ``spec`` if given, see :func:`shape`).

    The message names the first non-finite element: ``dd[1] is nan; expected finite
    numbers``.

    Examples
    --------
    >>> finite_array([1.0, float("inf")], "dd")
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: dd[1] is inf; expected finite numbers
    """
    arr = _as_float_array(values, name, error) if spec is None else shape(values, name, spec,
                                                                          error=error)
    # A sum is NaN or inf if any term is, and costs no temporary array; only then look
    # for the culprit (a sum that merely overflowed finds none and passes).
    with np.errstate(over="ignore"):
        total = arr.sum()
    if not np.isfinite(total) and not np.all(np.isfinite(arr)):
        if arr.ndim == 0:
            raise error(f"{name} is {arr}; expected a finite number")
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        index = ", ".join(str(i) for i in bad)
        raise error(f"{name}[{index}] is {arr[bad]}; expected finite numbers")
    return arr


def pose(values: ArrayLike, name: str = "initial pose", *,
         error: ErrorFactory = ModelError) -> NDArray[np.float64]:
    """A planar pose: three finite numbers ``x`` [m], ``y`` [m], ``θ`` [rad], shape (3,).

    Any array of three elements is accepted (a (1, 3) row too).

    Examples
    --------
    >>> pose([1, 2, 0.5]).tolist()
    [1.0, 2.0, 0.5]
    >>> pose((0, 0))
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: initial pose must be three finite numbers x, y, theta; got (0, 0)
    """
    try:
        p = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        p = np.empty(0)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise error(f"{name} must be three finite numbers x, y, theta; got {values!r}")
    return p


def covariance(cov: ArrayLike, name: str = "covariance", *, size: int = 3,
               variances: bool = False, error: ErrorFactory = ModelError) -> NDArray[np.float64]:
    """A finite, symmetric, positive semi-definite ``size × size`` covariance.

    Parameters
    ----------
    cov : array_like, shape (size, size), or (size,) if ``variances``
        The matrix; order x, y, θ for a pose covariance [m², m², rad²].
    name : str
        Field name for the message, e.g. ``"initial covariance"``.
    size : int
        Matrix dimension (3 for a planar pose).
    variances : bool
        Also accept ``size`` variances, the diagonal of an uncorrelated covariance.
    error : callable, optional
        Exception factory (default :class:`~odomkit.errors.ModelError`).

    Returns
    -------
    ndarray, shape (size, size)
        ``(C + Cᵀ)/2``: bit-identical to ``C`` when C is exactly symmetric.

    Examples
    --------
    >>> covariance([1e-4, 1e-4, 1e-3], "initial covariance", variances=True).diagonal().tolist()
    [0.0001, 0.0001, 0.001]
    >>> covariance([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "cov0")   # eigenvalues 3, 1, −1
    Traceback (most recent call last):
    ...
    odomkit.errors.ModelError: cov0 must be positive semi-definite (no negative variance \
along any direction), got [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    axes = " (x, y, theta)" if size == 3 else ""
    try:
        arr = np.asarray(cov, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{name} must be a {size}x{size} matrix of numbers, got {cov!r}") from None
    if variances and arr.shape == (size,):
        arr = np.diag(arr)
    if arr.shape != (size, size):
        want = f"{size} variances or a {size}x{size} matrix" if variances else f"{size}x{size}"
        raise error(f"{name} must be {want}{axes}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise error(f"{name} must hold finite numbers, got {arr.tolist()}")
    scale = float(np.max(np.abs(arr)))
    if np.any(np.abs(arr - arr.T) > _SYMMETRY_RTOL * scale):
        raise error(f"{name} must be symmetric, got {arr.tolist()}")
    sym = 0.5 * (arr + arr.T)
    if scale > 0 and float(np.min(np.linalg.eigvalsh(sym))) < -_PSD_RTOL * scale:
        raise error(f"{name} must be positive semi-definite (no negative variance along any "
                    f"direction), got {arr.tolist()}")
    return sym
