"""The documentation lists the noise keys of every robot type, with units and kind (issue 10,
item 9; the table moved from the README to docs/reference/robot-files.md in issue 13),
and the list agrees with what a robot file accepts (the noise registry and
:data:`odomkit.noise.parameters.PARAMETERS`)."""

from __future__ import annotations

import re
from dataclasses import fields
from pathlib import Path

import pytest

from odomkit.noise import NOISE_MODELS
from odomkit.noise.parameters import PARAMETERS
from odomkit.robot import ROBOT_TYPES

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "robot-files.md"
HEADER = "| type | white `[noise]` keys | bias `[noise.parameters]` keys |"
GENERIC = "Every type also takes the generic white models"


def _table() -> dict[str, tuple[str, str]]:
    """type -> (white cell, bias cell) of the page's noise-key table."""
    text = PAGE.read_text(encoding="utf-8")
    assert HEADER in text, f"{PAGE.name} lost its noise-key table"
    rows = {}
    for line in text.split(HEADER, 1)[1].splitlines()[2:]:
        if not line.startswith("| `"):
            break
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        rows[cells[0].strip("`")] = (cells[1], cells[2])
    return rows


def _generic() -> str:
    text = PAGE.read_text(encoding="utf-8")
    assert GENERIC in text, f"{PAGE.name} lost the sentence on the generic noise models"
    return text.split(GENERIC, 1)[1].split("\n\n", 1)[0]


def _keys(cell: str) -> list[str]:
    return [k for k in re.findall(r"`([a-z_]+)`", cell) if k not in ROBOT_TYPES]


def _accepted_white(type_name: str) -> set[str]:
    """Every [noise] key a robot of this type accepts: the fields of each white model that
    applies to it (no ``robot_types``: any robot)."""
    keys: set[str] = set()
    for cls in NOISE_MODELS.values():
        if cls.toml_table == "noise" and (not cls.robot_types or type_name in cls.robot_types):
            keys |= {f.name for f in fields(cls)}
    return keys


def _with_units(cell: str, keys: list[str]) -> list[str]:
    """The keys not followed by a unit "[...]" in their cell (a key shares the unit of the
    next one: `k_left`, `k_right` [m^½])."""
    return [k for k in keys if "[" not in cell[cell.index(f"`{k}`"):]]


def test_every_robot_type_has_a_row():
    assert set(_table()) == set(ROBOT_TYPES)


@pytest.mark.parametrize("type_name", sorted(ROBOT_TYPES))
def test_white_keys_agree_with_the_registry(type_name):
    white, _ = _table()[type_name]
    listed = set(_keys(white))
    generic = set(_keys(_generic())) - {"mode"}
    assert listed <= _accepted_white(type_name), f"{type_name}: listed but refused"
    assert _accepted_white(type_name) <= listed | generic, f"{type_name}: accepted but not listed"
    assert not _with_units(white, _keys(white)), f"{type_name}: white keys without a unit"


def test_generic_keys_have_units():
    text = _generic()
    assert not _with_units(text, [k for k in _keys(text) if k != "mode"])
    generic_models = {f.name for cls in NOISE_MODELS.values() if cls.toml_table == "noise"
                      and not cls.robot_types for f in fields(cls)}
    assert generic_models <= set(_keys(text))


@pytest.mark.parametrize("type_name", sorted(ROBOT_TYPES))
def test_bias_keys_agree_with_the_parameters(type_name):
    _, bias = _table()[type_name]
    assert _keys(bias) == list(PARAMETERS[type_name])
    assert not _with_units(bias, _keys(bias)), f"{type_name}: bias keys without a unit"
