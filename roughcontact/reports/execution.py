"""Running figure notebooks, and cleaning up after writers that were killed.

Every file is written under a temporary name beside it and renamed when
complete (:func:`roughcontact.study.provenance.atomic_path`:
``.<stem>.tmp<PID><suffix>``). A writer killed with SIGKILL (``kill -9``,
the out-of-memory killer, a cluster's wall-time limit) cannot remove its
temporary file, so every writer first removes those that processes no
longer running left beside its output (:func:`remove_stale_temporaries`):
the next run of the interrupted job cleans up after it.
:func:`execute_notebook` runs a papermill-parameterized figure notebook in
this process (:mod:`roughcontact.reports.notebook_engine`: no Jupyter kernel).
"""

from __future__ import annotations

import logging
import os
import re
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

from roughcontact.study.provenance import atomic_path

__all__ = ["dead_writers", "execute_figure", "execute_notebook", "process_running",
           "remove_stale_temporaries"]

log = logging.getLogger(__name__)


def process_running(pid: int) -> bool:
    """Whether a process ``pid`` runs on this machine (a zombie counts as running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # runs, as another user
        return True
    return True


def dead_writers(candidates: Iterable[Path], pattern: re.Pattern) -> Iterator[tuple[Path, str]]:
    """The ``candidates`` named after a process that no longer runs on this machine.

    A candidate counts when ``pattern`` matches its whole name with the PID as
    group 1; yields ``(candidate, PID)``.
    """
    for candidate in candidates:
        match = pattern.fullmatch(candidate.name)
        if match is not None and not process_running(int(match.group(1))):
            yield candidate, match.group(1)


def remove_stale_temporaries(path: str | os.PathLike) -> list[Path]:
    """Remove the temporary files of ``path`` that killed writers left behind.

    ``atomic_path`` writes ``path`` as ``.<stem>.tmp<PID><suffix>`` in the
    same folder. Those whose process no longer runs on this machine are
    removed; those of running processes (this one, or another writer of the
    same file) are kept. The workflow never runs two jobs for one output at
    once, so on a cluster's shared file system a temporary file of a job on
    another node is a dead one too; it is kept only while its PID happens to
    run here, which costs a file, never an output. Returns the removed paths.
    """
    path = Path(path)
    pattern = re.compile(rf"\.{re.escape(path.stem)}\.tmp(\d+){re.escape(path.suffix)}")
    removed = []
    if not path.parent.is_dir():
        return removed
    for candidate, pid in dead_writers(path.parent.iterdir(), pattern):
        candidate.unlink(missing_ok=True)
        log.warning("removed %s, left by an interrupted writer (process %s, no longer "
                    "running)", candidate, pid)
        removed.append(candidate)
    return removed


def execute_notebook(notebook, output, parameters: dict, log_path=None) -> None:
    """Execute ``notebook`` with papermill into ``output`` (atomically).

    The notebook must have a cell tagged ``parameters``; the entries of
    ``parameters`` that it declares there are injected after it (the workflow
    passes one set to every figure; the others are logged, not passed). The
    executed notebook is kept so a reader sees the code beside the figure. The
    cells run in this process (:class:`~roughcontact.reports.notebook_engine.InProcessEngine`),
    in the current working directory. A failing cell raises papermill's
    ``PapermillExecutionError`` with the cell's traceback, and no notebook is
    written at ``output``. Temporary notebooks
    that an earlier, killed execution left beside ``output`` are removed
    first (:func:`remove_stale_temporaries`).
    """
    import papermill

    from roughcontact.reports.notebook_engine import ENGINE_NAME

    start = time.perf_counter()
    declared = papermill.inspect_notebook(str(notebook))
    unused = sorted(set(parameters) - set(declared))
    parameters = {k: v for k, v in parameters.items() if k in declared}
    log.info("executing %s with parameters %s%s", notebook, sorted(parameters),
             f" (not declared there, not passed: {unused})" if unused else "")
    remove_stale_temporaries(output)
    with atomic_path(output) as tmp:
        papermill.execute_notebook(
            str(notebook),
            str(tmp),
            parameters=parameters,
            engine_name=ENGINE_NAME,
            progress_bar=False,
        )
    log.info("executed %s in %.1f s -> %s", notebook, time.perf_counter() - start, output)


def execute_figure(notebook, output, parameters: dict, answers, log_path=None) -> None:
    """Execute a figure's ``notebook`` (:func:`execute_notebook`) and leave its answers
    at ``answers``: the numbers the figure shows, as reStructuredText, that the report's
    caption includes after the plan's text (``report/figure.rst``).

    A notebook that states numbers declares a parameter ``answers`` and writes the
    file; for every other notebook the file is written empty. A file an earlier run
    left is removed first, so the caption never shows another run's numbers.
    """
    answers = Path(answers)
    answers.unlink(missing_ok=True)
    execute_notebook(notebook, output, dict(parameters, answers=str(answers)), log_path)
    if not answers.exists():
        answers.write_text("")
