"""Cases of issue 31's items 10, 14, 16, 17 and 19: options ignored in silence, extreme coordinates, a tiny
mesh, unbounded --workers / --refine-k, and the messages' flag names."""

from pathlib import Path

N_EXAMPLE = 500  # vertices of each bundled example


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _scaled(factor: float):
    """A setup writing both examples with their coordinates times ``factor`` (full precision) as r.off, b.off."""
    def setup(tmp: Path) -> None:
        for name, out in (("creature_rest.off", "r.off"), ("creature_bent.off", "b.off")):
            lines = (EXAMPLES / name).read_text().split("\n")
            n = int(lines[1].split()[0])
            lines[2:2 + n] = [" ".join(repr(float(x) * factor) for x in line.split()) for line in lines[2:2 + n]]
            (tmp / out).write_text("\n".join(lines))
    return setup


def _prisms(tmp: Path) -> None:
    """Two closed hexagonal prisms of 12 vertices (heights 1 and 1.5) as prism.off, prism2.off."""
    import math

    faces = [[i, (i + 1) % 6, 6 + (i + 1) % 6] for i in range(6)] + [[i, 6 + (i + 1) % 6, 6 + i] for i in range(6)]
    faces += [[0, t + 1, t] for t in range(1, 5)] + [[6, 6 + t, 7 + t] for t in range(1, 5)]
    for name, height in (("prism.off", 1.0), ("prism2.off", 1.5)):
        ring = [(math.cos(i * math.pi / 3), math.sin(i * math.pi / 3)) for i in range(6)]
        points = [(x, y, 0.0) for x, y in ring] + [(x, y, height) for x, y in ring]
        (tmp / name).write_text(f"OFF\n12 {len(faces)} 0\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points)
                                + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces))


def _identity_map(tmp: Path) -> None:
    (tmp / "m.txt").write_text("\n".join(str(i) for i in range(N_EXAMPLE)) + "\n")


def _fmap_file(tmp: Path) -> None:
    (tmp / "f.npz").write_bytes(b"")  # refused before it is read


def _no_map(tmp: Path) -> str | None:
    return "a map was written" if (tmp / "m.txt").exists() else None


def _same_map_as_examples(tmp: Path) -> str | None:
    """The scaled examples' map is the examples' own: their map does not depend on scale."""
    import subprocess
    import sys

    subprocess.run([sys.executable, "-m", "meshcorr", "match", str(EXAMPLES / "creature_rest.off"),
                    str(EXAMPLES / "creature_bent.off"), "-o", str(tmp / "ref.txt"), "-q"], check=True, timeout=120)
    return None if (tmp / "m.txt").read_text() == (tmp / "ref.txt").read_text() else "another map than the examples'"


def _refused(name: str, extra: list, message: str) -> dict:
    """``meshcorr match R B`` with ``extra``: refused before any work (exit 2), no map written."""
    return dict(name=name, argv=["match", "{R}", "{B}", "-o", "{tmp}/m.txt", *extra], exit=2, stderr=message,
                check=_no_map)


CASES = [
    # item 10: options that another option makes certain to be ignored
    _refused("--samples with --mode dense", ["--mode", "dense", "--samples", "30"], "n_samples=30 (--samples)"),
    _refused("--refine-k with --no-refine", ["--no-refine", "--refine-k", "20"], "refine=False (--no-refine)"),
    _refused("--control-points with --icp-iterations 0", ["--icp-iterations", "0", "--control-points", "40"],
             "n_control=40 (--control-points)"),
    _refused("--max-memory with --mode scalable", ["--mode", "scalable", "--max-memory", "4GiB"],
             "max_memory='4GiB' (--max-memory)"),
    dict(name="show --geodesic without --gt", setup=_identity_map,
         argv=["show", "{R}", "{B}", "{tmp}/m.txt", "-o", "{tmp}/p.png", "--geodesic", "fmm"], exit=2,
         stderr="without --gt", check=lambda tmp: "a picture was written" if (tmp / "p.png").exists() else None),
    dict(name="transfer --cmap with parts", setup=_identity_map,
         argv=["transfer", "{R}", "{B}", "{tmp}/m.txt", "--attribute", "parts", "--cmap", "coolwarm",
               "-o", "{tmp}/c.ply"], exit=2, stderr="--attribute parts gives colours",
         check=lambda tmp: "a mesh was written" if (tmp / "c.ply").exists() else None),
    dict(name="fmap --to-map with -k and --seed", setup=_fmap_file,
         argv=["fmap", "{R}", "{B}", "--to-map", "{tmp}/f.npz", "-k", "20", "--seed", "2", "-o", "{tmp}/m.txt"],
         exit=2, stderr="-k 20 and --seed 2", check=_no_map),
    # item 14: coordinates the numerics cannot take (an internal error near 1e200, "degenerate faces" near 1e-200)
    dict(name="coordinates near 1e200", setup=_scaled(1e200), argv=["match", "{tmp}/r.off", "{tmp}/b.off", "-o",
         "{tmp}/m.txt"], exit=3, stderr="coordinates as large as 3.59e+200", check=_no_map),
    dict(name="coordinates near 1e-200", setup=_scaled(1e-200), argv=["match", "{tmp}/r.off", "{tmp}/b.off", "-o",
         "{tmp}/m.txt"], exit=3, stderr="a bounding box only 4.86e-200 across", check=_no_map),
    dict(name="coordinates near 1e-30 give the examples' map", setup=_scaled(1e-30),
         argv=["match", "{tmp}/r.off", "{tmp}/b.off", "-o", "{tmp}/m.txt"], exit=0, check=_same_map_as_examples),
    # item 16: a tiny valid closed mesh (its spline system was singular: LinAlgError, an internal error)
    dict(name="a 12-vertex hexagonal prism", setup=_prisms,
         argv=["match", "{tmp}/prism.off", "{tmp}/prism2.off", "-o", "{tmp}/m.txt"], exit=0,
         check=lambda tmp: None if len((tmp / "m.txt").read_text().split()) == 12 else "no 12-line map"),
    # item 17: unbounded sizes (processes until the machine gave out; 131 s lowered to n - 1 in silence)
    dict(name="batch --workers 100000", argv=["batch", "--all-pairs", "{R}", "{B}", "--out", "{tmp}/out",
                                              "--workers", "100000"], exit=2, stderr="--workers 100000 would start",
         check=lambda tmp: "an output folder was made" if (tmp / "out").exists() else None),
    _refused("--refine-k 100000", ["--refine-k", "100000"], "refine_k=100000 (--refine-k) is more than"),
    # item 19: messages name the command line's flags, not only the settings
    _refused("--control-points 3 names its flag", ["--control-points", "3"],
             "'n_control' parameter (--control-points) must be an int >= 7"),
    _refused("--anchors -1 names its flag", ["--anchors", "-1"], "'n_anchors' parameter (--anchors) must be"),
    _refused("--alpha -1 names its flag", ["--alpha", "-1"], "'anchor_weight' parameter (--alpha) must be"),
]
