"""odomkit.workflows.results: what a command returns is finite and its covariances PSD, and
numeric trouble is one ModelError naming it (issue 10, item 8)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.workflows.results import RESULT_RTOL, check_result, numeric_guard


def test_finite_results_and_skipped_nones_pass():
    check_result("the fit", {"k": 1e-3, "mean": [0.0, -2.0], "not computed": None,
                             "nested": {"cw": [1.0, 2.0]}},
                 {"cov": np.eye(3), "track covs": np.stack([np.eye(3)] * 4), "none": None})


@pytest.mark.parametrize("value, shown", [(math.inf, "inf"), (-math.inf, "-inf"), (math.nan, "nan")])
def test_a_non_finite_number_is_named(value, shown):
    with pytest.raises(ModelError, match=rf"^the track: the poses is not finite \({shown}\); "):
        check_result("the track", {"the poses": [[0.0, 1.0, value]]})


def test_a_nested_entry_is_named_by_its_path():
    with pytest.raises(ModelError, match="UMBmark: cg.ccw is not finite"):
        check_result("UMBmark", {"cg": {"cw": [0.0, 0.0], "ccw": [math.nan, 0.0]}})


def test_a_covariance_must_be_symmetric_psd():
    bad = np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])   # eigenvalue −1
    with pytest.raises(ModelError, match="not a covariance"):
        check_result("the prediction", {}, {"the covariance": bad})
    skew = np.eye(3)
    skew[0, 1] = 1e-3
    with pytest.raises(ModelError, match="not a covariance"):
        check_result("the prediction", {}, {"the covariance": skew})
    # rounding of a long recursion is not a defect; the last of a stack is the one checked
    rounded = np.diag([1.0, 1e-20, 1.0])
    rounded[1, 1] = -0.1 * RESULT_RTOL
    check_result("the track", {}, {"the covariance": np.stack([bad, rounded])})
    # any non-finite entry of a stack fails
    stack = np.stack([np.eye(3), np.eye(3)])
    stack[0, 2, 2] = math.inf
    with pytest.raises(ModelError, match="not finite"):
        check_result("the track", {}, {"the covariance": stack})


def test_the_guard_silences_numpy_and_turns_overflow_into_one_error():
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # a RuntimeWarning would raise here
        with numeric_guard("the track"):
            assert np.isinf(np.float64(1e300) * 1e300)
            assert np.isnan(np.zeros(1) / 0.0)[0]
    with pytest.raises(ModelError, match="the noise fit: a number overflowed"):
        with numeric_guard("the noise fit"):
            _ = 1e200 ** 2.0
    with pytest.raises(ModelError, match="the track: the numerics failed"):
        with numeric_guard("the track"):
            np.linalg.inv(np.zeros((3, 3)))


def test_the_guard_lets_other_errors_through():
    with pytest.raises(KeyError):
        with numeric_guard("the track"):
            raise KeyError("a bug stays a bug")
