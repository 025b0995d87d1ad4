"""odomkit.robot: frozen parameter sets, metres per tick, corrections, bad parameters."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from odomkit import robot as robot_module
from odomkit.errors import ModelError
from odomkit.robot import (
    ROBOT_TYPES,
    CompassOdometry,
    DiffDrive,
    GyroOdometry,
    SystematicErrors,
    Tricycle,
    metres_per_tick,
    robot_type_name,
    true_robot,
)

# Fields that may be any finite number (offsets and biases); every other field of every
# robot is a length, a scale or a correction factor and must be positive.
MAY_BE_ANY_FINITE = {"steering_offset", "gyro_bias", "heading_offset", "yaw_rate_bias", "encoder_offset",
                     "steering_cubic"}
# Fields that are a word from a fixed set.
WORDS = {"encoder_at": ("rear", "front")}


def _example(cls: type) -> object:
    """An instance with every required field set to 0.5 (defaults elsewhere)."""
    required = {f.name: 0.5 for f in dataclasses.fields(cls)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    return cls(**required)


@pytest.mark.parametrize("name", sorted(ROBOT_TYPES))
def test_every_robot_type_is_a_frozen_dataclass_named_by_its_file_type(name):
    cls = ROBOT_TYPES[name]
    robot = _example(cls)
    assert dataclasses.is_dataclass(robot)
    field = dataclasses.fields(cls)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(robot, field, 1.0)
    assert robot_type_name(robot) == name
    assert robot == _example(cls) and hash(robot) == hash(_example(cls))


@pytest.mark.parametrize("name", sorted(ROBOT_TYPES))
def test_every_field_of_every_robot_rejects_bad_numbers_naming_class_and_field(name):
    cls = ROBOT_TYPES[name]
    base = _example(cls)
    for f in dataclasses.fields(cls):
        if f.name in WORDS:
            for bad in ("left", 1.0, None):
                with pytest.raises(ModelError, match=rf"^{cls.__name__}\.{f.name} must be "):
                    dataclasses.replace(base, **{f.name: bad})
            continue
        bad_values = [math.nan, math.inf, -math.inf, True, "1.0", None]
        if f.name not in MAY_BE_ANY_FINITE:
            bad_values += [0.0, -0.1]
        for bad in bad_values:
            with pytest.raises(ModelError, match=rf"^{cls.__name__}\.{f.name} must be a "):
                dataclasses.replace(base, **{f.name: bad})
        if f.name in MAY_BE_ANY_FINITE:
            assert getattr(dataclasses.replace(base, **{f.name: -0.1}), f.name) == -0.1


def test_numpy_scalars_are_numbers():
    r = DiffDrive(np.float64(0.4), np.float32(1e-4), np.int64(1))
    assert r.effective_wheel_base == pytest.approx(0.4)


def test_metres_per_tick_is_borenstein_feng_eq_2_1():
    """c_m = π·D_n/(n·C_e); the expected values are π·D/(n·C_e) worked out to 40 digits."""
    assert metres_per_tick(0.084, 64, 43.7) == pytest.approx(9.435561459580328662e-05, rel=1e-15)
    assert metres_per_tick(0.072, 512, 19) == pytest.approx(2.325191931110866706e-05, rel=1e-15)
    # a wheel of circumference 1 m read by 100 ticks per wheel turn: 1 cm per tick
    assert metres_per_tick(1 / math.pi, 100) == pytest.approx(0.01, rel=1e-15)
    # n·C_e ticks turn the wheel once: one circumference
    assert metres_per_tick(0.1, 500, 30) * 500 * 30 == pytest.approx(math.pi * 0.1, rel=1e-15)


@pytest.mark.parametrize("args", [(0, 64, 1), (0.08, 0, 1), (0.08, 64, 0), (0.08, 64, -2),
                                  (math.nan, 64, 1), (0.08, math.inf, 1)])
def test_metres_per_tick_rejects_non_positive_inputs(args):
    with pytest.raises(ModelError, match="metres_per_tick"):
        metres_per_tick(*args)


def test_from_wheels_builds_each_wheel_from_its_own_diameter():
    r = DiffDrive.from_wheels(0.3, 0.08, 0.082, encoder_resolution=100, gear_ratio=2, c_left=1.01)
    assert r.m_per_tick_left == pytest.approx(math.pi * 0.08 / 200, rel=1e-15)
    assert r.m_per_tick_right == pytest.approx(math.pi * 0.082 / 200, rel=1e-15)
    assert r.c_left == 1.01 and r.wheel_base == 0.3
    same = DiffDrive.from_wheels(0.3, 0.08, encoder_resolution=100)
    assert same.m_per_tick_left == same.m_per_tick_right


def test_corrections_scale_wheels_and_wheel_base():
    """Borenstein–Feng eq. (4.30)–(4.32): distance = c·m_per_tick·ticks, b = E_b·b_nominal."""
    r = DiffDrive(0.4, 2e-4, 3e-4, c_left=0.99, c_right=1.02, c_wheel_base=1.05)
    assert r.effective_wheel_base == pytest.approx(0.42, rel=1e-15)
    assert r.scale_left == pytest.approx(1.98e-4, rel=1e-15)
    assert r.scale_right == pytest.approx(3.06e-4, rel=1e-15)
    t = Tricycle(1.2, m_per_tick=5e-4, c_scale=0.98)
    assert t.scale == pytest.approx(4.9e-4, rel=1e-15)


def test_systematic_errors_are_borenstein_feng_section_2b():
    """D_R/D_L = E_d (eq. 2.3), (D_R + D_L)/2 = E_s·D_nominal, b_actual = E_b·b."""
    sys_err = SystematicErrors(E_d=1.01, E_b=1.02, E_s=0.995)
    left, right = sys_err.wheel_scales()
    assert right / left == pytest.approx(1.01, rel=1e-15)
    assert (left + right) / 2 == pytest.approx(0.995, rel=1e-15)
    truth = true_robot(sys_err, DiffDrive(0.5, 1e-4, 2e-4, c_left=1.3))  # corrections ignored
    assert truth.wheel_base == pytest.approx(0.51, rel=1e-15)
    assert truth.m_per_tick_left == pytest.approx(left * 1e-4, rel=1e-15)
    assert truth.m_per_tick_right == pytest.approx(right * 2e-4, rel=1e-15)
    assert (truth.c_left, truth.c_right, truth.c_wheel_base) == (1.0, 1.0, 1.0)
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(ModelError, match="SystematicErrors.E_b"):
            SystematicErrors(E_b=bad)


def test_robot_type_name_rejects_what_is_not_a_robot():
    with pytest.raises(ModelError, match="not an odomkit robot"):
        robot_type_name(SystematicErrors())  # type: ignore[arg-type]


def test_the_robot_union_lists_every_robot_type():
    assert set(ROBOT_TYPES.values()) == set(robot_module.Robot.__args__)
    assert {DiffDrive, Tricycle, GyroOdometry, CompassOdometry} <= set(ROBOT_TYPES.values())
