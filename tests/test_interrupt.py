"""Ctrl-C in every stage of ``meshcorr match`` exits 130, leaves no output and no thread behind.

The crash of issue 16 (exit 139 after "meshcorr: interrupted") came from
threads still running when the interpreter finalised: scipy's KD-tree query
threads outliving an interrupted join. The invariant that rules it out is
checked directly: after every interrupted run, the main thread is the only
one left. The many-tries version with random timing is
``benchmarks/interrupt.py`` (results in benchmarks/RESULTS-reliability.md).
"""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from meshcorr import datasets as ds
from meshcorr.io import write_mesh

STAGES = ["load", "geodesics", "embedding", "reorder", "symmetry", "icp", "matching", "refine"]

# One process, many runs: SIGINT is sent from a timer thread a few milliseconds
# after the chosen stage starts, with 8 pretended cores and KD-tree queries
# split from 40 points on, so that worker threads run in every stage.
CHILD = textwrap.dedent("""
    import io, json, os, signal, sys, threading
    signal.signal(signal.SIGINT, signal.default_int_handler)  # even if pytest runs with SIGINT ignored
    import meshcorr.runtime.threads as t
    import meshcorr.cli.match as cli_match
    from meshcorr.cli import main
    from meshcorr.runtime.progress import StderrProgress

    t._cores = lambda: 8
    t.QUERIES_PER_THREAD = 40
    source, target, folder, plan = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
    results = []
    for run, (stage, delay) in enumerate(plan):
        fired = []

        class Firing(StderrProgress):  # the command's reporter, its ticker thread included
            def __call__(self, name, done, total, stage=stage, delay=delay, fired=fired):
                super().__call__(name, done, total)
                if name == stage and not fired:
                    fired.append(threading.Timer(delay, os.kill, (os.getpid(), signal.SIGINT)))
                    fired[0].start()

        cli_match.progress_for = lambda args, label, run_plan=None: Firing(
            io.StringIO(), label=label, delay=0.0, plan=run_plan, tick=0.005)
        out = os.path.join(folder, f"map{run}.txt")
        code = main(["match", source, target, "-o", out, "--alternative-out", out + ".alt",
                     "--symmetry", "auto"])
        for timer in fired:
            timer.join()
        others = [th.name for th in threading.enumerate() if th is not threading.main_thread()]
        results.append([stage, code, bool(fired), others, sorted(os.listdir(folder))])
    print(json.dumps(results))
""")


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("interrupt")
    a, b = ds.creature(resolution=1), ds.creature(resolution=1, pose=0.4)
    write_mesh(folder / "a.off", a.vertices, a.faces)
    write_mesh(folder / "b.off", b.vertices, b.faces)
    return str(folder / "a.off"), str(folder / "b.off")


def test_ctrl_c_in_every_stage_exits_130_with_no_output_and_no_thread_left(meshes, tmp_path):
    import json

    # Each stage twice: at its start and a little into it.
    plan = [[stage, delay] for delay in (0.0, 0.02) for stage in STAGES]
    out = subprocess.run([sys.executable, "-c", CHILD, *meshes, str(tmp_path), json.dumps(plan)],
                         capture_output=True, text=True, timeout=240, env=dict(os.environ, PYTHONFAULTHANDLER="1"))
    assert out.returncode == 0, out.stderr[-3000:]
    results = json.loads(out.stdout.strip().splitlines()[-1])
    assert len(results) == len(plan)
    interrupted = 0
    for stage, code, fired, threads, files in results:
        assert fired, f"stage {stage} never started"
        assert threads == [], f"threads left after Ctrl-C in {stage}: {threads}"
        if code == 0:  # the signal came after the last write (the run was already complete)
            continue
        interrupted += 1
        assert code == 130, (stage, code)
        assert files == [], f"Ctrl-C in {stage} left {files}"
    assert interrupted >= len(plan) - 2
    assert out.stderr.count("meshcorr: interrupted") == interrupted


