"""A finding of the data checks (:mod:`odomkit.calibrate.check_finding`): its JSON form is
strict JSON whatever its figure, and it cannot be changed once made."""

from __future__ import annotations

import dataclasses
import json
import math
import typing

import numpy as np
import pytest

from odomkit.calibrate.check_finding import Finding, Status


def test_the_statuses_are_ok_warn_and_fail():
    assert set(typing.get_args(Status)) == {"ok", "warn", "fail"}


def test_a_finite_figure_reaches_the_json_as_the_same_number():
    """A numpy scalar (what the checks compute) becomes a plain float of the same value,
    and strict JSON (no NaN or Infinity tokens) round-trips every field."""
    value = np.float64(1.0) / 3.0
    found = Finding("identifiable", "warn", "E_b: weakly identified", "turn more", value)
    out = found.to_dict()
    assert type(out["value"]) is float and out["value"] == float(value)
    again = json.loads(json.dumps(out, allow_nan=False))
    assert again == {"check": "identifiable", "status": "warn", "message": "E_b: weakly identified",
                     "advice": "turn more", "value": float(value)}


@pytest.mark.parametrize("value", [None, math.inf, -math.inf, math.nan, np.float64("inf")])
def test_an_unbounded_or_missing_figure_is_null(value):
    """An unbounded standard error (a parameter the log cannot pin) has no JSON number: null."""
    out = Finding("identifiable", "fail", "not identifiable", "drive more", value).to_dict()
    assert out["value"] is None
    assert json.loads(json.dumps(out, allow_nan=False))["value"] is None


def test_a_finding_is_frozen():
    found = Finding("time", "ok", "steady")
    with pytest.raises(dataclasses.FrozenInstanceError):
        found.status = "fail"  # type: ignore[misc]
    assert found.advice is None and found.value is None
