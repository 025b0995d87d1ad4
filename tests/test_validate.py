"""The shared validators (odomkit.validate), each tested once on good and bad values."""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from odomkit import validate
from odomkit.errors import InputError, ModelError

NOT_NUMBERS = [True, False, np.True_, "1.0", None, 1 + 0j, [1.0], np.array([1.0])]
NOT_FINITE = [math.nan, math.inf, -math.inf, np.float32("nan"), 10**400]


# --- real numbers ---------------------------------------------------------------------

@pytest.mark.parametrize("value", [1, 0.5, np.float64(2.5), np.float32(0.25), np.int64(3), 10**300])
def test_positive_accepts_every_kind_of_real_number_and_returns_its_float(value):
    out = validate.positive(value, "x")
    assert type(out) is float and out == float(value)


@pytest.mark.parametrize("check, good, bad", [
    (validate.finite, [-1e300, -1, 0, -0.0, 5e-324], []),
    (validate.positive, [5e-324, 1, 1e300], [0, -0.0, -5e-324, -1]),
    (validate.non_negative, [0, -0.0, 5e-324, 7], [-5e-324, -1]),
])
def test_number_validators_on_their_boundaries(check, good, bad):
    for value in good:
        assert check(value, "x") == value
    for value in bad + NOT_FINITE + NOT_NUMBERS:
        with pytest.raises(ModelError):
            check(value, "x")


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_number_validators_agree_with_their_definition(x):
    """positive ⇔ finite and > 0; non_negative ⇔ finite and ≥ 0; finite ⇔ isfinite."""
    for check, accepts in ((validate.finite, math.isfinite(x)),
                           (validate.positive, math.isfinite(x) and x > 0),
                           (validate.non_negative, math.isfinite(x) and x >= 0)):
        if accepts:
            assert check(x, "x") == x
        else:
            with pytest.raises(ModelError):
                check(x, "x")


def test_number_messages_name_the_field_unit_and_value():
    with pytest.raises(ModelError) as info:
        validate.positive(-0.4, "DiffDrive.wheel_base", unit="m")
    assert str(info.value) == "DiffDrive.wheel_base must be a positive finite number [m], got -0.4"
    with pytest.raises(ModelError, match=r"^k_left must be a non-negative finite number, got nan$"):
        validate.non_negative(math.nan, "k_left")
    with pytest.raises(ModelError, match=r"^gyro_bias must be a finite number \[rad/s\], got True$"):
        validate.finite(True, "gyro_bias", unit="rad/s")


def test_error_factory_picks_the_exception_and_its_source():
    with pytest.raises(InputError, match=r"^log\.csv: period must be a positive"):
        validate.positive(0.0, "period", error=partial(InputError, source="log.csv"))


# --- integers --------------------------------------------------------------------------

@pytest.mark.parametrize("value", [1, 7, np.int64(3), np.uint8(255), 10**30])
def test_positive_int_accepts_integers(value):
    out = validate.positive_int(value, "runs")
    assert type(out) is int and out == value


@pytest.mark.parametrize("value", [0, -1, np.int32(0), True, False, np.True_, 1.0, 3.0, 1e9, 2.5,
                                   math.nan, "3", None])
def test_positive_int_rejects_the_rest_including_integral_floats(value):
    with pytest.raises(ModelError, match=r"^runs must be a positive integer, got "):
        validate.positive_int(value, "runs")


def test_non_negative_int_boundary():
    assert validate.non_negative_int(0, "seed") == 0
    assert validate.non_negative_int(np.int64(2**63 - 1), "seed") == 2**63 - 1
    for value in (-1, True, 0.0, None):
        with pytest.raises(ModelError, match="seed must be a non-negative integer"):
            validate.non_negative_int(value, "seed")


# --- arrays ----------------------------------------------------------------------------

def test_shape_matches_fixed_and_named_sizes():
    arr = validate.shape([[1, 2, 3], [4, 5, 6]], "poses", ("N", 3))
    assert arr.dtype == float and arr.shape == (2, 3)
    assert validate.shape(np.zeros(0), "t", ("N",)).shape == (0,)
    assert validate.shape(np.zeros((2, 2)), "cov", (2, 2)).shape == (2, 2)


