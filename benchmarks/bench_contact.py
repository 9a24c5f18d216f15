"""Speed and work of the contact solver on the paper's workload (run on demand).

Cases
-----
``blas-kernels``
    Best-of-5 times of a double and a single precision product of the paper's
    3600 x 3600 influence matrix with 60 fields, 1 and 2 BLAS threads.
``paper-sweep``
    The workload of Kumar et al. (2006), Section 4: 60 surfaces from
    ``generate_many`` (sigma 24.5 um, Sk 0, Ku 3, exponential ACF b = 1 mm,
    60 x 60 over 9 mm x 9 mm), gaps ``f = max z - z``, 30 approaches evenly
    spaced from first touch to ``APPROACH_END`` sigma (about 60 % real contact),
    tol 1e-8, tangent stiffness at every step, on the FE influence matrix of
    the paper's block (``influence_matrix(BlockGeometry())``, cached in /tmp).
    ``paper-subset`` runs the first 5 steps on 8 of the surfaces, to compare
    the predictor (``extrapolate``) on and off and 1 against 2 BLAS threads.
``baseline``
    Work per cold solve of ``"steepest"`` against ``"cg"``: a few surfaces at
    three approaches on the dense 60 x 60 half-space matrix (about 10, 30 and
    60 % contact), one on a periodic 256 x 256 grid at about 20 % contact, and
    one on the paper's block matrix at about 2 % contact (``steepest`` capped).
``periodic``
    One cold solve on a periodic 512 x 512 Gaussian surface (exponential ACF)
    at about 20 % contact, tol 1e-10, with the spectral half-space kernel
    ``2 / (E* |q|)`` that Tamaas and ContactMechanics use, so the three
    libraries solve the identical discrete problem; ours by displacement
    control, the others by load control at our solution's mean pressure.
    Every returned pressure is scored with our KKT residual.
``units``
    The sweep of issue 17 in units of one dense product, measured in the same
    process, so that machines and loads compare. Workload: 60 Gaussian
    surfaces from ``generate_many`` (sigma 30 um, Sk 0, Ku 3, exponential ACF
    b = 1 mm, 60 x 60 over 9 mm), gaps ``f = max z - z``, 30 approaches evenly
    spaced from 0.1 to 3 sigma after first touch (``--approach-range``), tol
    1e-8, the study's precision (``mixed``), tangent stiffness at every step,
    on the influence matrices of the paper's block (9 mm x 9 mm x 10 mm, nu 0,
    clamped base) built with the ``paper`` and the ``refined`` mesh presets
    (cached in /tmp). One child process per method (``--methods``, default
    ``cg``; any name ``sweep`` accepts) measures:

    - the GEMM unit: the best of 5 products ``C @ P``, C the paper matrix
      (3600 x 3600), P 3600 x 60, float64, one BLAS thread, taken before every
      round; the smallest over the rounds is used;
    - the sweep's wall time on each mesh, the minimum of ``--repeats`` rounds
      (default 3) run alternately paper, refined, paper, refined, ...;
    - ``units`` = sweep wall / GEMM unit per mesh, and their ratio paper /
      refined (issue 17: at most 500 units each, ratio at most 1.2);
    - the work from ``SweepResult``: total ``matvecs`` (products charged per
      surface, contact solves only: the stiffness CG's are not in the result),
      products and iterations per surface and step, and both at the steps
      whose mean real area fraction is nearest 1 %, 10 % and 30 % (the actual
      fractions are reported: this workload may not reach them);
    - whether every step converged, the worst KKT residual, the range of
      mean real area fraction and the final nominal pressure.

    Rows go to ``results/benchmarks/contact_units.csv`` and ``contact_units.md``.

Usage::

    .venv/bin/python benchmarks/bench_contact.py            # everything (~35 min)
    .venv/bin/python benchmarks/bench_contact.py --quick    # small smoke run
    .venv/bin/python benchmarks/bench_contact.py --only units --methods cg exact
    .venv/bin/python benchmarks/bench_contact.py --only units --quick   # 4 surfaces

``--only`` runs the named cases alone (e.g. ``--only units paper-subset``).
Writes ``results/benchmarks/contact.csv`` and ``contact.md`` (all cases but
``units``), ``contact_units.csv`` and ``contact_units.md`` (``units``). Each
case runs in a child process with the BLAS thread count set in its
environment, because OpenBLAS reads it only at start-up.
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

from roughcontact.contact import SolverOptions, kkt_residual, solve, solve_many, sweep  # noqa: E402
from roughcontact.elasticity.halfspace import (  # noqa: E402
    PeriodicHalfSpace,
    SpectralHalfSpace,
    halfspace_influence,
)

SIGMA = 24.5e-6  # surface standard deviation [m]
CORRELATION = 1.0e-3  # ACF length b at 10 % [m] (Eq 1)
SIZE = 9.0e-3  # nominal side [m]
E = 5.11e8  # Young's modulus [Pa] (Table 1)
NU = 0.0
#: Largest approach of the paper sweep in units of sigma: about 60 % mean real
#: contact on the paper's block for these surfaces (the measured fraction is
#: reported). The clamped 10 mm block is compliant (row sum L/E = 77 C_ii), so
#: most of the approach is bulk compression.
APPROACH_END = 1600.0
#: Cache of the paper's influence matrix (built in about 3 s otherwise).
MATRIX_CACHE = Path("/tmp/roughcontact_bench_block_influence.npy")
#: Half-space dense baseline: largest approach [sigma], about 60 % contact.
APPROACH_MAX = 28.0
#: ``units`` case (issue 17): surface standard deviation [m], approaches
#: after first touch [sigma], mesh presets and the GEMM unit's columns.
UNITS_SIGMA = 30e-6
UNITS_APPROACH = (0.1, 3.0)
UNITS_MESHES = ("paper", "refined")
UNITS_COLUMNS = 60
#: Mean real area fractions at which iterations and products per step are reported.
CONTACT_LEVELS = (0.01, 0.10, 0.30)


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


def block_matrix(mesh: str = "paper"):
    """Influence matrix [m/Pa] of the paper's block with a mesh preset, and its geometry.

    The block of Table 1 (9 mm x 9 mm, 10 mm thick, 60 x 60, E 511 MPa, nu 0,
    clamped base); cached in /tmp (``MATRIX_CACHE`` for the paper's mesh).
    """
    from roughcontact.elasticity.influence import BlockGeometry, influence_matrix

    geometry = BlockGeometry(mesh=mesh)
    cache = (MATRIX_CACHE if mesh == "paper"
             else MATRIX_CACHE.with_name(f"{MATRIX_CACHE.stem}_{mesh}.npy"))
    if cache.exists():
        return np.load(cache), geometry
    matrix = influence_matrix(geometry)
    np.save(cache.with_suffix(".tmp.npy"), matrix)
    os.replace(cache.with_suffix(".tmp.npy"), cache)
    return matrix, geometry


def study_gaps(count: int, sigma: float) -> np.ndarray:
    """Gaps f = max z - z [m] of ``count`` Gaussian surfaces of the library generator.

    ``generate_many`` with seeds 0..count-1: sigma [m], Sk 0, Ku 3, exponential
    ACF with b = 1 mm, 60 x 60 over 9 mm x 9 mm.
    """
    from roughcontact.surfaces.spec import SurfaceSpec
    from roughcontact.surfaces.synthetic import generate_many

    spec = SurfaceSpec(grid=(60, 60), size=(SIZE, SIZE), sigma=sigma, skew=0, kurt=3,
                       corr_length=(CORRELATION, CORRELATION))
    return initial_gaps(generate_many(spec, np.arange(count)))


def paper_problem(count: int):
    """The paper's block influence matrix [m/Pa], element area [m^2] and gaps [m]."""
    matrix, geometry = block_matrix("paper")
    return matrix, geometry.element_area, study_gaps(count, SIGMA)


def case_paper_sweep(args, surfaces: int, steps: int, extrapolate: bool) -> dict:
    matrix, area, gaps = paper_problem(surfaces)
    approaches = np.linspace(0.0, APPROACH_END * SIGMA, args.steps + 1)[1 : steps + 1]
    start = time.perf_counter()
    result = sweep(matrix, gaps, approaches, element_area=area,
                   options=SolverOptions(method="cg", tol=args.tol, precision="mixed",
                                         stiffness=True, extrapolate=extrapolate))
    wall = time.perf_counter() - start
    return dict(
        wall_s=wall,
        solves=int(result.load.size),
        iterations_per_solve=float(result.iterations.mean()),
        matvecs_per_solve=float(result.matvecs.mean()),
        converged=bool(result.converged.all()),
        stiffness_converged=bool(result.stiffness_converged.all()),
        final_contact=float(result.real_area_fraction[:, -1].mean()),
        final_pressure_MPa=float(result.nominal_pressure[:, -1].mean() / 1e6),
        max_residual=float(result.residual.max()),
    )


def summarize(results, wall) -> dict:
    return dict(
        wall_s=wall,
        solves=len(results),
        iterations_per_solve=float(np.mean([r.iterations for r in results])),
        matvecs_per_solve=float(np.mean([r.matvecs for r in results])),
        converged=all(r.converged for r in results),
        final_contact=float(np.mean([r.real_area_fraction for r in results])),
        max_residual=float(max(r.residual for r in results)),
    )


def case_baseline_dense(args, method: str) -> dict:
    count = max(1, min(4, args.surfaces))
    gaps = initial_gaps(gaussian_surfaces(count, 60, SIZE, seed=2006))
    influence = halfspace_influence((60, 60), (SIZE, SIZE), E, NU)
    area = (SIZE / 60) ** 2
    levels = np.array([4.0, 12.0, APPROACH_MAX]) * SIGMA  # ~10, 30, 60 % contact
    batch = np.repeat(gaps, levels.size, axis=0)
    approach = np.tile(levels, count)
    start = time.perf_counter()
    results = solve_many(influence, batch, approach, element_area=area,
                         options=SolverOptions(method=method, tol=args.tol))
    return summarize(results, time.perf_counter() - start)


def case_baseline_block(args, method: str) -> dict:
    """One cold solve on the paper's block at 4 sigma (about 2 % contact)."""
    matrix, area, gaps = paper_problem(1)
    limit = 20000 if method == "steepest" else None
    start = time.perf_counter()
    result = solve(matrix, gaps[0], 4.0 * SIGMA, element_area=area,
                   options=SolverOptions(method=method, tol=args.tol, max_iter=limit))
    return summarize([result], time.perf_counter() - start)


def periodic_problem(grid: int, spectral: bool):
    """Operator, gaps and the approach for about 20 % contact on a periodic grid."""
    size = SIZE * grid / 60  # same element size as the 60 x 60 study
    operator = (SpectralHalfSpace((grid, grid), (size, size), E, NU) if spectral
                else PeriodicHalfSpace((grid, grid), (size, size), E, NU))
    gap0 = initial_gaps(gaussian_surfaces(1, grid, size, seed=512)[0])
    # Bisection on the contact fraction with loose, cheap solves. The approach
    # is measured from the mean deflected plane (zero-mean convention), so it
    # must stay below the mean gap; near it the solves get hard: cap them.
    low, high = 0.0, float(gap0.mean())
    approach = 0.5 * (low + high)
    for _ in range(12):
        fraction = solve(operator, gap0, approach,
                         options=SolverOptions(tol=1e-5, max_iter=300)).real_area_fraction
        if abs(fraction - 0.2) < 0.01:
            break
        low, high = (approach, high) if fraction < 0.2 else (low, approach)
        approach = 0.5 * (low + high)
    return operator, gap0, approach, size


def case_periodic(args, method: str, grid: int, tol: float, spectral: bool) -> dict:
    operator, gap0, approach, _ = periodic_problem(grid, spectral)
    start = time.perf_counter()
    result = solve(operator, gap0, approach, options=SolverOptions(method=method, tol=tol))
    record = summarize([result], time.perf_counter() - start)
    record.update(max_pressure_MPa=result.max_pressure / 1e6,
                  final_pressure_MPa=result.nominal_pressure / 1e6)
    return record


def score(operator, gap0, pressure, hardness=None) -> float:
    """Our KKT residual of a load-controlled pressure, ``d`` fitted on the contact.

    With a cap ``hardness`` [Pa] the approach is fitted on the elastic
    contact ``0 < p < H`` only (the saturated elements have ``g <= 0``, not
    ``g = 0``) and the residual is the capped one.
    """
    gap = operator.matvec(pressure.ravel()).reshape(gap0.shape) + gap0
    contact = pressure > 0
    if hardness is not None:
        contact &= pressure < hardness
    approach = float(np.median(gap[contact])) if contact.any() else 0.0
    return kkt_residual(operator, gap0, approach, pressure, hardness=hardness)


def case_external(args, library: str, tol: float) -> dict:
    """Tamaas or ContactMechanics at our solution's mean pressure, same heights."""
    grid = args.periodic_grid
    operator, gap0, approach, size = periodic_problem(grid, spectral=True)
    ours = solve(operator, gap0, approach, options=SolverOptions(tol=tol))
    mean_pressure = ours.nominal_pressure
    heights = -gap0  # rough surface against a flat; contact where heights are high
    modulus = E / (1 - NU**2)
    if library == "tamaas":
        import tamaas as tm

        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [size, size], [grid, grid])
        model.E, model.nu = E, NU
        solver = tm.PolonskyKeerRey(model, np.ascontiguousarray(heights), tol)
        solver.max_iter = 100000
        start = time.perf_counter()
        solver.solve(mean_pressure)
        wall = time.perf_counter() - start
        pressure = np.array(model.traction).reshape(grid, grid)
        iterations = float("nan")
    else:
        from ContactMechanics import PeriodicFFTElasticHalfSpace
        from ContactMechanics.Optimization import constrained_conjugate_gradients

        substrate = PeriodicFFTElasticHalfSpace((grid, grid), modulus, physical_sizes=(size, size))
        scale = float(np.abs(approach - gap0).max())  # our residual's unit [m]
        force = mean_pressure * size * size
        start = time.perf_counter()
        solution = constrained_conjugate_gradients(
            substrate, np.ascontiguousarray(heights), external_force=force,
            pentol=tol * scale, forcetol=tol * force / grid**2, maxiter=100000)
        wall = time.perf_counter() - start
        pressure = np.asarray(solution.jac) / operator.element_area
        iterations = float(solution.nit)
        if not solution.success:
            print(f"ContactMechanics: {solution.message}", file=sys.stderr)
    pressure = np.maximum(pressure, 0.0)
    area = float(np.count_nonzero(pressure > 0) / pressure.size)
    return dict(
        wall_s=wall, solves=1, iterations_per_solve=iterations,
        matvecs_per_solve=float("nan"), converged=True,
        final_contact=area, max_pressure_MPa=float(pressure.max() / 1e6),
        final_pressure_MPa=float(pressure.mean() / 1e6),
        max_residual=score(operator, gap0, pressure),
        ours_wall_s=float("nan"), ours_contact=ours.real_area_fraction,
        ours_max_pressure_MPa=ours.max_pressure / 1e6,
    )


