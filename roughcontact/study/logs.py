"""Logging set-up for workflow jobs."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

from roughcontact.errors import DiskFullError, InfeasibleMoments, MeasurementError, StoredFileError

#: Errors a user can meet whose message says all there is to do (the file or the cell,
#: what was expected and found, the command or the value that fixes it): a job that
#: ends in one logs the message alone, not the traceback.
USER_ERRORS = (DiskFullError, InfeasibleMoments, MeasurementError, StoredFileError)


def _excepthook(kind, value, traceback) -> None:
    """End a job on a :data:`USER_ERRORS` error with its message (log and stderr)."""
    if issubclass(kind, USER_ERRORS):
        logging.getLogger("roughcontact").error("%s", value)
        return
    sys.__excepthook__(kind, value, traceback)


def route_logging(path: str | os.PathLike, level: int = logging.INFO) -> None:
    """Send the ``roughcontact`` loggers (and warnings) to ``path``, and to stderr.

    Each record carries a time stamp, so a job's log shows its progress. A
    job that ends in one of :data:`USER_ERRORS` (a stored file made for
    other parameters, a full disk, ...) logs its message as the last line,
    without a traceback (the process still exits with status 1).
    """
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    handlers = [logging.FileHandler(path, mode="w"), logging.StreamHandler()]
    root = logging.getLogger()
    for h in handlers:
        h.setFormatter(fmt)
        root.addHandler(h)
    root.setLevel(level)
    logging.captureWarnings(True)
    # scikit-fem reports every assembly at INFO; keep job logs to our own progress
    logging.getLogger("skfem").setLevel(logging.WARNING)
    sys.excepthook = _excepthook


class _Forward(logging.Handler):
    """Hands each record on to another logger (its message, at its level)."""

    def __init__(self, target: logging.Logger):
        super().__init__(logging.WARNING)
        self.target = target

    def emit(self, record: logging.LogRecord) -> None:
        self.target.log(record.levelno, record.getMessage())


def forward_plan_warnings(target: logging.Logger) -> None:
    """Send the warnings the ``roughcontact`` loggers give while the workflow is planned
    (a single-surface cell, ...) to ``target``, Snakemake's logger: they appear in its
    output and its log beside the plan. Once per process."""
    library = logging.getLogger("roughcontact")
    if not any(isinstance(h, _Forward) for h in library.handlers):
        library.addHandler(_Forward(target))
