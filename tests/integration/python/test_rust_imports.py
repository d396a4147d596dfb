"""The modules of every Rust crate import each other in one direction only: no
circle, and none points up (docs/developers.md draws the layers this keeps).
An import points up where a module's folder and a module beside it import each
other: `fmi2/calls.rs` using `logger.rs` while `logger.rs` uses `fmi2/mod.rs`'s
types is no circle of files, but the folder `fmi2/` and `logger.rs` are one.

An import of module A into module B of the same crate is a `use crate::…`,
`use super::…`, `use self::…` or a `use` of one of B's own child modules, or a
qualified path in B's code that starts with `crate::`, `$crate::`, `super::` or
`self::` or names one of B's child modules (`stepping::step(…)` in the module
that declares `mod stepping`). It points at the deepest module the path names
(`crate::Line`, re-exported by lib.rs, is lib.rs). A `mod` declaration is no
import: it says where a module sits, not what it uses. Comments and string
literals are not read; inline modules (`mod tests { … }`) count as their file.
The crates are those of every Cargo.toml the repository tracks; each target's
root (src/lib.rs, src/main.rs, src/bin/*.rs, a [[bin]]'s path) starts a tree.
"""

import importlib.util
import re
import subprocess
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
KEYWORDS = {"crate", "super", "self", "Self"}

# The circle finder of webline's own import test: one for Python's modules and Rust's.
_spec = importlib.util.spec_from_file_location("webline_imports", ROOT / "webline" / "tests" / "test_imports.py")
_webline_imports = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_webline_imports)
cycle = _webline_imports.cycle


def strip(text):
    """The code without comments, strings and char literals (each replaced by a blank)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif (m := re.match(r'b?r(#*)"', text[i:])) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = text.find('"' + m.group(1), i + m.end())
            i = n if end < 0 else end + 1 + len(m.group(1))
            out.append(' ""')
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            i += 1
            out.append(' ""')
        elif c == "'" and (m := re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|[^\\'])'", text[i:])):
            i += m.end()
            out.append(" ' '")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def use_paths(tree, prefix=()):
    """The paths of a use tree (`a::{b, c::d as e, self}`), as tuples of segments."""
    tree = tree.strip()
    if not tree:
        return []
    brace = tree.find("{")
    if brace < 0:
        segments = tuple(s.strip() for s in tree.split(" as ")[0].split("::") if s.strip())
        return [prefix + tuple(s for s in segments if s != "self")] if segments else []
    head = tuple(s.strip() for s in tree[:brace].split("::") if s.strip())
    inner, depth, part, parts = tree[brace + 1 : tree.rfind("}")], 0, "", []
    for c in inner:
        depth += c == "{"
        depth -= c == "}"
        if c == "," and depth == 0:
            parts.append(part)
            part = ""
        else:
            part += c
    parts.append(part)
    return [p for part in parts for p in use_paths(part, prefix + head)]


class Crate:
    """The module tree of one target of a crate: module path -> file, and each file's code."""

    def __init__(self, root_file):
        self.files, self.code, self.children = {}, {}, {}
        self.add((), Path(root_file), Path(root_file).parent)

    def add(self, path, file, child_dir):
        self.files[path] = file
        code = strip(file.read_text(encoding="utf-8"))
        self.code[path] = code
        self.children[path] = set()
        for m in re.finditer(r'((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;', code):
            name = m.group(2)
            given = re.search(r'#\[path\s*=\s*""\]', m.group(1))
            candidates = [child_dir / f"{name}.rs", child_dir / name / "mod.rs"]
            found = next((c for c in candidates if c.exists()), None)
            assert found and not given, f"{file}: mod {name}; has no file {candidates[0]} or {candidates[1]}"
            self.children[path].add(name)
            grandchildren = found.parent if found.name == "mod.rs" else found.parent / name
            self.add(path + (name,), found, grandchildren)

    def deepest(self, start, segments):
        """The module a path names from module `start`: as deep as its segments are modules."""
        module = start
        for s in segments:
            if s in self.children.get(module, ()):
                module = module + (s,)
            else:
                break
        return module

    def resolve(self, module, inline, segments):
        """Where a path in `module` points (None: outside the crate), written inside the
        inline modules `inline` of its file (their names, outermost first)."""
        if not segments:
            return None
        first, rest = segments[0], list(segments[1:])
        if first in ("crate", "$crate"):
            return self.deepest((), rest)
        if first == "super" or first == "self":
            base = module + tuple(inline)
            while segments and segments[0] in ("super", "self"):
                base = base[:-1] if segments[0] == "super" else base
                segments = segments[1:]
            # Still inside the file's inline modules: the file itself.
            return module if len(base) > len(module) else self.deepest(base, segments)
        if not inline and first in self.children[module]:
            return self.deepest(module, segments)
        return None

    def imports(self):
        """module -> the modules it imports (itself left out)."""
        graph = {}
        for module, code in self.code.items():
            blocks = inline_modules(code)
            inside = lambda pos: [name for start, end, name in blocks if start < pos < end]  # noqa: E731
            targets = set()
            for m in re.finditer(r"\buse\s+([^;]+);", code):
                for path in use_paths(m.group(1)):
                    targets.add(self.resolve(module, inside(m.start()), path))
            for m in re.finditer(r"(?<![\w:])(\$?[A-Za-z_]\w*)((?:::[A-Za-z_]\w*)+)", code):
                first = m.group(1)
                if first in KEYWORDS - {"Self"} or first == "$crate" or first in self.children[module]:
                    targets.add(self.resolve(module, inside(m.start()), (first, *m.group(2).split("::")[1:])))
            graph[module] = {t for t in targets if t is not None and t != module}
        return graph


