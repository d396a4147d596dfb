"""The suite's own rule, checked: every validation test derives its expected value in its docstring."""

import ast
from pathlib import Path

HERE = Path(__file__).parent


def test_every_check_derives_its_value_in_its_docstring():
    """A validation test without a docstring has no derivation, so its expected value could only
    have come from an engine: the suite refuses it."""
    missing = []
    for path in sorted(HERE.glob("test_*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_") and not ast.get_docstring(node):
                missing.append(f"{path.name}::{node.name}")
    assert not missing, f"validation tests without a derivation: {missing}"
