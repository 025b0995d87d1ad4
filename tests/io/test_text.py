"""odomkit.io.text through the log readers (issue 10 item 8): gzip read transparently,
other encodings, a binary file named, in both parsers."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.halmstad import read_khepera
from odomkit.io.optiodom import read_run

COLUMNS = {"t": "t", "ticks_left": "L", "ticks_right": "R"}



def write_bytes(tmp_path, name, data: bytes):
    path = tmp_path / name
    path.write_bytes(data)
    return path


def same_log(a, b):
    assert np.array_equal(a.t, b.t)
    assert a.channels.keys() == b.channels.keys()
    for name in a.channels:
        assert np.array_equal(a.channels[name], b.channels[name]), name


# --- gzip --------------------------------------------------------------------------------

CSV = "# logger v2\nt,L,R\n0,0,0\n0.05,3,4\n0.10,5,9\n0.15,9,13\n"


def test_gzip_csv_log_reads_like_the_plain_one(tmp_path, parser):
    plain = write_bytes(tmp_path, "log.csv", CSV.encode())
    packed = write_bytes(tmp_path, "log.csv.gz", gzip.compress(CSV.encode()))
    same_log(read_csv_log(packed, COLUMNS), read_csv_log(plain, COLUMNS))
    same_log(read_csv_log(packed, COLUMNS, cumulative=True), read_csv_log(plain, COLUMNS, cumulative=True))
    assert np.array_equal(read_csv_log(plain, COLUMNS).channels["ticks_right"], [0, 4, 9, 13])


def test_gzip_khepera_and_optiodom_logs(tmp_path, parser):
    counts = "0 0\n5 7\n12 13\n"
    same_log(read_khepera(write_bytes(tmp_path, "khepera.txt.gz", gzip.compress(counts.encode()))),
             read_khepera(write_bytes(tmp_path, "khepera.txt", counts.encode())))
    run = "0,0,0,0,1,2\n0.05,0.001,0,0.01,3,4\n"
    same_log(read_run(write_bytes(tmp_path, "x_run-01.csv.gz", gzip.compress(run.encode()))),
             read_run(write_bytes(tmp_path, "x_run-01.csv", run.encode())))


def test_a_damaged_gzip_file_is_named(tmp_path):
    path = write_bytes(tmp_path, "log.csv.gz", gzip.compress(CSV.encode())[:20])
    with pytest.raises(InputError, match=r"log\.csv\.gz: .*gzip"):
        read_csv_log(path, COLUMNS)


def test_an_error_in_a_gzip_log_names_the_line_of_the_text(tmp_path, parser):
    path = write_bytes(tmp_path, "log.csv.gz", gzip.compress((CSV + "0.2,x,1\n").encode()))
    with pytest.raises(InputError, match="line 7: column 2: 'x' is not a number"):
        read_csv_log(path, COLUMNS)


# --- encodings ---------------------------------------------------------------------------

def test_latin1_comment_and_header_are_read(tmp_path, parser):
    """A line that is not UTF-8 is read as Latin-1: comments and column names of an older
    logger; it cannot change a number."""
    text = "# mesur\xe9 le 3 mai\nt,gauche_\xe9,droite\n0,0,0\n1,2,3\n".encode("latin-1")
    log = read_csv_log(write_bytes(tmp_path, "l.csv", text),
                       {"t": "t", "ticks_left": "gauche_\xe9", "ticks_right": "droite"})
    assert np.array_equal(log.channels["ticks_right"], [0, 3])


def test_utf8_with_byte_order_mark(tmp_path, parser):
    log = read_csv_log(write_bytes(tmp_path, "b.csv", "\ufeff".encode() + b"t,L,R\n0,0,0\n1,2,3\n"), COLUMNS)
    assert np.array_equal(log.channels["ticks_left"], [0, 2])


def test_a_non_utf8_byte_in_a_data_row_is_named(tmp_path, parser):
    path = write_bytes(tmp_path, "l.csv", b"t,L,R\n0,0,0\n1,2\xff,3\n")
    with pytest.raises(InputError, match="line 3: column 2: '2\xff' is not a number"):
        read_csv_log(path, COLUMNS)


def test_a_binary_file_is_named(tmp_path, parser):
    path = write_bytes(tmp_path, "bag.csv", b"t,L,R\n0,0,0\n\x00\x01\x02\x03\n")
    with pytest.raises(InputError, match=r"bag\.csv, line 3: binary data"):
        read_csv_log(path, COLUMNS)



def test_read_text_directly(tmp_path):
    from odomkit.io.text import read_text

    plain = write_bytes(tmp_path, "a.txt", "\ufeffcaf\u00e9\r\n# r\xe9glage\n".encode("utf-8"))
    assert read_text(plain) == "caf\u00e9\r\n# r\xe9glage\n"
    mixed = write_bytes(tmp_path, "b.txt", "caf\u00e9\n".encode() + b"# r\xe9glage\n")
    assert read_text(mixed) == "caf\u00e9\n# r\u00e9glage\n"  # line by line: UTF-8, then Latin-1
    with pytest.raises(InputError, match=r"b\.txt, line 2: byte 0xe9 is not UTF-8 text"):
        read_text(mixed, strict_utf8=True)
    packed = write_bytes(tmp_path, "c.gz", gzip.compress(b"1 2\n"))
    assert read_text(packed) == "1 2\n"
    with pytest.raises(InputError, match="is gzip-compressed"):
        read_text(packed, compressed=False)
    with pytest.raises(InputError, match="no such file"):
        read_text(tmp_path / "missing.txt")
