"""Logging set-up for workflow jobs."""

from __future__ import annotations

import logging
import os
from pathlib import Path


def route_logging(path: str | os.PathLike, level: int = logging.INFO) -> None:
    """Send the ``roughcontact`` loggers (and warnings) to ``path``, and to stderr.

    Each record carries a time stamp, so a job's log shows its progress.
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