def case_blas_kernels(args) -> dict:
    """Best-of-5 times of the products that dominate the solvers [s]."""
    matrix, _, _ = paper_problem(1)
    single = matrix.astype(np.float32)
    batch = np.random.default_rng(0).random((args.surfaces, matrix.shape[0]))

    return dict(
        wall_s=best_time(lambda: batch @ matrix),
        gemm_double_s=best_time(lambda: batch @ matrix),
        gemm_single_s=best_time(lambda: batch.astype(np.float32) @ single),
        gemv_single_s=best_time(lambda: batch[0].astype(np.float32) @ single),
        solves=0,
        matvecs_per_solve=float("nan"),
        converged=True,
    )


def best_time(function, repeats: int = 5) -> float:
    """Smallest wall time [s] of ``repeats`` calls of ``function``, after one warm-up."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def at_contact_level(result, level: float) -> dict:
    """Work at the step whose mean real area fraction is nearest ``level``.

    Returns the step (1-based), that fraction and the mean iterations and
    products (``matvecs``) per surface at that step.
    """
    fraction = result.real_area_fraction.mean(axis=0)
    step = int(np.argmin(np.abs(fraction - level)))
    return dict(step=step + 1, contact=float(fraction[step]),
                iterations=float(result.iterations[:, step].mean()),
                matvecs=float(result.matvecs[:, step].mean()))


def case_units(args) -> dict:
    """The issue-17 sweep on the paper and refined meshes, in GEMM units (module docstring).

    Everything is measured in this process: the GEMM unit before every round,
    then one sweep per mesh, the meshes alternating.
    """
    problems = {mesh: block_matrix(mesh) for mesh in UNITS_MESHES}
    gaps = study_gaps(args.surfaces, UNITS_SIGMA)
    start, end = args.approach_range
    approaches = np.linspace(start, end, args.steps) * UNITS_SIGMA
    unit_matrix = problems["paper"][0]
    block = np.random.default_rng(0).random((unit_matrix.shape[1], UNITS_COLUMNS))
    units, walls, results = [], {mesh: [] for mesh in UNITS_MESHES}, {}
    for _ in range(args.repeats):
        units.append(best_time(lambda: unit_matrix @ block))
        for mesh, (matrix, geometry) in problems.items():
            begin = time.perf_counter()
            results[mesh] = sweep(matrix, gaps, approaches, element_area=geometry.element_area,
                                  options=SolverOptions(method=args.method, tol=args.tol,
                                                        precision=args.precision, stiffness=True))
            walls[mesh].append(time.perf_counter() - begin)
    unit = min(units)
    rows = []
    for mesh, result in results.items():
        fraction = result.real_area_fraction.mean(axis=0)
        row = dict(
            method=args.method, mesh=mesh, surfaces=args.surfaces, steps=args.steps,
            approach_sigma=f"{start:g}-{end:g}", precision=args.precision, tol=args.tol,
            repeats=args.repeats, gemm_unit_s=unit, wall_s=min(walls[mesh]),
            wall_max_s=max(walls[mesh]), units=min(walls[mesh]) / unit,
            matvecs_total=int(result.matvecs.sum()),
            products_per_step=float(result.matvecs.mean()),
            iterations_per_step=float(result.iterations.mean()),
            contact_first=float(fraction[0]), contact_last=float(fraction[-1]),
            final_pressure_MPa=float(result.nominal_pressure[:, -1].mean() / 1e6),
            converged=bool(result.converged.all()),
            stiffness_converged=bool(result.stiffness_converged.all()),
            max_residual=float(result.residual.max()),
        )
        for level in CONTACT_LEVELS:
            found = at_contact_level(result, level)
            tag = f"{level:.0%}".replace("%", "pct")
            row.update({f"contact_at_{tag}": found["contact"],
                        f"iterations_at_{tag}": found["iterations"],
                        f"products_at_{tag}": found["matvecs"]})
        rows.append(row)
    refined = next(row for row in rows if row["mesh"] == "refined")
    for row in rows:
        row["units_over_refined"] = row["units"] / refined["units"]
    return dict(rows=rows)


CASES = {
    "blas-kernels": case_blas_kernels,
    "paper-sweep": lambda a: case_paper_sweep(a, a.surfaces, a.steps, True),
    "paper-subset": lambda a: case_paper_sweep(a, a.subset, a.subset_steps, True),
    "paper-subset-noextrapolate": lambda a: case_paper_sweep(a, a.subset, a.subset_steps,
                                                             False),
    "baseline-dense-cg": lambda a: case_baseline_dense(a, "cg"),
    "baseline-dense-steepest": lambda a: case_baseline_dense(a, "steepest"),
    "baseline-block-cg": lambda a: case_baseline_block(a, "cg"),
    "baseline-block-steepest": lambda a: case_baseline_block(a, "steepest"),
    "baseline-periodic-cg": lambda a: case_periodic(a, "cg", a.baseline_grid, a.tol, False),
    "baseline-periodic-steepest": lambda a: case_periodic(a, "steepest", a.baseline_grid,
                                                          a.tol, False),
    "periodic-ours": lambda a: case_periodic(a, "cg", a.periodic_grid, 1e-10, True),
    "periodic-tamaas": lambda a: case_external(a, "tamaas", 1e-10),
    "periodic-contactmechanics": lambda a: case_external(a, "contactmechanics", 1e-10),
    "units": case_units,
}


def plan(args) -> list[tuple[str, int]]:
    runs = [("blas-kernels", threads) for threads in (1, 2)]
    runs += [("periodic-ours", 1), ("periodic-ours", 2), ("periodic-tamaas", 1),
             ("periodic-contactmechanics", 1)]
    runs += [(name, 1) for name in CASES if name.startswith("baseline")]
    runs += [("paper-subset", 1), ("paper-subset", 2), ("paper-subset-noextrapolate", 1)]
    runs += [("paper-sweep", 1)]
    if args.sweep_two_threads:
        runs += [("paper-sweep", 2)]
    return runs


def run_child(name: str, threads: int, args, extra=()) -> dict:
    """Run case ``name`` in a child process with ``threads`` BLAS threads.

    Returns the case's record with ``case`` and ``blas_threads`` added, or a
    record with the child's last error line in ``error``.
    """
    env = dict(os.environ, OPENBLAS_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads),
               MKL_NUM_THREADS=str(threads))
    command = [sys.executable, __file__, "--child", name, *args.forward, *extra]
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    if done.returncode:
        message = (done.stderr.strip().splitlines() or ["no output"])[-1]
        print(f"{name} failed: {message}", file=sys.stderr)
        return dict(case=name, blas_threads=threads, error=message[:200])
    record = json.loads(done.stdout.strip().splitlines()[-1])
    record.update(case=name, blas_threads=threads)
    return record


def run_units(method: str, args) -> list[dict]:
    """The ``units`` case for one method, one BLAS thread: one row per mesh."""
    record = run_child("units", 1, args, [f"--method={method}"])
    if "error" in record:
        return [dict(method=method, mesh=mesh, error=record["error"]) for mesh in UNITS_MESHES]
    return record["rows"]


UNITS_COLUMNS_OUT = [
    "method", "mesh", "surfaces", "steps", "approach_sigma", "precision", "tol", "repeats",
    "gemm_unit_s", "wall_s", "wall_max_s", "units", "units_over_refined", "matvecs_total",
    "products_per_step", "iterations_per_step",
    *(f"{name}_at_{level:.0%}".replace("%", "pct") for level in CONTACT_LEVELS
      for name in ("contact", "iterations", "products")),
    "contact_first", "contact_last", "final_pressure_MPa", "converged", "stiffness_converged",
    "max_residual", "error",
]
#: Issue 17's targets: GEMM units per mesh, and paper over refined.
UNITS_TARGET, RATIO_TARGET = 500.0, 1.2


def units_findings(table) -> list[str]:
    """Findings of the ``units`` case against issue 17's targets."""
    lines = []
    for method, rows in table.groupby("method", sort=False):
        by_mesh = {row.mesh: row for row in rows.itertuples() if np.isfinite(row.units)}
        if set(by_mesh) != set(UNITS_MESHES):
            lines.append(f"- {method}: failed ({rows.error.dropna().iloc[0]})"
                         if rows.error.notna().any() else f"- {method}: incomplete")
            continue
        paper, refined = by_mesh["paper"], by_mesh["refined"]
        ratio = paper.units / refined.units
        verdict = "meets" if max(paper.units, refined.units) <= UNITS_TARGET else "misses"
        lines.append(
            f"- {method}: paper {paper.units:.0f} units ({paper.wall_s:.2f} s), refined "
            f"{refined.units:.0f} units ({refined.wall_s:.2f} s), GEMM unit "
            f"{1e3 * paper.gemm_unit_s:.1f} ms: {verdict} the {UNITS_TARGET:.0f}-unit target; "
            f"paper / refined {ratio:.2f} "
            f"({'meets' if ratio <= RATIO_TARGET else 'misses'} the {RATIO_TARGET:g} target)")
        for row in (paper, refined):
            reach = []
            for level in CONTACT_LEVELS:
                found = getattr(row, f"contact_at_{level:.0%}".replace("%", "pct"))
                missed = " (not reached)" if found < 0.5 * level else ""
                reach.append(f"{found:.2%} for {level:.0%}{missed}")
            reach = ", ".join(reach)
            flags = "all steps converged" if row.converged else "NOT all steps converged"
            lines.append(
                f"  - {row.mesh}: mean real area {row.contact_first:.2%} to "
                f"{row.contact_last:.2%} over the sweep (nearest steps: {reach}), final "
                f"{row.final_pressure_MPa:.3g} MPa; {flags}, worst residual "
                f"{row.max_residual:.4g}")
    return lines


