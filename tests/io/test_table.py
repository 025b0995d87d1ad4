"""odomkit.io.table through the log readers (issue 10 items 5 and 8): bad fields named by
line and column, exact integer counters, and counters read the wrong way, in both parsers."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.halmstad import read_khepera

COLUMNS = {"t": "t", "ticks_left": "L", "ticks_right": "R"}



def write_bytes(tmp_path, name, data: bytes):
    path = tmp_path / name
    path.write_bytes(data)
    return path


# --- bad fields are named by line and column ---------------------------------------------

@pytest.mark.parametrize("field", ["1_000", "\uff11", "\u0663", "0x1f", "1d5", "nan(1)"])
def test_every_field_numpy_refuses_is_named(tmp_path, parser, field):
    """Python's float() accepts '1_000' and Unicode digits, numpy does not: the line that
    made numpy fail must still be found (it said 'could not be read as a numeric table')."""
    path = write_bytes(tmp_path, "log.csv", f"t,L,R\n0,0,0\n1,{field},3\n".encode())
    with pytest.raises(InputError, match=re.escape(f"log.csv, line 3: column 2: '{field}' is not a number")):
        read_csv_log(path, COLUMNS)


def test_inline_comment_is_allowed_like_numpy_does(tmp_path, parser):
    path = write_bytes(tmp_path, "log.csv", b"t,L,R\n0,0,0\n1,2,3 # bump\n")
    assert np.array_equal(read_csv_log(path, COLUMNS).channels["ticks_right"], [0, 3])


# --- integer counters --------------------------------------------------------------------

def wrapped_steps(values: list[int], bits: int) -> list[int]:
    """Steps of a ``bits``-bit counter in exact integer arithmetic: each difference taken
    modulo 2**bits into [−2**(bits−1), 2**(bits−1))."""
    half, span = 2 ** (bits - 1), 2**bits
    return [0] + [(b - a + half) % span - half for a, b in zip(values, values[1:], strict=False)]


@pytest.mark.parametrize("raw", [
    # a signed 64-bit counter crossing 2**63 - 1 -> -2**63
    [2**63 - 700, 2**63 - 401, 2**63 - 100, -(2**63) + 203, -(2**63) + 500, -(2**63) + 100],
    # an unsigned 64-bit counter crossing 2**63 (no wrap: too big for int64) ...
    [2**63 - 300, 2**63 + 1, 2**63 + 400, 2**63 + 399],
    # ... and crossing 2**64 - 1 -> 0, forwards and back
    [2**64 - 600, 2**64 - 250, 47, 349, 2**64 - 7],
])
def test_64_bit_counters_unwrap_exactly(tmp_path, parser, raw):
    """float64 holds 2**63 to ±1024: every step below would be rounded to 0 or ±2048."""
    lines = "\n".join(f"{0.1 * i:.1f},{c},{c}" for i, c in enumerate(raw))
    path = write_bytes(tmp_path, "c.csv", f"t,L,R\n{lines}\n".encode())
    log = read_csv_log(path, COLUMNS, cumulative=True, wrap_bits=64)
    assert log.channels["ticks_left"].tolist() == wrapped_steps(raw, 64)


def test_large_counters_difference_exactly_without_wrap(tmp_path, parser):
    raw = [2**60 + 1, 2**60 + 4, 2**60 + 6, 2**60 + 5]
    lines = "\n".join(f"{i},{c},{c}" for i, c in enumerate(raw))
    log = read_csv_log(write_bytes(tmp_path, "c.csv", f"t,L,R\n{lines}\n".encode()), COLUMNS,
                       cumulative=True)
    assert log.channels["ticks_left"].tolist() == [0, 3, 2, -1]


def test_khepera_counters_are_exact_integers(tmp_path, parser):
    raw = [2**62 + 3, 2**62 + 10, 2**62 + 8]
    log = read_khepera(write_bytes(tmp_path, "k.txt", "\n".join(f"{c} {c}" for c in raw).encode()))
    assert log.channels["ticks_left"].tolist() == [0, 7, -2]


def test_counts_written_as_integral_floats_still_unwrap(tmp_path, parser):
    raw = [65530, 65535, 3, 10]
    lines = "\n".join(f"{i},{c}.0,{c}" for i, c in enumerate(raw))
    log = read_csv_log(write_bytes(tmp_path, "c.csv", f"t,L,R\n{lines}\n".encode()), COLUMNS,
                       cumulative=True, wrap_bits=16)
    assert log.channels["ticks_left"].tolist() == [0, 5, 4, 7]


def test_a_count_beyond_the_counter_width_is_an_error(tmp_path, parser):
    path = write_bytes(tmp_path, "c.csv", b"t,L,R\n0,0,0\n1,70000,5\n")
    with pytest.raises(InputError, match=r"c\.csv, line 3: column 2 .*70000.*16-bit"):
        read_csv_log(path, COLUMNS, cumulative=True, wrap_bits=16)


def test_a_fractional_count_cannot_be_unwrapped(tmp_path, parser):
    path = write_bytes(tmp_path, "c.csv", b"t,L,R\n0,0,0\n1,2.5,5\n")
    with pytest.raises(InputError, match=r"line 3: column 2 .*2\.5.*integer"):
        read_csv_log(path, COLUMNS, cumulative=True, wrap_bits=16)


# --- a cumulative counter read as increments ---------------------------------------------

def test_a_counter_that_only_grows_warns_when_read_as_increments(tmp_path, parser):
    counts = np.cumsum(np.r_[0, np.arange(1, 60) % 7 + 1])  # a wheel driving forward
    lines = "\n".join(f"{0.05 * i:.2f},{c},{(i * 3) % 5}" for i, c in enumerate(counts))
    path = write_bytes(tmp_path, "odo.csv", f"t,L,R\n{lines}\n".encode())
    with pytest.warns(UserWarning, match=r"odo\.csv: column 'L' \(ticks_left\) never decreases") as record:
        read_csv_log(path, COLUMNS)
    assert len(record) == 1 and "--cumulative" in str(record[0].message)  # R is not flagged
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_csv_log(path, COLUMNS, cumulative=True)


@pytest.mark.parametrize("values", [
    np.full(100, 4),                              # a constant speed in ticks per row
    np.r_[0, 3, 4, 3, 5, 4] .repeat(20),          # jitter: increments go up and down
    np.arange(10),                                # a short ramp: too few values to say
])
def test_ordinary_increments_do_not_warn(tmp_path, parser, values):
    lines = "\n".join(f"{i},{v},{v}" for i, v in enumerate(values))
    path = write_bytes(tmp_path, "odo.csv", f"t,L,R\n{lines}\n".encode())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_csv_log(path, COLUMNS)


def test_integer_and_float_counters_unwrap_alike():
    """The integer path (exact) and the float path agree where floats are exact."""
    from odomkit.io.table import counter_increments, unwrap_counter

    raw = np.array([65530, 65535, 3, 10, 65534, 2])
    ints = counter_increments(raw, 16)
    floats = counter_increments(raw.astype(float), 16)
    assert np.array_equal(ints, floats) and ints.tolist() == wrapped_steps(raw.tolist(), 16)
    assert np.array_equal(unwrap_counter(raw, 16), unwrap_counter(raw.astype(float), 16))
    with pytest.raises(InputError, match="counter width must be"):
        counter_increments(raw, 12)
