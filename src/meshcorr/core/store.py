"""The per-shape store: quantities derived from one shape, computed once and kept with it.

A :class:`~meshcorr.core.mesh.Mesh` is immutable (its arrays are
read-only), so whatever is derived from it alone stays valid for its
lifetime. Each such quantity is kept in ``mesh.store`` under a key tuple
whose first item names the quantity and whose other items are the
parameters that produced it, for example ``("geodesic_matrix", "heat")``,
``("laplacian", "cotangent")`` or ``("laplace_basis", k, random_state)``;
a key never names a quantity that depends on another shape. The modules
that compute a quantity own its key (``grep '"<name>"'`` finds them);
:class:`~meshcorr.shapes.prepared.PreparedShape` writes the store's arrays
to its file and reads them back, which is how a prepared shape skips the
per-shape work.
"""

from __future__ import annotations

from typing import Any, Callable, Hashable, Iterator, TypeVar

__all__ = ["ShapeStore"]

T = TypeVar("T")


class ShapeStore:
    """A mapping ``key tuple -> value`` of quantities derived from one shape.

    Examples
    --------
    >>> store = ShapeStore()
    >>> store.get(("answer", 6), lambda: 42)
    42
    >>> ("answer", 6) in store
    True
    """

    def __init__(self) -> None:
        self._values: dict[tuple, Any] = {}

    def get(self, key: tuple[Hashable, ...], compute: Callable[[], T]) -> T:
        """The value under ``key``, computed by ``compute()`` and kept on the first call."""
        if key not in self._values:
            self._values[key] = compute()
        return self._values[key]

    def put(self, key: tuple[Hashable, ...], value: Any) -> None:
        """Keep ``value`` under ``key`` (replacing any value there)."""
        self._values[key] = value

    def __getitem__(self, key: tuple[Hashable, ...]) -> Any:
        return self._values[key]

    def __contains__(self, key: object) -> bool:
        return key in self._values

    def __iter__(self) -> Iterator[tuple]:
        return iter(list(self._values))

    def __len__(self) -> int:
        return len(self._values)

    def items(self) -> list[tuple[tuple, Any]]:
        """``(key, value)`` of every kept quantity (a list: safe to iterate while others add)."""
        return list(self._values.items())

    def __repr__(self) -> str:
        names = sorted({str(key[0]) for key in self._values})
        return f"ShapeStore({len(self._values)} values: {', '.join(names)})"
