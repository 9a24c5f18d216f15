"""Dense influence matrices against the matrix-free block operator: products, builds, solves.

Measured with one thread (OPENBLAS_NUM_THREADS, MKL_NUM_THREADS and
OMP_NUM_THREADS are set to 1 before numpy is imported, and inherited by every
case). Every case runs in its own Python process, so that its peak memory
(``ru_maxrss``: interpreter, libraries, MKL's own allocations) is measured
alone. The block is the paper's (Table 1 of Kumar et al. 2006: 9 mm x 9 mm,
L = 10 mm, nu = 0, clamped base); the contact grid varies.

Studies
-------
A. Product time ``u = E C p`` for a batch of m = 20 pressure fields, as the
   contact solver calls it (pressures one field per row): the dense matrix in
   float64 and in float32 (``precision="mixed"`` takes its search-direction
   products in float32), for grids up to 120 x 120 (a random symmetric matrix
   of the right size: the time does not depend on the values), against
   :class:`roughcontact.operators.BlockOperator` (hybrid, default coarse grid,
   and coarse grid at most 32 per side; the correction is a random symmetric
   matrix of the coarse size, so no finite-element model is built) and the
   half-space operator (Love alone), for grids 32 to 256 per side. Median of
   several repeats. Reports the crossover grid from which the hybrid operator
   is faster than the float32 dense product.
B. The matrix-free alternative without FFT: products through one sparse
   factorization of the finite-element stiffness ("refined" mesh, 32, 60 and
   120 per side), ``u = R K^-1 F^T p`` with F the load and R the centre
   operators of ``assembly.top_face_operators``. Factorized once by MKL PARDISO
   (``pypardiso``): LU of the full matrix (pypardiso's default, mtype 11) and
   Cholesky of the upper triangle (mtype 2, the cheapest); scipy's SuperLU
   when pypardiso is missing (grids up to 60). Time of assembly,
   factorization and one product of 20 fields, peak memory; at 32 x 32 the
   product is checked against ``unit_modulus_influence(geom, symmetric=False)
   @ p``. The per-product time is compared with study A's hybrid operator.
C. Build time and peak memory: the dense finite-element matrix
   (``unit_modulus_influence``) "refined" and "paper" at 60 x 60; the hybrid
   ``block_operator`` "refined" at 60 x 60 (coarse 30), 120 x 120 (coarse 60)
   and 256 x 256 (coarse 64); and the predicted cost of the dense "refined"
   matrix at 120 x 120 and 256 x 256 (``influence.estimate_cost``, not built;
   the matrix alone is 8 n^2 bytes).
D. Time per contact solve: ``nondim.solve_cell`` on 2 Gaussian surfaces
   (exponential ACF, b = 1 mm, sigma = 1) at 10 approaches up to
   ``contact.cell.approach_grid(heights, 4.0, 10)``, method "cg", tol 1e-8,
   precision "mixed", tangent stiffness at every step: at 60 x 60 on the dense
   "refined" matrix and the hybrid operator (coarse 30), with the largest
   relative difference of k_P, real area and peak pressure at the last step;
   at 120 x 120 (hybrid, coarse 60) and 256 x 256 (hybrid, coarse 64).

Writes results/benchmarks/operators.csv and operators.md (rewritten after
every case, so an interrupted run leaves what it measured).

Usage::

    .venv/bin/python benchmarks/bench_operators.py          # A-D (7-10 min, peak 7 GB)
    .venv/bin/python benchmarks/bench_operators.py --quick  # A to 64, B at 32, C, D at 60 (1.5 min)

Timings depend on the load of the machine; each row records the 1-minute
load average at its start, and the Markdown file the range over the run.
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.contact import nondim  # noqa: E402
from roughcontact.contact.cell import approach_grid  # noqa: E402
from roughcontact.contact.nondim import CellOptions  # noqa: E402
from roughcontact.elasticity import assembly, sparse_solve  # noqa: E402
from roughcontact.elasticity.influence import (  # noqa: E402
    BlockGeometry,
    build_mesh,
    estimate_cost,
    unit_modulus_influence,
)
from roughcontact.elasticity.operators import (  # noqa: E402
    BlockOperator,
    block_operator,
    default_coarse_grid,
    halfspace_operator,
)
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402
from roughcontact.surfaces.synthetic import generate_many  # noqa: E402

OUT = ROOT / "results" / "benchmarks"
SIZE = (9e-3, 9e-3)  # plan size of the block [m]
FIELDS = 20  # pressure fields per product
GRIDS = (32, 48, 60, 64, 96, 120, 128, 192, 256)
DENSE_MAX_GRID = 120  # largest grid with a dense product (14400^2 float64: 1.7 GB)
SMALL_COARSE = 32  # second hybrid variant of study A: coarse grid at most this per side
FE_GRIDS = (32, 60, 120)
SUPERLU_MAX_GRID = 60
CHECK_GRID = 32
CHECK_RTOL = 1e-8
SEEDS = (2006, 2007)  # surfaces of study D
STEPS = 10
PRESSURE_END = 4.0  # non-dimensional nominal pressure P L / (E sigma) at the last approach
TOL = 1e-8


def geometry(grid: int, mesh: str = "refined") -> BlockGeometry:
    """The paper's block (9 mm, L = 10 mm, nu = 0, clamped) on ``grid`` x ``grid`` elements."""
    return BlockGeometry(size=SIZE, grid=(grid, grid), mesh=mesh)


