"""The test suite's own layout: no test module imports another (shared code lives in helper modules without the
``test_`` prefix, e.g. disort_reference.py, epw_records.py; fixtures in conftest.py)."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_no_test_module_imports_another():
    offenders = []
    for path in sorted(TESTS.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            bad = [n for n in names if n.split(".")[0].startswith("test_")]
            offenders += [f"{path.name}:{node.lineno} imports {n}" for n in bad]
    assert not offenders, offenders
