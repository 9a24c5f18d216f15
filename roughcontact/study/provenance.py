"""Provenance and safe file writing: who made a result, from what, and how.

Every HDF5 output of the pipeline carries the package version, the git commit
of the source tree, a hash of the configuration and the creation time as
attributes, so that a number found in a study's outputs can be traced back.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import hashlib
import json
import os
import resource
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughcontact import __version__
from roughcontact.errors import DiskFullError
from roughcontact.study.layout import ROOT

_SOURCE_DIR = Path(__file__).resolve().parent.parent


def peak_rss_bytes() -> float:
    """Peak resident set of this process so far [bytes] (``ru_maxrss``: KiB on Linux)."""
    scale = 1 if sys.platform == "darwin" else 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale


def git_commit(path: str | os.PathLike | None = None) -> str:
    """Commit hash of the git tree holding ``path`` (default: this package).

    Appends ``-dirty`` when tracked files differ from the commit, and returns
    ``"unknown"`` outside a git checkout or without git.
    """
    where = Path(path) if path is not None else _SOURCE_DIR
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=where,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return commit + ("-dirty" if dirty else "")


def _canonical(obj):
    if isinstance(obj, dict):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, list | tuple):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj


def canonical_json(obj) -> str:
    """Deterministic JSON text of a nested structure (sorted keys, no spaces)."""
    return json.dumps(_canonical(obj), sort_keys=True, separators=(",", ":"))


def config_hash(config) -> str:
    """SHA-256 (hex, first 16 characters) of the canonical JSON of ``config``."""
    return hashlib.sha256(canonical_json(config).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class RunInfo:
    """What a job knows of the run that made it: the hash of the run's configuration
    (:func:`config_hash`; empty outside a run) and its ``study_seed`` (None outside a
    run: a stored file's seed is then not checked)."""

    config_hash: str = ""
    study_seed: int | None = None

    @classmethod
    def of(cls, config: dict | None) -> RunInfo:
        """The run of a validated configuration (a job's edge: what it records of the
        configuration it was run with); None: outside a run (:data:`NO_RUN`)."""
        if config is None:
            return cls()
        return cls(config_hash(config), int(config["study_seed"]))


#: Outside a workflow run: no configuration hash, no study seed.
NO_RUN = RunInfo()


def provenance(run: RunInfo = NO_RUN) -> dict:
    """Attributes describing how and when a result was made (in which ``run``)."""
    return {
        "package": "roughcontact",
        "package_version": __version__,
        "git_commit": git_commit(),
        "config_hash": run.config_hash,
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "numpy_version": np.__version__,
    }


#: The system's errors of a full disk (or quota).
NO_SPACE = (errno.ENOSPC, errno.EDQUOT)


def _size(size: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size:.0f} bytes"


def _largest_files(folder: Path, count: int = 3) -> list[tuple[int, Path]]:
    """The ``count`` largest files under ``folder`` (size [bytes], path), largest first."""
    sizes = []
    for root, _, names in os.walk(folder):
        for name in names:
            try:
                sizes.append((os.stat(os.path.join(root, name)).st_size, Path(root, name)))
            except OSError:
                continue
    return sorted(sizes, reverse=True)[:count]


def disk_full(path: Path, tmp: Path, err: OSError) -> DiskFullError:
    """The error of a write of ``path`` (through ``tmp``) that found the disk full: the
    file, the space left, the largest results beside it and what to free."""
    try:
        written = _size(tmp.stat().st_size)
        tmp.unlink()  # before the free space is measured
    except OSError:
        written = "nothing"
    try:
        free = _size(shutil.disk_usage(path.parent).free)
    except OSError:
        free = "unknown"
    parts = path.parts
    folder = Path(*parts[:parts.index(ROOT) + 1]) if ROOT in parts[:-1] \
        else path.parent
    largest = ", ".join(f"{p} ({_size(size)})" for size, p in _largest_files(folder))
    return DiskFullError(
        f"{path}: cannot be written, the disk holding it is full ({os.strerror(err.errno)}; "
        f"{written} of it had been written, {free} free now); nothing half-written was "
        f"left. Free space on that disk and run the same command again: delete results you "
        f"no longer need under {folder}" + (f" (the largest: {largest})" if largest else "")
        + f", files named .*.tmp* that killed jobs left (find {folder} -name '.*.tmp*' "
        "-delete), or old logs in .snakemake/log; or run from a folder on a larger disk.",
        path, err.errno)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    An interrupted or failed write leaves no file at ``path`` (the temporary
    file is removed), so a half-written output never looks finished. A full
    disk raises :class:`~roughcontact.errors.DiskFullError` naming ``path``,
    the space left and what to free, in place of the system's bare error.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.tmp{os.getpid()}{path.suffix}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        os.replace(tmp, path)
    except OSError as err:
        if err.errno in NO_SPACE and not isinstance(err, DiskFullError):
            raise disk_full(path, tmp, err) from None
        raise
    finally:
        if tmp.exists():
            tmp.unlink()


def short_hash(obj, digits: int) -> str:
    """The first ``digits`` hex digits of the SHA-256 of ``obj``'s canonical JSON."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:digits]
