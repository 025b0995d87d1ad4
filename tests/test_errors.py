"""odomkit.errors: one exception family; InputError names the file and line."""

from __future__ import annotations

import pytest

from odomkit.errors import InputError, ModelError, OdomkitError


def test_one_family():
    assert issubclass(InputError, OdomkitError) and issubclass(ModelError, OdomkitError)
    assert issubclass(OdomkitError, Exception)
    assert not issubclass(InputError, ModelError) and not issubclass(ModelError, InputError)


@pytest.mark.parametrize("source, line, expected", [
    (None, None, "expected 3 columns"),
    ("log.csv", None, "log.csv: expected 3 columns"),
    ("log.csv", 12, "log.csv, line 12: expected 3 columns"),
    (None, 12, "expected 3 columns"),          # a line means nothing without its file
])
def test_input_error_names_file_and_line(source, line, expected):
    err = InputError("expected 3 columns", source=source, line=line)
    assert str(err) == expected
    assert (err.source, err.line) == (source, line)


def test_model_error_is_its_message():
    assert str(ModelError("wheel_base must be positive")) == "wheel_base must be positive"
