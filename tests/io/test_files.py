"""meshcorr.io.files: atomic writes leave either the whole new file or the old one."""

import os

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
