"""A papermill engine that runs a notebook's code cells in this Python process.

Why: every figure is its own workflow job. Through a Jupyter kernel a figure
cost the job's process about 0.9 s of CPU (Python, papermill, nbclient and
jupyter_client imports) and the kernel another 2-3 s, of which about 0.8 s
went to starting the kernel and its ZMQ channels and about 1 s to importing
matplotlib, pandas and :mod:`roughcontact.reports.plotting`; the 14 figures
of ``config/quick.yaml`` were about 45 % of its CPU. This engine runs the
cells in the job's own process: no kernel is started and nothing is
imported twice. Three of the quick study's figures (fig03, fig07,
table_Eu), each executed in its own process as its job does, took 8.6 s of
CPU with a kernel and 6.1 s in-process (the least of 3 runs each,
alternating; 0.72 times, 0.8 s less a figure; 0.75 and 0.9 s in a second
measurement on a busier machine), with byte-identical PNGs; the whole quick
study 98 s of CPU and 58 s with a kernel, 89 s and 50 s in-process. Papermill
still reads the notebook, injects the parameters cell, records each cell's
status and times, writes the executed notebook and raises
:class:`papermill.exceptions.PapermillExecutionError` for a failing cell,
with the cell's traceback saved in the notebook.

What it does: the code cells run in order with :func:`exec` in one fresh
namespace (``__name__ == "__main__"``), numbered 1, 2, ... as a kernel
numbers them (empty cells are skipped). Each cell's outputs are nbformat v4
dicts, in the order they appear:

- ``stream``: what the cell writes to ``sys.stdout`` and ``sys.stderr``
  (``print``, and warnings, shown as Python shows them);
- ``display_data``: what the cell passes to ``display`` (a name of the
  namespace, as IPython makes it a builtin): an object, or with
  ``raw=True`` a dict from MIME type to text;
- ``execute_result``: the value of the cell's last expression unless it is
  ``None`` or the expression ends with ``;``, as IPython shows it;
- ``error``: the exception a cell raised (``ename``, ``evalue``, the
  traceback's lines from the cell's frame on); no further cell runs, and
  papermill raises.

An object's outputs are its ``repr`` as ``text/plain``, and the text of its
``_repr_html_``, ``_repr_markdown_`` and ``_repr_latex_`` where it has them.
The figures that the notebook opened with pyplot are closed at the end.

What differs from a kernel:

- No IPython: no magics (``%``, ``!``), no ``get_ipython``, no images or
  other binary display outputs (``_repr_png_``, inline figures), and
  ``IPython.display.display`` would print the object's ``repr`` (the
  namespace's ``display`` records it). The project's notebooks use none of
  these: they save their figures with
  :func:`roughcontact.reports.plotting.save_figure` and select matplotlib's
  Agg backend themselves (``matplotlib.use("Agg")`` before pyplot).
- ``text/plain`` is ``repr`` (IPython's pretty printer wraps long
  containers); tracebacks are Python's, without colours.
- Only what Python code writes to ``sys.stdout``/``sys.stderr`` is caught;
  what compiled code writes to the file descriptors goes to the job's own
  output. Log records go where the process's logging sends them (a figure
  job: its log file).
- The notebook shares the process: modules stay imported and settings it
  changes (matplotlib's backend, pandas options) stay changed after it
  ends. The workflow runs one notebook per job process.
- The executed notebook's cells carry papermill's times, not a kernel's
  ``execution`` timestamps.
"""

from __future__ import annotations

import ast
import builtins
import io
import linecache
import platform
import sys
import traceback
import warnings

from nbformat.v4 import new_output
from papermill.engines import Engine, papermill_engines

__all__ = ["ENGINE_NAME", "CellOutputs", "InProcessEngine", "cell_filename", "mime_bundle",
           "run_cell"]

#: The name the engine is registered under with papermill.
ENGINE_NAME = "roughcontact-in-process"

#: The notebook's ``language_info``, as a Python kernel reports it.
LANGUAGE_INFO = {
    "name": "python",
    "version": platform.python_version(),
    "mimetype": "text/x-python",
    "file_extension": ".py",
    "codemirror_mode": {"name": "ipython", "version": 3},
    "pygments_lexer": "ipython3",
    "nbconvert_exporter": "python",
}

#: Text representations recorded beside ``text/plain``: MIME type -> method.
RICH_REPRS = {"text/html": "_repr_html_", "text/markdown": "_repr_markdown_",
              "text/latex": "_repr_latex_"}


def mime_bundle(value) -> dict[str, str]:
    """``value`` as a MIME bundle: its ``repr``, and its text representations.

    A representation method that raises or returns something other than text
    is left out (IPython leaves it out too).
    """
    bundle = {"text/plain": repr(value)}
    if isinstance(value, type):  # a class: its _repr_*_ methods need an instance
        return bundle
    for mime, method in RICH_REPRS.items():
        try:
            text = getattr(value, method)()
        except Exception:  # no such method, or a failing one
            continue
        if isinstance(text, str):
            bundle[mime] = text
    return bundle


