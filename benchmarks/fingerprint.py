"""Fingerprints of maps: did a change that should not change behaviour keep every map bit for bit?

Runs ``meshcorr.match`` on a fixed list of pairs and option sets that cover
the pipeline's branches (whole shapes from every set of ``../shared/data``,
landmarks, parts both ways, the scalable mode, a point cloud, a one-to-one
map, no refinement, prepared shapes, every baseline on the bundled example)
and prints one SHA-256 per case of the map, the alternative map and the
candidate summaries. Run it before and after a refactoring and compare::

    python benchmarks/fingerprint.py --out /tmp/before.json
    # ... the change ...
    python benchmarks/fingerprint.py --out /tmp/after.json --compare /tmp/before.json

Cases that need ``../shared/data`` are skipped, with a line, when it is absent.
Exit status 1 when ``--compare`` finds a difference.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import meshcorr

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
EXAMPLES = ROOT / "examples"


def _digest(*arrays) -> str:
    h = hashlib.sha256()
    for array in arrays:
        if array is None:
            h.update(b"none")
        else:
            array = np.ascontiguousarray(array)
            h.update(str(array.dtype).encode() + str(array.shape).encode() + array.tobytes())
    return h.hexdigest()[:16]


def _candidates(result) -> str:
    rows = getattr(result, "map_candidates", None) or []
    return hashlib.sha256(json.dumps(rows, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _cut(path: Path, keep: float):
    from meshcorr.evaluation.metrics.cuts import cut_by_plane  # noqa: PLC0415 (the layout after issue 30)
    return cut_by_plane(path, keep=keep, random_state=0)[0]


def _cut_old(path: Path, keep: float):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return _cut(path, keep)
        except ImportError:
            from meshcorr.evaluation.cuts import cut_by_plane  # noqa: PLC0415 (the layout before issue 30)
            return cut_by_plane(path, keep=keep, random_state=0)[0]


def cases():
    """(name, thunk) of every case; a thunk returns a Correspondence."""
    rest, bent = EXAMPLES / "creature_rest.off", EXAMPLES / "creature_bent.off"
    out = [("example", lambda: meshcorr.match(rest, bent)),
           ("example-no-refine", lambda: meshcorr.match(rest, bent, refine=False)),
           ("figure-bijective", lambda: meshcorr.match(meshcorr.datasets.figure(), meshcorr.datasets.figure(pose="bent"),
                                                       bijective=True)),
           ("example-scalable", lambda: meshcorr.match(rest, bent, mode="scalable", n_samples=120)),
           ("example-landmarks", lambda: meshcorr.match(rest, bent, landmarks=[(0, 0), (100, 100), (250, 250)])),
           ("example-symmetry-cost", lambda: meshcorr.match(rest, bent, symmetry="cost")),
           ("example-oriented", lambda: meshcorr.match(rest, bent, oriented_starts=True)),
           ("example-prepared", lambda: meshcorr.match(meshcorr.prepare(rest), meshcorr.prepare(bent)))]
    for method in ("shapiro-brady", "shapiro-brady-scaled", "tps-rpm", "icp", "shape-context"):
        out.append((f"example-{method}", lambda method=method: meshcorr.match(rest, bent, method=method)))
    if not DATA.is_dir():
        return out
    tosca, noniso = DATA / "tosca5k", DATA / "tosca-noniso"
    shrec, sumner = DATA / "shrec07" / "Meshes", DATA / "sumner"
    pairs = [("tosca-cat", tosca / "cat0.off", tosca / "cat2.off", {}),
             ("tosca-michael", tosca / "michael11.off", tosca / "michael16.off", {}),
             ("tosca-centaur", tosca / "centaur0.off", tosca / "centaur1.off", {}),
             ("noniso-gorilla-man", noniso / "8_gorilla_01.off", noniso / "8_man_01.off", {}),
             ("noniso-gorilla-woman-landmarks", noniso / "8_gorilla_02.off", noniso / "8_woman_03.off", "landmarks"),
             ("shrec-human", shrec / "11.off", shrec / "14.off", {}),
             ("shrec-human-2", shrec / "12.off", shrec / "17.off", {}),
             ("shrec-fourleg", shrec / "391.off", shrec / "396.off", {}),
             ("cat-lion", sumner / "cat-poses" / "cat-reference.obj", sumner / "lion-poses" / "lion-reference.obj",
              {}),
             ("tosca-dog-scalable", tosca / "dog0.off", tosca / "dog2.off", {"mode": "scalable"})]
    for name, a, b, options in pairs:
        if options == "landmarks":
            options = {"landmarks": _truth_landmarks(a, b)}
        out.append((name, lambda a=a, b=b, options=options: meshcorr.match(a, b, **options)))
    dog, dog2 = tosca / "dog0.off", tosca / "dog3.off"
    out.append(("tosca-dog-part-source", lambda: meshcorr.match(_cut_old(dog, 0.7), dog2, partial="source")))
    out.append(("tosca-dog-part-target", lambda: meshcorr.match(dog2, _cut_old(dog, 0.7), partial="target")))
    out.append(("tosca-wolf-cloud", lambda: meshcorr.match(_cloud(tosca / "wolf0.off"), tosca / "wolf1.off")))
    return out


def _truth_landmarks(a: Path, b: Path) -> np.ndarray:
    corres = a.parent / "corres"
    va = np.loadtxt(corres / f"{a.stem}.vts", dtype=np.int64) - 1
    vb = np.loadtxt(corres / f"{b.stem}.vts", dtype=np.int64) - 1
    rows = np.linspace(0, len(va) - 1, 5).astype(int)
    return np.stack([va[rows], vb[rows]], axis=1)


def _cloud(path: Path):
    import trimesh  # noqa: PLC0415
    mesh = trimesh.load(path, process=False)
    return trimesh.PointCloud(np.asarray(mesh.vertices))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="write the fingerprints here (JSON)")
    parser.add_argument("--compare", type=Path, help="an earlier --out to compare with")
    parser.add_argument("--only", nargs="*", help="case names to run (default: all)")
    args = parser.parse_args(argv)
    if not DATA.is_dir():
        print(f"skipping the cases on real data: {DATA} is absent", file=sys.stderr)
    found = {}
    for name, thunk in cases():
        if args.only and name not in args.only:
            continue
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = thunk()
        found[name] = {"map": _digest(result.map), "alternative": _digest(result.alternative_map),
                       "candidates": _candidates(result)}
        print(f"{name:34s} {found[name]['map']} {found[name]['alternative']} {found[name]['candidates']} "
              f"{time.perf_counter() - start:6.1f} s", file=sys.stderr, flush=True)
    args.out.write_text(json.dumps(found, indent=1, sort_keys=True))
    if args.compare is None:
        return 0
    before = json.loads(args.compare.read_text())
    differ = [name for name in found if name in before and before[name] != found[name]]
    for name in differ:
        print(f"DIFFERS {name}: {before[name]} -> {found[name]}")
    print(f"{len(found) - len(differ)} of {len(found)} cases the same")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
