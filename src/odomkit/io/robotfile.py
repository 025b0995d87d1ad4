"""Robot files (TOML): describe a robot and its noise once.

Example (all lengths in metres, angles in radians)::

    [robot]
    type = "diff"               # diff | tricycle | gyro | compass | unicycle | car
    wheel_base = 0.2
    wheel_diameter = 0.084      # or wheel_diameter_left/_right, wheel_radius[_left/_right],
    encoder_resolution = 64     #    or m_per_tick[_left/_right] directly (one per wheel;
    gear_ratio = 43.7           #    encoder and gear go with a diameter or radius only)
    c_left = 1.0                # calibration factors (optional)
    c_right = 1.0
    c_wheel_base = 1.0

    [noise]                     # optional; one model per key set, see odomkit.noise
    k_left = 0.001              # WheelNoise [m^½]
    k_right = 0.001

    [noise.parameters]          # optional ParameterUncertainty
    sigma_wheel_base = 0.002
    mode = "bias"

    [truth]                     # optional; written by fit-noise: the noise of the truth
    sigma = 0.001               #    it fitted against [m], [rad]; evaluate and report add
    heading_sigma = 0.006       #    it to each scored window end (not the robot's own)
    time_sigma = 0.03

A car (rear-axle reference, speed measured at one wheel, front steering angle)::

    [robot]
    type = "car"
    wheel_base = 2.7            # L [m]
    encoder_offset = 0.8        # H [m], + left: lateral offset of the measuring wheel
    encoder_at = "rear"         # "rear" | "front": axle of the measuring wheel
    steering_ratio = 15.0       # measured steering angle per road-wheel angle: 1 (default)
                                #    for a road-wheel steer, ~12-18 for a steering wheel's
    steering_cubic = 0.0        # [rad^-2], a ratio varying with the angle: s + k s^3 (s = steer/ratio)
    steering_offset = 0.0       # [rad], added to the road-wheel angle (after the ratio)
    c_scale = 1.0               # measuring-wheel scale correction
    wheel_diameter = 0.65       # optional size of the measuring wheel (ticks only):
                                # m_per_tick, wheel_diameter or wheel_radius

A tricycle (rear-axle reference, one front wheel that steers and drives): ``wheel_to_axle``
[m], ``steering_offset`` [rad], ``c_scale``, the front wheel's size (ticks only), and
``steering_ratio``: the ``steer`` channel per radian of the wheel, 1 (default) for radians, an
absolute steering encoder's ticks per radian (8192 a turn: 1303.8) otherwise.

A unicycle (body velocities ``speed``, ``yaw_rate``): ``c_scale``, ``yaw_rate_bias``
[rad/s], ``yaw_rate_scale``, all optional.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import Any

import tomli_w

from odomkit.errors import InputError, ModelError
from odomkit.io.files import refuse_overwrite
from odomkit.io.text import read_text
from odomkit.noise import NOISE_MODELS, NoiseModel, ParameterUncertainty, noise_fields
from odomkit.noise.parameters import PARAMETERS
from odomkit.robot import (
    ENCODER_POSITIONS,
    ROBOT_TYPES,
    Car,
    CompassOdometry,
    DiffDrive,
    GyroOdometry,
    Robot,
    Tricycle,
    Unicycle,
    metres_per_tick,
    robot_type_name,
)

__all__ = ["TRUTH_KEYS", "TRUTH_SIGMAS", "read_robot", "read_robot_name", "read_truth_table", "robot_to_dict",
           "write_robot"]


class _Fields:
    """Typed access to one TOML table, with errors that name the file and field."""

    def __init__(self, table: dict[str, Any], section: str, source: str):
        self.table, self.section, self.source = table, section, source
        self.used: set[str] = set()

    def number(self, key: str, default: float | None = None) -> float:
        self.used.add(key)
        if key not in self.table:
            if default is None:
                raise InputError(f"[{self.section}] needs {key!r}", source=self.source)
            return default
        value = self.table[key]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"[{self.section}] {key} must be a number, got {value!r}",
                             source=self.source)
        return float(value)

    def word(self, key: str, choices: tuple[str, ...], default: str) -> str:
        self.used.add(key)
        value = self.table.get(key, default)
        if value not in choices:
            raise InputError(f"[{self.section}] {key} must be one of {', '.join(map(repr, choices))}, "
                             f"got {value!r}", source=self.source)
        return str(value)

    def has(self, key: str) -> bool:
        return key in self.table

    def check_unused(self) -> None:
        extra = sorted(set(self.table) - self.used)
        if extra:
            raise InputError(f"[{self.section}] has unknown field(s) {', '.join(extra)}",
                             source=self.source)


_SIZE_KEYS = ("m_per_tick", "wheel_diameter", "wheel_radius")
_ENCODER_KEYS = ("encoder_resolution", "gear_ratio")


class _WheelSizes:
    """The wheel sizes of one ``[robot]`` table: each wheel from exactly one description
    (``m_per_tick``, ``wheel_diameter`` or ``wheel_radius``, each also per wheel with a
    ``_left``/``_right``/``_front`` suffix), and the encoder keys only beside a diameter or
    radius. A wheel described twice is a conflict, named as one, not an "unknown field"."""

    def __init__(self, f: _Fields):
        self.f = f
        self.from_diameter = False

    def given(self, side: str | None) -> list[str]:
        """The keys present that describe the ``side`` wheel (``None``: the only wheel)."""
        keys = [k for base in _SIZE_KEYS for k in (base, f"{base}_{side}" if side else None) if k]
        return [k for k in keys if self.f.has(k)]

    def scale(self, side: str | None, wheel: str) -> float:
        """Metres per tick of one wheel (``wheel`` names it in messages, e.g. "left")."""
        given = self.given(side)
        if not given:
            suffix = f"[_{side}]" if side else ""
            raise InputError(
                f"[robot] needs the wheel size of the {wheel} wheel: m_per_tick{suffix}, "
                f"wheel_diameter{suffix} or wheel_radius{suffix} (a log in metres or m/s, dist or speed "
                "channels, is not scaled by it: m_per_tick = 1 will do)", source=self.f.source)
        if len(given) > 1:
            raise InputError(f"[robot] {' and '.join(given)} both give the {wheel} wheel's size; "
                             "keep one", source=self.f.source)
        key = given[0]
        value = self.f.number(key)
        if key.startswith("m_per_tick"):
            return value
        self.from_diameter = True
        diameter = 2.0 * value if key.startswith("wheel_radius") else value
        return metres_per_tick(diameter, self.resolution(), self.f.number("gear_ratio", 1.0))

    def resolution(self) -> float:
        """``encoder_resolution``: ticks per revolution, or ``"rad"`` for a wheel position in
        radians (a ROS ``JointState``: 2π "ticks" per revolution, so that ``wheel_radius``
        alone gives metres; without it a radian would be read as a whole revolution)."""
        if self.f.table.get("encoder_resolution") == "rad":
            self.f.used.add("encoder_resolution")
            return 2.0 * math.pi
        if isinstance(self.f.table.get("encoder_resolution"), str):
            raise InputError("[robot] encoder_resolution must be a number of ticks per revolution or "
                             f"\"rad\" (positions in radians), got {self.f.table['encoder_resolution']!r}",
                             source=self.f.source)
        return self.f.number("encoder_resolution", 1.0)

    def optional_scale(self, side: str | None, wheel: str) -> float:
        """:meth:`scale`, or 1.0 when the file gives no size (a log in metres needs none)."""
        return self.scale(side, wheel) if self.given(side) else 1.0

    def check_encoder(self) -> None:
        """Encoder resolution and gear ratio turn a wheel size into metres per tick; beside
        ``m_per_tick`` (metres per tick already) they would be silently ignored."""
        if self.from_diameter:
            return
        for key in _ENCODER_KEYS:
            if self.f.has(key):
                raise InputError(f"[robot] {key} applies to wheel_diameter or wheel_radius, not to "
                                 "m_per_tick (which is metres per tick already)", source=self.f.source)


def _robot_from_table(table: dict[str, Any], source: str) -> Robot:
    kind = table.get("type")
    f = _Fields(table, "robot", source)
    f.used.update({"type", "name"})
    if not isinstance(table.get("name", ""), str):
        raise InputError(f"[robot] name must be text, got {table['name']!r}", source=source)
    sizes = _WheelSizes(f)
    if kind == "diff":
        robot: Robot = DiffDrive(
            wheel_base=f.number("wheel_base"),
            m_per_tick_left=sizes.scale("left", "left"),
            m_per_tick_right=sizes.scale("right", "right"),
            c_left=f.number("c_left", 1.0),
            c_right=f.number("c_right", 1.0),
            c_wheel_base=f.number("c_wheel_base", 1.0),
        )
    elif kind == "tricycle":
        robot = Tricycle(
            wheel_to_axle=f.number("wheel_to_axle"),
            m_per_tick=sizes.optional_scale("front", "front"),
            steering_offset=f.number("steering_offset", 0.0),
            c_scale=f.number("c_scale", 1.0),
            steering_ratio=f.number("steering_ratio", 1.0),
        )
    elif kind == "gyro":
        robot = GyroOdometry(m_per_tick=sizes.optional_scale(None, "odometry"),
                             gyro_bias=f.number("gyro_bias", 0.0),
                             gyro_scale=f.number("gyro_scale", 1.0))
    elif kind == "compass":
        robot = CompassOdometry(m_per_tick=sizes.optional_scale(None, "odometry"),
                                heading_offset=f.number("heading_offset", 0.0))
    elif kind == "unicycle":
        robot = Unicycle(c_scale=f.number("c_scale", 1.0),
                         yaw_rate_bias=f.number("yaw_rate_bias", 0.0),
                         yaw_rate_scale=f.number("yaw_rate_scale", 1.0))
    elif kind == "car":
        robot = Car(wheel_base=f.number("wheel_base"),
                    encoder_offset=f.number("encoder_offset", 0.0),
                    encoder_at=f.word("encoder_at", ENCODER_POSITIONS, "rear"),
                    m_per_tick=sizes.optional_scale(None, "measuring"),
                    steering_offset=f.number("steering_offset", 0.0),
                    c_scale=f.number("c_scale", 1.0),
                    steering_ratio=f.number("steering_ratio", 1.0),
                    steering_cubic=f.number("steering_cubic", 0.0))
    else:
        raise InputError(f"[robot] type must be one of {', '.join(ROBOT_TYPES)}; got {kind!r}",
                         source=source)
    sizes.check_encoder()
    f.check_unused()
    return robot


def _applies(model: NoiseModel, robot: Robot, where: str, source: str) -> NoiseModel:
    """``model`` where it applies to the file's ``robot``; else the error names the file, the
    keys that gave it (``where``: ``"[noise] k_left, k_right"``) and the robot's type."""
    try:
        model.check_robot(robot)
    except ModelError as exc:
        raise InputError(f"{where}: {exc} (the file's [robot] type is {robot.type_name!r})",
                         source=source) from None
    return model


