"""Issue 31, item 9: landmarks that look wrong are named in a warning; the map is still written."""

from pathlib import Path

TRUTH = Path(__file__).resolve().parents[2] / "examples" / "creature_rest_to_bent.gt.txt"
SOURCES = (10, 100, 200, 300, 400, 480)


def _landmarks(tmp: Path, wrong: bool) -> None:
    truth = [int(line) for line in TRUTH.read_text().split()]
    pairs = [(a, truth[a]) for a in SOURCES]
    if wrong:
        pairs[2] = (SOURCES[2], truth[SOURCES[5]])  # vertex 200 sent where vertex 480 goes
    (tmp / "landmarks.txt").write_text("".join(f"{a} {b}\n" for a, b in pairs))


CASES = [
    dict(name="landmark file with one wrong pair of six", setup=lambda tmp: _landmarks(tmp, True),
         argv=["match", "{R}", "{B}", "--landmarks", "{tmp}/landmarks.txt", "-o", "{tmp}/m.txt"], exit=0,
         stderr="meshcorr: warning: 1 of the 6 landmark pairs look wrong",
         check=lambda tmp: None if (tmp / "m.txt").is_file() else "no map written"),
    dict(name="landmark file of six right pairs", setup=lambda tmp: _landmarks(tmp, False),
         argv=["match", "{R}", "{B}", "--landmarks", "{tmp}/landmarks.txt", "-o", "{tmp}/m.txt"], exit=0,
         check=lambda tmp: None if (tmp / "m.txt").is_file() else "no map written"),
]
