"""Cases of issue 31's items 6, 7 and 13: outputs named '-' or a folder, map and truth entries that cannot be
vertices, unreadable inputs (a folder, bytes that are no text; a file without read permission cannot be made
here, the sweep may run as root: tests/cli/test_match.py and test_evaluate.py patch the read instead).

Item 11 (a full disk) has no case here: a case cannot fill a disk or redirect the command's stdout;
tests/io/test_files.py and tests/cli/test_match.py make the writes fail with ENOSPC instead.
Item 2 (Correspondence.load) is library-only: tests/maps/test_result.py.
"""

from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _left(tmp: Path, *expected: str) -> str | None:
    """A failure unless the case's folder holds exactly ``expected`` (nothing written, inputs untouched)."""
    names = sorted(p.name for p in tmp.iterdir())
    return None if names == sorted(expected) else f"the folder holds {names}, expected {sorted(expected)}"


def _file_and_folder(tmp: Path) -> None:
    (tmp / "file.txt").write_text("mine\n")
    (tmp / "folder").mkdir()


def _untouched(tmp: Path) -> str | None:
    if (tmp / "file.txt").read_text() != "mine\n":
        return "file.txt was replaced"
    if any((tmp / "folder").iterdir()):
        return "a file was written into folder"
    return _left(tmp, "file.txt", "folder")


def _rest_map() -> np.ndarray:
    """A map of creature_rest onto itself (the identity): 500 entries."""
    from meshcorr.io import read_mesh

    return np.arange(len(read_mesh(EXAMPLES / "creature_rest.off")[0]), dtype=np.int64)


def _huge_uint64_map(tmp: Path) -> None:
    mapping = _rest_map().astype(np.uint64)
    mapping[7] = np.uint64(2 ** 64 - 1)
    np.save(tmp / "huge.npy", mapping)


def _truth_with_a_second_target(tmp: Path) -> None:
    mapping = _rest_map()
    np.savetxt(tmp / "map.txt", mapping, fmt="%d")
    (tmp / "pairs.txt").write_text("".join(f"{i} {i}\n" for i in mapping) + "3 7\n")


def _bad_inputs(tmp: Path) -> None:
    """A folder, bytes that are no text, and a truth pair outside the target's vertices."""
    (tmp / "folder").mkdir()
    (tmp / "bytes.txt").write_bytes(b"0 1\n\xff\xfe\n")
    (tmp / "bytes.vts").write_bytes(b"\xff\xfe\n")
    (tmp / "one.vts").write_text("1\n")
    (tmp / "far.txt").write_text("1 999999\n")


CASES = [
    dict(name="--alternative-out - is refused, not written to a file named '-'",
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--alternative-out", "-"], exit=2,
         stderr="Cannot write --alternative-out to stdout", check=lambda tmp: _left(tmp)),
    dict(name="--report - is refused, not written to a file named '-'",
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--report", "-"], exit=2,
         stderr="Cannot write --report to stdout", check=lambda tmp: _left(tmp)),
    dict(name="-o newdir/ (no such folder) is refused, not written as a file newdir", setup=_file_and_folder,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/newdir/"], exit=2, stderr="names a folder", check=_untouched),
    dict(name="-o file.txt/ is refused and file.txt kept", setup=_file_and_folder,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/file.txt/"], exit=2, stderr="file.txt is a file",
         check=_untouched),
    dict(name="-o folder/ (an existing folder) is refused", setup=_file_and_folder,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/folder/"], exit=2, stderr="names a folder", check=_untouched),
    dict(name="--report folder (an existing folder) is refused", setup=_file_and_folder,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--report", "{tmp}/folder"], exit=2,
         stderr="it is a folder", check=_untouched),
    dict(name="a uint64 map entry 2**64-1 is refused, not read as -1 (unmapped)", setup=_huge_uint64_map,
         argv=["evaluate", "{R}", "{R}", "{tmp}/huge.npy", "--gt", "identity"], exit=3,
         stderr="entry 7 is 18446744073709551615, too large for a vertex index"),
    dict(name="a truth file giving one source vertex two targets is refused", setup=_truth_with_a_second_target,
         argv=["evaluate", "{R}", "{R}", "{tmp}/map.txt", "--gt", "{tmp}/pairs.txt"], exit=3,
         stderr="line 501: source vertex 3 already has the true target 3 on line 4, and here 7"),
    dict(name="a folder as MAP is an input error", setup=_bad_inputs,
         argv=["evaluate", "{R}", "{B}", "{tmp}/folder", "--gt", "identity"], exit=3, stderr="folder"),
    dict(name="a --gt of bytes that are no text is an input error", setup=_bad_inputs,
         argv=["evaluate", "{R}", "{R}", "{tmp}/bytes.txt", "--gt", "{tmp}/bytes.txt"], exit=3,
         stderr="not a text file"),
    dict(name="a folder as --landmarks is an input error", setup=_bad_inputs,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--landmarks", "{tmp}/folder"], exit=3,
         stderr="is a folder", check=lambda tmp: "a map was written" if (tmp / "m.txt").exists() else None),
    dict(name="--landmarks-vts of bytes that are no text is an input error", setup=_bad_inputs,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--landmarks-vts", "{tmp}/bytes.vts", "{tmp}/one.vts"],
         exit=3, stderr="must be plain text",
         check=lambda tmp: "a map was written" if (tmp / "m.txt").exists() else None),
    # --method icp has no alternative map, which is found after the match (exit 2): the --gt must be refused first
    dict(name="match --gt is read and checked before the work", setup=_bad_inputs,
         argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", "--method", "icp", "--alternative-out", "{tmp}/alt.txt",
               "--report", "{tmp}/r.html", "--gt", "{tmp}/far.txt"], exit=3,
         stderr="names target vertex 999999, but the target mesh has 1000 vertices",
         check=lambda tmp: _left(tmp, "folder", "bytes.txt", "bytes.vts", "one.vts", "far.txt")),
]