def peak_gb() -> float:
    """Peak resident set of this process [GB]."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9


def median_time(function, budget: float = 1.0, least: int = 5, most: int = 30) -> float:
    """Median wall time [s] of ``function()`` after one warm-up call; more repeats when fast."""
    start = time.perf_counter()
    function()
    first = time.perf_counter() - start
    repeats = int(np.clip(budget / max(first, 1e-9), least, most))
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def random_symmetric(n: int, rng) -> np.ndarray:
    """A random symmetric (n, n) float64 matrix."""
    matrix = rng.random((n, n))
    matrix += matrix.T
    return matrix


def pressure_batch(grid: int) -> np.ndarray:
    """``FIELDS`` pressure fields, one per row, shape (m, n)."""
    return np.random.default_rng(1).random((FIELDS, grid * grid))


# ---------------------------------------------------------------------------
# Cases (each runs in a child process)


def case_dense_product(grid: int) -> dict:
    """A: ``P @ C`` in float64 and, as in ``precision="mixed"``, in float32 [s]."""
    n = grid * grid
    batch = pressure_batch(grid)
    matrix = random_symmetric(n, np.random.default_rng(0))
    single = matrix.astype(np.float32)
    return {
        "dense_f64_s": median_time(lambda: batch @ matrix),
        "dense_f32_s": median_time(lambda: (batch.astype(np.float32) @ single).astype(float)),
        "matrix_gb": 8.0 * n * n / 1e9,
        "peak_gb": peak_gb(),
    }


def random_hybrid(grid: int, coarse: tuple[int, int]) -> BlockOperator:
    """Hybrid operator with a random symmetric correction on the coarse grid."""
    nc = coarse[0] * coarse[1]
    correction = np.random.default_rng(2).standard_normal((nc, nc))
    correction += correction.T
    return BlockOperator(grid=(grid, grid), size=SIZE, nu=0.0, correction=correction,
                         coarse_grid=coarse)


def case_operator_product(grid: int) -> dict:
    """A: ``BlockOperator.matvec`` as the contact solver calls it (fields as rows) [s]."""
    batch = pressure_batch(grid)
    coarse = default_coarse_grid((grid, grid))
    small = default_coarse_grid((grid, grid), SMALL_COARSE)
    operators = {"hybrid": random_hybrid(grid, coarse), "hybrid_small": random_hybrid(grid, small),
                 "halfspace": halfspace_operator((grid, grid), SIZE, 0.0)}
    row = {"coarse": coarse[0], "coarse_small": small[0]}
    for name, op in operators.items():
        row[f"{name}_s"] = median_time(lambda op=op: np.ascontiguousarray(op.matvec(batch.T).T))
        row[f"{name}_gb"] = op.nbytes() / 1e9
    return row | {"peak_gb": peak_gb()}


def case_fe_product(grid: int, solver: str) -> dict:
    """B: ``u = R K^-1 F^T p`` through one sparse factorization of the "refined" stiffness."""
    geom = geometry(grid)
    start = time.perf_counter()
    mesh = build_mesh(geom)
    upper = assembly.assemble_stiffness(mesh, geom.nu, geom.base, E=1.0, upper=True)
    load, centre = assembly.top_face_operators(mesh, geom.grid, geom.base)
    assemble_s = time.perf_counter() - start
    row = {"dofs": upper.shape[0], "stiffness_nonzeros": int(upper.nnz), "assemble_s": assemble_s}
    start = time.perf_counter()
    if solver.startswith("pardiso"):
        from pypardiso import PyPardisoSolver

        if solver == "pardiso-lu":  # pypardiso's default: real nonsymmetric, full matrix
            matrix, mtype = sparse_solve.full_from_upper(upper).tocsr(), 11
        else:  # real symmetric positive definite: Cholesky of the upper triangle
            matrix, mtype = upper, 2
        del upper
        pardiso = PyPardisoSolver(mtype=mtype)
        pardiso.factorize(matrix)
        row["factor_nonzeros"] = int(pardiso.iparm[17])

        def solve(rhs):
            return pardiso.solve(matrix, rhs)
    else:
        from scipy.sparse.linalg import splu

        lu = splu(sparse_solve.full_from_upper(upper), permc_spec="MMD_AT_PLUS_A")
        del upper
        row["factor_nonzeros"] = int(lu.L.nnz + lu.U.nnz)
        solve = lu.solve
    row["factor_s"] = time.perf_counter() - start
    fields = pressure_batch(grid).T  # (n, m)

    def product(p):
        return centre @ solve(np.asfortranarray(load.T @ p))

    row["product_s"] = median_time(lambda: product(fields), budget=0.0, least=3)
    row["peak_gb"] = peak_gb()
    if grid == CHECK_GRID:
        raw = unit_modulus_influence(geom, symmetric=False)
        reference = raw @ fields
        u = product(fields)
        row["check_rel_error"] = float(np.linalg.norm(u - reference) / np.linalg.norm(reference))
        symmetric = 0.5 * (raw + raw.T) @ fields
        row["vs_symmetric_rel_error"] = float(np.linalg.norm(u - symmetric)
                                              / np.linalg.norm(symmetric))
    return row


def case_build(kind: str, grid: int, mesh: str, coarse: int | None) -> dict:
    """C: build time and peak memory of a dense FE matrix or a hybrid operator."""
    geom = geometry(grid, mesh)
    before = peak_gb()
    start = time.perf_counter()
    if kind == "dense":
        model = unit_modulus_influence(geom)
        held = model.nbytes
    else:
        model = block_operator(geom, coarse_grid=(coarse, coarse))
        held = model.nbytes()
    return {"build_s": time.perf_counter() - start, "peak_gb": peak_gb(),
            "increase_gb": peak_gb() - before, "held_gb": held / 1e9}


def case_solve(model: str, grid: int, coarse: int | None) -> dict:
    """D: ``nondim.solve_cell`` on the Gaussian surfaces; time per solve and last-step values."""
    geom = geometry(grid)
    start = time.perf_counter()
    unit = (unit_modulus_influence(geom) if model == "dense"
            else block_operator(geom, coarse_grid=(coarse, coarse)))
    build_s = time.perf_counter() - start
    spec = SurfaceSpec(grid=geom.grid, size=SIZE, corr_length=(1e-3, 1e-3), sigma=1.0)
    heights = generate_many(spec, SEEDS)
    approaches = approach_grid(heights, PRESSURE_END, STEPS)
    hx, hy = geom.spacing
    start = time.perf_counter()
    result = nondim.solve_cell(unit, heights, thickness=geom.thickness, element_area=hx * hy,
                               approaches=approaches,
                               options=CellOptions().with_(method="cg", tol=TOL, precision="mixed"))
    wall = time.perf_counter() - start
    solves = result.converged.size
    return {
        "build_s": build_s, "solve_wall_s": wall, "solves": solves,
        "seconds_per_solve": wall / solves,
        "matvecs_per_solve": float(result.matvecs.mean()),
        "iterations_per_solve": float(result.iterations.mean()),
        "converged": bool(result.converged.all()),
        "stiffness_converged": bool(result.stiffness_converged.all()),
        "final_pressure": float(result.nominal_pressure[:, -1].mean()),
        "final_real_area": float(result.real_area_fraction[:, -1].mean()),
        "last_k_P": result.normalized_stiffness[:, -1].tolist(),
        "last_real_area": result.real_area_fraction[:, -1].tolist(),
        "last_max_pressure": result.max_pressure[:, -1].tolist(),
        "peak_gb": peak_gb(),
    }


CASES = {
    "dense-product": lambda c: case_dense_product(c["grid"]),
    "operator-product": lambda c: case_operator_product(c["grid"]),
    "fe-product": lambda c: case_fe_product(c["grid"], c["solver"]),
    "build": lambda c: case_build(c["kind"], c["grid"], c["mesh"], c.get("coarse")),
    "solve": lambda c: case_solve(c["model"], c["grid"], c.get("coarse")),
}


def run_isolated(case: dict) -> dict:
    """Run ``case`` in a fresh interpreter; its row with the load average at its start."""
    load = os.getloadavg()[0]
    start = time.perf_counter()
    done = subprocess.run([sys.executable, __file__, "--case", json.dumps(case)],
                          capture_output=True, text=True, env={**os.environ})
    row = {**case, "load_1min": load, "case_wall_s": time.perf_counter() - start}
    if done.returncode:
        message = (done.stderr.strip().splitlines() or ["no output"])[-1][:160]
        row["status"] = f"failed (exit {done.returncode}): {message}"
    else:
        row |= {"status": "ok", **json.loads(done.stdout.strip().splitlines()[-1])}
    print(f"{case['study']} {case['name']:<16s} grid {case['grid']:>3d}: {row['status']}, "
          f"{row['case_wall_s']:.1f} s, load {load:.2f}", file=sys.stderr, flush=True)
    return row


def plan(quick: bool) -> list[dict]:
    """The cases of studies A-D."""
    grids = [g for g in GRIDS if not quick or g <= 64]
    cases = []
    for g in grids:
        if g <= DENSE_MAX_GRID:
            cases.append({"study": "A", "name": "dense-product", "grid": g})
        cases.append({"study": "A", "name": "operator-product", "grid": g})
    try:
        import pypardiso  # noqa: F401

        solvers = ("pardiso-lu", "pardiso-spd")
    except ImportError:
        solvers = ("superlu",)
    for g in FE_GRIDS if not quick else (CHECK_GRID,):
        for solver in solvers:
            if solver == "superlu" and g > SUPERLU_MAX_GRID:
                continue
            cases.append({"study": "B", "name": "fe-product", "grid": g, "solver": solver})
    builds = [("dense", 60, "paper", None), ("dense", 60, "refined", None),
              ("hybrid", 60, "refined", 30), ("hybrid", 120, "refined", 60),
              ("hybrid", 256, "refined", 64)]
    for kind, g, mesh, coarse in builds:
        if quick and g > 64:
            continue
        cases.append({"study": "C", "name": "build", "kind": kind, "grid": g, "mesh": mesh,
                      "coarse": coarse})
    solves = [("dense", 60, None), ("hybrid", 60, 30), ("hybrid", 120, 60), ("hybrid", 256, 64)]
    for model, g, coarse in solves:
        if quick and g > 64:
            continue
        cases.append({"study": "D", "name": "solve", "model": model, "grid": g, "coarse": coarse})
    return cases


def estimates(quick: bool) -> list[dict]:
    """C: predicted cost of the dense "refined" matrices that are not built."""
    rows = []
    for g in (120,) if quick else (120, 256):
        cost = estimate_cost(geometry(g))
        n = g * g
        rows.append({"study": "C", "name": "estimate", "kind": "dense", "grid": g,
                     "mesh": "refined", "status": "estimate only (not built)",
                     "dofs": cost.dofs, "estimate_gb": cost.peak_bytes / 1e9,
                     "held_gb": 8.0 * n * n / 1e9})
    return rows


# ---------------------------------------------------------------------------
# Tables


def crossover(rows: list[dict], column: str) -> int | None:
    """Smallest grid from which ``column`` stays faster than the float32 dense product."""
    dense = {r["grid"]: r["dense_f32_s"] for r in rows if r["name"] == "dense-product"
             and r["status"] == "ok"}
    ops = {r["grid"]: r[column] for r in rows if r["name"] == "operator-product"
           and r["status"] == "ok"}
    grids = sorted(set(dense) & set(ops))
    faster = [ops[g] < dense[g] for g in grids]
    for i, g in enumerate(grids):
        if all(faster[i:]):
            return g
    return None


def a_table(rows: list[dict]) -> list[str]:
    by_grid = {}
    for r in rows:
        if r["study"] == "A" and r["status"] == "ok":
            by_grid.setdefault(r["grid"], {}).update(
                {k: v for k, v in r.items() if k not in ("name", "peak_gb", "load_1min")}
                | {f"{r['name']}_peak_gb": r["peak_gb"], f"{r['name']}_load": r["load_1min"]})
    lines = [f"| grid | n | dense f64 [ms] | dense f32 [ms] | hybrid [ms] (coarse) "
             f"| hybrid, coarse <= {SMALL_COARSE} [ms] | half-space [ms] | hybrid / dense f32 "
             "| dense matrix [GB] | operator held [GB] | peak dense / operator [GB] | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for g, r in sorted(by_grid.items()):
        dense = r.get("dense_f32_s", np.nan)
        lines.append("| " + " | ".join([
            f"{g} x {g}", str(g * g), _ms(r.get("dense_f64_s")), _ms(r.get("dense_f32_s")),
            f"{_ms(r.get('hybrid_s'))} ({r.get('coarse', '')})",
            f"{_ms(r.get('hybrid_small_s'))} ({r.get('coarse_small', '')})",
            _ms(r.get("halfspace_s")), _num(r.get("hybrid_s", np.nan) / dense, 2),
            _num(r.get("matrix_gb"), 2), _num(r.get("hybrid_gb"), 3),
            f"{_num(r.get('dense-product_peak_gb'), 2)} / "
            f"{_num(r.get('operator-product_peak_gb'), 2)}",
            _num(r.get("operator-product_load"), 1)]) + " |")
    return lines


def b_table(rows: list[dict]) -> list[str]:
    hybrid = {r["grid"]: r for r in rows if r["name"] == "operator-product"
              and r["status"] == "ok"}
    dense = {r["grid"]: r for r in rows if r["name"] == "dense-product" and r["status"] == "ok"}
    lines = ["| grid | solver | dofs | factor nonzeros | assemble [s] | factorize [s] "
             "| product [s] | peak [GB] | hybrid product [s] | FE product / hybrid "
             "| FE product / dense f32 | check | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["study"] != "B":
            continue
        if r["status"] != "ok":
            lines.append(f"| {r['grid']} | {r['solver']} | {r['status']} |" + " |" * 10)
            continue
        op = hybrid.get(r["grid"], {}).get("hybrid_s", np.nan)
        f32 = dense.get(r["grid"], {}).get("dense_f32_s", np.nan)
        check = ""
        if "check_rel_error" in r:
            check = (f"{r['check_rel_error']:.1e} vs R K^-1 F^T; "
                     f"{r['vs_symmetric_rel_error']:.1e} vs its symmetric part")
        lines.append("| " + " | ".join([
            f"{r['grid']} x {r['grid']}", r["solver"], str(r["dofs"]),
            f"{r['factor_nonzeros']:.3g}",
            _num(r["assemble_s"], 1), _num(r["factor_s"], 1), _num(r["product_s"], 3),
            _num(r["peak_gb"], 2), _num(op, 4), _num(r["product_s"] / op, 0),
            _num(r["product_s"] / f32, 0), check, _num(r["load_1min"], 1)]) + " |")
    return lines


def c_table(rows: list[dict]) -> list[str]:
    lines = ["| model | mesh | grid | coarse | build [s] | peak [GB] | increase [GB] "
             "| held [GB] | dofs | estimate [GB] | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    built = [r for r in rows if r["study"] == "C" and r["name"] == "build"]
    for r in built + [r for r in rows if r["study"] == "C" and r["name"] == "estimate"]:
        model = "dense FE" if r["kind"] == "dense" else "hybrid operator"
        if r["status"] != "ok":
            lines.append(f"| {model} | {r['mesh']} | {r['grid']} x {r['grid']} | | "
                         f"{r['status']} | | | {_num(r.get('held_gb'), 1)} | "
                         f"{r.get('dofs', '')} | {_num(r.get('estimate_gb'), 1)} | |")
            continue
        estimate = dofs = ""
        if r["kind"] == "dense":
            cost = estimate_cost(geometry(r["grid"], r["mesh"]))
            estimate, dofs = _num(cost.peak_bytes / 1e9, 2), str(cost.dofs)
        lines.append("| " + " | ".join([
            model, r["mesh"], f"{r['grid']} x {r['grid']}", str(r.get("coarse") or ""),
            _num(r["build_s"], 1), _num(r["peak_gb"], 2), _num(r["increase_gb"], 2),
            _num(r["held_gb"], 3), dofs, estimate, _num(r["load_1min"], 1)]) + " |")
    return lines


def d_table(rows: list[dict]) -> list[str]:
    lines = ["| model | grid | coarse | build [s] | solves | s per solve | matvecs per solve "
             "| iterations per solve | converged | final P | final real area | peak [GB] "
             "| load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["study"] != "D":
            continue
        if r["status"] != "ok":
            lines.append(f"| {r['model']} | {r['grid']} | | {r['status']} |" + " |" * 9)
            continue
        lines.append("| " + " | ".join([
            "dense FE" if r["model"] == "dense" else "hybrid", f"{r['grid']} x {r['grid']}",
            str(r.get("coarse") or ""), _num(r["build_s"], 1), str(r["solves"]),
            _num(r["seconds_per_solve"], 3), _num(r["matvecs_per_solve"], 1),
            _num(r["iterations_per_solve"], 1),
            str(r["converged"] and r["stiffness_converged"]), _num(r["final_pressure"], 2),
            f"{r['final_real_area']:.1%}", _num(r["peak_gb"], 2), _num(r["load_1min"], 1),
        ]) + " |")
    return lines


def d_differences(rows: list[dict]) -> dict:
    """Largest relative difference hybrid / dense - 1 at the last step, 60 x 60."""
    pick = {r["model"]: r for r in rows if r["study"] == "D" and r["grid"] == 60
            and r["status"] == "ok"}
    if set(pick) != {"dense", "hybrid"}:
        return {}
    out = {}
    for name in ("k_P", "real_area", "max_pressure"):
        dense = np.asarray(pick["dense"][f"last_{name}"])
        hybrid = np.asarray(pick["hybrid"][f"last_{name}"])
        out[name] = float(np.max(np.abs(hybrid / dense - 1.0)))
    return out


def findings(rows: list[dict]) -> list[str]:
    lines = []
    for column, label in (("hybrid_s", "hybrid operator (default coarse grid)"),
                          ("hybrid_small_s", f"hybrid operator (coarse <= {SMALL_COARSE})"),
                          ("halfspace_s", "half-space operator")):
        grid = crossover(rows, column)
        where = (f"from {grid} x {grid} on" if grid is not None
                 else f"at no measured grid up to {DENSE_MAX_GRID} x {DENSE_MAX_GRID}")
        lines.append(f"- A: the {label} is faster than the float32 dense product {where}.")
    ratio = {r["grid"]: r["dense_f32_s"] / r["dense_f64_s"] for r in rows
             if r["name"] == "dense-product" and r["status"] == "ok"}
    slow = [g for g, v in ratio.items() if v > 0.9]
    others = [v for g, v in ratio.items() if v <= 0.9]
    if slow and others:
        lines.append(f"- A: at {', '.join(f'{g} x {g}' for g in slow)} the float32 dense "
                     f"product takes {', '.join(f'{100 * ratio[g]:.0f} %' for g in slow)} of "
                     f"the float64 time on this machine (at the other grids "
                     f"{100 * min(others):.0f}-{100 * max(others):.0f} %).")
    hybrid = {r["grid"]: r["hybrid_s"] for r in rows if r["name"] == "operator-product"
              and r["status"] == "ok"}
    for r in rows:
        if r["study"] == "B" and r["status"] == "ok" and r["grid"] in hybrid:
            lines.append(f"- B: {r['grid']} x {r['grid']}, {r['solver']}: one product through "
                         f"the factorization {r['product_s']:.3g} s = "
                         f"{r['product_s'] / hybrid[r['grid']]:.0f} x the hybrid operator "
                         f"({hybrid[r['grid']]:.3g} s), after a {r['factor_s']:.1f} s "
                         f"factorization, peak {r['peak_gb']:.2f} GB.")
        if r["study"] == "B" and r["status"] == "ok" and "check_rel_error" in r:
            verdict = "passed" if r["check_rel_error"] <= CHECK_RTOL else "FAILED"
            lines.append(f"- B check ({r['solver']}, {r['grid']} x {r['grid']}): relative "
                         f"difference from unit_modulus_influence(geom, symmetric=False) @ p "
                         f"{r['check_rel_error']:.1e} (tolerance {CHECK_RTOL:g}): {verdict}.")
    for r in rows:
        if r["study"] == "D" and r["status"] == "ok":
            lines.append(f"- D: {r['model']} {r['grid']} x {r['grid']}: "
                         f"{r['seconds_per_solve']:.3g} s per solve, converged "
                         f"{r['converged'] and r['stiffness_converged']}.")
    diff = d_differences(rows)
    if diff:
        lines.append("- D, 60 x 60, hybrid (coarse 30) against the dense \"refined\" matrix at "
                     "the last step, largest over the surfaces: " + ", ".join(
                         f"{k} {100 * v:.2f} %" for k, v in diff.items()) + ".")
    return lines


def write(rows: list[dict], header: dict) -> None:
    """operators.csv (every number) and operators.md (tables and findings), atomically."""
    import pandas as pd

    OUT.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame([{k: (json.dumps(v) if isinstance(v, list) else v)
                           for k, v in r.items()} for r in rows])
    first = ["study", "name", "grid", "status", "load_1min"]
    table = table[first + [c for c in table.columns if c not in first]].convert_dtypes()
    _atomic_write(OUT / "operators.csv", table.to_csv(index=False))
    loads = [r["load_1min"] for r in rows if "load_1min" in r]
    md = ["# Dense influence matrices and the matrix-free block operator", "",
          f"Run {header['started']} on {header['machine']}, {header['cpus']} CPUs (shared "
          f"with other jobs), one BLAS/MKL thread{' (--quick)' if header['quick'] else ''}. "
          f"Load average (1 min) at the start {header['load'][0]:.2f}, over the cases "
          f"{min(loads, default=np.nan):.2f}-{max(loads, default=np.nan):.2f}"
          f"{', at the end ' + format(header['end_load'], '.2f') if 'end_load' in header else ''}"
          ". Every case ran in its own process; peak = its peak resident set (ru_maxrss). "
          "Paper's block: 9 mm x 9 mm, L = 10 mm, nu = 0, clamped base.", "",
          "## Findings", "", *findings(rows), "",
          f"## A. Product of {FIELDS} pressure fields", "",
          "Dense: a random symmetric matrix of the size, `P @ C` (float32: converted as in "
          "the solver's mixed precision). Operators: `matvec(P.T).T` as the contact solver "
          "calls it; the hybrid corrections are random symmetric matrices of the coarse size. "
          "Median of 5-30 repeats.", "", *a_table(rows), "",
          "## B. Products through the sparse factorization (\"refined\" mesh)", "",
          f"`u = R K^-1 F^T p` for {FIELDS} fields; pardiso-lu: pypardiso's default (LU of "
          "the full matrix), pardiso-spd: Cholesky of the upper triangle. Hybrid product: "
          "study A at the same grid (default coarse grid).", "", *b_table(rows), "",
          "## C. Build time and peak memory", "",
          "held = the dense matrix (8 n^2 bytes) or the operator's arrays; estimate = "
          "influence.estimate_cost of the dense finite-element build.", "", *c_table(rows), "",
          "## D. Contact solves (nondim.solve_cell)", "",
          f"{len(SEEDS)} Gaussian surfaces (b = 1 mm over 9 mm, sigma = 1) x {STEPS} approaches "
          f"up to sweep_approaches(heights, {PRESSURE_END}, {STEPS}); cg, tol {TOL:g}, "
          "precision mixed, tangent stiffness at every step; both surfaces solved as one batch, "
          "so the products carry 2 fields (the dense one is then bound by reading the matrix). "
          "Build time not in the solve time.",
          "", *d_table(rows), ""]
    _atomic_write(OUT / "operators.md", "\n".join(md))


def _ms(value) -> str:
    return "" if value is None or not np.isfinite(value) else f"{1e3 * value:.3g}"


def _num(value, digits: int) -> str:
    if value is None or not np.isfinite(value):
        return ""
    return f"{value:.{digits}f}"


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="grids up to 64, no 120/256 builds or solves (under 2 min)")
    parser.add_argument("--case", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        case = json.loads(args.case)
        print(json.dumps(CASES[case["name"]](case)))
        return
    header = {"cpus": os.cpu_count(), "load": os.getloadavg(), "quick": args.quick,
              "machine": platform.processor() or platform.machine(),
              "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    rows = estimates(args.quick)
    for case in plan(args.quick):
        rows.append(run_isolated(case))
        write(rows, header)
    header["end_load"] = os.getloadavg()[0]
    write(rows, header)
    print(f"wrote {OUT / 'operators.csv'} and {OUT / 'operators.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
