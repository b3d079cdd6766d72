"""The command line's reliability (issue 16) and polish (issue 14, item 8).

Outputs are checked before the work and never replace an input; bad data
and bad usage exit with different codes; late errors leave no output.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from meshcorr.cli import EXIT_INPUT, EXIT_USAGE, main


FAST = ["--reorder", "greedy", "--no-refine"]


def _run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def test_output_equal_to_an_input_is_refused_before_the_work(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    before = open(tgt, "rb").read()
    code, _, err = _run(["match", src, tgt, "-o", tgt, *FAST], capsys)
    assert code == EXIT_USAGE and "is the input TARGET" in err
    assert open(tgt, "rb").read() == before
    # the same file through another spelling of its path
    other = os.path.join(os.path.dirname(src), ".", os.path.basename(src))
    code, _, err = _run(["match", src, tgt, "-o", other, *FAST], capsys)
    assert code == EXIT_USAGE and "is the input SOURCE" in err


def test_two_outputs_on_one_path_are_refused(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    out = str(tmp_path / "m.txt")
    code, _, err = _run(["match", src, tgt, "-o", out, "--alternative-out", out, *FAST], capsys)
    assert code == EXIT_USAGE and "are the same file" in err
    assert not os.path.exists(out)


def test_unwritable_outputs_are_found_before_the_work(tube_files_with_truth, tmp_path, capsys, monkeypatch):
    src, tgt, _ = tube_files_with_truth
    import meshcorr.pipeline.run

    def no_work(*args, **kwargs):  # the checks must come first
        raise AssertionError("match ran")

    # meshcorr.match first: the package loads its public names on first use (meshcorr.__getattr__),
    # and would otherwise record the patched pipeline.match as the value to restore.
    monkeypatch.setattr(meshcorr, "match", no_work)
    monkeypatch.setattr(meshcorr.pipeline.run, "match", no_work)
    for out, message in [("/proc/meshcorr-map.txt", "no file can be created in /proc"),
                         (str(tmp_path / "missing" / "m.txt"), "does not exist"),
                         (str(tmp_path), "it is a folder"),
                         ("/dev/null", "not a regular file")]:
        code, _, err = _run(["match", src, tgt, "-o", out, *FAST], capsys)
        assert code == EXIT_USAGE and message in err, err
    locked = tmp_path / "locked.txt"
    locked.write_text("keep")
    locked.chmod(0o444)
    if os.access(locked, os.W_OK):  # root ignores the mode: use an immutable file if allowed
        locked.chmod(0o644)
        if subprocess.run(["chattr", "+i", str(locked)], capture_output=True).returncode != 0:
            pytest.skip("no way to make a file that cannot be replaced here")
    try:
        code, _, err = _run(["match", src, tgt, "-o", str(locked), *FAST], capsys)
        assert code == EXIT_USAGE and "cannot be replaced" in err
    finally:
        subprocess.run(["chattr", "-i", str(locked)], capture_output=True)
    assert locked.read_text() == "keep"


def test_a_failed_report_leaves_no_map(tube_files_with_truth, tmp_path, capsys, monkeypatch):
    src, tgt, _ = tube_files_with_truth
    import meshcorr.viz.report

    def broken(*args, **kwargs):
        raise meshcorr.errors.ParameterError("report failed")

    monkeypatch.setattr(meshcorr.viz.report, "write_report", broken)
    out = tmp_path / "m.txt"
    code, _, err = _run(["match", src, tgt, "-o", str(out), "--report", str(tmp_path / "r.html"), *FAST],
                        capsys)
    assert code == EXIT_USAGE and "report failed" in err
    assert os.listdir(tmp_path) == []


def test_negative_seed_is_a_usage_error(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    with pytest.raises(SystemExit) as exc:
        main(["match", src, tgt, "-o", str(tmp_path / "m.txt"), "--seed=-1"])
    assert exc.value.code == EXIT_USAGE and "expected an integer >= 0, got -1" in capsys.readouterr().err


def test_bad_data_and_bad_usage_exit_differently(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    broken = tmp_path / "cut.off"
    broken.write_text(open(src).read()[:-40])
    code, _, err = _run(["match", str(broken), tgt, "-o", str(tmp_path / "m.txt")], capsys)
    assert code == EXIT_INPUT and "cut.off, line" in err and "truncated" in err
    with pytest.raises(SystemExit) as exc:
        main(["match", src, tgt, "-o", str(tmp_path / "m.txt"), "--no-such-flag"])
    assert exc.value.code == EXIT_USAGE
    assert not list(tmp_path.glob("m.txt"))


def test_help_lists_the_exit_codes_and_the_k_limit(capsys):
    with pytest.raises(SystemExit):
        main(["match", "--help"])
    text = capsys.readouterr().out
    assert "2 to 10" in text
    assert "3    bad input data" in text and "130  interrupted" in text


def test_map_on_stdout_and_json_without_output(tube_files_with_truth, tmp_path, capsys, monkeypatch):
    src, tgt, truth = tube_files_with_truth
    monkeypatch.chdir(tmp_path)
    code, out, err = _run(["match", src, tgt, "-o", "-", *FAST], capsys)
    assert code == 0 and not os.path.exists("-")
    np.testing.assert_array_equal(np.array(out.split(), dtype=np.int64), truth)
    assert "wrote stdout" in err
    code, out, _ = _run(["match", src, tgt, "--json", *FAST], capsys)
    assert code == 0 and json.loads(out)["n_mapped"] == len(truth) and os.listdir(tmp_path) == []
    code, _, err = _run(["match", src, tgt, *FAST], capsys)
    assert code == EXIT_USAGE and "Give -o MAP" in err
    code, _, err = _run(["match", src, tgt, "-o", "-", "--json", *FAST], capsys)
    assert code == EXIT_USAGE and "both write to stdout" in err


def test_debug_quiet_and_verbose_after_the_command(tube_files_with_truth, tmp_path, capsys, monkeypatch):
    src, tgt, _ = tube_files_with_truth
    code, _, err = _run(["match", src, tgt, "-o", str(tmp_path / "a.txt"), "-v", *FAST], capsys)
    assert code == 0
    assert "matching " in err and "source.off -> target.ply [geodesics] done in" in err
    assert "distinct target vertices" in err
    code, _, err = _run(["match", src, tgt, "-o", str(tmp_path / "b.txt"), "-q", *FAST], capsys)
    assert code == 0 and err == ""
    with pytest.raises(SystemExit) as exc:
        main(["match", src, tgt, "-o", str(tmp_path / "c.txt"), "-q", "-v"])
    assert exc.value.code == EXIT_USAGE and "contradict" in capsys.readouterr().err

    import meshcorr

    def bug(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(meshcorr, "match", bug)
    code, _, err = _run(["match", src, tgt, "-o", str(tmp_path / "d.txt")], capsys)
    assert code == 1 and "internal error: RuntimeError: a bug" in err
    for args in (["--debug", "match", src, tgt, "-o", str(tmp_path / "d.txt")],
                 ["match", src, tgt, "-o", str(tmp_path / "d.txt"), "--debug"]):
        with pytest.raises(RuntimeError, match="a bug"):
            main(args)


def test_gt_takes_one_value_and_leaves_positionals(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    report = tmp_path / "r.html"
    code, _, err = _run(["match", "--report", str(report), "--gt", "identity", src, tgt,
                         "-o", str(tmp_path / "m.txt"), *FAST], capsys)
    assert code == 0 and report.is_file() and "wrote the report" in err


def test_new_match_options_reach_the_pipeline(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    code, out, _ = _run(["match", src, tgt, "--json", "--control-points", "50", "--anneal", "0.8",
                         "--refine-k", "12", "--scalable-above", "100000", "--reorder", "greedy"], capsys)
    params = json.loads(out)["params"]
    assert code == 0 and (params["n_control"], params["anneal"], params["refine_k"]) == (50, 0.8, 12)


def test_show_transfer_embed_status_goes_to_stderr_and_q_silences_it(tube_files_with_truth, tmp_path, capsys):
    src, tgt, truth = tube_files_with_truth
    mapping = tmp_path / "m.txt"
    mapping.write_text("".join(f"{i}\n" for i in truth))
    out = tmp_path / "t.ply"
    code, stdout, err = _run(["transfer", src, tgt, str(mapping), "--attribute", "xyz", "-o", str(out)], capsys)
    assert code == 0 and stdout == "" and "wrote" in err
    code, stdout, err = _run(["transfer", src, tgt, str(mapping), "--attribute", "xyz", "-o", str(out), "-q"],
                             capsys)
    assert code == 0 and stdout == "" and err == ""
    code, _, err = _run(["transfer", src, tgt, str(mapping), "--attribute", "xyz", "-o", str(out),
                         "--values-out", str(mapping)], capsys)
    assert code == EXIT_USAGE and "--values-out" in err and "is the input MAP" in err


def test_missing_map_names_the_argument(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    code, _, err = _run(["evaluate", src, tgt, str(tmp_path / "none.txt"), "--gt", "identity"], capsys)
    assert code == EXIT_INPUT and "none.txt (MAP)" in err


def test_binary_map_file_is_refused(tube_files_with_truth, tmp_path, capsys):
    src, tgt, _ = tube_files_with_truth
    binary = tmp_path / "m.txt"
    binary.write_bytes(bytes(range(256)))
    code, _, err = _run(["evaluate", src, tgt, str(binary), "--gt", "identity"], capsys)
    assert code == EXIT_INPUT and "not a text file" in err


def test_evaluate_into_a_closed_pipe_exits_quietly(tube_files_with_truth, tmp_path):
    src, tgt, truth = tube_files_with_truth
    mapping = tmp_path / "m.txt"
    mapping.write_text("".join(f"{i}\n" for i in truth))
    command = (f"{sys.executable} -m meshcorr evaluate {src} {tgt} {mapping} --gt identity --json "
               "--thresholds " + ",".join(str(t / 1000) for t in range(1, 400)) + " | head -c 1")
    proc = subprocess.run(["bash", "-o", "pipefail", "-c", command], capture_output=True, text=True,
                          timeout=120)
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
    assert proc.returncode in (0, 141)
