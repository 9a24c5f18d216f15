"""The shape of the library's code: no function longer than 80 lines (issue 43), none
taking more than 12 parameters.

A function that does one thing fits on a screen; past 80 lines (docstring included)
it is split. Counted with the ``ast`` line numbers of every function and method
under ``roughcontact/``. A function that needs more than a dozen values takes a
record of them (the solver: one problem, one options record).
"""

import ast
import inspect
from pathlib import Path

import roughcontact
from roughcontact import contact
from roughcontact.contact import cell, nondim

LIMIT = 80
#: The most parameters a function takes (``self``/``cls`` not counted; ``*args`` and
#: ``**kwargs`` count one each).
MAX_PARAMETERS = 12
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


def parameter_count(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """The parameters of a function definition, ``self``/``cls`` not counted."""
    args = node.args
    count = (len(args.posonlyargs) + len(args.args) + len(args.kwonlyargs)
             + (args.vararg is not None) + (args.kwarg is not None))
    first = (args.posonlyargs + args.args)[:1]
    return count - (bool(first) and first[0].arg in ("self", "cls"))


def crowded_functions(root: Path = ROOT, limit: int = MAX_PARAMETERS) -> list[str]:
    """``path:line name (parameters)`` of every function under ``root`` taking more
    than ``limit`` parameters."""
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                count = parameter_count(node)
                if count > limit:
                    found.append(f"{path.relative_to(root.parent)}:{node.lineno} "
                                 f"{node.name} ({count})")
    return found


def test_no_function_takes_more_than_12_parameters():
    assert crowded_functions() == []


def test_the_count_sees_a_crowded_method_and_spares_self(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(
        "class A:\n    def crowded(self, a, b, c, d, e, f, g, h, i, j, k, *, l, **m):\n"
        "        pass\n\n    def full(self, a, b, c, d, e, f, g, h, i, j, k, l):\n"
        "        pass\n")
    assert crowded_functions(tmp_path / "pkg") == ["pkg/m.py:2 crowded (13)"]


def test_the_solver_takes_a_short_form_and_the_cell_sweeps_their_options_whole():
    for function in (contact.solve, contact.solve_many, contact.sweep):
        assert len(inspect.signature(function).parameters) <= 8, function.__name__
        assert "options" in inspect.signature(function).parameters
    for function in (nondim.solve_cell, cell.sweep_cell, cell.sweep_and_aggregate):
        kinds = {p.kind for p in inspect.signature(function).parameters.values()}
        assert inspect.Parameter.VAR_KEYWORD not in kinds, function.__name__
