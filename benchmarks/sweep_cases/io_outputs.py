"""Cases of issue 31's items 6, 7 and 13: outputs named '-' or a folder, map and truth entries that cannot be
vertices, unreadable inputs.

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
]
