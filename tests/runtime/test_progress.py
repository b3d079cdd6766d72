"""meshcorr.runtime.progress: what the ``progress`` option of match turns into."""

import pytest

from meshcorr.errors import ParameterError
from meshcorr.runtime.progress import as_progress


def test_no_progress_for_none_and_false():
    assert as_progress(None) is None
    assert as_progress(False) is None


def test_a_callable_is_used_as_it_is():
    def callback(stage, done, total):
        pass

    assert as_progress(callback) is callback


@pytest.mark.parametrize("value", [1, "yes", 0.5])
def test_anything_else_is_refused(value):
    with pytest.raises(ParameterError, match="The 'progress' parameter must be True, False, None or a callable"):
        as_progress(value)


def test_true_gives_a_bar_that_follows_the_stages(tmp_path):
    pytest.importorskip("tqdm")
    bar = as_progress(True)
    try:
        bar("geodesics", 2, 4)
        assert bar.bar.total == 4 and bar.bar.n == 2
        bar("geodesics", 9, 4)  # never beyond the total
        assert bar.bar.n == 4
        bar("embedding", 0, 1)
        assert bar.stages == ["geodesics", "embedding"]
        assert bar.bar.n == 0
    finally:
        bar.close()