def _noise_from_table(table: dict[str, Any], source: str, robot: Robot) -> tuple[NoiseModel, ...]:
    """The noise models of a ``[noise]`` table: each registered model
    (:data:`odomkit.noise.NOISE_MODELS`) whose keys (its fields) are present, plus the
    models of sub-tables such as ``[noise.parameters]``; each must apply to ``robot`` (the
    file's own), or the error names its keys."""
    models: list[NoiseModel] = []
    sub_tables = {cls.toml_table.split(".", 1)[1]: cls for cls in NOISE_MODELS.values()
                  if cls.toml_table.startswith("noise.")}
    plain = {k: v for k, v in table.items() if k not in sub_tables}
    f = _Fields(plain, "noise", source)
    for cls in NOISE_MODELS.values():
        if cls.toml_table != "noise":
            continue
        required, optional = noise_fields(cls)
        # A model is named by its required keys, or, where it has none (every field
        # defaults to zero, as TurnNoise's), by any of its keys.
        present = (required or optional) & set(plain)
        if not present:
            continue
        if required - present:
            missing = ", ".join(sorted(required - present))
            raise InputError(f"[noise] {cls.__name__} also needs {missing}", source=source)
        kwargs = {k: f.number(k) for k in sorted(required | (optional & set(plain)))}
        models.append(_applies(cls(**kwargs), robot, f"[noise] {', '.join(kwargs)}", source))
    f.check_unused()
    for name, cls in sub_tables.items():
        sub = table.get(name)
        if sub is None:
            continue
        if not isinstance(sub, dict):
            raise InputError(f"[noise] {name} must be a table ([noise.{name}])", source=source)
        pf = _Fields(sub, f"noise.{name}", source)
        kwargs = {}
        for fld in fields(cls):  # type: ignore[arg-type]
            if isinstance(fld.default, str):  # a mode word, checked by the class
                pf.used.add(fld.name)
                if fld.name in sub:
                    kwargs[fld.name] = sub[fld.name]
            elif fld.name in sub:
                kwargs[fld.name] = pf.number(fld.name)
        models.append(_applies(cls(**kwargs), robot, f"[noise.{name}] {', '.join(sub)}", source))
        pf.check_unused()
    return tuple(models)


