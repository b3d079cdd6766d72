"""``meshcorr batch``'s own option checks (the batch itself: tests/collection/test_batch.py)."""

import os

import pytest

from meshcorr.cli import main
from meshcorr.collection.cluster import MAX_WORKERS, max_workers


def test_workers_are_bounded_before_any_work(tmp_path, capsys):
    # --workers 100000 started processes until the machine gave out (issue 31, item 17).
    assert max_workers() == min(4 * (os.cpu_count() or 1), MAX_WORKERS)
    a, b = (str(tmp_path / name) for name in ("a.off", "b.off"))  # refused before they are read
    out = tmp_path / "out"
    assert main(["batch", "--all-pairs", a, b, "--out", str(out), "--workers", "100000"]) == 2
    err = capsys.readouterr().err
    assert f"give at most {max_workers()}" in err and "--scheduler" in err and not out.exists()


def test_the_library_batch_bounds_its_local_workers_too(tmp_path):
    from meshcorr.collection.batch import batch
    from meshcorr.errors import ParameterError

    with pytest.raises(ParameterError, match=f"give at most {max_workers()}"):
        batch([("examples/creature_rest.off", "examples/creature_bent.off")], tmp_path / "out",
              n_workers=max_workers() + 1)
    assert not (tmp_path / "out" / "maps").exists()
