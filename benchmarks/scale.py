"""Time and memory of meshcorr from 0.5k to 115k vertices, dense vs scalable, and against pyFM (issue 5).

One command reproduces every figure of ``benchmarks/RESULTS-scale.md``::

    nice -n 10 python benchmarks/scale.py [--data ../shared/data] [--runs 5] [--out benchmarks/RESULTS-scale.md]

Sections of the report:

1. **Scaling.** Mesh pairs of growing size, each run in a fresh subprocess:
   end-to-end seconds of ``meshcorr.match`` (file reading included), CPU
   seconds, and per stage the seconds and the peak resident memory (VmHWM,
   reset through ``/proc/self/clear_refs`` as each stage starts, so a
   stage's figure is the process's peak while that stage ran, imports
   included). The scalable mode (the default, ``mode="auto"``, above 2000
   vertices) at every size, ``refine=False`` as well at every size (the
   ZoomOut refinement of :mod:`meshcorr.stages.refine` is a separate stage), the
   dense mode where it runs in minutes (<= ``--dense-max`` vertices). Pairs:
   the libigl knight (502 vertices) and its midpoint subdivision (2002)
   against a rotated, scaled, re-indexed copy; TOSCA cat0/cat1 (5000) and
   their midpoint subdivisions (19994/19996, 79970/79980: new vertices are
   appended, so the TOSCA ground truth still holds); the Sumner
   cat-reference/cat-01 poses subdivided twice (115282 vertices, ground
   truth the identity). Accuracy: mean geodesic error on the target
   divided by sqrt(area), over the ground-truth points (at most 1000).
2. **5k pair against pyFM.** TOSCA cat0 -> cat1, ``--runs`` alternating runs
   of meshcorr (default settings) and of pyFM's automatic functional-map
   pipeline as its README gives it (``pip install pyfmaps``: area-normalised
   meshes, 200 Laplace-Beltrami eigenpairs, WKS descriptors,
   ``fit(K=30, w_descr=1, w_lap=0.1, w_dcomm=1, w_orient=1)``, ZoomOut
   ``nit=16, step=5``, point-to-point map), medians and the ratio.
3. **Accuracy, dense vs scalable** on TOSCA 5k pairs, default settings
   otherwise: mean geodesic error per pair and mode, and the error against
   the mirrored truth (``.sym.vts``).

Data: ``../shared/data`` beside the repository (TOSCA, Sumner, libigl
meshes); the script exits with a message when it is absent. Derived meshes
are cached in ``benchmarks/cache/scale`` (git-ignored). Machine load is
recorded with every run: other jobs on a shared machine slow every figure,
so compare numbers measured side by side (the ratios), not across runs.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from meshcorr.runtime.timing import peak_resident_mib, reset_peak
from meshcorr.spectral.modes import SCALABLE_ABOVE

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = HERE.parent.parent / "shared" / "data"
CACHE = HERE / "cache" / "scale"
ACCURACY_PAIRS = ("cat0-cat1,centaur0-centaur1,david0-david1,dog0-dog1,horse0-horse10,"
                  "michael13-michael18,victoria0-victoria1,wolf0-wolf1")
MAX_EVAL_POINTS = 1000


# --- meshes -------------------------------------------------------------------

def _load(path: Path) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def _subdivide(V, F, times: int):
    import trimesh

    for _ in range(times):
        V, F = trimesh.remesh.subdivide(V, F)  # midpoints appended: original indices kept
    return V, F


def _rigid_copy(V, F, seed: int = 0):
    """Rotated, scaled, re-indexed copy; ``truth[i]`` is the copy's index of vertex i."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    perm = rng.permutation(len(V))
    truth = np.empty(len(V), dtype=np.int64)
    truth[perm] = np.arange(len(V))
    return 2.5 * V[perm] @ Q.T + 1.0, truth[F], truth


def _write(path: Path, V, F) -> Path:
    from meshcorr.io import write_mesh

    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        write_mesh(path, V, F)
    return path