class CellOutputs:
    """Collects the outputs of the running cell into ``target`` (its output list)."""

    def __init__(self):
        self.target = []

    def stream(self, name: str, text: str) -> None:
        """Append ``text`` to the cell's ``name`` stream (``stdout`` or ``stderr``)."""
        last = self.target[-1] if self.target else None
        if last is not None and last.output_type == "stream" and last.name == name:
            last.text += text
        elif text:
            self.target.append(new_output("stream", name=name, text=text))

    def display(self, *objs, raw: bool = False) -> None:
        """Record ``objs`` as display outputs; with ``raw``, each is a MIME bundle."""
        for obj in objs:
            self.target.append(new_output("display_data", data=obj if raw else mime_bundle(obj)))

    def result(self, value, execution_count: int) -> None:
        """Record ``value`` as the cell's result."""
        self.target.append(new_output("execute_result", data=mime_bundle(value),
                                      execution_count=execution_count))

    def error(self, exc: BaseException, tb) -> None:
        """Record ``exc`` with its traceback from ``tb`` on."""
        lines = traceback.format_exception(type(exc), exc, tb)
        self.target.append(new_output("error", ename=type(exc).__name__, evalue=str(exc),
                                      traceback=[line.rstrip("\n") for line in lines]))


class _Stream(io.TextIOBase):
    """``sys.stdout`` or ``sys.stderr`` while a cell runs: writes become its outputs."""

    encoding = "utf-8"

    def __init__(self, name: str, outputs: CellOutputs):
        self.name = name
        self.outputs = outputs

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        self.outputs.stream(self.name, text)
        return len(text)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """Show a warning as Python does, on the running cell's stderr."""
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def _compile_cell(source: str, filename: str):
    """The cell's statements, and its last expression apart (``None``: none to show).

    The last statement is shown if it is an expression that is not followed
    by ``;`` (as in IPython).
    """
    tree = ast.parse(source, filename)
    last = tree.body[-1] if tree.body else None
    if isinstance(last, ast.Expr):
        line = source.splitlines()[last.end_lineno - 1].encode()  # offsets count UTF-8 bytes
        if not line[last.end_col_offset:].lstrip().startswith(b";"):
            tree.body.pop()
            expression = compile(ast.Expression(last.value), filename, "eval")
            return compile(tree, filename, "exec"), expression
    return compile(tree, filename, "exec"), None


def cell_filename(execution_count: int) -> str:
    """The file name of a cell's code in tracebacks (as IPython's ``Cell In[n]``)."""
    return f"<cell In[{execution_count}]>"


def run_cell(source: str, namespace: dict, outputs: CellOutputs, execution_count: int) -> bool:
    """Run one code cell in ``namespace``, its outputs into ``outputs``; whether it succeeded.

    The cell's lines are registered with :mod:`linecache` under
    :func:`cell_filename`, so tracebacks show them (the caller removes them
    when the notebook is done). A cell that raises (or does not parse) gets
    an ``error`` output and returns ``False``; ``KeyboardInterrupt``
    propagates.
    """
    filename = cell_filename(execution_count)
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    stdout, stderr = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _Stream("stdout", outputs), _Stream("stderr", outputs)
    try:
        try:
            statements, expression = _compile_cell(source, filename)
        except SyntaxError as exc:
            outputs.error(exc, None)
            return False
        try:
            exec(statements, namespace)
            value = None if expression is None else eval(expression, namespace)
        except (Exception, SystemExit) as exc:
            outputs.error(exc, exc.__traceback__.tb_next)  # from the cell's frame on
            return False
        if value is not None:
            outputs.result(value, execution_count)
        return True
    finally:
        sys.stdout, sys.stderr = stdout, stderr


def _open_figures() -> set:
    """The numbers of pyplot's open figures (none if pyplot is not imported)."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    return set(pyplot.get_fignums()) if pyplot is not None else set()


class InProcessEngine(Engine):
    """Papermill engine: the notebook's code cells run in this process (see the module)."""

    @classmethod
    def execute_managed_notebook(cls, nb_man, kernel_name, **kwargs):
        """Run the code cells of ``nb_man.nb`` in order until one fails.

        ``kernel_name`` and the kernel's options papermill passes (timeouts,
        ``log_output``, ``stdout_file``, ...) are ignored. Each cell, code
        or not, goes through ``nb_man.cell_start`` and ``cell_complete``
        (a failing one also through ``cell_exception``), as with papermill's
        own engine; papermill then raises for the failed cell.
        """
        nb = nb_man.nb
        nb.metadata["language_info"] = dict(LANGUAGE_INFO)
        outputs = CellOutputs()
        namespace = {"__name__": "__main__", "__builtins__": builtins,
                     "display": outputs.display}
        figures = _open_figures()
        execution_count = 0
        try:
            with warnings.catch_warnings():
                warnings.showwarning = _show_warning
                for index, cell in enumerate(nb.cells):
                    nb_man.cell_start(cell, index)
                    failed = False
                    try:
                        if cell.cell_type == "code" and cell.source.strip():
                            execution_count += 1
                            cell.execution_count = execution_count
                            outputs.target = cell.outputs
                            failed = not run_cell(cell.source, namespace, outputs,
                                                  execution_count)
                        if failed:
                            nb_man.cell_exception(cell, cell_index=index)
                    finally:
                        nb_man.cell_complete(cell, cell_index=index)
                    if failed:
                        break
        finally:
            outputs.target = []
            namespace.clear()
            for count in range(1, execution_count + 1):
                linecache.cache.pop(cell_filename(count), None)
            pyplot = sys.modules.get("matplotlib.pyplot")
            for number in _open_figures() - figures:
                pyplot.close(number)
        return nb


papermill_engines.register(ENGINE_NAME, InProcessEngine)
