"""meshcorr.maps.result: a saved Correspondence is read back only with a map that fits its meshes (issue 31)."""

import errno

import numpy as np
import pytest

from meshcorr.core.mesh import Mesh
from meshcorr.errors import InputError, MeshcorrError
from meshcorr.maps.result import Correspondence


def _grid(n_side: int) -> Mesh:
    """A flat ``n_side x n_side`` grid of triangles."""
    x, y = np.meshgrid(np.arange(n_side, dtype=float), np.arange(n_side, dtype=float))
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(n_side * n_side)])
    faces = []
    for i in range(n_side - 1):
        for j in range(n_side - 1):
            a = i * n_side + j
            faces += [(a, a + 1, a + n_side), (a + 1, a + n_side + 1, a + n_side)]
    return Mesh(vertices, np.array(faces))


@pytest.fixture
def saved(tmp_path):
    """A saved result from a 25-vertex source to a 16-vertex target, and a function that rewrites its map."""
    source, target = _grid(5), _grid(4)
    mapping = np.arange(25) % 16
    path = tmp_path / "result.npz"
    Correspondence(map=mapping, source=source, target=target).save(path)

    def with_map(new_map, name="map"):
        arrays = dict(np.load(path))
        arrays[name] = new_map
        changed = tmp_path / "changed.npz"
        np.savez(changed, **arrays)
        return changed

    return path, with_map


def test_a_saved_result_is_read_back(saved):
    path, _ = saved
    loaded = Correspondence.load(path)
    assert loaded.map.dtype == np.int64 and loaded.map.tolist() == (np.arange(25) % 16).tolist()


@pytest.mark.parametrize("bad, words", [
    (np.arange(10), ["has 10 entries", "has 25 vertices"]),
    (np.full(25, 16), ["entry 0 is 16", "-1..15", "16 vertices"]),
    (np.full(25, -2), ["entry 0 is -2", "-1..15"]),
    (np.arange(25) % 16 + 0.4, ["holds float64 values", "integers"]),
    (np.zeros((25, 2), dtype=np.int64), ["has shape (25, 2)", "1-D"]),
    (np.full(25, 2 ** 64 - 1, dtype=np.uint64), ["entry 0 is 18446744073709551615"]),
])
def test_a_map_that_does_not_fit_its_meshes_is_refused(saved, bad, words):
    # it was accepted: transfer then gave 10 values for 25 source vertices, inverse() rounded floats
    _, with_map = saved
    path = with_map(bad)
    with pytest.raises(InputError) as caught:
        Correspondence.load(path)
    message = str(caught.value)
    assert str(path) in message and "save the result again" in message
    for word in words:
        assert word in message


def test_the_alternative_map_is_checked_too(saved):
    _, with_map = saved
    with pytest.raises(InputError, match="its alternative_map has 3 entries"):
        Correspondence.load(with_map(np.arange(3), name="alternative_map"))


def test_a_full_disk_is_a_meshcorr_error_naming_the_path(saved, tmp_path, monkeypatch):
    # it was a raw OSError; nothing partial is left
    path, _ = saved
    result = Correspondence.load(path)
    import meshcorr.io.arrays

    def full(file, **arrays):
        file.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(meshcorr.io.arrays.np, "savez_compressed", full)
    out = tmp_path / "again.npz"
    with pytest.raises(MeshcorrError, match="disk") as caught:
        result.save(out)
    assert str(out) in str(caught.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.npz"]
