"""meshcorr.io.indices: index files (truths, landmarks) that cannot be read are input errors, never a crash."""

import pytest

from meshcorr.errors import InputError
from meshcorr.io.indices import read_index_lines


def test_an_unreadable_index_file_is_an_input_error_naming_it(tmp_path, no_read_permission):
    # a PermissionError went up to the command line as an internal error, exit 1 (issue 31, item 13)
    path = tmp_path / "locked.txt"
    path.write_text("0 1\n")
    no_read_permission("locked.txt")
    with pytest.raises(InputError, match=r"Cannot read the landmark file .*locked.txt: Permission denied"):
        read_index_lines(path, "landmark")


def test_a_folder_or_bytes_that_are_no_text_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="is a folder"):
        read_index_lines(tmp_path, "ground-truth")
    (tmp_path / "bytes.txt").write_bytes(b"0 1\n\xff\xfe 2\n")
    with pytest.raises(InputError, match=r"must be plain text \(byte 4 is not ASCII\)"):
        read_index_lines(tmp_path / "bytes.txt", "ground-truth")