def inline_modules(code):
    """The inline modules of a file's code (`mod tests { ... }`): (start, end, name), outermost first."""
    blocks = []
    for m in re.finditer(r"\bmod\s+(\w+)\s*\{", code):
        depth, i = 1, m.end()
        while i < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[i], 0)
            i += 1
        blocks.append((m.start(), i, m.group(1)))
    return blocks


def target_roots(manifest):
    """The root files of a crate's lib and binaries."""
    folder = manifest.parent
    spec = tomllib.loads(manifest.read_text(encoding="utf-8"))
    if "package" not in spec:
        return []
    roots = [folder / spec.get("lib", {}).get("path", "src/lib.rs"), folder / "src" / "main.rs"]
    roots += sorted((folder / "src" / "bin").glob("*.rs"))
    roots += [folder / b["path"] for b in spec.get("bin", []) if "path" in b]
    return sorted({r.resolve() for r in roots if r.exists()})


def manifests():
    listed = subprocess.run(["git", "ls-files", "*Cargo.toml"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [ROOT / line for line in listed.split()]


def circle_in(root_file):
    crate = Crate(root_file)
    found = cycle(crate.imports())
    return found and " -> ".join(str(crate.files[m].relative_to(ROOT)) for m in found)


def upward_in(root_file, base=ROOT):
    """The first import that points up in a crate: where the subtrees of two
    modules or more beside each other (the children of one module) import each
    other in a circle, that circle with an import that makes each step."""
    crate = Crate(root_file)
    graph = crate.imports()
    for parent, children in sorted(crate.children.items()):
        beside = lambda module: module[len(parent)] if module[: len(parent)] == parent and len(module) > len(parent) else None  # noqa: E731
        folded, witness = {child: set() for child in children}, {}
        for module, targets in sorted(graph.items()):
            for target in sorted(targets):
                a, b = beside(module), beside(target)
                if a is not None and b is not None and a != b:
                    folded[a].add(b)
                    witness.setdefault((a, b), (module, target))
        found = cycle(folded)
        if found:
            name = lambda module: crate.files[module].relative_to(base).as_posix()  # noqa: E731
            steps = [witness[a, b] for a, b in zip(found, found[1:])]
            return " and ".join(f"{name(m)} -> {name(t)}" for m, t in steps)
    return None


def test_no_rust_import_points_up():
    roots = [r for m in manifests() for r in target_roots(m)]
    assert len(roots) > 15, roots
    upward = [u for u in map(upward_in, roots) if u]
    assert not upward, "\n".join(upward)


def test_no_rust_crate_has_an_import_circle():
    roots = [r for m in manifests() for r in target_roots(m)]
    assert len(roots) > 15, roots
    circles = [c for c in map(circle_in, roots) if c]
    assert not circles, "\n".join(circles)


def test_the_imports_are_read():
    """The checker sees what the Line crate's layers are made of (so that a silent miss cannot pass)."""
    crate = Crate(ROOT / "models" / "line" / "src" / "lib.rs")
    graph = crate.imports()
    assert ("port",) in graph[("part",)]
    assert ("part",) in graph[("network",)] and ("chain",) in graph[("network",)]
    assert ("ode",) in graph[("stepping",)] and ("line",) in graph[()]


def test_the_check_finds_a_circle(tmp_path):
    """A crate whose modules import each other through each way an import is written."""
    src = tmp_path / "src"
    (src / "inner").mkdir(parents=True)
    (src / "lib.rs").write_text("pub mod a;\nmod b;\npub mod inner;\npub use a::A;\n// use crate::inner;\n")
    (src / "a.rs").write_text("pub struct A;\npub fn f() { crate::b::g() }\n")
    (src / "b.rs").write_text('use super::inner::{x, Y as Z};\npub fn g() { let _ = "crate::a::f"; }\n')
    (src / "inner" / "mod.rs").write_text("mod deep;\npub fn x() { deep::h() }\npub struct Y;\n")
    (src / "inner" / "deep.rs").write_text("pub fn h() { let _ = crate::A; }\n")
    assert cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    found = circle_in_tmp(src / "lib.rs")
    assert found == ["", "a", "b", "inner", "inner.deep", ""], found
    # Without the path back to the root (deep uses lib.rs's re-export of A) the crate has no circle.
    (src / "inner" / "deep.rs").write_text("pub fn h() {}\n")
    assert circle_in_tmp(src / "lib.rs") is None


def circle_in_tmp(root_file):
    found = cycle(Crate(root_file).imports())
    return found and [".".join(m) for m in found]


def test_the_check_finds_an_import_pointing_up(tmp_path):
    """A standard's calls use a logger beside its folder, and that logger uses the
    standard's types: no circle of files, but one of the folder and the logger."""
    src = tmp_path / "src"
    (src / "std2").mkdir(parents=True)
    (src / "lib.rs").write_text("mod logger;\npub mod std2;\n")
    (src / "logger.rs").write_text("use crate::std2::Callback;\npub struct Logger(pub Callback);\n")
    (src / "std2" / "mod.rs").write_text("pub mod calls;\npub type Callback = fn();\n")
    (src / "std2" / "calls.rs").write_text("use crate::logger::Logger;\npub fn f(l: Logger) {}\n")
    assert cycle(Crate(src / "lib.rs").imports()) is None
    assert upward_in(src / "lib.rs", tmp_path) == "src/logger.rs -> src/std2/mod.rs and src/std2/calls.rs -> src/logger.rs"
    # With the logger inside the standard's folder nothing points up.
    (src / "lib.rs").write_text("pub mod std2;\n")
    (src / "logger.rs").rename(src / "std2" / "logger.rs")
    (src / "std2" / "logger.rs").write_text("use super::Callback;\npub struct Logger(pub Callback);\n")
    (src / "std2" / "mod.rs").write_text("pub mod calls;\nmod logger;\npub type Callback = fn();\n")
    (src / "std2" / "calls.rs").write_text("use super::logger::Logger;\npub fn f(l: Logger) {}\n")
    assert upward_in(src / "lib.rs", tmp_path) is None
