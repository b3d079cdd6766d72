"""``--set`` values are checked before any work, as the method itself checks them.

Before, only the KEY of ``meshcorr bench --set METHOD:KEY=VALUE`` (and of ``meshcorr batch --set``) was
checked: ``spectral:k=abc``, ``spectral:k=-3`` or ``spectral:reorder=nonsense`` loaded every pair and
failed each one with the same error (exit 4), and bench kept the bad value as its folder's setting.
Options that a method checks only once its data is loaded (``icp_iterations``, ``n_control``,
``icp:trim``, ...) slipped through ``meshcorr batch`` as well.
"""

import csv
import inspect
import json

import pytest
import trimesh

import meshcorr.evaluation.benchmark as benchmark
from meshcorr import datasets as ds
from meshcorr.cli import EXIT_USAGE, main
from meshcorr.errors import ParameterError
from meshcorr.pipeline.methods import _LATER_CHECKS, check_options, method_function, method_options, run_method

SHAPE = ds.tube(n_along=10, n_around=6)


def make_dataset(root):
    """One pair, a tube onto itself, with the identity as its truth (TOSCA layout)."""
    (root / "corres").mkdir(parents=True)
    for name in ("tube0", "tube1"):
        trimesh.Trimesh(SHAPE.vertices, SHAPE.faces, process=False).export(root / f"{name}.off")
        (root / "corres" / f"{name}.vts").write_text("".join(f"{i + 1}\n" for i in range(SHAPE.n_vertices)))
    (root / "test_pairs.txt").write_text("tube0 tube1\n")
    return root


@pytest.fixture()
def dataset(tmp_path):
    return make_dataset(tmp_path / "data")


# The method's own message for each: the option, the value and what is allowed.
BAD = [
    ("spectral", "k", "abc", "The 'k' parameter must be an int. Got 'abc' instead."),  # a bad int
    ("spectral", "k", "-3", "The 'k' parameter must be an int >= 2. Got -3 instead."),
    ("spectral", "reorder", "nonsense", "The 'reorder' parameter must be one of 'exhaustive', 'greedy', "
                                        "'signs', 'signs-greedy', 'none'. Got 'nonsense' instead."),  # a bad choice
    ("spectral", "bijective", "true", "The 'bijective' parameter must be True or False. Got 'true' instead."),
    # checked by the method only once the meshes are loaded (meshcorr.stages.icp.tps_icp, meshcorr.spectral.modes.select_mode)
    ("spectral", "icp_iterations", "-1", "The 'icp_iterations' parameter must be an int >= 0. Got -1 instead."),
    ("spectral", "n_control", "6", "The 'n_control' parameter (--control-points) must be an int >= 7. Got 6 instead."),
    ("spectral", "scalable_above", "'many'", "The 'scalable_above' parameter must be an int. Got 'many' instead."),
    ("icp", "trim", "5", "The 'trim' parameter must be a number <= 1.0. Got 5.0 instead."),
    ("shape-context", "assignment", "greedy", "The 'assignment' parameter must be one of 'hungarian', 'argmin'. "
                                              "Got 'greedy' instead."),
]


@pytest.mark.parametrize("method, key, value, message", BAD)
def test_bench_refuses_a_bad_set_value_before_any_work(dataset, tmp_path, capsys, monkeypatch,
                                                       method, key, value, message):
    def no_run(*args, **kwargs):
        raise AssertionError("a method ran")

    monkeypatch.setattr(benchmark, "run_method", no_run)
    monkeypatch.setattr(benchmark, "_load_pair", no_run)
    out = tmp_path / "out"
    item = f"{method}:{key}={value}"
    code = main(["bench", str(dataset), "--methods", method, "--out", str(out), "--no-plot", "-q", "--set", item])
    err = capsys.readouterr().err
    assert code == EXIT_USAGE, err  # was 4: every pair failed with this message
    assert err.startswith(f"meshcorr: error: --set {item!r}: {message} Correct this --set") and err.count("\n") == 1
    assert "leave it out to keep the method's default" in err
    assert not out.exists()  # no run.json keeps the bad value


