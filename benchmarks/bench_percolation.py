"""Where the leak stops: the percolation threshold of elastic contact against Dapp et al. (2012).

Isotropic self-affine surfaces (Hurst 0.8, Gaussian process: ``method="paper"``;
roll-off and short cut-off wavelengths per cell, ``--cells``; each surface
zero mean, unit rms) pressed on an elastic half-space that repeats with the
surface (:class:`roughcontact.elasticity.halfspace.PeriodicHalfSpace`, E = 1, nu = 0:
the threshold area is scale free). At a rigid approach ``d`` the contact solver
(:func:`roughcontact.contact.solve`, tol 1e-8) gives the pressure and the gap;
the flow gap is the solver's gap clipped at 0, and 0 where the pressure is
positive. The free space connects inlet (x = 0) to outlet (x = L) or not
(:func:`roughcontact.transport.solve_flow`, open elements 4-connected,
periodic sides, :attr:`FlowResult.connected`). Taking connectivity to be lost
once as ``d`` grows, each surface's threshold is bracketed by bisection on
``d`` (``--steps`` halvings from [0, mean initial gap], where the load is
unbounded; a bisection finds one crossing, not all); the threshold relative
contact area is the mean of the bracket's two areas (their difference is
reported). Cells: roll-off L / 4 and cut-off L / 16 on 128^2 (8 elements per
cut-off wavelength, 40 surfaces) and on 256^2 (16, 40 surfaces): the grid;
roll-off L / 8 and cut-off L / 32 on 512^2 (16, 20 surfaces): twice the
roll-off wavelengths across the cell.

Usage::

    .venv/bin/python benchmarks/bench_percolation.py               # ~14 min
    .venv/bin/python benchmarks/bench_percolation.py --cells 128:4:16:4

Writes ``results/benchmarks/flow_percolation.csv`` (one row per surface) and
``.md`` (mean and 95 % t-interval per grid, against 0.42 of Dapp et al. 2012
and 0.415 of Wang & Mueser 2021).
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import logging  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact import contact  # noqa: E402
from roughcontact.contact import SolverOptions  # noqa: E402
from roughcontact.elasticity.halfspace import PeriodicHalfSpace  # noqa: E402
from roughcontact.surfaces import synthetic  # noqa: E402
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402
from roughcontact.transport import FlowSetup, solve_flow  # noqa: E402

DAPP_2012 = 0.42
WANG_MUESER_2021 = 0.415


def flow_gap(result) -> np.ndarray:
    """The solver's gap clipped at 0, closed where the pressure is positive [m]."""
    return np.where(result.pressure > 0.0, 0.0, np.maximum(result.gap, 0.0))


def threshold(operator, gap0: np.ndarray, steps: int) -> dict:
    """Bisection on the approach for the loss of inlet-outlet connectivity along x."""
    setup = FlowSetup((1.0 / gap0.shape[1], 1.0 / gap0.shape[0]))
    # the load grows without bound as d reaches the mean initial separation
    low, high = 0.0, float(gap0.mean()) * (1.0 - 1e-6)
    low_area, high_area, warm = 0.0, 1.0, None
    solves = 0
    for _ in range(steps):
        middle = 0.5 * (low + high)
        result = contact.solve(operator, gap0, middle, p0=warm, options=SolverOptions(tol=1e-8))
        solves += 1
        if bool(solve_flow(flow_gap(result), setup).connected):
            low, low_area, warm = middle, result.real_area_fraction, result.pressure
        else:
            high, high_area = middle, result.real_area_fraction
    return dict(threshold_area=0.5 * (low_area + high_area), connected_area=low_area,
                closed_area=high_area, bracket=high_area - low_area, solves=solves)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", nargs="+", default=["128:4:16:40", "256:4:16:40",
                                                       "512:8:32:20"],
                        help="grid:L/roll-off:L/cut-off:surfaces, each a cell")
    parser.add_argument("--steps", type=int, default=12)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    rows = []
    start = time.perf_counter()
    for cell in args.cells:
        n, rolloff, cutoff, count = (int(part) for part in cell.split(":"))
        spec = SurfaceSpec(grid=n, size=1.0, sigma=1.0, acf="self-affine", hurst=0.8,
                           rolloff_wavelength=1.0 / rolloff, cutoff_wavelength=1.0 / cutoff)
        z = synthetic.generate_many(spec, synthetic.derive_seeds(2012, f"percolation-{cell}",
                                                                 count), method="paper")
        operator = PeriodicHalfSpace((n, n), (1.0, 1.0), 1.0, 0.0)
        for index, heights in enumerate(z):
            heights = (heights - heights.mean()) / heights.std()
            row = dict(grid=n, rolloff_per_side=rolloff, elements_per_cutoff=n // cutoff,
                       surface=index,
                       **threshold(operator, heights.max() - heights, args.steps))
            rows.append(row)
            print(f"  {n}^2 surface {index}: threshold area {row['threshold_area']:.4f} "
                  f"(bracket {row['bracket']:.1e}) {time.perf_counter() - start:.0f} s", flush=True)
    table = pd.DataFrame(rows)
    summary = []
    for (n, rolloff, per_cutoff), part in table.groupby(["grid", "rolloff_per_side",
                                                         "elements_per_cutoff"]):
        values = part.threshold_area.to_numpy()
        half = stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values))
        summary.append(dict(grid=n, rolloff_per_side=rolloff, elements_per_cutoff=per_cutoff,
                            surfaces=len(values),
                            threshold_area=values.mean(), band95=half, sd=values.std(ddof=1),
                            dapp_2012=DAPP_2012, wang_mueser_2021=WANG_MUESER_2021))
    summary = pd.DataFrame(summary)
    out = ROOT / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    partial = out / "flow_percolation.csv.part"
    table.to_csv(partial, index=False)
    partial.replace(out / "flow_percolation.csv")
    header = (f"# Percolation threshold of elastic self-affine contacts (flow along x, "
              f"periodic sides)\n\n{datetime.date.today()}, "
              f"{platform.processor() or platform.machine()}, one thread; "
              f"`benchmarks/bench_percolation.py`, {time.perf_counter() - start:.0f} s\n\n")
    (out / "flow_percolation.md").write_text(
        header + summary.to_markdown(index=False, floatfmt=".4g") + "\n\nPer surface:\n\n"
        + table.to_markdown(index=False, floatfmt=".4g") + "\n")
    print(summary.to_string(index=False))


if __name__ == "__main__":
    main()
