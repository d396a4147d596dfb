"""JSON with positions: every value knows the line and column it starts at.

Python's json module forgets where a value came from; scene errors must name
the file position of the offending key or value, so scenes are read with
this small recursive-descent parser (RFC 8259 JSON, nothing more). Objects
become `Obj` (an ordered dict of key -> `Node`, duplicate keys refused),
arrays `list` of `Node`, scalars their Python values, each wrapped in a `Node`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field


class JsonError(ValueError):
    """A syntax error, with the file position."""


@dataclass
class Node:
    value: object
    line: int
    col: int
    # For a value inside an object: where its key starts (errors about the key point there).
    key_line: int = 0
    key_col: int = 0

    def where(self, path: str = "") -> str:
        return f"{path}:{self.line}:{self.col}" if path else f"{self.line}:{self.col}"


@dataclass
class Obj:
    """A JSON object: key -> Node, in file order."""

    items: dict = field(default_factory=dict)

    def __contains__(self, key):
        return key in self.items

    def __getitem__(self, key):
        return self.items[key]

    def keys(self):
        return self.items.keys()

    def get(self, key, default=None):
        return self.items.get(key, default)


_NUMBER = re.compile(r"-?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?")
_ESCAPES = {'"': '"', "\\": "\\", "/": "/", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t"}


class _Parser:
    def __init__(self, text: str, source: str):
        self.text = text
        self.source = source
        self.i = 0
        # Offsets where lines start, for offset -> (line, column).
        self.line_starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def position(self, offset: int):
        lo, hi = 0, len(self.line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self.line_starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - self.line_starts[lo] + 1

    def fail(self, message: str, offset: int | None = None):
        line, col = self.position(self.i if offset is None else offset)
        raise JsonError(f"{self.source}:{line}:{col}: {message}")

    def skip_space(self):
        while self.i < len(self.text) and self.text[self.i] in " \t\r\n":
            self.i += 1

    def peek(self):
        self.skip_space()
        return self.text[self.i] if self.i < len(self.text) else ""

    def expect(self, ch: str):
        if self.peek() != ch:
            found = repr(self.text[self.i]) if self.i < len(self.text) else "the end of the file"
            self.fail(f"expected {ch!r}, found {found}")
        self.i += 1

    def value(self) -> Node:
        ch = self.peek()
        start = self.i
        line, col = self.position(start)
        if ch == "{":
            return Node(self.obj(), line, col)
        if ch == "[":
            return Node(self.array(), line, col)
        if ch == '"':
            return Node(self.string(), line, col)
        for word, val in (("true", True), ("false", False), ("null", None)):
            if self.text.startswith(word, self.i):
                self.i += len(word)
                return Node(val, line, col)
        m = _NUMBER.match(self.text, self.i)
        if m and m.end() > self.i:
            self.i = m.end()
            s = m.group(0)
            return Node(float(s) if any(c in s for c in ".eE") else int(s), line, col)
        if ch == "":
            self.fail("unexpected end of the file: a value is missing")
        self.fail(f"unexpected {ch!r}: not a JSON value")

    def obj(self) -> Obj:
        self.expect("{")
        out = Obj()
        if self.peek() == "}":
            self.i += 1
            return out
        while True:
            if self.peek() != '"':
                self.fail("expected a key in double quotes")
            key_line, key_col = self.position(self.i)
            key_offset = self.i
            key = self.string()
            if key in out.items:
                self.fail(f"the key {key!r} appears twice in this object", key_offset)
            self.expect(":")
            node = self.value()
            node.key_line, node.key_col = key_line, key_col
            out.items[key] = node
            if self.peek() == ",":
                self.i += 1
                continue
            self.expect("}")
            return out

    def array(self) -> list:
        self.expect("[")
        out = []
        if self.peek() == "]":
            self.i += 1
            return out
        while True:
            out.append(self.value())
            if self.peek() == ",":
                self.i += 1
                continue
            self.expect("]")
            return out

    def string(self) -> str:
        self.expect('"')
        parts = []
        while True:
            if self.i >= len(self.text):
                self.fail("unterminated string")
            ch = self.text[self.i]
            if ch == '"':
                self.i += 1
                return "".join(parts)
            if ch == "\\":
                esc = self.text[self.i + 1 : self.i + 2]
                if esc == "u":
                    code = self.text[self.i + 2 : self.i + 6]
                    if not re.fullmatch(r"[0-9a-fA-F]{4}", code):
                        self.fail("bad \\u escape")
                    parts.append(chr(int(code, 16)))
                    self.i += 6
                elif esc in _ESCAPES:
                    parts.append(_ESCAPES[esc])
                    self.i += 2
                else:
                    self.fail(f"bad escape \\{esc}")
                continue
            if ch < " ":
                self.fail("control character in a string")
            parts.append(ch)
            self.i += 1


def parse(text: str, source: str = "<scene>") -> Node:
    p = _Parser(text, source)
    node = p.value()
    if p.peek() != "":
        p.fail("unexpected text after the JSON value")
    return node


def to_plain(node: Node):
    """The node as plain Python values (dicts, lists, scalars)."""
    v = node.value
    if isinstance(v, Obj):
        return {k: to_plain(n) for k, n in v.items.items()}
    if isinstance(v, list):
        return [to_plain(n) for n in v]
    return v
