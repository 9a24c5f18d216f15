"""Grid convergence of contact on self-affine surfaces with a cut-off vs the exponential ACF.

The same physical window (9 mm square, sigma = 24.5 um, Gaussian heights,
E = 511 MPa, nu = 0) meshed with 30, 60, 120 and 240 elements per side, solved
on Love's half-space (matrix-free FFT operator,
:func:`roughcontact.elasticity.operators.halfspace_operator`, through
:func:`roughcontact.reports.speed.experiments.grid_study` with
``influence="halfspace_fft"``) at nominal pressures 0.3, 1 and 3 MPa, for

- ``self-affine``: isotropic PSD, roll-off 3 mm, cut-off 0.6 mm, H = 0.8
  (``SurfaceSpec(acf="self-affine", ...)``): the cut-off is two spacings on
  the 30 grid and 16 on the 240 grid;
- ``exponential``: the paper's Eq 1 ACF with b = 1 mm, whose spectrum reaches
  the grid scale whatever the grid.

Surfaces are paired as in the grid study (``pairing="nested"``): ``--surfaces``
surfaces generated on the 240 grid (filter method, seeds from
``derive_seeds``), the coarser grids point-sample them. Reported per grid and
pressure: mean real area fraction and peak pressure over the surfaces, and the
relative change ``q(g) / q(240) - 1`` (the 120 row is the change between the two
finest grids).

Usage::

    .venv/bin/python benchmarks/bench_selfaffine_grid.py              # ~1 min, 2 threads
    .venv/bin/python benchmarks/bench_selfaffine_grid.py --cutoff-mm 1.2 --tag c12

Writes ``results/benchmarks/selfaffine_grid[_<tag>].csv`` and ``.md``.
Measured numbers are in the module's README section below (MEASURED).
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "2")

import argparse  # noqa: E402
import logging  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.reports.speed.experiments import grid_study  # noqa: E402

MM = 1e-3
COLUMNS = ["spectrum", "grid", "pressure_Pa", "real_area_fraction", "real_area_change",
           "max_pressure_Pa", "max_pressure_change", "k_P_Pa", "k_P_change", "solve_s"]


def run(spectrum: dict | None, label: str, args) -> pd.DataFrame:
    start = time.perf_counter()
    table = grid_study(grids=args.grids, influence="halfspace_fft", surfaces=args.surfaces,
                       pressures=[p * 1e6 for p in args.pressures_mpa], size=9 * MM,
                       sigma=24.5e-6, b=1 * MM, spectrum=spectrum, progress=print)
    print(f"{label}: {time.perf_counter() - start:.1f} s", flush=True)
    table.insert(0, "spectrum", label)
    return table[COLUMNS]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grids", type=int, nargs="+", default=[30, 60, 120, 240])
    parser.add_argument("--surfaces", type=int, default=4)
    parser.add_argument("--pressures-mpa", type=float, nargs="+", default=[0.3, 1.0, 3.0])
    parser.add_argument("--hurst", type=float, default=0.8)
    parser.add_argument("--rolloff-mm", type=float, default=3.0)
    parser.add_argument("--cutoff-mm", type=float, default=0.6)
    parser.add_argument("--skip-exponential", action="store_true")
    parser.add_argument("--tag", default="")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    spectrum = dict(acf="self-affine", hurst=args.hurst, rolloff_wavelength=args.rolloff_mm * MM,
                    cutoff_wavelength=args.cutoff_mm * MM)
    label = f"self-affine H {args.hurst:g}, {args.rolloff_mm:g}/{args.cutoff_mm:g} mm"
    tables = [run(spectrum, label, args)]
    if not args.skip_exponential:
        tables.append(run(None, "exponential b 1 mm", args))
    table = pd.concat(tables, ignore_index=True)
    out = ROOT / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    stem = "selfaffine_grid" + (f"_{args.tag}" if args.tag else "")
    table.to_csv(out / f"{stem}.csv", index=False)
    shown = table.assign(real_area_pct=100 * table.real_area_fraction,
                         max_pressure_MPa=table.max_pressure_Pa / 1e6,
                         pressure_MPa=table.pressure_Pa / 1e6)
    shown = shown[["spectrum", "grid", "pressure_MPa", "real_area_pct", "real_area_change",
                   "max_pressure_MPa", "max_pressure_change", "solve_s"]]
    header = (f"# contact grid study, self-affine vs exponential, half-space (FFT), "
              f"{args.surfaces} nested surfaces\n\n{platform.processor() or platform.machine()}, "
              f"Python {platform.python_version()}, numpy {np.__version__}\n\n")
    (out / f"{stem}.md").write_text(header + shown.to_markdown(index=False, floatfmt=".4g")
                                    + "\n")
    print(shown.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    print(f"wrote {out / stem}.csv and .md")


if __name__ == "__main__":
    main()
