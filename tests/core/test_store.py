"""meshcorr.core.store: the per-shape store computes each quantity once and keeps it."""

import numpy as np
import pytest

import meshcorr.datasets as datasets
from meshcorr.core.mesh import as_mesh
from meshcorr.core.store import ShapeStore


def test_get_computes_once():
    store = ShapeStore()
    calls = []

    def compute():
        calls.append(1)
        return len(calls)

    assert store.get(("count",), compute) == 1
    assert store.get(("count",), compute) == 1
    assert calls == [1]
    assert store.get(("count", 2), compute) == 2  # another parameter, another value


def test_put_replaces_and_the_mapping_protocol():
    store = ShapeStore()
    store.put(("a", 1), "x")
    store.put(("a", 1), "y")
    store.put(("b",), 3)
    assert store[("a", 1)] == "y"
    assert ("b",) in store and ("c",) not in store
    assert len(store) == 2 and sorted(store, key=str) == [("a", 1), ("b",)]
    assert dict(store.items()) == {("a", 1): "y", ("b",): 3}
    assert repr(store) == "ShapeStore(2 values: a, b)"
    with pytest.raises(KeyError):
        store[("c",)]


def test_iterating_while_adding_is_safe():
    store = ShapeStore()
    store.put(("a",), 1)
    for key in store:
        store.put(("b",), 2)
    for key, _ in store.items():
        store.put(("c",), 3)
    assert len(store) == 3


def test_a_mesh_keeps_its_quantities_in_its_own_store():
    shape = datasets.tube(n_along=10, n_around=8)
    one, two = as_mesh((shape.vertices, shape.faces)), as_mesh((shape.vertices, shape.faces))
    assert isinstance(one.store, ShapeStore)
    one.store.put(("answer",), np.arange(3))
    assert ("answer",) in one.store and ("answer",) not in two.store
