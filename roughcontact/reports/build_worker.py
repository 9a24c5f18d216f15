"""One influence build, measured: run in a fresh interpreter so its peak memory is its own.

The mesh-convergence report (:mod:`roughcontact.reports.convergence`) builds
each preset's ``E C`` here. This module imports only the elasticity stage, so
a build process carries no more than the build itself.
"""

from __future__ import annotations

import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import (
    BlockGeometry,
    estimate_cost,
    unit_modulus_influence,
)
from roughcontact.study.provenance import peak_rss_bytes
from roughcontact.units import GB

#: Label of Love's half-space row.
HALFSPACE = "halfspace"


def centre_entries(ec: np.ndarray, geom: BlockGeometry, far: int) -> dict:
    """Centre-row entries E C / h and row-sum checks of one matrix ``ec = E * C`` [m]."""
    nx, ny = geom.grid
    ix, iy = nx // 2, ny // 2
    c = iy * nx + ix
    h = math.sqrt(geom.spacing[0] * geom.spacing[1])
    far = max(0, min(int(far), nx - 1 - ix))

    def entry(dx: int, dy: int) -> float:
        if ix + dx >= nx or iy + dy >= ny:
            return math.nan
        return float(ec[c, c + dy * nx + dx] / h)

    sums = ec.sum(axis=1) / geom.thickness
    return {
        "self_compliance": entry(0, 0),
        "neighbour_1_0": entry(1, 0),
        "neighbour_1_1": entry(1, 1),
        "neighbour_2_0": entry(2, 0),
        "far_entry": entry(far, 0),
        "far_offset": far,
        "row_sum_over_L": float(sums[c]),
        "row_sum_max_error": float(np.abs(sums - 1.0).max()),
    }


def build(task: dict) -> tuple[np.ndarray, dict]:
    """Build one matrix ``E C`` [m] (finite elements, or Love's half-space) and measure it.

    Returns the matrix and a row: dofs, build time, estimated and measured
    peak memory (measured only when ``task["isolated"]``), centre entries.
    """
    geom: BlockGeometry = task["geometry"]
    rss_before = peak_rss_bytes()
    start = time.perf_counter()
    if task["kind"] == HALFSPACE:
        ec = halfspace_influence(geom.grid, geom.size, 1.0, geom.nu)
        dofs, estimate = 0, math.nan
    else:
        cost = estimate_cost(geom, task["solver"])
        dofs, estimate = cost.dofs, cost.peak_bytes / GB
        ec = unit_modulus_influence(geom, solver=task["solver"], max_bytes=task["max_bytes"])
    seconds = time.perf_counter() - start
    peak = peak_rss_bytes()
    return ec, {
        "dofs": dofs, "build_s": seconds, "estimate_GB": estimate,
        "peak_memory_GB": peak / GB if task["isolated"] else math.nan,
        "memory_increase_GB": (peak - rss_before) / GB if task["isolated"] else math.nan,
        **centre_entries(ec, geom, task["far"]),
    }


def main(task_path: str, result_path: str) -> None:
    """Entry point of the build process: read a pickled task, write a pickled result."""
    with open(task_path, "rb") as fh:
        task = pickle.load(fh)
    try:
        outcome = {"ok": build(task)}
    except Exception as err:  # noqa: BLE001 - handed back to the parent and re-raised
        outcome = {"error": err}
    with open(result_path, "wb") as fh:
        pickle.dump(outcome, fh)


def run_isolated(task: dict, prefix: str = "roughcontact-convergence-"
                 ) -> tuple[np.ndarray, dict]:
    """:func:`build` in a fresh interpreter, so that its peak memory is its own.

    The task and result files live in a folder ``<prefix><random>`` of the
    system's temporary folder, removed when the build ends.
    """
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        task_path, result_path = Path(tmp) / "task.pkl", Path(tmp) / "result.pkl"
        with open(task_path, "wb") as fh:
            pickle.dump(task, fh)
        code = ("import sys; from roughcontact.reports.build_worker import main; "
                "main(sys.argv[1], sys.argv[2])")
        proc = subprocess.run([sys.executable, "-c", code, str(task_path), str(result_path)],
                              capture_output=True, text=True, env={**os.environ})
        if proc.returncode != 0 or not result_path.exists():
            raise RuntimeError(
                f"influence build process for {task['label']!r} failed with exit code "
                f"{proc.returncode} (killed for memory if -9):\n{proc.stderr[-3000:]}")
        with open(result_path, "rb") as fh:
            outcome = pickle.load(fh)
    if "error" in outcome:
        raise outcome["error"]
    return outcome["ok"]