def prepare_pairs(data: Path) -> list[dict]:
    """The scaling pairs: name, mesh files and ground truth (source point -> target point)."""
    tosca, sumner = data / "tosca5k", data / "sumner" / "cat-poses"
    knight = data / "meshes" / "libigl" / "decimated-knight.off"
    pairs = []
    for name, times in (("knight", 0), ("knight-x1", 1)):
        V, F = _subdivide(*_load(knight), times)
        W, G, truth = _rigid_copy(V, F)
        a, b = _write(CACHE / f"{name}-a.ply", V, F), _write(CACHE / f"{name}-b.ply", W, G)
        pairs.append(dict(name=name, source=str(a), target=str(b), truth=("perm", truth.tolist())))
    vts = [str(tosca / "corres" / f"{s}.vts") for s in ("cat0", "cat1")]
    pairs.append(dict(name="tosca-cat", source=str(tosca / "cat0.off"), target=str(tosca / "cat1.off"),
                      truth=("vts", vts), sym=str(tosca / "corres" / "cat1.sym.vts")))
    for times in (1, 2):
        files = [_write(CACHE / f"{s}-x{times}.ply", *_subdivide(*_load(tosca / f"{s}.off"), times))
                 for s in ("cat0", "cat1")]
        pairs.append(dict(name=f"tosca-cat-x{times}", source=str(files[0]), target=str(files[1]),
                          truth=("vts", vts)))
    files = [_write(CACHE / f"{s}-x2.ply", *_subdivide(*_load(sumner / f"{s}.obj"), 2))
             for s in ("cat-reference", "cat-01")]
    pairs.append(dict(name="sumner-cat-x2", source=str(files[0]), target=str(files[1]), truth=("identity", None)))
    return pairs


def _truth_points(truth, n_source: int) -> tuple[np.ndarray, np.ndarray]:
    kind, value = truth
    if kind == "vts":
        a, b = (np.loadtxt(v, dtype=np.int64) - 1 for v in value)
        return a, b
    if kind == "perm":
        return np.arange(n_source), np.asarray(value, dtype=np.int64)
    return np.arange(n_source), np.arange(n_source)


# --- the worker: one run in a fresh process -------------------------------------

def _hwm_kib() -> float:
    """The process's peak resident KiB since the last :func:`meshcorr.runtime.timing.reset_peak` (0 off Linux)."""
    return 1024 * (peak_resident_mib() or 0.0)


def _errors(target: str, mapping: np.ndarray, job: dict) -> dict:
    from meshcorr.evaluation.metrics import geodesic_errors

    src_pts, tgt_pts = _truth_points(job["truth"], len(mapping))
    sym_pts = np.loadtxt(job["sym"], dtype=np.int64) - 1 if job.get("sym") else None
    if len(src_pts) > MAX_EVAL_POINTS and job.get("sample", True):
        keep = np.random.default_rng(0).choice(len(src_pts), MAX_EVAL_POINTS, replace=False)
        src_pts, tgt_pts = src_pts[keep], tgt_pts[keep]
        sym_pts = None if sym_pts is None else sym_pts[keep]
    out = {"error": float(geodesic_errors(target, mapping[src_pts], tgt_pts).mean())}
    if sym_pts is not None:
        out["error_sym"] = float(geodesic_errors(target, mapping[src_pts], sym_pts).mean())
    return out


def _run_meshcorr(job: dict) -> dict:
    import potpourri3d  # noqa: F401 - imports outside the timing, as for pyFM
    import trimesh  # noqa: F401

    import meshcorr

    peaks: dict[str, int] = {}

    def progress(stage, done, total):
        if done == 0:
            reset_peak()
        elif done == total:
            peaks[stage] = max(peaks.get(stage, 0), _hwm_kib())

    start, cpu = time.perf_counter(), time.process_time()
    reset_peak()
    result = meshcorr.match(job["source"], job["target"], progress=progress, **job["options"])
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    out = dict(wall=wall, cpu=cpu, timings=result.timings, peak_mib={k: v / 1024 for k, v in peaks.items()},
               mode=result.params.get("mode"), n_source=int(len(result.map)))
    out.update(_errors(job["target"], result.map, job))
    return out


