"""The house rules of the package, checked on its source (docs/architecture.md).

- at most 12 modules at the top of the package;
- no import cycle between modules, counting imports inside functions;
- no import against the layers (a lower layer never imports a higher one),
  except the few lazy ones listed in :data:`LAZY_UPWARD`;
- no private name (``_x``) imported from another module;
- no function outside ``cli/`` longer than 80 lines of code;
- every subpackage named in docs/architecture.md, and docstrings cite no
  file outside the repository.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "meshcorr"
ARCHITECTURE = PACKAGE.parents[1] / "docs" / "architecture.md"

#: The layers, bottom to top; a module may import its own layer and the ones below.
LAYERS = [("errors", "_version", "_moved"), ("runtime",), ("io",), ("core",), ("spectral",), ("stages",), ("choice",),
          ("shapes",), ("maps",), ("pipeline", "baselines"), ("evaluation", "collection", "viz"),
          ("cli", "_console", "__main__", "__init__")]

#: Imports against the layers that stay, each inside a function: (importer's subpackage, imported subpackage).
LAZY_UPWARD = {
    ("maps", "viz"),  # Correspondence.show() draws the map
    ("maps", "evaluation"),  # Correspondence.evaluate() measures it
    ("maps", "collection"),  # Correspondence.inverse()/compose() of a collection's maps
}

MAX_TOP_LEVEL = 12
MAX_CODE_LINES = 80


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path):
    """``(imported module, imported name or None, at module level)`` of every import of the package."""
    tree = ast.parse(path.read_text())
    top = {id(node) for node in tree.body}
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                base = ".".join(base + ([node.module] if node.module else []))
            elif node.module and node.module.split(".")[0] == "meshcorr":
                base = node.module
            else:
                continue
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                if sub in MODULES:
                    yield sub, None, id(node) in top
                else:
                    yield base, alias.name, id(node) in top
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "meshcorr":
                    yield alias.name, None, id(node) in top


def _graph() -> dict[str, set[str]]:
    graph = {name: set() for name in MODULES}
    for name, path in MODULES.items():
        for target, _, _ in _imports(name, path):
            while target not in MODULES and "." in target:
                target = target.rpartition(".")[0]
            if target != name and target in MODULES:
                graph[name].add(target)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _layer(module: str) -> int:
    part = module.split(".")[1] if "." in module else "__init__"
    for rank, names in enumerate(LAYERS):
        if part in names:
            return rank
    raise AssertionError(f"{module}: its subpackage is in no layer of LAYERS (tests/test_architecture.py)")


def _code_lines(function: ast.AST, lines: list[str]) -> int:
    strings = set()
    for node in ast.walk(function):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            strings.update(range(node.lineno, node.end_lineno + 1))
    return sum(1 for number in range(function.lineno, function.end_lineno + 1)
               if number not in strings and (text := lines[number - 1].strip()) and not text.startswith("#"))


def test_at_most_twelve_modules_at_the_top_of_the_package():
    top = sorted(path.name for path in PACKAGE.glob("*.py"))
    assert len(top) <= MAX_TOP_LEVEL, top


def test_no_import_cycle_even_through_imports_inside_functions():
    assert _cycles(_graph()) == []


def test_cycle_finder_finds_a_cycle():  # the check above can fail
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_module_imports_a_higher_layer():
    against = []
    for name, path in MODULES.items():
        for target, _, at_top in _imports(name, path):
            while target not in MODULES and "." in target:
                target = target.rpartition(".")[0]
            if target not in MODULES or target == "meshcorr":
                continue
            if _layer(target) > _layer(name):
                pair = (name.split(".")[1], target.split(".")[1])
                if at_top or pair not in LAZY_UPWARD:
                    against.append(f"{name} -> {target}")
    assert against == []


def test_no_private_name_is_imported_from_another_module():
    private = [f"{name} imports {target}.{imported}" for name, path in MODULES.items()
               for target, imported, _ in _imports(name, path)
               if imported and imported.startswith("_") and not imported.startswith("__") and target != name]
    assert private == []


def test_no_function_outside_the_cli_is_longer_than_80_lines_of_code():
    long = []
    for name, path in MODULES.items():
        if name.startswith("meshcorr.cli"):
            continue
        text = path.read_text()
        lines = text.splitlines()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                count = _code_lines(node, lines)
                if count > MAX_CODE_LINES:
                    long.append(f"{name}.{node.name}: {count}")
    assert long == []


def test_architecture_page_names_every_subpackage():
    page = ARCHITECTURE.read_text()
    subpackages = sorted(path.parent.name for path in PACKAGE.glob("*/__init__.py"))
    missing = [name for name in subpackages if f"`{name}/`" not in page]
    assert len(subpackages) >= 10 and missing == []


def test_docstrings_cite_no_file_outside_the_repository():
    cited = [str(path.relative_to(PACKAGE)) for path in PACKAGE.rglob("*.py")
             if re.search(r"ALGORITHM\.md|\.\./shared", path.read_text())]
    assert cited == []


@pytest.mark.parametrize("old, new, name", [("refine", "meshcorr.stages.refine", "zoomout"),
                                            ("landmarks", "meshcorr.core.sampling", "farthest_point_sampling"),
                                            ("prepared", "meshcorr.shapes.prepared", "PreparedShape")])
def test_old_flat_import_paths_warn_and_name_the_new_one(old, new, name, monkeypatch):
    import importlib
    import sys

    sys.modules.pop(f"meshcorr.{old}", None)
    with pytest.warns(DeprecationWarning, match=re.escape(new)):
        module = importlib.import_module(f"meshcorr.{old}")
    target = importlib.import_module(new)
    assert module is target and getattr(module, name) is getattr(target, name)
    assert target.__name__ == new and target.__spec__.name == new  # pickles and relative imports unaffected
    monkeypatch.setattr(module, name, "patched")  # patching the old path patches the module users run
    assert getattr(target, name) == "patched"


@pytest.mark.filterwarnings(r"ignore:meshcorr\.\w+ moved to meshcorr\.[\w.]+; import meshcorr")
@pytest.mark.parametrize("statement, home", [
    ("from meshcorr.refine import laplace_basis", "meshcorr.spectral.basis.laplace_basis"),
    ("from meshcorr.orientation import orientation_score", "meshcorr.core.map_orientation.orientation_score"),
    ("from meshcorr.symmetry import Candidate", "meshcorr.choice.symmetry.ConfigurationCandidate"),
    ("from meshcorr.collection import read_pairs", "meshcorr.collection.pairs.read_pair_list"),
])
def test_names_that_left_their_module_are_found_at_their_new_home_with_a_warning(statement, home):
    import importlib

    with pytest.warns(DeprecationWarning, match=re.escape(home)):
        namespace: dict = {}
        exec(statement, namespace)
    module, _, attribute = home.rpartition(".")
    value = [v for k, v in namespace.items() if not k.startswith("__")][0]
    assert value is getattr(importlib.import_module(module), attribute)


def test_an_unknown_name_of_an_old_path_is_an_import_error():
    import meshcorr.stages.refine  # noqa: F401

    with pytest.raises(ImportError, match="nothing_here"):
        from meshcorr.refine import nothing_here  # noqa: F401


def test_public_short_module_names_stay_without_a_warning(recwarn):
    import meshcorr

    assert meshcorr.datasets.__name__ == "meshcorr.evaluation.datasets"
    assert meshcorr.fmap.__name__ == "meshcorr.spectral.fmap"
    assert not [w for w in recwarn if issubclass(w.category, DeprecationWarning)]


def test_replaced_modules_keep_their_names_through_the_new_subpackage():
    from meshcorr.evaluation import geodesic_errors
    from meshcorr.evaluation.metrics import geodesic_errors as direct
    from meshcorr.pipeline import match

    import meshcorr

    assert geodesic_errors is direct and match is meshcorr.match
    with pytest.raises(ImportError, match="nothing_here"):
        from meshcorr.pipeline import nothing_here  # noqa: F401