@pytest.mark.parametrize("values, spec, expected", [
    (np.zeros((5, 2)), ("N", 3), r"poses must have shape \(N, 3\), got \(5, 2\)"),
    (np.zeros(5), ("N", 3), r"poses must have shape \(N, 3\), got \(5,\)"),
    (np.zeros((1, 5, 3)), ("N", 3), r"got \(1, 5, 3\)"),
    (np.zeros(4), (5,), r"poses must have shape \(5,\), got \(4,\)"),
    (["a", "b"], ("N",), r"poses must be an array of numbers"),
    ([[1, 2], [3]], ("N", 2), r"poses must be an array of numbers"),
])
def test_shape_rejects_wrong_shapes_naming_field_and_both_shapes(values, spec, expected):
    with pytest.raises(ModelError, match=expected):
        validate.shape(values, "poses", spec)


def test_finite_array_names_the_first_bad_element():
    assert validate.finite_array([1.0, -2.0], "dd").tolist() == [1.0, -2.0]
    with pytest.raises(ModelError, match=r"^dd\[1\] is nan; expected finite numbers$"):
        validate.finite_array([0.0, math.nan, math.inf], "dd")
    with pytest.raises(InputError, match=r"^errors\[2, 1\] is -inf"):
        validate.finite_array(np.array([[0, 0], [1, 1], [2, -np.inf]]), "errors", ("n", 2),
                              error=InputError)
    with pytest.raises(ModelError, match=r"^dd is inf"):
        validate.finite_array(math.inf, "dd")
    with pytest.raises(ModelError, match="shape"):
        validate.finite_array(np.zeros((3, 3)), "errors", ("n", 2))


def test_finite_array_is_not_fooled_by_a_sum_that_overflows():
    big = np.full(4, 1e308)   # every element finite, the sum is inf
    with np.errstate(over="ignore"):
        assert np.isinf(big.sum())
    assert validate.finite_array(big, "dd") is not None


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), max_size=20))
def test_finite_array_accepts_exactly_the_all_finite_arrays(values):
    if all(math.isfinite(v) for v in values):
        np.testing.assert_array_equal(validate.finite_array(values, "v"), values)
    else:
        first = next(i for i, v in enumerate(values) if not math.isfinite(v))
        with pytest.raises(ModelError, match=rf"^v\[{first}\] is "):
            validate.finite_array(values, "v")


def test_pose_accepts_three_finite_numbers_in_any_layout():
    for value in ([1, 2, 3], (1.0, 2.0, 3.0), np.array([[1, 2, 3]])):
        assert validate.pose(value).tolist() == [1.0, 2.0, 3.0]
    for bad in [(0, 0), (0, 0, 0, 0), (0, math.nan, 0), (0, 0, math.inf), ("a", 0, 0), None]:
        with pytest.raises(ModelError, match=r"^initial pose must be three finite numbers x, y, theta"):
            validate.pose(bad)
    with pytest.raises(ModelError, match="^predicted pose"):
        validate.pose((0, 0), "predicted pose")


# --- covariance ------------------------------------------------------------------------

def _rotation(a: float, b: float, c: float) -> np.ndarray:
    """An orthogonal 3x3 matrix from three angles (z-y-x rotations)."""
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rz @ ry @ rx


def test_covariance_returns_a_symmetric_matrix_identical_to_a_symmetric_input():
    cov = np.array([[4e-4, 1e-4, -2e-5], [1e-4, 9e-4, 3e-5], [-2e-5, 3e-5, 1e-3]])
    out = validate.covariance(cov, "cov0")
    assert out is not cov and np.array_equal(out, cov)
    assert np.array_equal(validate.covariance(np.zeros((3, 3))), np.zeros((3, 3)))


