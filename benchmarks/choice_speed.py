"""Speed and memory of the whole-map choice, side by side in one run (issue 34).

One command reproduces the speed table of ``benchmarks/RESULTS-robustness.md``::

    nice -n 10 python benchmarks/choice_speed.py [--rounds 3] [--data ../shared/data]

Every run is a fresh process (``/usr/bin/time`` gives its wall seconds and
peak resident memory), so imports and file reading count, as for a user;
the runs of one round alternate, so they see the same machine load:

- **5k**: TOSCA cat0 -> cat1 with ``meshcorr match`` (default settings)
  and with pyFM's automatic pipeline (the settings of
  ``benchmarks/tosca_symmetry.py``, the same as ``robustness.py``'s);
- **115k**: Sumner's cat reference -> cat-04, each subdivided twice
  (115 282 vertices; the map's truth is the identity), with the default
  settings (the choice on coarse copies) and with ``--coarse-vertices 0``
  (every stage on the full meshes), and the mean Euclidean error of each
  map over sqrt(area).

The report gives the medians and the ratios: pyFM / meshcorr at 5k, and
115k / 5k for meshcorr. Needs ``../shared/data`` (exits with a message
without it) and pyFM for the 5k comparison (``pip install pyfmaps``).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parents[0].parent / "shared" / "data"
CACHE = HERE / "cache" / "choice-speed"
PYFM = ("import sys; sys.path.insert(0, {here!r}); import numpy as np; from meshcorr.core.mesh import as_mesh; "
        "from tosca_symmetry import pyfm_map; "
        "np.savetxt({out!r}, pyfm_map(as_mesh({a!r}), as_mesh({b!r})), fmt='%d')")


def timed(argv: list[str]) -> tuple[float, float]:
    """Wall seconds and peak resident memory (MiB) of one fresh process."""
    done = subprocess.run(["/usr/bin/time", "-f", "TIME %e %M", *argv], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"choice_speed: {' '.join(argv[:4])} ... failed:\n{done.stderr[-2000:]}")
    line = [x for x in done.stderr.splitlines() if x.startswith("TIME ")][-1].split()
    return float(line[1]), float(line[2]) / 1024


def big_pair(data: Path) -> tuple[Path, Path]:
    """The Sumner cat pair subdivided twice, written once into ``CACHE``."""
    import trimesh

    files = []
    for name in ("cat-reference", "cat-04"):
        path = CACHE / f"{name}-x2.ply"
        if not path.is_file():
            mesh = trimesh.load(data / "sumner" / "cat-poses" / f"{name}.obj", process=False)
            vertices, faces = mesh.vertices, mesh.faces
            for _ in range(2):
                vertices, faces = trimesh.remesh.subdivide(vertices, faces)
            CACHE.mkdir(parents=True, exist_ok=True)
            trimesh.Trimesh(vertices, faces, process=False).export(path)
        files.append(path)
    return files[0], files[1]


def identity_error(target: Path, map_file: Path) -> float:
    """Mean Euclidean distance of each mapped vertex from its truth (the same index), over sqrt(area)."""
    import trimesh

    mesh = trimesh.load(target, process=False)
    mapping = np.loadtxt(map_file, dtype=np.int64)
    return float(np.linalg.norm(mesh.vertices[mapping] - mesh.vertices, axis=1).mean() / np.sqrt(mesh.area))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--no-pyfm", action="store_true", help="leave pyFM out")
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"choice_speed: {args.data} is absent; this benchmark needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    a5, b5 = args.data / "tosca5k" / "cat0.off", args.data / "tosca5k" / "cat1.off"
    a115, b115 = big_pair(args.data)
    runs: dict[str, list[tuple[float, float]]] = {}
    errors: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "map.txt"
        meshcorr = [sys.executable, "-m", "meshcorr", "match"]
        cases = {"meshcorr 5k": meshcorr + [str(a5), str(b5), "-o", str(out), "-q"],
                 "meshcorr 115k": meshcorr + [str(a115), str(b115), "-o", str(out), "-q"],
                 "meshcorr 115k, --coarse-vertices 0": meshcorr + [str(a115), str(b115), "-o", str(out), "-q",
                                                                   "--coarse-vertices", "0"]}
        if not args.no_pyfm:
            cases["pyFM 5k"] = [sys.executable, "-c", PYFM.format(here=str(HERE), out=str(out), a=str(a5), b=str(b5))]
        for round_ in range(args.rounds):
            for name, command in cases.items():
                if "--coarse-vertices 0" in name and round_ > 0:
                    continue  # ~2 minutes a run: once is enough for the ratio
                runs.setdefault(name, []).append(timed(command))
                if "115k" in name and name not in errors:
                    errors[name] = identity_error(b115, out)
                print(f"{name}: {runs[name][-1][0]:.1f} s, {runs[name][-1][1]:.0f} MiB", file=sys.stderr, flush=True)
    median = {name: statistics.median(s for s, _ in values) for name, values in runs.items()}
    print("| run | runs | median seconds | peak MiB (largest) | error (115k) |")
    print("|---|---|---|---|---|")
    for name, values in runs.items():
        error = f"{errors[name]:.4f}" if name in errors else "-"
        print(f"| {name} | {len(values)} | {median[name]:.2f} | {max(m for _, m in values):.0f} | {error} |")
    if "pyFM 5k" in median:
        print(f"\npyFM / meshcorr at 5k: {median['pyFM 5k'] / median['meshcorr 5k']:.2f}x")
    print(f"meshcorr 115k / 5k: {median['meshcorr 115k'] / median['meshcorr 5k']:.1f}x "
          f"(every stage on the full meshes: {median['meshcorr 115k, --coarse-vertices 0'] / median['meshcorr 5k']:.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