def test_sigint_to_the_console_script_exits_130_and_writes_nothing(meshes, tmp_path):
    """The real signal path, from outside, while the pipeline runs."""
    output = tmp_path / "map.txt"
    # preexec_fn: the child gets the default SIGINT even where pytest was started with it ignored.
    proc = subprocess.Popen([sys.executable, "-m", "meshcorr", "match", *meshes, "-o", str(output), "-v"],
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONFAULTHANDLER="1"),
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    line = ""
    while "[load]" not in line and "[geodesics]" not in line:  # -v reports each stage as it ends
        line = proc.stderr.readline()
        assert line or proc.poll() is None, "the run ended before its first stage"
    time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "meshcorr: interrupted" in err and "Fatal Python error" not in err and "Traceback" not in err
    assert os.listdir(tmp_path) == []


QUERY = textwrap.dedent("""
    import signal, sys, threading
    import numpy as np
    from scipy.spatial import cKDTree
    import meshcorr.runtime.threads as t

    t._cores = lambda: 4
    points = np.random.default_rng(0).random((400_000, 3))
    tree = cKDTree(points)
    signal.signal(signal.SIGALRM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt))
    signal.setitimer(signal.ITIMER_REAL, 0.05)
    try:
        t.kdtree_query(tree, points, k=4)
        print("finished before the interrupt")
    except KeyboardInterrupt:
        print("interrupted", [th.name for th in threading.enumerate() if th is not threading.main_thread()])
""")


def test_ctrl_c_during_a_kdtree_query_leaves_no_query_thread():
    """scipy's ``query(workers=n)`` left its daemon threads querying after an interrupted join:
    the interpreter then freed the tree under them (the segmentation fault of issue 16)."""
    out = subprocess.run([sys.executable, "-c", QUERY], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "interrupted []"


# SIGTERM arrives while the map is being written: the writer's fsync sends it (issue 31, item 15).
TERM_WHILE_WRITING = textwrap.dedent("""
    import os, signal, sys
    import meshcorr.io.files as files
    from meshcorr.cli import main

    real_fsync = files.os.fsync

    def fsync(fd):
        real_fsync(fd)
        os.kill(os.getpid(), signal.SIGTERM)

    files.os.fsync = fsync
    code = main(["match", sys.argv[1], sys.argv[2], "-o", os.path.join(sys.argv[3], "map.txt")])
    print(code, sorted(os.listdir(sys.argv[3])))
""")


def test_sigterm_while_the_map_is_written_exits_143_and_leaves_no_temporary_file(meshes, tmp_path):
    out = subprocess.run([sys.executable, "-c", TERM_WHILE_WRITING, *meshes, str(tmp_path)], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:], os.listdir(tmp_path))
    assert out.stdout.strip().splitlines()[-1] == "143 []"
    assert out.stderr.strip().splitlines()[-1] == "meshcorr: terminated" and "Traceback" not in out.stderr


def test_sigterm_to_a_batch_writes_its_summary_and_exits_143(meshes, tmp_path):
    pytest.importorskip("distributed")
    a, b = meshes
    proc = subprocess.Popen([sys.executable, "-m", "meshcorr", "batch", "--all-pairs", a, b, "--workers", "1",
                             "--out", str(tmp_path / "out")], stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:  # the first progress line: the cluster runs and the pairs are submitted
        if line.startswith("[batch]"):
            break
    proc.send_signal(signal.SIGTERM)
    rest = proc.stderr.read()
    assert proc.wait(timeout=60) == 143, rest
    assert "Traceback" not in rest and rest.strip().splitlines()[-1] == "meshcorr: terminated", rest
    assert (tmp_path / "out" / "summary.json").is_file()
    left = [p.name for p in (tmp_path / "out").rglob("*") if p.name.endswith(".tmp")]
    assert left == []