#: The ``[truth]`` table's keys: what the ground truth a robot was calibrated and fitted
#: against adds, not the robot's own. ``sigma``, ``heading_sigma``, ``time_sigma``: the
#: truth's noise (``odomkit fit-noise`` writes them), σ of a truth position per axis [m], of
#: a truth heading [rad] and of a fix's time against the log's clock [s]; ``evaluate`` and
#: ``report`` add them to each scored window end where no ``--truth-sigma``/
#: ``--truth-heading-sigma``/``--truth-time-sigma`` says otherwise. ``time_offset`` [s]: how
#: late the truth's clock runs against the log's (a fix stamped t is the pose at log time
#: t − time_offset; ``odomkit calibrate --truth`` fits it); every command reading truth with
#: this robot file applies it where no ``--truth-time-offset`` says otherwise.
TRUTH_KEYS = ("sigma", "heading_sigma", "time_sigma", "time_offset")
#: The keys of :data:`TRUTH_KEYS` that are standard deviations (never negative).
TRUTH_SIGMAS = ("sigma", "heading_sigma", "time_sigma")


def read_robot(path: str | Path) -> tuple[Robot, tuple[NoiseModel, ...]]:
    """Read a robot file.

    Returns
    -------
    robot : DiffDrive | Tricycle | GyroOdometry | CompassOdometry | Unicycle | Car
    noise : tuple of noise models
        Empty when the file has no ``[noise]`` table. Not in the file's order: the models
        of ``[noise]``'s own keys in the registry's order (:data:`odomkit.noise.NOISE_MODELS`),
        then those of its sub-tables (``[noise.parameters]``), so that a file read and
        written again (:func:`write_robot`) lists them in one order. Find a model by its
        type rather than by its place: ``NoiseSet.of(noise).get(WheelNoise)`` (None where
        the file has none; :class:`odomkit.noise.NoiseSet`).

    Examples
    --------
    >>> from odomkit.data import builtin_data_path
    >>> from odomkit.noise import NoiseSet, WheelNoise
    >>> robot, noise = read_robot(builtin_data_path("optiodom_diff.toml"))
    >>> NoiseSet.of(noise).get(WheelNoise)
    WheelNoise(k_left=0.001, k_right=0.001)
    """
    path = Path(path)
    doc = _document(path)
    try:
        robot = _robot_from_table(doc["robot"], str(path))
        noise = _noise_from_table(doc.get("noise", {}), str(path), robot)
    except ModelError as exc:
        raise InputError(str(exc), source=str(path)) from None
    return robot, noise


