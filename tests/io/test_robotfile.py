"""Robot files as users write them (issue 10 item 8): every mistake is one line naming the
file and the field, never a traceback and never a misleading "unknown field"."""

from __future__ import annotations

import gzip
import math

import pytest

from odomkit.errors import InputError
from odomkit.io.robotfile import read_robot
from odomkit.robot import CompassOdometry, GyroOdometry, Tricycle

DIFF = '[robot]\ntype = "diff"\nwheel_base = 0.3\n'


def robot_file(tmp_path, body: str | bytes):
    path = tmp_path / "robot.toml"
    path.write_bytes(body if isinstance(body, bytes) else body.encode())
    return path


@pytest.mark.parametrize(("body", "message"), [
    # the same wheel described twice
    (DIFF + "wheel_diameter = 0.1\nwheel_radius = 0.05\n",
     "wheel_diameter and wheel_radius both give the left wheel's size"),
    (DIFF + "m_per_tick = 1e-4\nwheel_diameter = 0.1\n",
     "m_per_tick and wheel_diameter both give the left wheel's size"),
    (DIFF + "m_per_tick = 1e-4\nm_per_tick_right = 2e-4\n",
     "m_per_tick and m_per_tick_right both give the right wheel's size"),
    (DIFF + "wheel_radius_left = 0.05\nwheel_diameter_left = 0.1\nwheel_radius_right = 0.05\n",
     "wheel_diameter_left and wheel_radius_left both give the left wheel's size"),
    ('[robot]\ntype = "tricycle"\nwheel_to_axle = 0.7\nwheel_diameter = 0.1\nwheel_radius = 0.05\n',
     "wheel_diameter and wheel_radius both give the front wheel's size"),
    # encoder and gear belong to a wheel size, not to metres per tick
    (DIFF + "m_per_tick = 1e-4\nencoder_resolution = 512\n",
     "encoder_resolution applies to wheel_diameter or wheel_radius, not to m_per_tick"),
    (DIFF + "m_per_tick = 1e-4\ngear_ratio = 10\n",
     "gear_ratio applies to wheel_diameter or wheel_radius, not to m_per_tick"),
    # tables that are not tables
    (DIFF + "m_per_tick = 1.0\nnoise = [1, 2]\n", "[robot] has unknown field(s) noise"),
    ("noise = [1, 2]\n" + DIFF + "m_per_tick = 1.0\n", "[noise] must be a table, got [1, 2]"),
    (DIFF + "m_per_tick = 1.0\n[[noise]]\nk_left = 0.1\n", "[noise] must be a table"),
    ("robot = 5\n", "needs a [robot] table"),
    (DIFF + "m_per_tick = 1.0\n[noise]\nparameters = 5\n", "[noise] parameters must be a table"),
    (DIFF + "m_per_tick = 1.0\n[noise]\nparameters = [1]\n", "[noise] parameters must be a table"),
    (DIFF + "m_per_tick = 1.0\n[noise]\nk_left = [1]\nk_right = 1\n", "[noise] k_left must be a number"),
    (DIFF + "m_per_tick = 1.0\n[noise.parameters]\nmode = 5\n", "mode must be"),
    (DIFF + "m_per_tick = 1.0\n[noise.parameters]\nsigma_wheel_base = '0.1'\n",
     "[noise.parameters] sigma_wheel_base must be a number"),
    ('[robot]\ntype = ["diff"]\n', "type must be one of"),
    (DIFF + "m_per_tick = nan\n", "must be a positive"),
    (DIFF + "m_per_tick = 1.0\nname = 7\n", "[robot] name must be text, got 7"),
    # files that are not UTF-8 TOML text
    (DIFF.encode() + b"m_per_tick = 1.0\n# r\xe9glage\n", "line 5: byte 0xe9 is not UTF-8"),
    (b"\x00\x01\x02", "binary data"),
])
def test_bad_robot_files_name_the_field(tmp_path, body, message):
    path = robot_file(tmp_path, body)
    with pytest.raises(InputError) as info:
        read_robot(path)
    text = str(info.value)
    assert text.startswith(f"{path}") and message in text and "\n" not in text


def test_a_gzip_robot_file_is_refused_by_name(tmp_path):
    path = robot_file(tmp_path, gzip.compress((DIFF + "m_per_tick = 1.0\n").encode()))
    with pytest.raises(InputError, match=r"robot\.toml: is gzip-compressed; a TOML robot file is plain text"):
        read_robot(path)