def test_bench_runs_the_corrected_value(dataset, tmp_path, capsys):
    out = tmp_path / "out"
    base = ["bench", str(dataset), "--methods", "spectral,icp", "--out", str(out), "--no-plot", "-q"]
    assert main([*base, "--set", "spectral:n_control=4"]) == EXIT_USAGE  # k=6: at least 7
    assert "'n_control' parameter (--control-points) must be an int >= 7. Got 4" in capsys.readouterr().err and not out.exists()
    good = ["--set", "spectral:reorder=greedy", "--set", "spectral:n_control=7", "--set", "spectral:k=5",
            "--set", "icp:trim=0.8"]
    assert main([*base, *good]) == 0, capsys.readouterr().err
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(r["method"], r["status"]) for r in rows] == [("spectral", "ok"), ("icp", "ok")]
    recorded = json.loads((out / "run.json").read_text())["method_options"]
    assert recorded == {"spectral": {"reorder": "greedy", "n_control": 7, "k": 5}, "icp": {"trim": 0.8}}


def test_run_benchmark_checks_the_method_options_before_any_work(dataset, tmp_path):
    out = tmp_path / "out"
    with pytest.raises(ParameterError, match=r"The 'anneal' parameter must be a number <= 1.0. Got 2.0 instead"):
        benchmark.run_benchmark(dataset, ["spectral"], out, method_options={"spectral": {"anneal": 2.0}})
    with pytest.raises(ParameterError, match=r"The 'anneal_rate' parameter must be a number > 0.0. Got -1"):
        benchmark.run_benchmark(dataset, ["tps-rpm"], out, method_options={"tps-rpm": {"anneal_rate": -1}})
    assert not out.exists()


@pytest.mark.parametrize("method, options", [
    ("spectral", {"icp_iterations": -1}),
    ("spectral", {"k": 4, "n_control": 4}),
    ("spectral", {"anneal": 0.0}),
    ("spectral", {"reorder": "nonsense"}),
    ("spectral", {"scalable_above": -5, "mode": "auto"}),
    ("icp", {"trim": 5}),
    ("icp", {"n_rotations": 0}),
    ("tps-rpm", {"inner_iterations": 0, "n_points": 20}),
    ("shapiro-brady", {"k": 11}),
])
def test_check_options_raises_what_the_run_raises(method, options):
    """The same message as the method's own run on meshes (that run got past loading first)."""
    with pytest.raises(ParameterError) as checked:
        check_options(method, **options)
    with pytest.raises(ParameterError) as ran:
        run_method(method, SHAPE, SHAPE, **options)
    assert str(checked.value) == str(ran.value)


def test_check_options_takes_good_values_and_knows_each_later_check():
    for method, options in [("spectral", {}), ("spectral", dict(k=5, reorder="greedy", icp_iterations=1,
                                                                   n_control=6, anneal=1.0, scalable_above=0)),
                            ("spectral", dict(partial="source", mode="scalable", n_samples=50)),
                            ("icp", dict(trim=0.8, huber=1.5, n_rotations=4, prealign=False)),
                            ("tps-rpm", dict(anneal_rate=0.9, inner_iterations=2, n_points=10)),
                            ("shape-context", dict(assignment="argmin", r_inner=0.2, r_outer=1.0)),
                            ("shapiro-brady-scaled", dict(k=3, geodesic="dijkstra"))]:
        check_options(method, **options)
    with pytest.raises(ParameterError, match="The method 'icp' has no option 'k'. Its options are: trim"):
        check_options("icp", k=4)
    with pytest.raises(ParameterError, match="The 'method' parameter must be one of"):
        check_options("nonsense")
    # Each option checked later is one of the method's, passed on under a keyword its checker takes.
    for method, stages in _LATER_CHECKS.items():
        for module, function, keywords, _ in stages:
            taken = inspect.signature(getattr(__import__(module, fromlist=[function]), function)).parameters
            assert set(keywords) <= set(method_options(method)), method
            assert set(keywords) <= set(method_options(method)) and set(keywords.values()) <= set(taken)


# ---------------------------------------------------------------- batch


def batch_args(tmp_path, *extra):
    meshes = []
    for name in ("a", "b"):
        path = tmp_path / f"{name}.off"
        trimesh.Trimesh(SHAPE.vertices, SHAPE.faces, process=False).export(path)
        meshes.append(str(path))
    return ["batch", "--all-pairs", *meshes, "--out", str(tmp_path / "out"), "-q", *extra]


