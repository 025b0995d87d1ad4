"""odomkit.io.files: every output path is checked before anything is written (issue 10)."""

from __future__ import annotations

import os
import stat

import pytest

from odomkit.errors import InputError
from odomkit.io import files
from odomkit.io.files import check_outputs


def test_new_files_in_an_existing_folder_pass(tmp_path):
    got = check_outputs({"--out": tmp_path / "a.csv", "--tum": tmp_path / "a.tum", "--plot": None})
    assert got == {"--out": tmp_path / "a.csv", "--tum": tmp_path / "a.tum"}


def test_an_existing_file_needs_force(tmp_path):
    (tmp_path / "a.csv").write_text("mine")
    with pytest.raises(InputError, match="a.csv: exists already; pass --force"):
        check_outputs({"--out": tmp_path / "a.csv"})
    check_outputs({"--out": tmp_path / "a.csv"}, overwrite=True)


def test_a_folder_or_a_missing_folder_is_named(tmp_path):
    (tmp_path / "x").mkdir()
    with pytest.raises(InputError, match="--out names a folder; give a file path"):
        check_outputs({"--out": tmp_path / "x"}, overwrite=True)
    with pytest.raises(InputError, match="--out: no such folder"):
        check_outputs({"--out": tmp_path / "nodir" / "out.csv"}, overwrite=True)


def test_a_file_where_a_folder_should_be(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(InputError, match="is a file, not a folder"):
        check_outputs({"--out": tmp_path / "f" / "out.csv"})


def test_two_outputs_on_one_path_are_refused_whatever_the_spelling(tmp_path):
    with pytest.raises(InputError, match="--out and --tum name the same file"):
        check_outputs({"--out": tmp_path / "t.csv", "--tum": tmp_path / "sub" / ".." / "t.csv"},
                      overwrite=True)


def test_an_output_on_an_input_is_refused_even_with_force(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text("1,2\n")
    with pytest.raises(InputError, match="--out would replace an input"):
        check_outputs({"--out": log}, overwrite=True, inputs=[log])
    assert log.read_text() == "1,2\n"


def test_a_folder_output(tmp_path):
    # missing (made later, parents too) or existing: fine; an existing file: refused
    check_outputs({"--out": tmp_path / "new" / "deeper"}, folders={"--out"})
    check_outputs({"--out": tmp_path}, folders={"--out"})
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="--out names an existing file; give a folder"):
        check_outputs({"--out": tmp_path / "file"}, folders={"--out"})
    # files inside a folder the command makes need no existing parent
    check_outputs({"--out": tmp_path / "new", "summary": tmp_path / "new" / "summary.json"},
                  folders={"--out"})


def test_a_read_only_folder_is_named(tmp_path, monkeypatch):
    # as root every folder is writable, so the permission check is simulated here;
    # test_a_read_only_folder_for_real checks the same with a real chmod
    real_access = os.access
    monkeypatch.setattr(files.os, "access",
                        lambda p, mode: False if str(p) == str(tmp_path) else real_access(p, mode))
    with pytest.raises(InputError, match="is not writable"):
        check_outputs({"--out": tmp_path / "a.csv"})
    with pytest.raises(InputError, match="is not writable"):
        check_outputs({"--out": tmp_path / "new"}, folders={"--out"})


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write anywhere")
def test_a_read_only_folder_for_real(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        with pytest.raises(InputError, match="is not writable"):
            check_outputs({"--out": folder / "a.csv"})
    finally:
        folder.chmod(stat.S_IRWXU)


def test_a_python_writer_on_an_existing_file_names_its_overwrite_parameter(tmp_path):
    """API user study, L1: ``write_robot`` and ``write_tum`` said "pass --force", which a
    Python caller has not; their parameter is ``overwrite=True``. The message names both."""
    import numpy as np

    from odomkit.io.robotfile import write_robot
    from odomkit.io.trackio import write_tum
    from odomkit.log import OdometryLog
    from odomkit.robot import DiffDrive, Unicycle
    from odomkit.track import dead_reckon_log

    robot_path, tum_path = tmp_path / "r.toml", tmp_path / "t.tum"
    robot_path.write_text("mine")
    tum_path.write_text("mine")
    log = OdometryLog(np.arange(3.0), {"speed": np.ones(3), "yaw_rate": np.zeros(3)})
    track = dead_reckon_log(log, Unicycle())
    for call in (lambda: write_robot(robot_path, DiffDrive(0.2)), lambda: write_tum(tum_path, track),
                 lambda: check_outputs({"--out": tum_path})):
        with pytest.raises(InputError, match=r"exists already; pass --force to replace it "
                                             r"\(overwrite=True from Python\)$"):
            call()
    assert robot_path.read_text() == tum_path.read_text() == "mine"
    write_robot(robot_path, DiffDrive(0.2), overwrite=True)