def test_covariance_from_variances_only_when_asked():
    np.testing.assert_array_equal(
        validate.covariance([1e-4, 2e-4, 3e-3], "initial covariance", variances=True),
        np.diag([1e-4, 2e-4, 3e-3]))
    with pytest.raises(ModelError, match=r"^initial covariance must be 3x3 \(x, y, theta\), got shape"):
        validate.covariance([1e-4, 2e-4, 3e-3], "initial covariance")
    with pytest.raises(ModelError, match="positive semi-definite"):
        validate.covariance([1e-4, -2e-4, 3e-3], "initial covariance", variances=True)


@pytest.mark.parametrize("bad, expected", [
    (np.eye(2), r"cov0 must be 3x3 \(x, y, theta\), got shape \(2, 2\)"),
    (np.eye(4), r"got shape \(4, 4\)"),
    ([["a", 0, 0], [0, 1, 0], [0, 0, 1]], "cov0 must be a 3x3 matrix of numbers"),
    (np.diag([1.0, np.nan, 1.0]), "cov0 must hold finite numbers"),
    (np.diag([1.0, np.inf, 1.0]), "cov0 must hold finite numbers"),
    ([[1, 2, 0], [0, 1, 0], [0, 0, 1]], "cov0 must be symmetric"),
    ([[1, 1e-6, 0], [0, 1, 0], [0, 0, 1]], "cov0 must be symmetric"),
    ([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "cov0 must be positive semi-definite"),  # eig 3, 1, −1
    (np.diag([1.0, 1.0, -1e-9]), "cov0 must be positive semi-definite"),
])
def test_covariance_rejects(bad, expected):
    with pytest.raises(ModelError, match=expected):
        validate.covariance(bad, "cov0")


def test_covariance_of_other_sizes():
    assert validate.covariance(np.eye(2), "P", size=2).shape == (2, 2)
    with pytest.raises(ModelError, match=r"^P must be 2x2, got shape \(3, 3\)"):
        validate.covariance(np.eye(3), "P", size=2)


def test_rounding_is_not_an_error():
    """A singular covariance computed in floating point (rank 1: v·vᵀ rotated) has
    eigenvalues a few ulps below zero and asymmetry of rounding; both are accepted and the
    result is exactly symmetric."""
    q = _rotation(0.3, -1.1, 2.0)
    cov = q @ np.diag([1.0, 1e-3, 0.0]) @ q.T
    assert np.min(np.linalg.eigvalsh(cov)) < 0.0       # the premise: rounding went negative
    cov[0, 1] += 1e-15                                   # and rounding-level asymmetry
    out = validate.covariance(cov, "cov0")
    assert np.array_equal(out, out.T)
    np.testing.assert_allclose(out, cov, rtol=0, atol=1e-15)
    validate.covariance(np.diag([1.0, 1.0, -1e-14]), "cov0")      # −1e-14 of the scale: rounding


@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3),
       st.lists(st.floats(0, 1), min_size=3, max_size=3),
       st.floats(-12, 6))
def test_covariance_accepts_psd_and_rejects_negative_eigenvalues_at_any_scale(a, b, c, eig, log_scale):
    """Built from eigenvalues we chose, so the truth is known: non-negative ones pass at
    any scale; one eigenvalue of −1e-6 of the largest fails."""
    q = _rotation(a, b, c)
    scale = 10.0**log_scale
    lam = np.array(eig) * scale
    lam[0] = scale                           # the largest entry is of order `scale`
    good = q @ np.diag(lam) @ q.T
    good = 0.5 * (good + good.T)
    np.testing.assert_allclose(validate.covariance(good, "cov0"), good, rtol=0, atol=0)
    bad_lam = lam.copy()
    bad_lam[1] = -1e-6 * scale
    bad = q @ np.diag(bad_lam) @ q.T
    with pytest.raises(ModelError, match="positive semi-definite"):
        validate.covariance(0.5 * (bad + bad.T), "cov0")


def test_everything_is_exported():
    assert set(validate.__all__) >= {"finite", "positive", "non_negative", "positive_int",
                                     "non_negative_int", "shape", "finite_array", "pose",
                                     "covariance"}
