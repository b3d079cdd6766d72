"""Cases of issue 31's items 10, 14, 16, 17 and 19: options ignored in silence, extreme coordinates, a tiny
mesh, unbounded --workers / --refine-k, and the messages' option names."""

from pathlib import Path

N_EXAMPLE = 500  # vertices of each bundled example


def _identity_map(tmp: Path) -> None:
    (tmp / "m.txt").write_text("\n".join(str(i) for i in range(N_EXAMPLE)) + "\n")


def _fmap_file(tmp: Path) -> None:
    (tmp / "f.npz").write_bytes(b"")  # refused before it is read


def _no_map(tmp: Path) -> str | None:
    return "a map was written" if (tmp / "m.txt").exists() else None


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
]
