"""Speed and work of the contact solver on the paper's workload (run on demand).

Cases
-----
``blas-kernels``
    Best-of-5 times of a double and a single precision product of the
    3600 x 3600 matrix with 60 fields, and of a Cholesky factorization of its
    leading half, with 1 and 2 BLAS threads.
``sweep``
    The workload of Kumar et al. (2006), Section 4: 60 Gaussian surfaces
    (sigma 24.5 um, exponential ACF with b = 1 mm, Eq 1) on a 60 x 60 grid over
    9 mm x 9 mm, 30 approach steps up to about 60 % real contact, tol 1e-8,
    tangent stiffness at every step. The dense half-space matrix
    (``halfspace_influence``, E = 5.11e8 Pa, nu = 0) stands in for the FE
    influence matrix (same size, symmetric positive definite). Run for
    ``precision`` double and mixed and for OPENBLAS_NUM_THREADS = 1 and 2.
``baseline``
    Work per solve of ``"steepest"`` against ``"cg"``: cold solves of a few
    of the same surfaces at three approaches (about 10, 30 and 60 % contact)
    on the dense 60 x 60 matrix, and on a periodic 256 x 256 grid at about
    20 % contact.
``periodic``
    One cold ``"cg"`` solve on a periodic 512 x 512 grid (``PeriodicHalfSpace``)
    at about 20 % contact, tol 1e-10.

Usage::

    .venv/bin/python benchmarks/bench_contact.py            # everything (~10 min)
    .venv/bin/python benchmarks/bench_contact.py --quick    # small smoke run

Writes ``results/benchmarks/contact.csv`` and ``contact.md``. Each case runs in
a child process with the BLAS thread count set in its environment, because
OpenBLAS reads it only at start-up.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.contact import solve, solve_many, sweep  # noqa: E402
from roughcontact.halfspace import PeriodicHalfSpace, halfspace_influence  # noqa: E402

SIGMA = 24.5e-6  # surface standard deviation [m]
CORRELATION = 1.0e-3  # ACF length b at 10 % [m] (Eq 1)
SIZE = 9.0e-3  # nominal side [m]
E = 5.11e8  # Young's modulus [Pa] (Table 1)
NU = 0.0
#: Largest approach of the sweep in units of sigma: about 60 % contact on the
#: half-space for these surfaces (the measured fraction is reported).
APPROACH_MAX = 28.0


def gaussian_surfaces(count: int, grid: int, size: float, seed: int) -> np.ndarray:
    """Periodic Gaussian surfaces [m] with the exponential ACF of Eq 1.

    Zero-phase FFT filter of white noise (Eq 9-11): ``|H| = sqrt(S_z)``, with
    ``S_z`` the transform of ``R(r) = exp(-2.3 r / b)``; each surface is then
    scaled to zero mean and standard deviation ``SIGMA``. Shape (count, grid, grid).
    """
    spacing = size / grid
    lag = np.fft.fftfreq(grid, 1.0 / grid) * spacing
    acf = np.exp(-2.3 * np.hypot(lag[None, :], lag[:, None]) / CORRELATION)
    filter_modulus = np.sqrt(np.abs(np.fft.fft2(acf)))
    noise = np.random.default_rng(seed).standard_normal((count, grid, grid))
    z = np.fft.ifft2(np.fft.fft2(noise) * filter_modulus).real
    z -= z.mean(axis=(1, 2), keepdims=True)
    return z * (SIGMA / z.std(axis=(1, 2), keepdims=True))


def initial_gaps(z: np.ndarray) -> np.ndarray:
    """Initial separation f = z_max - z [m] per surface (Eq 21)."""
    return z.max(axis=(-2, -1), keepdims=True) - z


def case_sweep(args, precision: str, stiffness: bool) -> dict:
    gaps = initial_gaps(gaussian_surfaces(args.surfaces, args.grid, SIZE, seed=2006))
    influence = halfspace_influence((args.grid, args.grid), (SIZE, SIZE), E, NU)
    area = (SIZE / args.grid) ** 2
    approaches = np.linspace(0.0, APPROACH_MAX * SIGMA, args.steps + 1)[1:]
    start = time.perf_counter()
    result = sweep(influence, gaps, approaches, element_area=area, tol=args.tol,
                   precision=precision, stiffness=stiffness)
    wall = time.perf_counter() - start
    return dict(
        wall_s=wall,
        solves=int(result.load.size),
        iterations_per_solve=float(result.iterations.mean()),
        matvecs_per_solve=float(result.matvecs.mean()),
        converged=bool(result.converged.all()),
        stiffness_converged=bool(result.stiffness_converged.all()) if stiffness else None,
        final_contact=float(result.real_area_fraction[:, -1].mean()),
        final_pressure_MPa=float(result.nominal_pressure[:, -1].mean() / 1e6),
        max_residual=float(result.residual.max()),
    )


def case_baseline_dense(args, method: str) -> dict:
    count = max(1, min(4, args.surfaces))
    gaps = initial_gaps(gaussian_surfaces(count, args.grid, SIZE, seed=2006))
    influence = halfspace_influence((args.grid, args.grid), (SIZE, SIZE), E, NU)
    area = (SIZE / args.grid) ** 2
    levels = np.array([4.0, 12.0, APPROACH_MAX]) * SIGMA  # ~10, 30, 60 % contact
    batch = np.repeat(gaps, levels.size, axis=0)
    approach = np.tile(levels, count)
    start = time.perf_counter()
    results = solve_many(influence, batch, approach, method=method, element_area=area,
                         tol=args.tol)
    wall = time.perf_counter() - start
    return dict(
        wall_s=wall,
        solves=len(results),
        iterations_per_solve=float(np.mean([r.iterations for r in results])),
        matvecs_per_solve=float(np.mean([r.matvecs for r in results])),
        converged=all(r.converged for r in results),
        final_contact=float(np.mean([r.real_area_fraction for r in results])),
        max_residual=float(max(r.residual for r in results)),
    )


def periodic_problem(grid: int):
    """Operator, gaps and the approach for about 20 % contact on a periodic grid."""
    size = SIZE * grid / 60  # same element size as the 60 x 60 study
    operator = PeriodicHalfSpace((grid, grid), (size, size), E, NU)
    gap0 = initial_gaps(gaussian_surfaces(1, grid, size, seed=512)[0])
    # Bisection on the contact fraction with loose, cheap solves. The approach
    # is measured from the mean deflected plane (zero-mean convention), so it
    # must stay below the mean gap; near it the solves get hard: cap them.
    low, high = 0.0, float(gap0.mean())
    approach = 0.5 * (low + high)
    for _ in range(12):
        fraction = solve(operator, gap0, approach, tol=1e-5, max_iter=300).real_area_fraction
        if abs(fraction - 0.2) < 0.01:
            break
        low, high = (approach, high) if fraction < 0.2 else (low, approach)
        approach = 0.5 * (low + high)
    return operator, gap0, approach


def case_periodic(args, method: str, grid: int, tol: float) -> dict:
    operator, gap0, approach = periodic_problem(grid)
    start = time.perf_counter()
    result = solve(operator, gap0, approach, method=method, tol=tol)
    wall = time.perf_counter() - start
    return dict(
        wall_s=wall,
        solves=1,
        iterations_per_solve=float(result.iterations),
        matvecs_per_solve=float(result.matvecs),
        converged=bool(result.converged),
        final_contact=float(result.real_area_fraction),
        max_residual=float(result.residual),
    )


def case_blas_kernels(args) -> dict:
    """Best-of-5 times of the products that dominate the solvers [s]."""
    import scipy.linalg

    influence = halfspace_influence((args.grid, args.grid), (SIZE, SIZE), E, NU)
    single = influence.astype(np.float32)
    batch = np.random.default_rng(0).random((args.surfaces, influence.shape[0]))
    block = influence[: influence.shape[0] // 2, : influence.shape[0] // 2]

    def best(function):
        function()
        times = []
        for _ in range(5):
            start = time.perf_counter()
            function()
            times.append(time.perf_counter() - start)
        return min(times)

    return dict(
        wall_s=best(lambda: batch @ influence),
        gemm_double_s=best(lambda: batch @ influence),
        gemm_single_s=best(lambda: batch.astype(np.float32) @ single),
        cholesky_half_s=best(lambda: scipy.linalg.cho_factor(block, check_finite=False)),
        solves=0,
        matvecs_per_solve=float("nan"),
        converged=True,
    )


CASES = {
    "blas-kernels": case_blas_kernels,
    "sweep-double": lambda a: case_sweep(a, "double", True),
    "sweep-mixed": lambda a: case_sweep(a, "mixed", True),
    "sweep-mixed-nostiffness": lambda a: case_sweep(a, "mixed", False),
    "baseline-dense-cg": lambda a: case_baseline_dense(a, "cg"),
    "baseline-dense-steepest": lambda a: case_baseline_dense(a, "steepest"),
    "baseline-periodic-cg": lambda a: case_periodic(a, "cg", a.baseline_grid, a.tol),
    "baseline-periodic-steepest": lambda a: case_periodic(a, "steepest", a.baseline_grid,
                                                          a.tol),
    "periodic-512": lambda a: case_periodic(a, "cg", a.periodic_grid, 1e-10),
}


def plan(args) -> list[tuple[str, int]]:
    runs = [("blas-kernels", threads) for threads in (1, 2)]
    runs += [(name, threads) for name in ("sweep-double", "sweep-mixed") for threads in (1, 2)]
    runs += [("sweep-mixed-nostiffness", 1)]
    runs += [(name, 1) for name in CASES if name.startswith("baseline")]
    runs += [("periodic-512", threads) for threads in (1, 2)]
    return runs


def run_child(name: str, threads: int, args) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads),
               MKL_NUM_THREADS=str(threads))
    command = [sys.executable, __file__, "--child", name, *args.forward]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    record = json.loads(done.stdout.strip().splitlines()[-1])
    record.update(case=name, blas_threads=threads)
    return record


def summary(table, args) -> list[str]:
    """Findings against the targets, from the measured table."""
    lines = []

    def pick(case, threads=1):
        rows = table[(table.case == case) & (table.blas_threads == threads)]
        return rows.iloc[0] if len(rows) else None

    for precision in ("double", "mixed"):
        one, two = pick(f"sweep-{precision}", 1), pick(f"sweep-{precision}", 2)
        if one is not None:
            verdict = "meets" if one.wall_s < 30 else "misses"
            lines.append(f"- Sweep, {precision} precision: {one.wall_s:.1f} s with 1 BLAS thread "
                         f"({verdict} the 30 s target)")
        if one is not None and two is not None:
            faster = "2 threads" if two.wall_s < one.wall_s else "1 thread"
            lines.append(f"  - 2 threads: {two.wall_s:.1f} s; faster: {faster} "
                         f"(ratio 1/2 = {one.wall_s / two.wall_s:.2f})")
    one, two = pick("blas-kernels", 1), pick("blas-kernels", 2)
    if one is not None and two is not None:
        for column, label in (("gemm_double_s", "double GEMM C x 60 fields"),
                              ("gemm_single_s", "single GEMM C x 60 fields"),
                              ("cholesky_half_s", "Cholesky of C[:n/2, :n/2]")):
            lines.append(f"- BLAS {label}: {one[column] * 1e3:.1f} ms (1 thread), "
                         f"{two[column] * 1e3:.1f} ms (2 threads)")
    for kind in ("dense", "periodic"):
        cg, steepest = pick(f"baseline-{kind}-cg"), pick(f"baseline-{kind}-steepest")
        if cg is not None and steepest is not None:
            ratio = steepest.matvecs_per_solve / cg.matvecs_per_solve
            verdict = "meets" if ratio >= 20 else "misses"
            grid = f"{args.grid} x {args.grid}" if kind == "dense" else (
                f"{args.baseline_grid} x {args.baseline_grid}")
            lines.append(f"- Matvecs per cold solve, {kind} {grid}: steepest "
                         f"{steepest.matvecs_per_solve:.0f}, cg {cg.matvecs_per_solve:.0f}: "
                         f"{ratio:.1f}x fewer for cg ({verdict} the 20x target)")
    for threads in (1, 2):
        row = pick("periodic-512", threads)
        if row is not None:
            grid = args.periodic_grid
            lines.append(f"- Periodic {grid} x {grid}, {row.final_contact:.1%} contact, tol 1e-10: "
                         f"{row.wall_s:.2f} s, {row.matvecs_per_solve:.0f} matvecs "
                         f"({threads} BLAS thread{'s' if threads > 1 else ''})")
    return lines


def write_tables(records: list[dict], args, out: Path) -> None:
    import pandas as pd

    out.mkdir(parents=True, exist_ok=True)
    columns = ["case", "blas_threads", "wall_s", "solves", "iterations_per_solve",
               "matvecs_per_solve", "converged", "stiffness_converged", "final_contact",
               "final_pressure_MPa", "max_residual", "gemm_double_s", "gemm_single_s",
               "cholesky_half_s"]
    table = pd.DataFrame(records).reindex(columns=columns)
    table.to_csv(out / "contact.csv.tmp", index=False)
    os.replace(out / "contact.csv.tmp", out / "contact.csv")
    write_report(table, args, out)


def write_report(table, args, out: Path) -> None:
    header = (
        "# Contact solver benchmark\n\n"
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores "
        f"(shared with other jobs; wall times vary with their load). numpy {np.__version__}.\n"
        f"Sweep: {args.surfaces} surfaces x {args.steps} steps, {args.grid} x {args.grid} "
        f"dense half-space matrix, tol {args.tol:g}, approach up to {APPROACH_MAX:g} sigma, "
        f"tangent stiffness at every step unless 'nostiffness'; baseline and periodic: "
        f"cold solves. matvecs count partial (column-subset) products by their share.\n\n"
    )
    findings = "\n".join(["## Findings", "", *summary(table, args)]) + "\n\n"
    text = header + findings + table.to_markdown(index=False, floatfmt=".4g") + "\n"
    (out / "contact.md.tmp").write_text(text)
    os.replace(out / "contact.md.tmp", out / "contact.md")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--surfaces", type=int, default=60)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--grid", type=int, default=60)
    parser.add_argument("--tol", type=float, default=1e-8)
    parser.add_argument("--periodic-grid", type=int, default=512)
    parser.add_argument("--baseline-grid", type=int, default=256)
    parser.add_argument("--quick", action="store_true", help="small sizes, for a smoke test")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "benchmarks")
    parser.add_argument("--report", action="store_true",
                        help="only rewrite contact.md from an existing contact.csv")
    parser.add_argument("--child", choices=sorted(CASES), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:
        args.surfaces, args.steps, args.grid = 6, 5, 30
        args.periodic_grid, args.baseline_grid = 128, 64
    if args.child:
        print(json.dumps(CASES[args.child](args)))
        return
    if args.report:
        import pandas as pd

        write_report(pd.read_csv(args.out / "contact.csv"), args, args.out)
        return
    args.forward = [f"--surfaces={args.surfaces}", f"--steps={args.steps}",
                    f"--grid={args.grid}", f"--tol={args.tol}",
                    f"--periodic-grid={args.periodic_grid}",
                    f"--baseline-grid={args.baseline_grid}"]
    records = []
    for name, threads in plan(args):
        record = run_child(name, threads, args)
        print(f"{name:28s} threads={threads} wall={record['wall_s']:8.2f} s "
              f"matvecs/solve={record['matvecs_per_solve']:8.1f} "
              f"converged={record['converged']}", flush=True)
        records.append(record)
        write_tables(records, args, args.out)
    print(f"wrote {args.out / 'contact.csv'} and {args.out / 'contact.md'}")


if __name__ == "__main__":
    main()
