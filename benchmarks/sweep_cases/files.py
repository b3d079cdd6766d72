"""Cases of the first two fixes of issue 31: a PLY with more records than its header, a 250-character output name."""

from pathlib import Path


def _long_ply(tmp: Path) -> None:
    lines = ["ply", "format ascii 1.0", "element vertex 4", "property float x", "property float y",
             "property float z", "element face 4", "property list uchar int vertex_indices", "end_header",
             "0 0 0", "1 0 0", "0 1 0", "0 0 1", "3 0 2 1", "3 0 1 3", "3 0 3 2", "3 1 2 3", "3 0 1 2"]
    (tmp / "long.ply").write_text("\n".join(lines) + "\n")


CASES = [
    dict(name="ASCII PLY with more face lines than its header declares", setup=_long_ply,
         argv=["match", "{tmp}/long.ply", "{R}", "-o", "{tmp}/m.txt"], exit=3, stderr="the header declares 8 records",
         check=lambda tmp: "a map was written" if (tmp / "m.txt").exists() else None),
    dict(name="250-character output name", argv=["match", "{R}", "{B}", "-o", "{tmp}/" + "m" * 246 + ".txt"],
         exit=0, check=lambda tmp: None if (tmp / ("m" * 246 + ".txt")).is_file() else "no map written"),
]