def test_per_side_wheel_sizes_still_read(tmp_path):
    robot, _ = read_robot(robot_file(tmp_path, DIFF + "wheel_diameter_left = 0.1\nwheel_radius_right = 0.06\n"
                                     "encoder_resolution = 100\ngear_ratio = 2\n"))
    assert robot.m_per_tick_left == pytest.approx(math.pi * 0.1 / 200, rel=1e-15)
    assert robot.m_per_tick_right == pytest.approx(math.pi * 0.12 / 200, rel=1e-15)


@pytest.mark.parametrize(("kind", "cls", "extra"), [
    ("gyro", GyroOdometry, ""), ("compass", CompassOdometry, ""),
    ("tricycle", Tricycle, "wheel_to_axle = 0.7\n"),
])
def test_every_vehicle_takes_a_wheel_size(tmp_path, kind, cls, extra):
    """A speed-and-gyro robot with an encoder is described like any other wheel."""
    body = f'[robot]\ntype = "{kind}"\n{extra}wheel_diameter = 0.2\nencoder_resolution = 1000\n'
    robot, _ = read_robot(robot_file(tmp_path, body))
    assert isinstance(robot, cls)
    assert robot.m_per_tick == pytest.approx(math.pi * 0.2 / 1000, rel=1e-15)


def test_car_and_unicycle_files_read_and_round_trip(tmp_path):
    """Issue 12 item 3: the car's geometry keys and the unicycle's corrections; a car's
    encoder position is a word from a fixed set, named when wrong."""
    from odomkit.io.robotfile import write_robot
    from odomkit.noise import ParameterUncertainty, TricycleNoise
    from odomkit.robot import Car, Unicycle

    body = ('[robot]\ntype = "car"\nwheel_base = 2.7\nencoder_offset = -0.8\nencoder_at = "front"\n'
            'wheel_radius = 0.3\nencoder_resolution = 1000\nsteering_offset = 0.01\nc_scale = 1.02\n'
            '[noise]\nsigma_speed = 0.05\nsigma_steer = 0.002\n'
            '[noise.parameters]\nsigma_scale_left = 0.01\nsigma_steering_offset = 0.003\n')
    robot, noise = read_robot(robot_file(tmp_path, body))
    assert robot == Car(2.7, -0.8, "front", math.pi * 0.6 / 1000, 0.01, 1.02)
    assert noise == (TricycleNoise(0.05, 0.002),
                     ParameterUncertainty(sigma_scale_left=0.01, sigma_steering_offset=0.003))
    again = write_robot(tmp_path / "again.toml", robot, noise)
    assert read_robot(again) == (robot, noise)
    # The file lists the car's own bias parameters only, not a gyro's or a diff's at zero.
    import tomllib

    written = tomllib.loads(again.read_text())["noise"]["parameters"]
    assert set(written) == {"sigma_wheel_base", "sigma_scale_left", "sigma_steering_offset", "mode"}
    geared = '[robot]\ntype = "car"\nwheel_base = 2.69\nsteering_ratio = 15.5\nsteering_cubic = 39.0\n'
    ratio, _ = read_robot(robot_file(tmp_path, geared))
    assert ratio == Car(2.69, steering_ratio=15.5, steering_cubic=39.0)
    assert read_robot(write_robot(tmp_path / "ratio.toml", ratio)) == (ratio, ())
    with pytest.raises(InputError, match="steering_ratio"):
        read_robot(robot_file(tmp_path, '[robot]\ntype = "car"\nwheel_base = 2.69\nsteering_ratio = 0\n'))
    uni, _ = read_robot(robot_file(tmp_path, '[robot]\ntype = "unicycle"\nyaw_rate_bias = 0.002\n'))
    assert uni == Unicycle(yaw_rate_bias=0.002)
    for bad, message in (('encoder_at = "middle"\n',
                          "encoder_at must be one of 'rear', 'front', got 'middle'"),
                         ("", "needs 'wheel_base'")):
        text = '[robot]\ntype = "car"\n' + ("wheel_base = 2.7\n" if bad else "") + bad
        with pytest.raises(InputError, match=message):
            read_robot(robot_file(tmp_path, text))
    with pytest.raises(InputError, match="unknown field"):
        read_robot(robot_file(tmp_path, '[robot]\ntype = "unicycle"\nm_per_tick = 0.1\nwheel_base = 1\n'))


