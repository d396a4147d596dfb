"""webline's modules import each other in one direction only: no cycle,
counting imports inside functions too (a cycle there still ties the modules
together, it only hides from a reader of the file's head), and none points up:
a package (`scene/`) and a module beside it do not import each other, even where
no two files do."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "webline"


def module_names(package=PACKAGE):
    """Every module of the package by its dotted name below it: `compiler`, `scene` (scene/__init__.py),
    `scene.types`; the package's own __init__.py is `__init__`."""
    names = {}
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package).with_suffix("").parts
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def imports_of(path, name, known):
    """The modules of `known` (names as module_names gives them) that module `name` at `path` imports."""
    is_package = path.name == "__init__.py"
    here = [] if name == "__init__" else name.split(".")
    package = here if is_package else here[:-1]
    found = set()

    def add(parts):
        # The deepest module a path names: `scene.types.Web` is scene.types, `scene.Scene` is scene.
        for n in range(len(parts), 0, -1):
            if ".".join(parts[:n]) in known:
                found.add(".".join(parts[:n]))
                return

    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level >= 1:
            base = package[: len(package) - (node.level - 1)] + (node.module.split(".") if node.module else [])
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("webline."):
            base = node.module.split(".")[1:]
        else:
            continue
        for alias in node.names:  # `from . import units`, `from .scene import types`
            add(base + [alias.name])
    return found - {name}


def graph_of(package=PACKAGE):
    known = module_names(package)
    return {name: imports_of(path, name, known) for name, path in known.items()}


def pointing_up(graph):
    """A circle among modules and packages beside each other (the files of one package, its
    subpackages each taken whole), or None."""
    packages = {""} | {name.rpartition(".")[0] for name in graph if "." in name}
    for package in sorted(packages):
        prefix = package + "." if package else ""
        beside = lambda name: name[len(prefix):].split(".")[0] if name.startswith(prefix) and name != package else None  # noqa: E731
        folded = {}
        for name, targets in graph.items():
            a = beside(name)
            if a is None:
                continue
            folded.setdefault(a, set()).update(b for b in map(beside, targets) if b is not None and b != a)
        found = cycle(folded)
        if found:
            return [prefix + x for x in found]
    return None


def cycle(graph):
    """One cycle of module names, or None."""
    state, stack = {}, []

    def visit(module):
        state[module] = "open"
        stack.append(module)
        for other in sorted(graph.get(module, ())):
            if state.get(other) == "open":
                return stack[stack.index(other):] + [other]
            if other not in state:
                found = visit(other)
                if found:
                    return found
        stack.pop()
        state[module] = "done"
        return None

    for module in sorted(graph):
        if module not in state:
            found = visit(module)
            if found:
                return found
    return None


def test_webline_has_no_import_cycle():
    graph = graph_of()
    assert len(graph) > 10 and "scene.types" in graph, sorted(graph)
    assert "scene" in graph["compiler"] and "records" in graph["scene.types"], graph
    assert cycle(graph) is None, " -> ".join(cycle(graph))


def test_no_webline_import_points_up():
    found = pointing_up(graph_of())
    assert found is None, " -> ".join(found)


def test_the_check_finds_a_cycle():
    assert cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert cycle({"a": {"b"}, "b": set()}) is None


def test_the_check_finds_an_import_pointing_up(tmp_path):
    """scene/reading.py uses a module beside the package that uses scene/types.py: no cycle of
    files, but one of the package and that module."""
    (tmp_path / "scene").mkdir()
    (tmp_path / "__init__.py").write_text("from .scene import load\n")
    (tmp_path / "scene" / "__init__.py").write_text("from .reading import load\nfrom .types import Web\n")
    (tmp_path / "scene" / "types.py").write_text("class Web: pass\n")
    (tmp_path / "scene" / "reading.py").write_text("from .. import physics\ndef load(): pass\n")
    (tmp_path / "physics.py").write_text("from .scene.types import Web\n")
    graph = graph_of(tmp_path)
    assert graph["scene.reading"] == {"physics"} and graph["physics"] == {"scene.types"}, graph
    assert cycle(graph) is None
    assert pointing_up(graph) == ["scene", "physics", "scene"]
    (tmp_path / "physics.py").write_text("def strain(): pass\n")
    assert pointing_up(graph_of(tmp_path)) is None