@pytest.fixture()
def batches(monkeypatch):
    """meshcorr.collection.batch.batch records its options instead of starting a cluster."""
    made = []

    def fake(pairs, out, **kwargs):
        made.append(kwargs)
        return []

    monkeypatch.setattr("meshcorr.collection.batch.batch", fake)
    return made


@pytest.mark.parametrize("item, message", [
    ("icp_iterations=abc", "The 'icp_iterations' parameter must be an int. Got 'abc' instead."),  # a bad int
    ("n_control=3", "The 'n_control' parameter (--control-points) must be an int >= 7. Got 3 instead."),
    ("symmetry=left", "The 'symmetry' parameter must be one of 'auto', 'cost', 'mirror'. Got 'left' instead."),
    ("anneal=5", "The 'anneal' parameter must be a number <= 1.0. Got 5.0 instead."),
])
def test_batch_refuses_a_bad_set_value_before_any_work(tmp_path, capsys, batches, item, message):
    assert main(batch_args(tmp_path, "--set", item)) == EXIT_USAGE
    err = capsys.readouterr().err
    assert err.startswith(f"meshcorr: error: --set {item!r}: {message} Correct this --set") and err.count("\n") == 1
    assert batches == [] and not (tmp_path / "out").exists()


def test_batch_passes_good_set_values_on_and_blames_a_bad_flag_on_itself(tmp_path, capsys, batches):
    good = ["--set", "reorder=greedy", "--set", "n_control=20", "--set", "anneal=0.7", "--set", "symmetry=cost"]
    assert main(batch_args(tmp_path, *good, "-k", "5")) == 0, capsys.readouterr().err
    assert len(batches) == 1
    assert {key: batches[0][key] for key in ("reorder", "n_control", "anneal", "symmetry", "k")} == dict(
        reorder="greedy", n_control=20, anneal=0.7, symmetry="cost", k=5)
    # -k 50 with a good --set: the error is -k's, not the --set item's.
    assert main(batch_args(tmp_path, "-k", "50", "--set", "symmetry=cost")) == EXIT_USAGE
    assert capsys.readouterr().err == "meshcorr: error: The 'k' parameter must be an int <= 10. Got 50 instead.\n"
    assert main(batch_args(tmp_path, "-k", "4", "--set", "n_control=4")) == EXIT_USAGE  # k=4: at least 5
    assert "--set 'n_control=4': The 'n_control' parameter (--control-points) must be an int >= 5" in capsys.readouterr().err
    assert len(batches) == 1


def test_the_batch_library_checks_every_value_before_any_work(tmp_path, monkeypatch):
    pytest.importorskip("distributed", reason="meshcorr.collection.batch.batch needs meshcorr[dask]")
    from meshcorr.collection import batch as collection

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster was started")

    monkeypatch.setattr(collection, "_client", no_cluster)
    pairs = [(str(tmp_path / "a.off"), str(tmp_path / "b.off"))]
    for options, message in [({"icp_iterations": -2}, "'icp_iterations' parameter must be an int >= 0"),
                             ({"scalable_above": 1.5}, "'scalable_above' parameter must be an int. Got 1.5"),
                             ({"colour": 1}, "Unknown option of meshcorr.batch: 'colour'")]:
        with pytest.raises(ParameterError, match=message):
            collection.batch(pairs, tmp_path / "out", **options)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["bench", "batch"])
def test_help_says_set_values_are_literals_checked_before_any_work(capsys, command):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "Python literal such as 8, 0.5, True or None" in text and "before any work (exit 2)" in text


@pytest.mark.parametrize("method, option", [("icp", "prealign"), ("icp", "bijective"),
                                            ("shapiro-brady", "largest_component")])
def test_baseline_switches_take_only_true_or_false(method, option):
    # "false" from a --set is no Python literal: it stayed the string 'false', and ran as True.
    from meshcorr import datasets
    from meshcorr.pipeline.methods import run_method

    with pytest.raises(ParameterError, match=f"'{option}' parameter must be True or False"):
        check_options(method, **{option: "false"})
    shape = datasets.tube(n_along=6, n_around=6)
    with pytest.raises(ParameterError, match=f"'{option}' parameter must be True or False"):
        run_method(method, shape, shape, **{option: "false"})
