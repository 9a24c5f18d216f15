"""What certifying an influence operator positive definite costs, next to one solve.

The entry points of :mod:`roughcontact.contact` certify the operator once
(:mod:`roughcontact.elasticity.definiteness`) and keep the certificate on it.
Measured here with one thread (the BLAS and FFT thread counts are set to 1
before numpy is imported), each time against one cold contact solve on the
same operator (a Gaussian surface, exponential ACF, b = 1 mm on the paper's
9 mm block, L = 10 mm, nu = 0; the dimensionless problem of
:mod:`roughcontact.contact.nondim` at the middle approach of
``approach_grid(heights, 4, 10)``, tol 1e-8, precision "mixed", method
"auto") and one sweep of that surface over the 10
approaches with the tangent stiffness at each (what a contact job does per
surface, 20 approaches in the study):

- dense 60 x 60: Love's half-space matrix (the cost does not depend on the
  values; the finite-element matrix of the same grid costs the same): the
  symmetry check alone and the whole certificate (symmetry and Cholesky);
  the solve by block principal pivoting ("auto") and by CG.
- matrix-free 256 x 256 and 1024 x 1024: Love's half-space operator and the
  hybrid block operator (correction from the "refined" finite-element model
  on the default 64 x 64 coarse grid, built once): the 12-step
  preconditioned Lanczos certificate; the solve by preconditioned CG.

Each certificate is taken with the kept one dropped first, the median of
3 to 5 repeats after a first run. Writes results/benchmarks/certify.md.

Usage::

    .venv/bin/python benchmarks/bench_certify.py           # 256 and 1024 (5-10 min, 2.5 GB)
    .venv/bin/python benchmarks/bench_certify.py --quick   # dense 60 and 256 only (1 min)
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_operators import (  # noqa: E402
    OUT,
    PRESSURE_END,
    SIZE,
    STEPS,
    TOL,
    geometry,
    median_time,
)

from roughcontact import contact  # noqa: E402
from roughcontact.contact import SolverOptions, cell, nondim  # noqa: E402
from roughcontact.contact.nondim import CellOptions  # noqa: E402
from roughcontact.elasticity import definiteness, halfspace, influence, operators  # noqa: E402
from roughcontact.elasticity.protocol import DenseInfluence  # noqa: E402
from roughcontact.surfaces import spec, synthetic  # noqa: E402

THICKNESS = geometry(60).thickness  # m, the paper's block


def certify_anew(operator) -> None:
    """Certify ``operator`` as if it had never been: its kept certificate dropped first."""
    object.__setattr__(operator, definiteness.ATTRIBUTE, None)
    definiteness.certify(operator)


def surface(grid: int):
    """Heights (1, ny, nx) in units of sigma and the approaches of their sweep."""
    shape = spec.SurfaceSpec(grid=(grid, grid), size=SIZE, corr_length=(1e-3, 1e-3), sigma=1.0)
    heights = synthetic.generate_many(shape, (2006,))
    return heights, cell.approach_grid(heights, PRESSURE_END, STEPS)


def one_solve(unit, grid: int, method: str = "auto") -> tuple[float, int]:
    """A cold solve of the dimensionless problem at the middle approach: [s], products."""
    heights, approaches = surface(grid)
    n = grid * grid
    operator = contact.checks.as_operator(nondim.dimensionless_operator(unit, THICKNESS), 1 / n)
    definiteness.certify(operator)  # kept on it: the solve below does not pay it
    gap = nondim.initial_separation(heights)[0]
    start = time.perf_counter()
    result = contact.solve(operator, gap, approaches[STEPS // 2],
                           options=SolverOptions(method=method, tol=TOL, precision="mixed"))
    return time.perf_counter() - start, int(result.matvecs)


def one_sweep(unit, grid: int) -> float:
    """One surface over the sweep's approaches, with the stiffness at each [s] (certified
    before: the sweep does not pay it)."""
    heights, approaches = surface(grid)
    definiteness.certify(unit)
    start = time.perf_counter()
    nondim.solve_cell(unit, heights, thickness=THICKNESS, element_area=SIZE[0] * SIZE[1] / grid**2,
                      approaches=approaches,
                      options=CellOptions().with_(method="auto", tol=TOL, precision="mixed"))
    return time.perf_counter() - start


def dense_rows(grid: int = 60) -> list[dict]:
    matrix = halfspace.halfspace_influence((grid, grid), SIZE, 1.0, 0.0)
    unit = DenseInfluence(matrix, SIZE[0] * SIZE[1] / grid**2)
    symmetry = median_time(lambda: definiteness.check_symmetric(matrix), least=3)
    certify = median_time(lambda: certify_anew(unit), least=3)
    sweep = one_sweep(unit, grid)
    rows = []
    for method in ("auto", "cg"):
        solve, products = one_solve(unit, grid, method)
        rows.append({"operator": f"dense {grid}^2 ({'pivot' if method == 'auto' else method})",
                     "check": "Cholesky", "check_s": certify, "symmetry_s": symmetry,
                     "solve_s": solve, "products": products, "sweep_s": sweep})
    return rows


def matrix_free_rows(grids) -> list[dict]:
    coarse = geometry(operators.default_coarse_grid((256, 256))[0])
    coarse_unit = influence.unit_modulus_influence(coarse)
    rows = []
    for grid in grids:
        fine = geometry(grid)
        makers = {
            "halfspace": lambda fine=fine: operators.halfspace_operator(fine.grid, SIZE, 0.0),
            "hybrid": lambda fine=fine: operators.hybrid_operator(fine, coarse_unit.copy(),
                                                                  coarse)}
        for name, make in makers.items():
            unit = make()
            certify = median_time(lambda unit=unit: certify_anew(unit), least=3, most=5)
            solve, products = one_solve(make(), grid)
            rows.append({"operator": f"{name} {grid}^2 (pcg)", "check": "Lanczos, 12 steps",
                         "check_s": certify, "symmetry_s": float("nan"), "solve_s": solve,
                         "products": products, "sweep_s": one_sweep(make(), grid)})
    return rows


#: The columns of the table: header and how a row fills it.
COLUMNS = (
    ("operator", lambda r: r["operator"]),
    ("check", lambda r: r["check"]),
    ("check [s]", lambda r: f"{r['check_s']:.3f}"),
    ("of which symmetry [s]", lambda r: f"{r['symmetry_s']:.3f}"),
    ("one solve [s]", lambda r: f"{r['solve_s']:.3f}"),
    ("products", lambda r: str(r["products"])),
    ("check / solve", lambda r: f"{r['check_s'] / r['solve_s']:.2f}"),
    ("one sweep [s]", lambda r: f"{r['sweep_s']:.2f}"),
    ("check / sweep", lambda r: f"{r['check_s'] / r['sweep_s']:.2f}"),
)


def markdown(rows: list[dict]) -> str:
    """The rows as a Markdown table under a title and what was measured."""
    def line(cells) -> str:
        return "| " + " | ".join(cells) + " |"

    head = ["# Certifying an influence operator positive definite", "",
            f"One thread, load average {os.getloadavg()[0]:.1f} at the end. check: the whole "
            "certificate (median of repeats, the kept certificate dropped before each); solve: "
            "one cold solve at the middle approach; sweep: one surface over 10 approaches with "
            "the stiffness.", "",
            line(name for name, _ in COLUMNS), line("---" for _ in COLUMNS)]
    return "\n".join(head + [line(cell(r) for _, cell in COLUMNS) for r in rows]) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="dense 60 and 256 only")
    args = parser.parse_args(argv)
    rows = dense_rows()
    rows += matrix_free_rows((256,) if args.quick else (256, 1024))
    text = markdown(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "certify.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
