"""The on-disk cache of prepared shapes: keys, refusals, concurrent writers, CLI (issue 13)."""

from __future__ import annotations

import multiprocessing

import numpy as np
import pytest

import meshcorr
from meshcorr import datasets as ds
from meshcorr.shapes.cache import ShapeCache, as_cache, default_cache_dir
from meshcorr.cli import main
from meshcorr.errors import ParameterError, PreparedShapeError
from meshcorr.pipeline.prepare import prepare
from meshcorr.pipeline.settings import SHAPE_SETTINGS
from meshcorr.shapes.prepared import PreparedShape, load_mesh


@pytest.fixture(scope="module")
def mesh():
    shape = ds.creature(resolution=1)
    return load_mesh((shape.vertices, shape.faces), SHAPE_SETTINGS, name="creature")


def test_a_cache_hit_is_the_same_shape_and_settings_change_the_key(mesh, tmp_path):
    cache = ShapeCache(tmp_path / "c")
    first = prepare(mesh, cache=cache)
    assert cache.info()["files"] == 1 and cache.info()["bytes"] > 0
    hit = cache.get(mesh, SHAPE_SETTINGS, "dense")
    assert hit is not None and hit is not first
    np.testing.assert_array_equal(hit.spectrum.embedding, first.spectrum.embedding)
    other = ds.creature(resolution=1, pose="bent")
    np.testing.assert_array_equal(meshcorr.match(hit, (other.vertices, other.faces)).map,
                                  meshcorr.match(mesh, (other.vertices, other.faces)).map)
    keys = {cache.key(mesh, SHAPE_SETTINGS, "dense"), cache.key(mesh, SHAPE_SETTINGS, "scalable"),
            cache.key(mesh, dict(SHAPE_SETTINGS, random_state=1), "dense"),
            cache.key(mesh, dict(SHAPE_SETTINGS, refine_k=30), "dense")}
    assert len(keys) == 4
    prepare(mesh, cache=cache, random_state=1)
    assert cache.info()["files"] == 2