def write_units(rows: list[dict], args, out: Path) -> None:
    """``contact_units.csv`` and ``contact_units.md`` from the ``units`` rows."""
    import pandas as pd

    out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows).reindex(columns=UNITS_COLUMNS_OUT)
    table.to_csv(out / "contact_units.csv.tmp", index=False)
    os.replace(out / "contact_units.csv.tmp", out / "contact_units.csv")
    start, end = args.approach_range
    header = (
        "# Contact sweep in GEMM units (issue 17)\n\n"
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"1 BLAS thread; numpy {np.__version__}. Units are only comparable when measured on "
        f"an idle machine.\n"
        f"Workload: {args.surfaces} Gaussian surfaces (sigma {UNITS_SIGMA * 1e6:g} um, b 1 mm, "
        f"60 x 60 over 9 mm) x {args.steps} approaches from {start:g} to {end:g} sigma after "
        f"first touch, tol {args.tol:g}, precision {args.precision}, tangent stiffness at "
        f"every step, on the paper's block (10 mm, nu 0, clamped) with the paper and the "
        f"refined mesh. GEMM unit: best of 5 products C @ P (3600 x 3600 by 3600 x "
        f"{UNITS_COLUMNS}, float64) before each round, the smallest kept; wall: the smallest "
        f"of {args.repeats} sweeps per mesh, meshes alternating. products: matvecs of the "
        f"contact solves, charged per surface (the stiffness CG's are not counted); "
        f"*_per_step: mean per surface and step; *_at_Npct: at the step whose mean real area "
        f"is nearest N % (contact_at_Npct is that step's fraction).\n\n"
    )
    findings = "\n".join(["## Findings", "", *units_findings(table)]) + "\n\n"
    summary_columns = ["method", "mesh", "units", "units_over_refined", "wall_s", "gemm_unit_s",
                       "products_per_step", "iterations_per_step",
                       *(f"{name}_at_{level:.0%}".replace("%", "pct") for level in CONTACT_LEVELS
                         for name in ("contact", "iterations"))]
    text = (header + findings + "## Summary\n\n"
            + table.reindex(columns=summary_columns).to_markdown(index=False, floatfmt=".4g")
            + "\n\n## All columns\n\n" + table.to_markdown(index=False, floatfmt=".4g") + "\n")
    (out / "contact_units.md.tmp").write_text(text)
    os.replace(out / "contact_units.md.tmp", out / "contact_units.md")


