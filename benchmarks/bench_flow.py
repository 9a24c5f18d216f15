"""Patir & Cheng's pressure flow factor of rigid Gaussian surfaces, and the flow solvers' cost.

A rigid rough surface ``z`` (Gaussian heights, zero mean, unit rms ``sigma``:
each generated surface is set to exactly that) faces a flat at the nominal
separation ``h`` of the mean planes: the gap is ``max(h - z, 0)`` and
``phi_x = K / h^3`` (:meth:`roughcontact.transport.flow.FlowResult.patir_cheng_factor`),
flow along x, against Patir & Cheng's (1978) fit
(:func:`roughcontact.transport.references.patir_cheng_phi_x`). Surfaces:
``SurfaceSpec(acf="gaussian")`` (ACF ``exp(-2.3 r^2)``, ``b`` the lag of 10 %
correlation, the 0.5 lag is ``0.549 b``) generated with ``method="paper"`` (a
Gaussian process), seeds from ``derive_seeds(1978, ...)``.

Parts (``--parts``):

- ``table``: 256^2, b = 8 elements, 60 surfaces, h / sigma = 0.5 ... 3, sealed
  and periodic sides, harmonic rule: mean and 95 % t-interval over surfaces;
- ``resolution``: b = 4, 8, 16, 32 elements on a domain of 16 b (64^2 ... 512^2),
  the same surfaces point sampled from 512^2;
- ``domain``: b = 8 elements, domains of 8, 16, 32, 64 b (64^2 ... 512^2);
- ``rule``: harmonic against arithmetic face rule (the table's case);
- ``acf``: the exponential ACF ``exp(-2.3 r)`` instead (same b);
- ``anisotropy``: b_x / b_y = 3 and 1/3 (b_x b_y = 8^2 elements), flow along x,
  against Patir & Cheng's gamma = 3 and 1/3 fits;
- ``timing``: DirectSolver against JacobiCG at 64^2 ... 1024^2 on the gap at
  h / sigma = 1 (b = n / 32), alternated runs, minimum of 3;
- ``ordering``: SuperLU's column orderings (time and fill-in) at 256^2 and 512^2.

Usage::

    .venv/bin/python benchmarks/bench_flow.py                  # all: ~23 + 15 min
    .venv/bin/python benchmarks/bench_flow.py --parts timing

Writes ``results/benchmarks/flow_patir_cheng.csv`` and ``.md`` (the phi_x parts),
``flow_solvers.csv`` / ``.md`` (timing) and ``flow_ordering.csv`` / ``.md``.
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
import scipy.sparse.linalg as spla  # noqa: E402
from scipy import stats  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.surfaces import synthetic  # noqa: E402
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402
from roughcontact.transport import (  # noqa: E402
    ARITHMETIC,
    HARMONIC,
    PERIODIC,
    SEALED,
    DirectSolver,
    FlowSetup,
    JacobiCG,
    patir_cheng_phi_x,
    solve_flow,
)

RATIOS = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)


def surfaces(n: int, b: tuple[float, float], count: int, acf: str = "gaussian",
             key: str = "table") -> np.ndarray:
    """``count`` Gaussian surfaces (count, n, n), each zero mean and unit rms, b in elements."""
    spec = SurfaceSpec(grid=n, size=float(n), corr_length=b, sigma=1.0, acf=acf)
    z = synthetic.generate_many(spec, synthetic.derive_seeds(1978, f"{key}-{n}-{b}-{acf}", count),
                                method="paper")
    z = z - z.mean(axis=(1, 2), keepdims=True)
    return z / z.std(axis=(1, 2), keepdims=True)


def band(values: np.ndarray) -> tuple[float, float]:
    """Mean and the half width of its 95 % t-interval."""
    count = len(values)
    return (float(values.mean()),
            float(stats.t.ppf(0.975, count - 1) * values.std(ddof=1) / np.sqrt(count)))


def phi_rows(z, label: str, ratios=RATIOS, sides=(SEALED, PERIODIC), rules=(HARMONIC,),
             gamma=1, **extra) -> list[dict]:
    rows = []
    for ratio in ratios:
        gap = np.maximum(ratio - z, 0.0)
        for side in sides:
            for rule in rules:
                start = time.perf_counter()
                result = solve_flow(gap, FlowSetup((1.0, 1.0), sides=side, face_rule=rule))
                phi = result.patir_cheng_factor(ratio)
                mean, half = band(phi)
                fit = float(patir_cheng_phi_x(ratio, gamma)) if ratio >= 0.5 else np.nan
                rows.append(dict(study=label, h_over_sigma=ratio, sides=side.name, rule=rule.name,
                                 surfaces=len(z), phi_x=mean, band95=half, fit=fit,
                                 excess=mean - fit, contact=float(1 - result.open_fraction.mean()),
                                 connected=float(result.connected.mean()), **extra))
                print(f"  {label} h/s={ratio:g} {side.name} {rule.name}: phi_x {mean:.4f} "
                      f"+- {half:.4f} (fit {fit:.4f}) {time.perf_counter() - start:.1f} s",
                      flush=True)
    return rows


def part_table(args) -> list[dict]:
    return phi_rows(surfaces(256, (8.0, 8.0), args.surfaces), "table", n=256, b=8, domain_b=32)


def part_resolution(args) -> list[dict]:
    """The same surfaces on every grid: generated at b = 32 elements (512^2), point
    sampled every 2, 4, 8 elements (the Gaussian ACF is smooth, so the coarse
    surface is the fine one at the shared points)."""
    fine = surfaces(512, (32.0, 32.0), args.study_surfaces, key="res")
    rows = []
    for b in (4, 8, 16, 32):
        stride = 32 // b
        z = fine[:, ::stride, ::stride]
        z = (z - z.mean(axis=(1, 2), keepdims=True)) / z.std(axis=(1, 2), keepdims=True)
        rows += phi_rows(z, "resolution", ratios=(1.0, 2.0, 3.0), sides=(SEALED,),
                         n=512 // stride, b=b, domain_b=16)
    return rows


def part_domain(args) -> list[dict]:
    rows = []
    for domain in (8, 16, 32, 64):
        n = 8 * domain
        rows += phi_rows(surfaces(n, (8.0, 8.0), args.study_surfaces, key="dom"), "domain",
                         ratios=(1.0, 2.0, 3.0), sides=(SEALED, PERIODIC), n=n, b=8,
                         domain_b=domain)
    return rows


def part_rule(args) -> list[dict]:
    return phi_rows(surfaces(256, (8.0, 8.0), args.study_surfaces, key="rule"), "rule",
                    sides=(SEALED,), rules=(HARMONIC, ARITHMETIC), n=256, b=8, domain_b=32)


def part_acf(args) -> list[dict]:
    rows = []
    for b in (8, 16):
        rows += phi_rows(surfaces(256, (float(b), float(b)), args.study_surfaces,
                                  acf="exponential", key="acf"), "acf exponential",
                         ratios=(1.0, 2.0, 3.0), sides=(SEALED,), n=256, b=b, domain_b=256 // b)
    return rows


def part_anisotropy(args) -> list[dict]:
    rows = []
    for gamma, b in ((3, (8.0 * np.sqrt(3), 8.0 / np.sqrt(3))),
                     ("1/3", (8.0 / np.sqrt(3), 8.0 * np.sqrt(3)))):
        rows += phi_rows(surfaces(256, b, args.study_surfaces, key=f"gamma{gamma}"),
                         f"gamma {gamma}", sides=(SEALED, PERIODIC), gamma=gamma, n=256,
                         b=round(float(np.sqrt(b[0] * b[1])), 3), domain_b=32)
    return rows


def part_timing(args) -> list[dict]:
    rows = []
    for n in args.timing_grids:
        z = surfaces(n, (n / 32, n / 32), 1, key="timing")
        gap = np.maximum(1.0 - z, 0.0)
        solvers = {"direct": DirectSolver(), "jacobi_cg": JacobiCG(rtol=1e-10)}
        best = {name: np.inf for name in solvers}
        iterations = {}
        for _ in range(args.repeats):
            for name, solver in solvers.items():
                setup = FlowSetup((1.0, 1.0), solver=solver)
                start = time.perf_counter()
                result = solve_flow(gap, setup)
                best[name] = min(best[name], time.perf_counter() - start)
                iterations[name] = int(result.iterations[0])
        rows.append(dict(n=n, unknowns=n * n, direct_s=best["direct"],
                         jacobi_cg_s=best["jacobi_cg"],
                         cg_over_direct=best["jacobi_cg"] / best["direct"],
                         cg_iterations=iterations["jacobi_cg"]))
        print(f"  timing {n}^2: direct {best['direct']:.3f} s, JacobiCG {best['jacobi_cg']:.3f} s"
              f" ({iterations['jacobi_cg']} it)", flush=True)
    return rows


def part_ordering(args) -> list[dict]:
    """SuperLU's fill-in and time by column ordering, on the timing part's gaps."""
    rows = []
    for n in (256, 512):
        z = surfaces(n, (n / 32, n / 32), 1, key="timing")
        gap = np.maximum(1.0 - z, 0.0)
        for ordering in ("MMD_AT_PLUS_A", "COLAMD", "MMD_ATA"):
            solver = DirectSolver(ordering=ordering)
            best = np.inf
            for _ in range(args.repeats):
                start = time.perf_counter()
                solve_flow(gap, FlowSetup((1.0, 1.0), solver=solver))
                best = min(best, time.perf_counter() - start)
            fill = _fill(gap, ordering)
            rows.append(dict(study="ordering", n=n, ordering=ordering, solve_s=best,
                             lu_nonzeros=fill))
            print(f"  ordering {n}^2 {ordering}: {best:.3f} s, nnz(L+U) {fill}", flush=True)
    return rows


def _fill(gap, ordering: str) -> int:
    """Non-zeros of SuperLU's factors of the gap's flow system (captured from the solve)."""
    captured = {}

    class Capture(DirectSolver):
        def solve(self, matrix, rhs):
            factor = spla.splu(matrix.tocsc(), permc_spec=self.ordering,
                               options={"SymmetricMode": True})
            captured["nnz"] = factor.L.nnz + factor.U.nnz
            return factor.solve(rhs), 0

    solve_flow(gap, FlowSetup((1.0, 1.0), solver=Capture(ordering=ordering)))
    return int(captured["nnz"])


PARTS = {"table": part_table, "resolution": part_resolution, "domain": part_domain,
         "rule": part_rule, "acf": part_acf, "anisotropy": part_anisotropy,
         "timing": part_timing, "ordering": part_ordering}


def write(rows: list[dict], stem: str, title: str, args) -> None:
    """The rows into ``stem``.csv and .md, replacing the rows of the same studies from
    an earlier run and keeping the others."""
    out = ROOT / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows)
    if (out / f"{stem}.csv").exists() and "study" in table:
        earlier = pd.read_csv(out / f"{stem}.csv")
        table = pd.concat([earlier[~earlier.study.isin(table.study.unique())], table],
                          ignore_index=True)
    partial = out / f"{stem}.csv.part"
    table.to_csv(partial, index=False)
    partial.replace(out / f"{stem}.csv")
    header = (f"# {title}\n\n{datetime.date.today()}, {platform.processor() or platform.machine()},"
              f" Python {platform.python_version()}, numpy {np.__version__}, one thread; "
              f"`benchmarks/bench_flow.py` (last run: `--parts {' '.join(args.parts)}`)\n\n")
    (out / f"{stem}.md").write_text(header + table.to_markdown(index=False, floatfmt=".4g") + "\n")
    print(f"wrote {out / stem}.csv and .md")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="+", default=list(PARTS), choices=list(PARTS))
    parser.add_argument("--surfaces", type=int, default=60)
    parser.add_argument("--study-surfaces", type=int, default=16)
    parser.add_argument("--timing-grids", type=int, nargs="+", default=[64, 128, 256, 512, 1024])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    start = time.perf_counter()
    phi, timing, ordering = [], [], []
    for part in args.parts:
        print(f"{part} ({time.perf_counter() - start:.0f} s)", flush=True)
        {"timing": timing, "ordering": ordering}.get(part, phi).extend(PARTS[part](args))
    if phi:
        write(phi, "flow_patir_cheng", "Patir & Cheng's phi_x of rigid Gaussian surfaces", args)
    if timing:
        write(timing, "flow_solvers", "Flow solvers: SuperLU against Jacobi CG", args)
    if ordering:
        write(ordering, "flow_ordering", "SuperLU's column orderings on the flow system", args)
    print(f"done in {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