def _run_pyfm(job: dict) -> dict:
    import warnings

    warnings.simplefilter("ignore")
    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    start, cpu = time.perf_counter(), time.process_time()
    # pyFM maps mesh2 -> mesh1 (p2p_21): mesh1 is our target, mesh2 our source.
    mesh1 = TriMesh.load(job["target"], area_normalize=True, center=True)
    mesh2 = TriMesh.load(job["source"], area_normalize=True, center=True)
    model = FunctionalMapping(mesh1, mesh2)
    model.preprocess(descr_type="WKS", subsample_step=2, verbose=False)
    model.fit(K=30, w_descr=1e0, w_lap=1e-1, w_dcomm=1e0, w_orient=1e0, verbose=False)
    mapping = np.asarray(model.get_p2p(model.zoomout_refine(nit=16, step=5)), dtype=np.int64)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    out = dict(wall=wall, cpu=cpu, peak_mib={"total": _hwm_kib() / 1024}, n_source=int(len(mapping)))
    out.update(_errors(job["target"], mapping, job))
    return out


def worker(spec: str) -> None:
    job = json.loads(spec)
    load = os.getloadavg()[0]
    out = _run_pyfm(job) if job.get("tool") == "pyfm" else _run_meshcorr(job)
    out["load"] = (load + os.getloadavg()[0]) / 2
    print(json.dumps(out))


SINGLE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def run_job(job: dict, timeout: float = 3600, env: dict | None = None) -> dict:
    """One run in a fresh interpreter (``env`` added to the environment); its JSON result or error."""
    proc = subprocess.run([sys.executable, __file__, "--worker", json.dumps(job)], capture_output=True,
                          text=True, timeout=timeout, env=dict(os.environ, **(env or {})))
    if proc.returncode != 0:
        tail = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        return {"failed": f"exit {proc.returncode}: {tail}"}
    return json.loads(proc.stdout.strip().splitlines()[-1])


# --- the report -----------------------------------------------------------------