def summary(table, args) -> list[str]:
    """Findings against the targets, from the measured table."""
    lines = []

    def pick(case, threads=1):
        rows = table[(table.case == case) & (table.blas_threads == threads)]
        return rows.iloc[0] if len(rows) and np.isfinite(rows.iloc[0].wall_s) else None

    row = pick("paper-sweep")
    if row is not None:
        verdict = "meets" if row.wall_s < 30 else "misses"
        lines.append(f"- Paper sweep ({args.surfaces} x {args.steps}, mixed, stiffness): "
                     f"{row.wall_s:.1f} s with 1 BLAS thread ({verdict} the 30 s target), "
                     f"{row.iterations_per_solve:.0f} iterations per solve, final contact "
                     f"{row.final_contact:.1%}")
    on, off, two = (pick("paper-subset"), pick("paper-subset-noextrapolate"),
                    pick("paper-subset", 2))
    if on is not None and off is not None:
        lines.append(f"- Subset ({args.subset} surfaces, {args.subset_steps} steps): predictor on "
                     f"{on.wall_s:.1f} s / {on.iterations_per_solve:.0f} it per solve, off "
                     f"{off.wall_s:.1f} s / {off.iterations_per_solve:.0f} it")
    if on is not None and two is not None:
        lines.append(f"  - 2 BLAS threads: {two.wall_s:.1f} s (1 thread / 2 threads = "
                     f"{on.wall_s / two.wall_s:.2f})")
    for kind in ("dense", "block", "periodic"):
        cg, steepest = pick(f"baseline-{kind}-cg"), pick(f"baseline-{kind}-steepest")
        if cg is not None and steepest is not None:
            ratio = steepest.matvecs_per_solve / cg.matvecs_per_solve
            verdict = "meets" if ratio >= 20 else "misses"
            capped = "" if steepest.converged else " (steepest hit its cap: lower bound)"
            lines.append(f"- Matvecs per cold solve, {kind}: steepest "
                         f"{steepest.matvecs_per_solve:.0f}, cg {cg.matvecs_per_solve:.0f}: "
                         f"{ratio:.1f}x fewer for cg ({verdict} the 20x target){capped}")
    ours = pick("periodic-ours")
    for library in ("tamaas", "contactmechanics"):
        other = pick(f"periodic-{library}")
        if ours is not None and other is not None:
            lines.append(
                f"- Periodic {args.periodic_grid}^2, tol 1e-10: {library} {other.wall_s:.2f} s vs "
                f"ours {ours.wall_s:.2f} s ({other.wall_s / ours.wall_s:.1f}x); contact "
                f"{other.final_contact:.4%} vs {ours.final_contact:.4%}, max pressure "
                f"{other.max_pressure_MPa:.6g} vs {ours.max_pressure_MPa:.6g} MPa; "
                f"our KKT residual of its pressure {other.max_residual:.2g}")
    return lines