def read_robot_name(path: str | Path) -> str | None:
    """A robot file's ``[robot] name`` (None when it has none): the files odomkit writes from
    it (``calibrate --out-robot``, ``fit-noise --out``) keep it."""
    path = Path(path)
    name = _document(path)["robot"].get("name")
    if name is not None and not isinstance(name, str):
        raise InputError(f"[robot] name must be text, got {name!r}", source=str(path))
    return name


def read_truth_table(path: str | Path) -> dict[str, float]:
    """A robot file's ``[truth]`` table (:data:`TRUTH_KEYS`), empty when it has none."""
    f = _Fields(_document(Path(path)).get("truth", {}), "truth", str(path))
    out = {key: f.number(key) for key in TRUTH_KEYS if f.has(key)}
    f.check_unused()
    for key, value in out.items():
        if not math.isfinite(value):
            raise InputError(f"[truth] {key} must be a finite number, got {value!r}", source=str(path))
    for key in TRUTH_SIGMAS:
        if out.get(key, 0.0) < 0:
            raise InputError(f"[truth] {key} must be >= 0, got {out[key]!r}", source=str(path))
    return out


def _document(path: Path) -> dict[str, Any]:
    """The checked TOML document of a robot file."""
    if not path.is_file():
        raise InputError("no such robot file", source=str(path))
    # TOML is UTF-8 text by definition: a compressed or otherwise encoded file is refused.
    text = read_text(path, compressed=False, strict_utf8=True, kind="TOML robot file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML ({exc})", source=str(path)) from None
    if "robot" not in doc or not isinstance(doc["robot"], dict):
        raise InputError("needs a [robot] table", source=str(path))
    for name in ("noise", "truth"):
        if name in doc and not isinstance(doc[name], dict):
            raise InputError(f"[{name}] must be a table, got {doc[name]!r}", source=str(path))
    unknown = sorted(set(doc) - {"robot", "noise", "truth"})
    if unknown:
        raise InputError(f"unknown table(s) {', '.join(unknown)}; expected [robot], [noise] and [truth]",
                         source=str(path))
    return doc