STAGES = ("load", "geodesics", "embedding", "reorder", "symmetry", "icp", "matching", "refine")


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _fmt(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def machine() -> str:
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem = next((int(l.split()[1]) for l in open("/proc/meminfo") if l.startswith("MemTotal")), 0) / 1024 ** 2
    import numpy
    import scipy

    return (f"{os.cpu_count()} cores ({cpu}), {mem:.0f} GiB, no GPU; Python {platform.python_version()}, "
            f"numpy {numpy.__version__}, scipy {scipy.__version__}; OPENBLAS_CORETYPE="
            f"{os.environ.get('OPENBLAS_CORETYPE', '(unset)')}; {datetime.datetime.now():%Y-%m-%d %H:%M}")


def scaling_section(pairs, args) -> list[str]:
    lines = ["## 1. Scaling: seconds and peak memory per stage", "",
             "One fresh process per run. `wall`: end-to-end seconds of `meshcorr.match` (reading the files "
             "included, imports not); `cpu`: CPU seconds of the process; per stage: seconds / peak resident "
             "MiB while the stage ran; `err`: mean geodesic error / sqrt(area) against the ground truth; "
             "`machine load`: the 1-minute load average during the run (2 cores: above 2, other jobs were "
             "competing).", "",
             "| pair | n | mode | options | wall s | cpu s | " + " | ".join(f"{s} s / MiB" for s in STAGES) + " | peak MiB | err | machine load |",
             "|---" * (len(STAGES) + 10) + "|"]
    for pair in pairs:
        variants = [("auto", {}), ("auto", {"refine": False})]
        if SCALABLE_ABOVE < pair["n"] <= args.dense_max:  # below, the default is the dense mode
            variants.append(("dense", {"mode": "dense"}))
        for label, options in variants:
            runs = args.runs if pair["name"] == "tosca-cat" and label == "auto" and not options else 1
            results = []
            for r in range(runs):
                _log(f"scaling: {pair['name']} {options or 'default'} run {r + 1}/{runs}")
                results.append(run_job(dict(pair, options=dict(options, random_state=0))))
            ok = [res for res in results if "failed" not in res]
            if not ok:
                lines.append(f"| {pair['name']} | {pair['n']} | {label} | {options or 'default'} | "
                             f"failed: {results[0]['failed']} |")
                continue
            res = sorted(ok, key=lambda x: x["wall"])[len(ok) // 2]  # the median run
            cells = [f"{_fmt(res['timings'].get(s))} / {res['peak_mib'].get(s, 0):.0f}"
                     if s in res["timings"] else "-" for s in STAGES]
            wall = (f"{statistics.median(x['wall'] for x in ok):.2f} (median of {len(ok)}: "
                    + ", ".join(f"{x['wall']:.2f}" for x in ok) + ")") if len(ok) > 1 else f"{res['wall']:.2f}"
            opts = ", ".join(f"{k}={v}" for k, v in options.items() if k != "mode") or "default"
            lines.append(f"| {pair['name']} | {pair['n']} | {res['mode']} | {opts} | {wall} | {res['cpu']:.1f} | "
                         + " | ".join(cells) + f" | {max(res['peak_mib'].values()):.0f} | {res['error']:.4f} | "
                         f"{res['load']:.1f} |")
    return lines


def _pyfm_rounds(pair, runs: int, env: dict | None) -> dict:
    series = {"meshcorr": [], "meshcorr, refine=False": [], "pyFM": []}
    for r in range(runs):
        _log(f"pyFM comparison ({'single-threaded BLAS' if env else 'default threads'}): round {r + 1}/{runs}")
        series["meshcorr"].append(run_job(dict(pair, options=dict(random_state=0)), env=env))
        series["meshcorr, refine=False"].append(run_job(dict(pair, options=dict(random_state=0, refine=False)),
                                                        env=env))
        series["pyFM"].append(run_job(dict(pair, tool="pyfm"), env=env))
    return series


def pyfm_section(pair, args) -> list[str]:
    lines = ["## 2. TOSCA cat0 -> cat1 (5000 vertices): meshcorr against pyFM", "",
             f"{args.runs} rounds of three runs (meshcorr with default settings, meshcorr without the ZoomOut "
             "refinement, pyFM), each in a fresh process; all of it twice: with the default BLAS threads "
             "and with single-threaded BLAS (`OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1`), as threaded BLAS "
             "slows pyFM several-fold on a loaded machine (meshcorr limits it where it hurts).", ""]
    for title, env in (("default BLAS threads", None), ("single-threaded BLAS", SINGLE_THREAD)):
        series = _pyfm_rounds(pair, args.runs, env)
        failed = [x["failed"] for res in series.values() for x in res if "failed" in x]
        if failed:
            lines += [f"{title}: failed: {failed[0]} (pyFM: `pip install pyfmaps`).", ""]
            continue
        median = {name: statistics.median(x["wall"] for x in res) for name, res in series.items()}
        lines += [f"### {title}", "",
                  "| tool | wall s, each run | median wall s | median cpu s | peak MiB | mean error | "
                  "error vs mirrored truth |", "|---|---|---|---|---|---|---|"]
        for name, res in series.items():
            lines.append(f"| {name} | " + ", ".join(f"{x['wall']:.2f}" for x in res) + f" | {median[name]:.2f} | "
                         f"{statistics.median(x['cpu'] for x in res):.2f} | "
                         f"{statistics.median(max(x['peak_mib'].values()) for x in res):.0f} | "
                         f"{statistics.median(x['error'] for x in res):.4f} | "
                         f"{statistics.median(x.get('error_sym', float('nan')) for x in res):.4f} |")
        ours, theirs = series["meshcorr"], series["pyFM"]
        pairwise = statistics.median(t["wall"] / o["wall"] for o, t in zip(ours, theirs))
        stages = {s: statistics.median(x["timings"].get(s, 0.0) for x in ours) for s in STAGES}
        loads = [x["load"] for res in series.values() for x in res]
        lines += ["", f"**pyFM / meshcorr, medians: {median['pyFM'] / median['meshcorr']:.1f}x** (median of the "
                  f"per-round ratios {pairwise:.1f}x); without the refinement "
                  f"{median['pyFM'] / median['meshcorr, refine=False']:.1f}x. Machine load "
                  f"{statistics.median(loads):.1f}.", "",
                  "meshcorr (default) median seconds per stage: "
                  + ", ".join(f"{s} {v:.2f}" for s, v in stages.items()) + ".", ""]
    return lines


def accuracy_section(data: Path, args) -> list[str]:
    tosca = data / "tosca5k"
    lines = ["## 3. Accuracy: dense vs scalable on TOSCA 5k pairs (default settings otherwise)", "",
             "Mean geodesic error / sqrt(area) over all 5000 ground-truth points; in brackets the error against "
             "the left/right mirrored truth (a low value there means the map is the mirror image).", "",
             "| pair | dense | scalable | dense s | scalable s |", "|---|---|---|---|---|"]
    errors = {"dense": [], "scalable": []}
    for spec in args.pairs.split(","):
        a, b = spec.split("-")
        job = dict(source=str(tosca / f"{a}.off"), target=str(tosca / f"{b}.off"),
                   truth=("vts", [str(tosca / "corres" / f"{s}.vts") for s in (a, b)]),
                   sym=str(tosca / "corres" / f"{b}.sym.vts"), sample=False)
        row = {}
        for mode in ("dense", "scalable"):
            _log(f"accuracy: {spec} {mode}")
            row[mode] = run_job(dict(job, options=dict(mode=mode, random_state=0)))
        if any("failed" in r for r in row.values()):
            lines.append(f"| {spec} | failed | | | |")
            continue
        for mode in errors:
            errors[mode].append((row[mode]["error"], row[mode]["error_sym"]))
        lines.append(f"| {spec} | {row['dense']['error']:.4f} ({row['dense']['error_sym']:.4f}) | "
                     f"{row['scalable']['error']:.4f} ({row['scalable']['error_sym']:.4f}) | "
                     f"{row['dense']['wall']:.1f} | {row['scalable']['wall']:.1f} |")
    if errors["dense"]:
        d, s = np.array(errors["dense"]), np.array(errors["scalable"])
        lines += [f"| **mean** | **{d[:, 0].mean():.4f}** | **{s[:, 0].mean():.4f}** | | |",
                  f"| mean, mirror forgiven (min of the two) | {d.min(axis=1).mean():.4f} | "
                  f"{s.min(axis=1).mean():.4f} | | |", "",
                  f"Scalable / dense mean error: **{s[:, 0].mean() / d[:, 0].mean():.3f}** "
                  f"(mirror forgiven: {s.min(axis=1).mean() / d.min(axis=1).mean():.3f})."]
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="the shared data folder")
    parser.add_argument("--runs", type=int, default=5, help="runs of the 5k pair (median)")
    parser.add_argument("--dense-max", type=int, default=5000, help="largest pair run in dense mode")
    parser.add_argument("--max-n", type=int, default=None, help="skip scaling pairs larger than this")
    parser.add_argument("--pairs", default=ACCURACY_PAIRS, help="TOSCA pairs of the accuracy section")
    parser.add_argument("--sections", default="1,2,3", help="which sections to run")
    parser.add_argument("--out", type=Path, default=HERE / "RESULTS-scale.md")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.worker)
        return 0
    if not (args.data / "tosca5k").is_dir():
        print(f"benchmarks/scale.py: no data at {args.data} (needs ../shared/data beside the repository); "
              "skipped.", file=sys.stderr)
        return 0
    pairs = prepare_pairs(args.data)
    for pair in pairs:
        from meshcorr.io import read_mesh

        pair["n"] = len(read_mesh(pair["source"])[0])
    five_k = next(p for p in pairs if p["name"] == "tosca-cat")
    pairs = [p for p in pairs if args.max_n is None or p["n"] <= args.max_n]
    sections = set(args.sections.split(","))
    command = "nice -n 10 python benchmarks/scale.py " + " ".join(a for a in (argv or sys.argv[1:]))
    lines = ["# Scale and speed (issue 5)", "", f"Command: `{command.strip()}`", "", f"Machine: {machine()}", ""]
    if "1" in sections:
        lines += scaling_section(pairs, args) + [""]
    if "2" in sections:
        lines += pyfm_section(five_k, args) + [""]
    if "3" in sections:
        lines += accuracy_section(args.data, args) + [""]
    from meshcorr.io import atomic_write

    atomic_write(args.out, lambda f: f.write(("\n".join(lines) + "\n").encode()))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
