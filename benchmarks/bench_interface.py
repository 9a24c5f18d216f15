"""What the interface quantities cost inside a sweep (spots, perimeter, corrected area, gaps).

:mod:`roughcontact.contact.interface` is run at every step of a sweep when an
``interface`` grid is given. Measured here with one thread (the BLAS and FFT
thread counts are set to 1 before numpy is imported), the same sweep with and
without them, alternated in one process, the minimum of ``--repeats`` runs of
each, and, within the runs with them, the time spent in
:func:`roughcontact.contact.interface.describe` itself (timed around each call):
its share of the sweep is the cost, measured in the same run, where the A/B
difference of two sweeps is within the machine's noise (the same sweep's wall time
varies by 10-30 % on the shared 2-core machine):

- 60 x 60: the study's contact job, one batch of 60 Gaussian surfaces
  (exponential ACF, b = 1 mm on the paper's 9 mm block) on Love's dense
  half-space matrix (a finite-element matrix of the grid costs the same),
  dimensionless (:func:`roughcontact.contact.nondim.solve_cell`), 20 approaches
  of :func:`roughcontact.contact.cell.approach_grid` to P L / (E sigma) = 4, tol
  1e-8, precision "mixed", tangent stiffness at every step, method "auto"
  (block principal pivoting);
- 1024 x 1024: one self-affine-like Gaussian surface (b = 1/32 of the period)
  on the periodic half-space, preconditioned CG ("auto"), 4 approaches, tol
  1e-8, no stiffness (the grid-convergence study's sweep), periodic spots.

The acceptance bound of issue 37 is 5 % of a sweep's time. Writes
results/benchmarks/interface.md.

Usage::

    .venv/bin/python benchmarks/bench_interface.py             # both grids (5-10 min)
    .venv/bin/python benchmarks/bench_interface.py --quick     # 60 x 60 only (1-2 min)
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import datetime  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from roughcontact import contact  # noqa: E402
from roughcontact.contact import SolverOptions, cell, interface, nondim  # noqa: E402
from roughcontact.contact.nondim import CellOptions  # noqa: E402
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence  # noqa: E402
from roughcontact.surfaces import synthetic  # noqa: E402
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"
SIZE, THICKNESS = 9e-3, 10e-3


class _Timed:
    """``interface.describe`` with the wall time of its calls added up in ``seconds``."""

    def __init__(self, function):
        self.function, self.seconds = function, 0.0

    def __call__(self, *args, **kwargs):
        start = time.perf_counter()
        try:
            return self.function(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - start


def alternated(runs: dict, repeats: int) -> dict:
    """Minimum wall time [s] of each callable of ``runs``, called in turn ``repeats`` times,
    and ``share``: the smallest ratio, over the runs of ``"with"``, of the time spent in
    :func:`interface.describe` to the rest of that run's sweep."""
    best = dict.fromkeys(runs, np.inf)
    share = np.inf
    original = interface.describe
    for _ in range(repeats):
        for name, run in runs.items():
            timed = _Timed(original)
            interface.describe = timed
            try:
                start = time.perf_counter()
                run()
                elapsed = time.perf_counter() - start
            finally:
                interface.describe = original
            best[name] = min(best[name], elapsed)
            if name == "with":
                share = min(share, timed.seconds / (elapsed - timed.seconds))
    return {**best, "share": share}


def cell_60(repeats: int) -> dict:
    grid = 60
    spec = SurfaceSpec(grid=grid, size=SIZE, corr_length=1e-3)
    heights = synthetic.generate_many(spec, range(60))
    unit = halfspace_influence((grid, grid), (SIZE, SIZE), 1.0, 0.0)
    approaches = cell.approach_grid(heights, 4.0, 20)
    element_area = (SIZE / grid) ** 2
    spacing = interface.InterfaceGrid((SIZE / grid, SIZE / grid))

    def run(grid_or_none):
        return lambda: nondim.solve_cell(unit, heights, thickness=THICKNESS,
                                         element_area=element_area, approaches=approaches,
                                         options=CellOptions().with_(method="auto", tol=1e-8,
                                                                     precision="mixed",
                                                                     interface=grid_or_none))

    times = alternated({"without": run(None), "with": run(spacing)}, repeats)
    swept = run(spacing)()
    return {"grid": "60 x 60, 60 surfaces x 20 steps, pivot", **times,
            "spots": float(swept.spot_count[:, -1].mean())}


def sweep_1024(repeats: int) -> dict:
    grid = 1024
    period = 1e-3
    spec = SurfaceSpec(grid=grid, size=period, corr_length=period / 32)
    heights = synthetic.generate(spec, seed=1)
    heights = heights / heights.std() * 1e-6
    op = PeriodicHalfSpace((grid, grid), (period, period), 1.0e9, 0.0)
    gaps = (heights.max() - heights)[None]
    approaches = np.linspace(0.3, 0.6, 4) * gaps.mean()
    spacing = interface.InterfaceGrid.of(op, (period, period))

    def run(grid_or_none):
        return lambda: contact.sweep(op, gaps, approaches, interface=grid_or_none,
                                     options=SolverOptions(method="auto", tol=1e-8,
                                                           stiffness=False))

    times = alternated({"without": run(None), "with": run(spacing)}, repeats)
    swept = run(spacing)()
    return {"grid": "1024 x 1024, 1 surface x 4 steps, pcg, periodic", **times,
            "spots": float(swept.spot_count[0, -1])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="60 x 60 only")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    rows = [cell_60(args.repeats)]
    if not args.quick:
        rows.append(sweep_1024(args.repeats))
    lines = [
        "# Cost of the interface quantities in a sweep",
        "",
        f"{datetime.date.today()}, {platform.processor() or platform.machine()}, one thread; "
        f"minimum of {args.repeats} alternated runs each (`benchmarks/bench_interface.py`).",
        "",
        "| sweep | without [s] | with [s] | A/B difference | time in describe / rest of "
        "the sweep | spots at the last step |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        extra = row["with"] / row["without"] - 1.0
        lines.append(f"| {row['grid']} | {row['without']:.2f} | {row['with']:.2f} | "
                     f"{100 * extra:+.1f} % | {100 * row['share']:.1f} % | "
                     f"{row['spots']:.0f} |")
        print(lines[-1], flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "interface.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
