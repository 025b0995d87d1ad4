"""Robot files (TOML): describe a robot and its noise once.

Example (all lengths in metres, angles in radians)::

    [robot]
    type = "diff"               # diff | tricycle | gyro | compass
    wheel_base = 0.2
    wheel_diameter = 0.084      # or wheel_diameter_left/_right, wheel_radius[_left/_right],
    encoder_resolution = 64     #    or m_per_tick[_left/_right] directly
    gear_ratio = 43.7
    c_left = 1.0                # calibration factors (optional)
    c_right = 1.0
    c_wheel_base = 1.0

    [noise]                     # optional; one model per key set, see odomkit.noise
    k_left = 0.001              # WheelNoise [m^½]
    k_right = 0.001

    [noise.parameters]          # optional ParameterUncertainty
    sigma_wheel_base = 0.002
    mode = "bias"
"""

from __future__ import annotations

import tomllib
from dataclasses import fields
from pathlib import Path
from typing import Any

import tomli_w

from odomkit.errors import InputError, ModelError
from odomkit.io.files import refuse_overwrite
from odomkit.noise import NOISE_MODELS, NoiseModel, noise_fields
from odomkit.robot import (
    CompassOdometry,
    DiffDrive,
    GyroOdometry,
    Robot,
    Tricycle,
    metres_per_tick,
    robot_type_name,
)

__all__ = ["read_robot", "robot_to_dict", "write_robot"]


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

    def has(self, key: str) -> bool:
        return key in self.table

    def check_unused(self) -> None:
        extra = sorted(set(self.table) - self.used)
        if extra:
            raise InputError(f"[{self.section}] has unknown field(s) {', '.join(extra)}",
                             source=self.source)


def _wheel_scale(f: _Fields, side: str) -> float:
    """Metres per tick of one wheel from whichever description the file uses."""
    for key in (f"m_per_tick_{side}", "m_per_tick"):
        if f.has(key):
            return f.number(key)
    diameter = None
    for key, factor in ((f"wheel_diameter_{side}", 1.0), ("wheel_diameter", 1.0),
                        (f"wheel_radius_{side}", 2.0), ("wheel_radius", 2.0)):
        if f.has(key):
            diameter = factor * f.number(key)
            break
    if diameter is None:
        raise InputError(
            "[robot] needs the wheel size: m_per_tick[_left/_right], "
            "wheel_diameter[_left/_right] or wheel_radius[_left/_right]",
            source=f.source,
        )
    return metres_per_tick(diameter, f.number("encoder_resolution", 1.0), f.number("gear_ratio", 1.0))


def _robot_from_table(table: dict[str, Any], source: str) -> Robot:
    kind = table.get("type")
    f = _Fields(table, "robot", source)
    f.used.update({"type", "name"})
    if kind == "diff":
        robot: Robot = DiffDrive(
            wheel_base=f.number("wheel_base"),
            m_per_tick_left=_wheel_scale(f, "left"),
            m_per_tick_right=_wheel_scale(f, "right"),
            c_left=f.number("c_left", 1.0),
            c_right=f.number("c_right", 1.0),
            c_wheel_base=f.number("c_wheel_base", 1.0),
        )
    elif kind == "tricycle":
        scale = 1.0
        if any(f.has(k) for k in ("m_per_tick", "wheel_diameter", "wheel_radius")):
            scale = _wheel_scale(f, "front")
        robot = Tricycle(
            wheel_to_axle=f.number("wheel_to_axle"),
            m_per_tick=scale,
            steering_offset=f.number("steering_offset", 0.0),
            c_scale=f.number("c_scale", 1.0),
        )
    elif kind == "gyro":
        robot = GyroOdometry(m_per_tick=f.number("m_per_tick", 1.0),
                             gyro_bias=f.number("gyro_bias", 0.0),
                             gyro_scale=f.number("gyro_scale", 1.0))
    elif kind == "compass":
        robot = CompassOdometry(m_per_tick=f.number("m_per_tick", 1.0),
                                heading_offset=f.number("heading_offset", 0.0))
    else:
        raise InputError(f"[robot] type must be one of diff, tricycle, gyro, compass; got {kind!r}",
                         source=source)
    f.check_unused()
    return robot


def _noise_from_table(table: dict[str, Any], source: str) -> tuple[NoiseModel, ...]:
    """The noise models of a ``[noise]`` table: each registered model
    (:data:`odomkit.noise.NOISE_MODELS`) whose keys (its fields) are present, plus the
    models of sub-tables such as ``[noise.parameters]``."""
    models: list[NoiseModel] = []
    sub_tables = {cls.toml_table.split(".", 1)[1]: cls for cls in NOISE_MODELS.values()
                  if cls.toml_table.startswith("noise.")}
    plain = {k: v for k, v in table.items() if k not in sub_tables}
    f = _Fields(plain, "noise", source)
    for cls in NOISE_MODELS.values():
        if cls.toml_table != "noise":
            continue
        required, optional = noise_fields(cls)
        present = required & set(plain)
        if not present:
            continue
        if present != required:
            missing = ", ".join(sorted(required - present))
            raise InputError(f"[noise] {cls.__name__} also needs {missing}", source=source)
        kwargs = {k: f.number(k) for k in sorted(required | (optional & set(plain)))}
        models.append(cls(**kwargs))
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
        models.append(cls(**kwargs))
        pf.check_unused()
    return tuple(models)


def read_robot(path: str | Path) -> tuple[Robot, tuple[NoiseModel, ...]]:
    """Read a robot file.

    Returns
    -------
    robot : DiffDrive | Tricycle | GyroOdometry | CompassOdometry
    noise : tuple of noise models (empty when the file has no [noise] table)
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such robot file", source=str(path))
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML ({exc})", source=str(path)) from None
    if "robot" not in doc or not isinstance(doc["robot"], dict):
        raise InputError("needs a [robot] table", source=str(path))
    unknown = sorted(set(doc) - {"robot", "noise"})
    if unknown:
        raise InputError(f"unknown table(s) {', '.join(unknown)}; expected [robot] and [noise]",
                         source=str(path))
    try:
        robot = _robot_from_table(doc["robot"], str(path))
        noise = _noise_from_table(doc.get("noise", {}), str(path))
    except ModelError as exc:
        raise InputError(str(exc), source=str(path)) from None
    return robot, noise


def robot_to_dict(robot: Robot, noise: tuple[NoiseModel, ...] = ()) -> dict[str, Any]:
    """The TOML document of a robot (and noise), as written by :func:`write_robot`."""
    from dataclasses import asdict

    table: dict[str, Any] = {"type": robot_type_name(robot)}
    table.update(asdict(robot))
    doc: dict[str, Any] = {"robot": table}
    if noise:
        noise_table: dict[str, Any] = {}
        for model in noise:
            if model.toml_table.startswith("noise."):
                noise_table[model.toml_table.split(".", 1)[1]] = model.to_dict()
            else:
                noise_table.update(model.to_dict())
        doc["noise"] = noise_table
    return doc


def write_robot(path: str | Path, robot: Robot, noise: tuple[NoiseModel, ...] = (),
                overwrite: bool = False) -> Path:
    """Write a robot file; refuse to replace an existing file unless ``overwrite``."""
    path = Path(path)
    refuse_overwrite(path, overwrite=overwrite)
    path.write_text(tomli_w.dumps(robot_to_dict(robot, noise)), encoding="utf-8")
    return path