def test_the_cache_refuses_a_file_from_other_settings(mesh, tmp_path):
    cache = ShapeCache(tmp_path)
    # A file made with random_state=1 put under the key of random_state=0 is not used: it is prepared again.
    wrong = prepare(mesh, random_state=1)
    path = cache.path(cache.key(mesh, SHAPE_SETTINGS, "dense"))
    wrong.save(path)
    assert cache.get(mesh, SHAPE_SETTINGS, "dense") is None
    shape = cache.prepare(mesh, SHAPE_SETTINGS, "dense")
    assert shape.settings["random_state"] == 0
    assert PreparedShape.load(path).settings["random_state"] == 0  # replaced
    path.write_bytes(b"damaged")
    assert cache.get(mesh, SHAPE_SETTINGS, "dense") is None
    # A file cut short (a full disk, a killed copy) is a damaged zip: prepared again and replaced.
    complete = cache.prepare(mesh, SHAPE_SETTINGS, "dense")
    data = path.read_bytes()
    for damaged in (data[:len(data) // 2], b""):
        path.write_bytes(damaged)
        with pytest.raises(PreparedShapeError, match="not a prepared shape written by meshcorr"):
            PreparedShape.load(path)
        again = cache.prepare(mesh, SHAPE_SETTINGS, "dense")
        np.testing.assert_array_equal(again.spectrum.embedding, complete.spectrum.embedding)
        assert PreparedShape.load(path).digest == complete.digest


def _prepare_into(root: str) -> str:
    shape = ds.creature(resolution=1)
    return prepare((shape.vertices, shape.faces), cache=root, name="creature").digest


def test_concurrent_writers_leave_a_valid_cache(mesh, tmp_path):
    root = str(tmp_path / "shared")
    with multiprocessing.get_context("spawn").Pool(3) as pool:
        digests = pool.map(_prepare_into, [root] * 3)
    cache = ShapeCache(root)
    assert len(set(digests)) == 1 and cache.info()["files"] == 1
    assert not [p for p in cache.root.iterdir() if p.name.endswith(".tmp")]
    loaded = cache.get(mesh, SHAPE_SETTINGS, "dense")
    np.testing.assert_array_equal(loaded.spectrum.embedding, prepare(mesh).spectrum.embedding)


def test_cache_folder_and_cli(mesh, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MESHCORR_CACHE", str(tmp_path / "env"))
    assert default_cache_dir() == tmp_path / "env"
    monkeypatch.delenv("MESHCORR_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_cache_dir() == tmp_path / "xdg" / "meshcorr"
    assert as_cache(True).root == tmp_path / "xdg" / "meshcorr"
    prepare(mesh, cache=str(tmp_path / "c"))
    key = ShapeCache(tmp_path / "c").files()[0].name
    (tmp_path / "c" / f".{key}.0a1b2c.tmp").write_bytes(b"left by a killed writer")
    # The user's own files in the folder are neither counted nor removed.
    (tmp_path / "c" / "my_data.npz").write_bytes(b"mine")
    (tmp_path / "c" / "notes.tmp").write_bytes(b"mine")
    assert main(["cache", "info", "--dir", str(tmp_path / "c")]) == 0
    assert ": 1 prepared shapes, " in capsys.readouterr().out
    assert main(["cache", "clear", "--dir", str(tmp_path / "c")]) == 0
    assert "removed 1 prepared shapes" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == ["my_data.npz", "notes.tmp"]
    assert main(["cache", "info", "--dir", str(tmp_path / "none")]) == 0
    assert ": 0 prepared shapes, 0.0 MiB" in capsys.readouterr().out


def test_bad_cache_arguments(tmp_path, capsys):
    with pytest.raises(ParameterError, match="must be a ShapeCache, a folder path or True"):
        as_cache(3)
    (tmp_path / "file").write_text("x")
    with pytest.raises(ParameterError, match="is a file: give a folder"):
        ShapeCache(tmp_path / "file")
    assert main(["cache", "info", "--dir", str(tmp_path / "file")]) == 2
    assert "is a file" in capsys.readouterr().err


def _with_raw_member(path, member: str) -> None:
    """Rewrite the ``.npz`` at ``path`` with ``member`` stored as raw bytes (no ``.npy``): NumPy then hands
    back bytes for it, not an array."""
    import io
    import zipfile

    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files}
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, array in arrays.items():
            if name == member:
                archive.writestr(name, b"not an array")
            else:
                item = io.BytesIO()
                np.save(item, array)
                archive.writestr(f"{name}.npy", item.getvalue())
    path.write_bytes(buffer.getvalue())


@pytest.mark.parametrize("member", ["header", "spectrum.embedding"])
def test_a_cache_entry_whose_member_is_no_array_is_prepared_again(mesh, tmp_path, member):
    cache = ShapeCache(tmp_path)
    complete = cache.prepare(mesh, SHAPE_SETTINGS, "dense")
    path = cache.files()[0]
    _with_raw_member(path, member)
    with pytest.raises(PreparedShapeError, match=f"member '{member}' is not an array"):
        PreparedShape.load(path)
    assert cache.get(mesh, SHAPE_SETTINGS, "dense") is None  # was an AttributeError (header) or a bad shape
    again = cache.prepare(mesh, SHAPE_SETTINGS, "dense")  # repaired: replaced by a complete file
    np.testing.assert_array_equal(again.spectrum.embedding, complete.spectrum.embedding)
    assert PreparedShape.load(path).digest == complete.digest


def test_a_cache_folder_that_cannot_be_written_is_told_and_its_shapes_still_prepared(mesh, tmp_path, monkeypatch):
    from meshcorr.errors import OutputError
    from meshcorr.shapes.cache import CacheWarning

    (tmp_path / "file").write_text("x")
    cache = ShapeCache(tmp_path / "file" / "cache")  # its parent is a regular file: nothing can be made there
    with pytest.raises(OutputError, match="cache folder .*file/cache cannot be written"):
        cache.check_writable()
    with pytest.warns(CacheWarning, match="could not be stored in the cache"):
        shape = cache.prepare(mesh, SHAPE_SETTINGS, "dense")
    np.testing.assert_array_equal(shape.spectrum.embedding, prepare(mesh).spectrum.embedding)
    # A full disk: the probe's byte cannot be written.
    full = ShapeCache(tmp_path / "full")

    def no_space(fd, data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("meshcorr.shapes.cache.os.write", no_space)
    with pytest.raises(OutputError, match="No space left on device"):
        full.check_writable()
    assert not [p for p in (tmp_path / "full").iterdir()]  # the probe is removed
    monkeypatch.undo()
    ShapeCache(tmp_path / "ok").check_writable()
    assert list((tmp_path / "ok").iterdir()) == []
