"""odomkit.path: segment parsing and wheel travel against hand geometry."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import diff_body_steps
from odomkit.path import Arc, KellyArc, Spin, SteerArc, Straight, parse_segment


@pytest.mark.parametrize("text, model, expected", [
    ("arc:3,1", "diff", Arc(3.0, 1.0)),
    ("arc:-0.5,2e-1", "diff", Arc(-0.5, 0.2)),
    ("ARC :3,1", "diff", Arc(3.0, 1.0)),
    ("straight:2", "diff", Straight(2.0)),
    ("spin:-1.5", "diff", Spin(-1.5)),
    ("arc:0.5,0.2,10", "gyro", KellyArc(0.5, 0.2, 10.0)),
    ("straight:0.5,10", "gyro", KellyArc(0.5, 0.0, 10.0)),
    ("arc:1,-0.1,0", "compass", KellyArc(1.0, -0.1, 0.0)),
])
def test_parse_segment(text, model, expected):
    assert parse_segment(text, model) == expected


@pytest.mark.parametrize("text, model", [
    ("arc:3", "diff"), ("arc:1,2,3", "diff"), ("straight:1,2", "diff"), ("spin:", "diff"),
    ("arc", "diff"), ("curve:1,2", "diff"), ("arc:a,b", "diff"), ("arc:nan,1", "diff"),
    ("straight:inf", "diff"), ("", "diff"), ("spin:1", "gyro"), ("arc:1,2", "gyro"),
    ("straight:1", "compass"), ("arc:1,0.1,-5", "gyro"),
])
def test_bad_segment_strings_name_the_option_and_the_syntax(text, model):
    with pytest.raises(ModelError) as info:
        parse_segment(text, model)
    message = str(info.value)
    assert "duration" in message or (repr(text) in message and "expected" in message)


def test_unknown_model():
    with pytest.raises(ModelError, match="unknown model 'boat'"):
        parse_segment("arc:1,2", "boat")


def test_steered_segments_by_robot_type():
    """``odomkit predict --robot`` reads a tricycle's or car's segments as wheel speed,
    steering angle and duration."""
    assert parse_segment("arc:0.5,0.2,4", "car") == SteerArc(0.5, 0.2, 4.0)
    assert parse_segment("straight:0.5,4", "tricycle") == SteerArc(0.5, 0.0, 4.0)
    assert parse_segment("arc:0.5,0.2,4", "unicycle") == KellyArc(0.5, 0.2, 4.0)
    with pytest.raises(ModelError, match=r"for model 'tricycle'; expected arc:V,ALPHA,T"):
        parse_segment("arc:3,1", "tricycle")


@pytest.mark.parametrize("radius, angle", [(2.0, math.pi / 3), (0.7, -1.2), (-1.5, 0.4), (5.0, 2 * math.pi)])
def test_an_arcs_wheel_travel_follows_from_its_radius_and_angle(radius, angle):
    """Axle centre on a circle of signed radius R through angle φ: each wheel rides a
    concentric circle, the left of radius R − b/2 and the right of R + b/2, so they travel
    (R ∓ b/2)·φ; the robot ends at (R sin φ, R(1 − cos φ), φ)."""
    b = 0.4
    left, right = (radius - b / 2) * angle, (radius + b / 2) * angle
    arc = Arc(left, right)
    assert arc.wheel_travel(b) == (left, right)
    dd, dtheta = diff_body_steps([left], [right], b)
    assert dd[0] == pytest.approx(radius * angle, rel=1e-14)
    assert dtheta[0] == pytest.approx(angle, rel=1e-14)
    end = dead_reckon(dd, dtheta)[-1]
    np.testing.assert_allclose(end, [radius * math.sin(angle), radius * (1 - math.cos(angle)), angle],
                               rtol=0, atol=1e-14)


def test_straight_and_spin_wheel_travel():
    """A straight line moves both wheels by D; a spin by Δθ on the spot moves each wheel
    along a circle of radius b/2: ∓(b/2)·Δθ."""
    assert Straight(-1.5).wheel_travel(0.4) == (-1.5, -1.5)
    left, right = Spin(math.pi).wheel_travel(0.4)
    assert (left, right) == pytest.approx((-0.2 * math.pi, 0.2 * math.pi), rel=1e-15)
    np.testing.assert_allclose(dead_reckon(*diff_body_steps([left], [right], 0.4))[-1],
                               [0.0, 0.0, math.pi], atol=1e-15)


@pytest.mark.parametrize("make, field", [
    (lambda v: Arc(v, 1.0), "Arc.left"), (lambda v: Arc(1.0, v), "Arc.right"),
    (lambda v: Straight(v), "Straight.distance"), (lambda v: Spin(v), "Spin.dtheta"),
    (lambda v: KellyArc(v, 0.0, 1.0), "KellyArc.speed"),
    (lambda v: KellyArc(1.0, v, 1.0), "KellyArc.yaw_rate"),
    (lambda v: KellyArc(1.0, 0.0, v), "segment duration"),
])
def test_segments_reject_non_finite_numbers(make, field):
    for bad in (math.nan, math.inf, "1", None):
        with pytest.raises(ModelError, match=field):
            make(bad)


def test_kelly_duration_may_be_zero_but_not_negative():
    assert KellyArc(1.0, 0.5, 0.0).duration == 0.0
    with pytest.raises(ModelError, match="segment duration must be a non-negative"):
        KellyArc(1.0, 0.5, -1.0)


def test_segments_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Arc(1.0, 2.0).left = 3.0  # type: ignore[misc]
