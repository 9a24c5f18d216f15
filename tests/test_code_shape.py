"""The shape of the library's code: no function longer than 80 lines (issue 43).

A function that does one thing fits on a screen; past 80 lines (docstring included)
it is split. Counted with the ``ast`` line numbers of every function and method
under ``roughcontact/``.
"""

import ast
from pathlib import Path

import roughcontact

LIMIT = 80
ROOT = Path(roughcontact.__file__).parent


def long_functions(root: Path = ROOT, limit: int = LIMIT) -> list[str]:
    """``path:line name (lines)`` of every function under ``root`` over ``limit`` lines."""
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > limit:
                    found.append(f"{path.relative_to(root.parent)}:{node.lineno} "
                                 f"{node.name} ({lines})")
    return found


def test_no_function_is_longer_than_80_lines():
    assert long_functions() == []


def test_the_count_sees_a_long_method_and_spares_a_short_one(tmp_path):
    body = "\n".join(f"        x{i} = {i}" for i in range(88))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(
        'class A:\n    def long(self):\n        """90 lines."""\n' + body
        + "\n\n\ndef short():\n    return 1\n")
    assert long_functions(tmp_path / "pkg") == ["pkg/m.py:2 long (90)"]