def write_tables(records: list[dict], args, out: Path) -> None:
    import pandas as pd

    out.mkdir(parents=True, exist_ok=True)
    columns = ["case", "blas_threads", "wall_s", "solves", "iterations_per_solve",
               "matvecs_per_solve", "converged", "stiffness_converged", "final_contact",
               "final_pressure_MPa", "max_pressure_MPa", "max_residual", "gemm_double_s",
               "gemm_single_s", "gemv_single_s", "error"]
    table = pd.DataFrame(records).reindex(columns=columns)
    table.to_csv(out / "contact.csv.tmp", index=False)
    os.replace(out / "contact.csv.tmp", out / "contact.csv")
    write_report(table, args, out)


def write_report(table, args, out: Path) -> None:
    header = (
        "# Contact solver benchmark\n\n"
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores "
        f"(shared; wall times vary with load). numpy {np.__version__}.\n"
        f"Paper sweep: {args.surfaces} surfaces x {args.steps} steps on the paper's FE block "
        f"matrix (3600 x 3600), tol {args.tol:g}, approach up to {APPROACH_END:g} sigma, "
        f"precision mixed, tangent stiffness at every step. Baselines: cold solves. "
        f"Periodic: spectral kernel shared by all three libraries, 1 thread; "
        f"max_residual is our KKT residual. matvecs count partial products by share.\n\n"
    )
    findings = "\n".join(["## Findings", "", *summary(table, args)]) + "\n\n"
    text = header + findings + table.to_markdown(index=False, floatfmt=".4g") + "\n"
    (out / "contact.md.tmp").write_text(text)
    os.replace(out / "contact.md.tmp", out / "contact.md")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--surfaces", type=int, default=60)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--subset", type=int, default=8)
    parser.add_argument("--subset-steps", type=int, default=5)
    parser.add_argument("--tol", type=float, default=1e-8)
    parser.add_argument("--periodic-grid", type=int, default=512)
    parser.add_argument("--baseline-grid", type=int, default=256)
    parser.add_argument("--sweep-two-threads", action="store_true",
                        help="also run the full paper sweep with 2 BLAS threads")
    parser.add_argument("--only", nargs="+", choices=sorted(CASES), metavar="CASE",
                        help=f"run only these cases (of: {', '.join(sorted(CASES))})")
    parser.add_argument("--methods", nargs="+", default=["cg"],
                        help="units: contact methods to measure, one child each (default cg)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="units: sweeps per mesh, alternating meshes; the minimum is kept")
    parser.add_argument("--approach-range", type=float, nargs=2, default=UNITS_APPROACH,
                        metavar=("START", "END"),
                        help="units: first and last approach after first touch [sigma]")
    parser.add_argument("--precision", default="mixed",
                        help="units: sweep precision (the study's: mixed)")
    parser.add_argument("--quick", action="store_true", help="small sizes, for a smoke test")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "benchmarks")
    parser.add_argument("--report", action="store_true",
                        help="only rewrite contact.md (and contact_units.md) from the csv files")
    parser.add_argument("--child", choices=sorted(CASES), help=argparse.SUPPRESS)
    parser.add_argument("--method", default="cg", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:
        args.surfaces, args.steps, args.subset, args.subset_steps = 4, 30, 2, 2
        args.periodic_grid, args.baseline_grid = 128, 64
    if args.child:
        print(json.dumps(CASES[args.child](args)))
        return
    if args.report:
        import pandas as pd

        if (args.out / "contact.csv").exists():
            write_report(pd.read_csv(args.out / "contact.csv"), args, args.out)
        if (args.out / "contact_units.csv").exists():
            write_units(pd.read_csv(args.out / "contact_units.csv").to_dict("records"),
                        args, args.out)
        return
    args.forward = [f"--surfaces={args.surfaces}", f"--steps={args.steps}",
                    f"--subset={args.subset}", f"--subset-steps={args.subset_steps}",
                    f"--tol={args.tol}", f"--periodic-grid={args.periodic_grid}",
                    f"--baseline-grid={args.baseline_grid}", f"--repeats={args.repeats}",
                    "--approach-range", *map(str, args.approach_range),
                    f"--precision={args.precision}"]
    selected = set(args.only or CASES)
    records = []
    for name, threads in plan(args):
        if name not in selected or (args.quick and name == "paper-sweep" and not args.only):
            continue
        record = run_child(name, threads, args)
        print(f"{name:28s} threads={threads} wall={record.get('wall_s', float('nan')):8.2f} s "
              f"matvecs/solve={record.get('matvecs_per_solve', float('nan')):8.1f} "
              f"converged={record.get('converged')}", flush=True)
        records.append(record)
        write_tables(records, args, args.out)
    if records:
        print(f"wrote {args.out / 'contact.csv'} and {args.out / 'contact.md'}")
    if "units" in selected:
        rows = []
        for method in args.methods:
            rows += run_units(method, args)
            for row in rows[-len(UNITS_MESHES):]:
                print(f"units {row['method']:9s} {row['mesh']:8s} "
                      f"wall={row.get('wall_s', float('nan')):8.2f} s "
                      f"units={row.get('units', float('nan')):7.0f} "
                      f"products/step={row.get('products_per_step', float('nan')):6.1f} "
                      f"contact={row.get('contact_last', float('nan')):.2%} "
                      f"converged={row.get('converged')}", flush=True)
            write_units(rows, args, args.out)
        print(f"wrote {args.out / 'contact_units.csv'} and {args.out / 'contact_units.md'}")


if __name__ == "__main__":
    main()
