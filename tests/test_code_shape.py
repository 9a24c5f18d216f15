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


# ---------------------------------------------------------------------------
# One place for one decision (issue 45): the configuration's dict stops at its edge,
# the results/ layout is spelled in one module, the flow's column names in transport/,
# the workflow's glue is a few generic input functions.

REPO = ROOT.parent
#: The functions that take the configuration's dict: the schema's validation, the one
#: Study made of it, a run's hash and seed, and the job entry points whose rules'
#: scripts pass it (their text must not change: Snakemake reruns a job whose script does).
CONFIG_EDGE = {
    "roughcontact/study/config.py": {"schema_errors", "apply_schema", "_fill_defaults",
                                     "validated"},
    "roughcontact/study/settings.py": {"from_config"},
    "roughcontact/study/provenance.py": {"config_hash", "of"},
    "roughcontact/study/jobs/contact.py": {"solve_contact_job"},
    "roughcontact/study/jobs/surfaces.py": {"build_surface_cell"},
    "roughcontact/study/jobs/influence.py": {"build_influence", "choose_influence",
                                             "build_pair"},
}


def _functions_with(name: str, path) -> set[str]:
    """The functions of a module with a parameter ``name``."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            args = node.args.posonlyargs + node.args.args + node.args.kwonlyargs
            if any(arg.arg == name for arg in args):
                found.add(node.name)
    return found


def functions_taking(name: str, paths) -> dict[str, set[str]]:
    """Path (relative to the repository) -> the functions with a parameter ``name``."""
    return {str(path.relative_to(REPO)): found for path in paths
            if (found := _functions_with(name, path))}


def library_and_scripts():
    return [*sorted(ROOT.rglob("*.py")), *sorted((REPO / "scripts").glob("*.py"))]


def test_the_configuration_dict_stops_at_its_edge():
    assert functions_taking("config", library_and_scripts()) == CONFIG_EDGE
    assert sum(map(len, CONFIG_EDGE.values())) <= 12


def test_the_count_sees_a_config_parameter(tmp_path):
    (tmp_path / "m.py").write_text("def f(a, *, config=None):\n    return a\n")
    assert _functions_with("config", tmp_path / "m.py") == {"f"}


def code_strings(path) -> list[str]:
    """The string constants of a module's code (f-strings' parts included), docstrings
    left out."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef
                                | ast.AsyncFunctionDef)
                  and node.body and isinstance(node.body[0], ast.Expr)
                  and isinstance(node.body[0].value, ast.Constant)}
    return [node.value for node in ast.walk(tree) if isinstance(node, ast.Constant)
            and isinstance(node.value, str) and id(node) not in docstrings]


def test_the_results_layout_is_spelled_in_one_module():
    spelled = sorted(str(path.relative_to(REPO)) for path in library_and_scripts()
                     if any(text == "results" or "results/" in text
                            for text in code_strings(path)))
    assert spelled == ["roughcontact/study/layout.py"]


def test_the_layout_count_sees_a_path_and_spares_a_docstring(tmp_path):
    (tmp_path / "m.py").write_text('"""Files under results/."""\nP = f"results/{1}.h5"\n')
    (tmp_path / "n.py").write_text('def f():\n    """In results/ too."""\n    return 1\n')
    assert [bool(code_strings(tmp_path / name)) for name in ("m.py", "n.py")] == [True, False]


def test_the_flow_names_its_columns_in_transport_only():
    import re

    pattern = re.compile(r"flow_conductance|flow_factor|flow_connected|flow_balance|leak_rate_")
    spelled = {str(path.relative_to(ROOT)).split("/")[0] for path in ROOT.rglob("*.py")
               if pattern.search(path.read_text())}
    assert spelled == {"transport"}


def test_the_rules_glue_is_a_few_input_functions():
    import re

    text = "".join(path.read_text() for path in (REPO / "rules").glob("*.smk"))
    getters = re.findall(r"^def (get_\w+)\(", text, re.M)
    assert len(getters) == len(set(getters)) and 0 < len(getters) <= 25
    # resources through two generic getters, by the kind of job
    assert {"get_mem_mb", "get_runtime"} <= set(getters)
    assert not [g for g in getters if g.endswith(("_mem_mb", "_runtime"))
                and g not in ("get_mem_mb", "get_runtime")]
