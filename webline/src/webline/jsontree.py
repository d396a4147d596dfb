"""JSON with positions: every value knows the line and column it starts at.

Scene errors name the file position of the offending key or value, which
Python's json module forgets. So a scene is read twice, by two libraries:
the standard `json` module decides whether the text is JSON (RFC 8259, no
NaN or Infinity; its errors carry line and column), and tree-sitter's JSON
grammar (`tree-sitter-json`) gives the syntax tree with the position of every
key and value. Each scalar's value is the `json` module's reading of that
node's text. Objects become `Obj` (an ordered dict of key -> `Node`, a
duplicate key refused at its position), arrays `list` of `Node`, scalars
their Python values, each wrapped in a `Node`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import lru_cache


class JsonError(ValueError):
    """Text that is not JSON, with the file position."""


@dataclass
class Node:
    value: object
    line: int
    col: int
    # For a value inside an object: where its key starts (errors about the key point there).
    key_line: int = 0
    key_col: int = 0


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


@lru_cache(maxsize=1)
def _parser():
    import tree_sitter_json
    from tree_sitter import Language, Parser

    return Parser(Language(tree_sitter_json.language()))


def _refuse_constant(name):
    raise ValueError(f"{name} is not a JSON value")


class _Tree:
    def __init__(self, data: bytes, source: str):
        self.data = data
        self.source = source

    def position(self, node):
        """1-based line and column (in characters; tree-sitter counts bytes)."""
        row, byte_col = node.start_point
        line_start = node.start_byte - byte_col
        col = len(self.data[line_start : node.start_byte].decode("utf-8")) + 1
        return row + 1, col

    def fail(self, node, message):
        line, col = self.position(node)
        raise JsonError(f"{self.source}:{line}:{col}: {message}")

    def value(self, node) -> Node:
        line, col = self.position(node)
        if node.type == "object":
            out = Obj()
            for pair in node.named_children:
                if pair.type != "pair":  # a comment or an error: json has refused it already
                    self.fail(pair, "not JSON")
                key_node = pair.child_by_field_name("key")
                key = json.loads(key_node.text)
                if key in out.items:
                    self.fail(key_node, f"the key {key!r} appears twice in this object")
                item = self.value(pair.child_by_field_name("value"))
                item.key_line, item.key_col = self.position(key_node)
                out.items[key] = item
            return Node(out, line, col)
        if node.type == "array":
            return Node([self.value(n) for n in node.named_children], line, col)
        if node.type in ("string", "number", "true", "false", "null"):
            return Node(json.loads(node.text, parse_constant=_refuse_constant), line, col)
        self.fail(node, f"unexpected {node.type}: not a JSON value")


def _first_error(node):
    """The outermost syntax error in tree-sitter's tree (or the node itself)."""
    while node.type != "ERROR" and not node.is_missing:
        inner = next((c for c in node.children if c.has_error), None)
        if inner is None:
            break
        node = inner
    return node


def parse(text: str, source: str = "<scene>") -> Node:
    """The JSON text as a tree of `Node`s; `source` names it in errors."""
    constant = None
    try:
        json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as e:
        # json says "Expecting ',' delimiter"; scene errors are lower case.
        message = e.msg.replace("Expecting", "expected", 1)
        raise JsonError(f"{source}:{e.lineno}:{e.colno}: not valid JSON: {message}") from None
    except ValueError as e:  # NaN, Infinity: json has no position for them, the tree has
        constant = e
    data = text.encode("utf-8")
    document = _parser().parse(data).root_node
    tree = _Tree(data, source)
    if constant is not None:
        tree.fail(_first_error(document), f"not valid JSON: {constant}")
    values = [n for n in document.named_children if n.type != "comment"]
    if len(values) != 1:
        tree.fail(document, "expected one JSON value")
    return tree.value(values[0])
