"""Cases of issue 31's batch items: resuming by content and whole maps (3), one run per folder (4),
a cache folder that cannot be written (12)."""

import fcntl
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REST, BENT = ROOT / "examples" / "creature_rest.off", ROOT / "examples" / "creature_bent.off"
_HELD = []  # the lock file descriptors a case holds while its command runs


def _hold_lock(tmp: Path) -> None:
    (tmp / "out").mkdir()
    fd = os.open(tmp / "out" / ".lock", os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # another batch writing into out/
    _HELD.append(fd)


def _release_lock(tmp: Path):
    while _HELD:
        os.close(_HELD.pop())
    return "the refused run wrote a summary" if (tmp / "out" / "summary.json").exists() else None


def _done_batch(tmp: Path) -> None:
    """Copies of the two examples mapped into tmp/out (one pair)."""
    for source in (REST, BENT):
        (tmp / source.name).write_bytes(source.read_bytes())
    subprocess.run([sys.executable, "-m", "meshcorr", "batch", "--template", str(tmp / REST.name),
                    str(tmp / BENT.name), "--out", str(tmp / "out"), "--workers", "1", "-q"], check=True, cwd=tmp)
    record = json.loads((tmp / "out" / "summary.json").read_text())["pairs"][0]
    (tmp / "before.json").write_text(json.dumps({"mtime": os.stat(record["map"]).st_mtime_ns}))


def _cut_map(tmp: Path) -> None:
    _done_batch(tmp)
    path = tmp / "out" / "maps" / "creature_rest__creature_bent.txt"
    path.write_text(path.read_text()[:100])


def _edit_in_place(tmp: Path) -> None:
    """One digit of a vertex of the target changed: the same size, the same modification time."""
    _done_batch(tmp)
    path = tmp / BENT.name
    info, lines = path.stat(), path.read_text().splitlines(keepends=True)
    digit = next(i for i, c in enumerate(lines[2]) if c in "12345678")
    lines[2] = lines[2][:digit] + str(int(lines[2][digit]) + 1) + lines[2][digit + 1:]
    path.write_text("".join(lines))
    os.utime(path, ns=(info.st_atime_ns, info.st_mtime_ns))


def _remapped(tmp: Path):
    record = json.loads((tmp / "out" / "summary.json").read_text())["pairs"][0]
    if os.stat(record["map"]).st_mtime_ns == json.loads((tmp / "before.json").read_text())["mtime"]:
        return "the pair was skipped: its stale map kept"
    if len(Path(record["map"]).read_text().splitlines()) != record["map_length"]:
        return "the map written again is not whole"
    return None


def _mapped(tmp: Path):
    return None if (tmp / "out" / "maps" / "creature_rest__creature_bent.txt").is_file() else "no map written"


_PAIR = ["batch", "--template", "{tmp}/creature_rest.off", "{tmp}/creature_bent.off", "--out", "{tmp}/out",
         "--workers", "1", "-q"]

CASES = [
    dict(name="batch into a folder another batch is writing into", setup=_hold_lock,
         argv=["batch", "--template", "{R}", "{B}", "--out", "{tmp}/out"], exit=2,
         stderr="Another meshcorr batch is writing into", check=_release_lock),
    dict(name="batch with a --cache folder that cannot be made", setup=lambda tmp: (tmp / "file").write_text("x"),
         argv=["batch", "--template", "{R}", "{B}", "--out", "{tmp}/out", "--workers", "1", "--cache",
               "{tmp}/file/cache"], exit=0, stderr="The batch runs without the cache", check=_mapped, slow=True),
    dict(name="batch rerun after a map file was cut short", setup=_cut_map, argv=_PAIR, exit=0, check=_remapped,
         slow=True),
    dict(name="batch rerun after a mesh changed in place (same size and time)", setup=_edit_in_place, argv=_PAIR,
         exit=0, check=_remapped, slow=True),
]
