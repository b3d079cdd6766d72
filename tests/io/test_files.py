"""meshcorr.io.files: atomic writes leave either the whole new file or the old one."""

import errno
import os

import numpy as np
import pytest

from meshcorr.errors import ParameterError
from meshcorr.io import atomic_write


def test_atomic_write_failure_leaves_nothing(tmp_path):
    def writer(file):
        file.write(b"partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        atomic_write(tmp_path / "out.bin", writer)
    assert os.listdir(tmp_path) == []


def test_atomic_write_failure_keeps_old_file(tmp_path):
    path = tmp_path / "out.txt"
    path.write_bytes(b"old")

    def writer(file):
        file.write(b"new but broken")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(path, writer)
    assert path.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["out.txt"]


def test_atomic_write_replaces_file(tmp_path):
    path = tmp_path / "out.txt"
    path.write_bytes(b"old")
    atomic_write(path, lambda file: file.write(b"new"))
    assert path.read_bytes() == b"new"
    assert os.listdir(tmp_path) == ["out.txt"]


def test_atomic_write_missing_directory(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        atomic_write(tmp_path / "no" / "out.txt", lambda file: file.write(b"x"))


def test_a_valid_output_name_of_250_characters_is_written_and_leaves_no_temporary_file(tmp_path):
    # the temporary name adds ".<12 hex>.tmp": it must be cut to fit, not refused (issue 31)
    from meshcorr.io.files import check_outputs
    from meshcorr.io.maps import write_map

    path = tmp_path / ("m" * 246 + ".txt")
    check_outputs({"the map": path})
    write_map(path, np.arange(5))
    assert path.read_text().split() == ["0", "1", "2", "3", "4"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]
    from meshcorr.io.files import sibling

    temp = sibling(path, "tmp")
    assert len(temp.name.encode()) <= 255 and temp.parent == tmp_path and temp.name.startswith(".mmm")
    assert sibling(tmp_path / "map.txt", "tmp").name.startswith(".map.txt.")  # short names are kept whole


@pytest.mark.parametrize("name", ["newdir/", "file.txt/", "folder/"])
def test_an_output_path_ending_with_a_separator_is_refused(tmp_path, name):
    # Path() drops the separator: 'newdir/' wrote a file 'newdir' and 'file.txt/' replaced file.txt (issue 31)
    from meshcorr.io.files import check_outputs
    from meshcorr.io.maps import write_map

    (tmp_path / "file.txt").write_text("old\n")
    (tmp_path / "folder").mkdir()
    path = f"{tmp_path}/{name}"
    with pytest.raises(ParameterError, match="names a folder"):
        check_outputs({"-o": path})
    with pytest.raises(ParameterError, match="names a folder"):
        write_map(path, np.arange(3))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "folder"]
    assert (tmp_path / "file.txt").read_text() == "old\n" and not any((tmp_path / "folder").iterdir())


def test_stdout_is_taken_only_for_the_outputs_that_can_go_there(tmp_path):
    from meshcorr.io.files import check_outputs

    check_outputs({"-o": "-"}, stdout=("-o",))
    with pytest.raises(ParameterError, match=r"Cannot write --report to stdout .*\./- for a file named"):
        check_outputs({"-o": "-", "--report": "-"}, stdout=("-o",))


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT])
@pytest.mark.parametrize("when", ["write", "fsync"])
def test_a_full_disk_is_said_with_the_path_and_leaves_nothing(tmp_path, monkeypatch, code, when):
    from meshcorr.errors import DiskFullError, OutputError

    path = tmp_path / "out.bin"
    path.write_bytes(b"old")

    def full(*args):
        raise OSError(code, os.strerror(code))

    def writer(file):
        file.write(b"partial")
        if when == "write":
            full()

    if when == "fsync":
        monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(DiskFullError) as caught:
        atomic_write(path, writer)
    assert isinstance(caught.value, OutputError) and str(path) in str(caught.value)
    assert ("disk is full" if code == errno.ENOSPC else "quota is exceeded") in str(caught.value)
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["out.bin"]