def test_encoder_resolution_rad_reads_wheel_positions_in_radians(tmp_path):
    """A JointState wheel position is in radians: with encoder_resolution = "rad" a wheel
    radius r gives r metres per radian (one turn, 2π rad, is 2πr metres); a plain number
    still means ticks per revolution, and another word is refused by name."""
    import math

    from odomkit.errors import InputError
    from odomkit.io.robotfile import read_robot

    def robot(extra):
        path = tmp_path / "r.toml"
        path.write_text(f'[robot]\ntype = "diff"\nwheel_base = 0.3\nwheel_radius = 0.05\n{extra}\n')
        return read_robot(path)[0]

    r = robot('encoder_resolution = "rad"')
    assert r.m_per_tick_left == r.m_per_tick_right == pytest.approx(0.05, rel=1e-15)
    assert robot("encoder_resolution = 4096").m_per_tick_left == pytest.approx(2 * math.pi * 0.05 / 4096)
    with pytest.raises(InputError, match='ticks per revolution or "rad"'):
        robot('encoder_resolution = "deg"')


def test_noise_comes_in_the_documented_order_whatever_the_files_and_is_found_by_type(tmp_path):
    """API user study, L3: ``noise[0]`` was taken for the file's first model. The reader's
    order is the registry's (:data:`odomkit.noise.NOISE_MODELS`), then ``[noise.parameters]``,
    whatever the file's order; that is documented, and so is the lookup by type."""
    from odomkit.noise import (
        NOISE_MODELS,
        LateralSlipNoise,
        NoiseSet,
        ParameterUncertainty,
        SpeedNoise,
        WheelNoise,
    )

    body = ('[robot]\ntype = "diff"\nwheel_base = 0.2\nm_per_tick = 1e-4\n'
            '[noise.parameters]\nsigma_wheel_base = 0.002\n'
            '[noise]\nk_left = 0.001\nk_right = 0.002\nalpha_ss = 1e-5\nalpha_lateral = 3e-5\n')
    path = tmp_path / "robot.toml"
    path.write_text(body)
    _, noise = read_robot(path)
    registry = list(NOISE_MODELS.values())
    plain = [m for m in noise if not isinstance(m, ParameterUncertainty)]
    assert [type(m) for m in plain] == sorted((type(m) for m in plain), key=registry.index)
    assert isinstance(noise[-1], ParameterUncertainty)
    found = NoiseSet.of(noise)
    assert found.get(WheelNoise) == WheelNoise(0.001, 0.002)
    assert found.get(SpeedNoise) == SpeedNoise(alpha_ss=1e-5)
    assert found.get(LateralSlipNoise) == LateralSlipNoise(3e-5)
    doc = read_robot.__doc__
    assert "NOISE_MODELS" in doc and "NoiseSet.of(noise).get(" in doc


@pytest.mark.parametrize(("body", "said"), [
    ('[robot]\ntype = "unicycle"\n[noise]\nk_left = 0.001\nk_right = 0.001\n',
     "[noise] k_left, k_right: WheelNoise applies to a DiffDrive robot, not a Unicycle (the file's [robot] "
     "type is 'unicycle')"),
    (DIFF + "m_per_tick = 1e-4\n[noise]\nalpha_turn = 0.01\n",
     "[noise] alpha_turn: TurnNoise applies to a GyroOdometry or Unicycle robot, not a DiffDrive"),
    ('[robot]\ntype = "unicycle"\n[noise.parameters]\nsigma_wheel_base = 0.01\n',
     "[noise.parameters] sigma_wheel_base: ParameterUncertainty.sigma_wheel_base does not apply to a "
     "Unicycle"),
])
def test_noise_that_does_not_fit_the_files_robot_names_the_file_and_its_keys(tmp_path, body, said):
    """MRCLAM user study: a unicycle file with a differential drive's k_left, k_right said
    only "WheelNoise applies to a DiffDrive robot, not a Unicycle", from deep in track,
    naming neither the file nor the keys (and check and calibrate read the file happily)."""
    path = robot_file(tmp_path, body)
    with pytest.raises(InputError) as info:
        read_robot(path)
    text = str(info.value)
    assert text.startswith(f"{path}: {said}"), text