#: Robots whose ``[robot]`` table may go without a wheel size (their logs may give speeds or
#: distances in metres): the reader then takes ``m_per_tick`` = 1.
_SIZE_OPTIONAL = (Tricycle, GyroOdometry, CompassOdometry, Car)


def robot_to_dict(robot: Robot, noise: tuple[NoiseModel, ...] = (),
                  truth: Mapping[str, float] | None = None, name: str | None = None) -> dict[str, Any]:
    """The TOML document of a robot (and noise, the ``[truth]`` table: :data:`TRUTH_KEYS`,
    and ``[robot] name`` when given), as written by :func:`write_robot`: it reads back to the
    same robot and noise (:func:`read_robot`), without the reader's default ``m_per_tick``
    = 1 of a robot that needs no wheel size, and with ``[noise.parameters]``' ``mode`` after
    its σ's."""
    from dataclasses import asdict

    table: dict[str, Any] = {"type": robot_type_name(robot)}
    if name is not None:
        table["name"] = name
    table.update(asdict(robot))
    if isinstance(robot, _SIZE_OPTIONAL) and robot.m_per_tick == 1.0:
        # The reader's default where no wheel size is given, and noise in the file of a robot
        # fed speeds or metres (a car's speed channel is m/s, which m_per_tick never scales).
        del table["m_per_tick"]
    doc: dict[str, Any] = {"robot": table}
    if noise:
        noise_table: dict[str, Any] = {}
        for model in noise:
            entry = model.to_dict()
            if isinstance(model, ParameterUncertainty):
                # Only the robot's own bias parameters (and any other that is set, which the
                # reader then refuses by name): a car's file need not list a gyro's, at zero.
                own = set(PARAMETERS[robot_type_name(robot)])
                entry = {key: value for key, value in entry.items()
                         if key != "mode" and (key in own or value)}
                entry["mode"] = model.mode  # after the σ's it qualifies, as documented above
            if model.toml_table.startswith("noise."):
                noise_table[model.toml_table.split(".", 1)[1]] = entry
            else:
                noise_table.update(entry)
        doc["noise"] = noise_table
    if truth:
        doc["truth"] = _truth_table(truth)
    return doc


def _truth_table(truth: Mapping[str, float]) -> dict[str, float]:
    """``truth`` as the file's ``[truth]`` table: :data:`TRUTH_KEYS`, or the same with a
    ``truth_`` prefix (the names of ``NoiseFit.truth_noise`` and fit-noise's JSON) mapped to
    them; any other key, or one key given in both spellings, is refused rather than dropped
    (a file without its truth's noise scores every window far too confidently)."""
    table: dict[str, float] = {}
    for given, value in truth.items():
        key = given.removeprefix("truth_")
        if key not in TRUTH_KEYS:
            accepted = ", ".join(TRUTH_KEYS)
            raise InputError(f"truth has an unknown key {given!r}; expected {accepted} "
                             f"(or the same with a truth_ prefix)")
        if key in table:
            raise InputError(f"truth gives {key!r} twice ({key} and truth_{key}); give one")
        table[key] = float(value)
    # The file's order, whatever the mapping's.
    return {key: table[key] for key in TRUTH_KEYS if key in table}


def write_robot(path: str | Path, robot: Robot, noise: tuple[NoiseModel, ...] = (),
                overwrite: bool = False, truth: Mapping[str, float] | None = None,
                name: str | None = None) -> Path:
    """Write a robot file; refuse to replace an existing file unless ``overwrite``.

    Parameters
    ----------
    path : the TOML file to write
    robot, noise : the ``[robot]`` and ``[noise]`` tables (as :func:`read_robot` returns them)
    overwrite : replace an existing file (``--force`` on the command line)
    truth : mapping, optional
        The ``[truth]`` table, :data:`TRUTH_KEYS`: ``sigma`` [m], ``heading_sigma`` [rad],
        ``time_sigma`` [s], ``time_offset`` [s]. Each may also be spelled with a ``truth_``
        prefix (``truth_sigma``, as ``NoiseFit.truth_noise`` and fit-noise's JSON name them),
        so ``truth=fit.truth_noise`` writes the fitted truth noise. Any other key raises
        :class:`~odomkit.errors.InputError`.
    name : the ``[robot] name`` (None: none written)
    """
    path = Path(path)
    # The document first: a bad truth key is refused before an existing file is touched.
    text = tomli_w.dumps(robot_to_dict(robot, noise, truth, name))
    refuse_overwrite(path, overwrite=overwrite)
    path.write_text(text, encoding="utf-8")
    return path
