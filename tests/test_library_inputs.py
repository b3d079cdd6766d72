"""Library input checks: dense-map truth files, .npz archives, precise_map's basis size, cache listings."""

import io

import numpy as np
import pytest

from meshcorr.errors import InputError, MeshError
from meshcorr.evaluation.ground_truth import load_ground_truth, read_pairs
from meshcorr.io import read_map, read_mesh, read_npz


def _write_lines(path, values):
    path.write_text("".join(f"{value}\n" for value in values))
    return path


# ---------------------------------------------------------------- dense-map truth files

def test_dense_truth_with_too_few_lines_is_refused(tmp_path):
    short = _write_lines(tmp_path / "short.txt", range(10))  # was scored on its 10 lines
    with pytest.raises(InputError, match=r"short\.txt has 10 lines .* source mesh has 500 vertices") as error:
        load_ground_truth(short, n_source=500, n_target=500)
    assert "one line per source vertex" in str(error.value) and "'i j'" in str(error.value)
    with pytest.raises(InputError, match="has 10 lines"):
        read_pairs(short, n_source=500)


def test_dense_truth_with_too_many_lines_is_refused(tmp_path):
    long = _write_lines(tmp_path / "long.txt", [*range(10), -1, -1])  # trailing -1 lines were ignored
    with pytest.raises(InputError, match="has 12 lines .* has 10 vertices"):
        load_ground_truth(long, n_source=10, n_target=10)


def test_dense_truth_of_the_right_length_and_pair_files_still_load(tmp_path):
    dense = load_ground_truth(_write_lines(tmp_path / "d.txt", [2, -1, 0]), n_source=3, n_target=3)
    np.testing.assert_array_equal(dense.source, [0, 2])
    pairs = load_ground_truth(_write_lines(tmp_path / "p.txt", ["0 1"]), n_source=500, n_target=3)
    assert len(pairs) == 1  # a sparse file of pairs needs no line per vertex
    assert len(read_pairs(tmp_path / "d.txt")) == 2  # without a vertex count: unchecked, as before


# ---------------------------------------------------------------- .npz archives

def _npy_bytes(array):
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


@pytest.mark.parametrize("name, make, found", [
    ("array.npy", lambda p: np.save(p, np.arange(3)), "it is a .npy array"),  # was a raw TypeError
    ("named.npz", lambda p: p.write_bytes(_npy_bytes(np.arange(3))), "it is a .npy array"),
    ("words.txt", lambda p: p.write_text("1 2 3\n"), "it is a text file, not an .npz archive"),
    ("noise.bin", lambda p: p.write_bytes(b"\x00\x01garbage\xff"), "it is not an .npz archive"),
    ("empty.npz", lambda p: p.write_bytes(b""), "it is an empty file, not an .npz archive"),
])
def test_read_npz_names_a_file_that_is_no_npz(tmp_path, name, make, found):
    path = tmp_path / name
    make(path)
    with pytest.raises(InputError, match="not a saved meshcorr result") as error:  # text and noise: advice
        read_npz(path, "a saved meshcorr result")  # to load them with allow_pickle
    message = str(error.value)
    assert str(path) in message and found in message and "pickle" not in message


def test_read_npz_refuses_a_plain_zip_and_object_arrays(tmp_path):
    import zipfile

    with zipfile.ZipFile(tmp_path / "plain.zip", "w") as archive:
        archive.writestr("notes.txt", "hi")
    with pytest.raises(InputError, match="a zip archive, not an .npz archive .*'notes.txt'"):
        read_npz(tmp_path / "plain.zip", "a functional map file")
    np.savez(tmp_path / "objects.npz", a=np.array([object()]))
    with pytest.raises(InputError, match="Python objects") as error:
        read_npz(tmp_path / "objects.npz", "a functional map file")
    assert "allow_pickle" not in str(error.value)
    np.savez(tmp_path / "good.npz", a=np.arange(3))
    np.testing.assert_array_equal(read_npz(tmp_path / "good.npz", "x")["a"], [0, 1, 2])


def test_npy_readers_name_what_the_file_is(tmp_path):
    path = tmp_path / "x.npy"
    path.write_text("1\n2\n")  # numpy's message advised loading it with allow_pickle
    for read, error in ((read_map, InputError), (read_mesh, MeshError)):
        with pytest.raises(error, match="it is a text file, not a .npy array") as caught:
            read(path)
        assert "pickle" not in str(caught.value)
    np.savez(path.with_suffix(".npz"), a=np.arange(3))
    path.write_bytes(path.with_suffix(".npz").read_bytes())  # an .npz named .npy: an AttributeError
    for read, error in ((read_map, InputError), (read_mesh, MeshError)):
        with pytest.raises(error, match="it is a zip archive such as an .npz"):
            read(path)


# ---------------------------------------------------------------- precise_map's basis size

def test_precise_map_refuses_a_basis_larger_than_the_mesh():
    from meshcorr.datasets import tube
    from meshcorr.errors import ParameterError
    from meshcorr.fmap import functional_map
    from meshcorr.core.mesh import Mesh
    from meshcorr.precise import precise_map

    shape = tube(n_along=6, n_around=5)  # 32 vertices
    mesh = Mesh(shape.vertices, shape.faces)
    identity = np.arange(mesh.n_vertices)
    with pytest.raises(ParameterError, match="must be an int <= 31") as fmap_error:
        functional_map(mesh, mesh, identity, 1000)
    with pytest.raises(ParameterError) as error:  # was lowered to 31 in silence
        precise_map(mesh, mesh, identity, k=1000)
    message = str(error.value)
    assert message.startswith(str(fmap_error.value)) and "has 32 vertices" in message and "k <= 31" in message
    assert precise_map(mesh, mesh, identity, k=31).vertex_map().tolist() == identity.tolist()


# ---------------------------------------------------------------- cache listings

def test_cache_lists_and_clears_regular_files_only(tmp_path):
    from meshcorr.shapes.cache import ShapeCache

    root = tmp_path / "cache"
    (root / ("a" * 64 + ".npz")).mkdir(parents=True)  # a folder named like a key: was one prepared shape
    (root / ("." + "b" * 64 + ".npz.1f.tmp")).mkdir()  # named like a writer's temporary file
    (root / ("a" * 64 + ".npz") / "inside.txt").write_text("kept")
    real = root / ("c" * 64 + ".npz")
    real.write_bytes(b"12345")
    cache = ShapeCache(root)
    assert cache.files() == [real]
    assert cache.info() == {"path": str(root), "files": 1, "bytes": 5}
    assert cache.clear()["files"] == 1  # unlinking the folders raised IsADirectoryError
    assert not real.exists() and (root / ("a" * 64 + ".npz") / "inside.txt").read_text() == "kept"
    assert (root / ("." + "b" * 64 + ".npz.1f.tmp")).is_dir() and cache.files() == []
