"""Experiments of the speed-against-error report: solver, mesh, contact grid, surface count.

Every result of the study (Figs 7, 9-14 of Kumar, Sadeghi & Krousgrill 2006)
carries four numerical errors besides the physics: the contact solver stops
at a tolerance (Eq 27 solved to a KKT residual), the influence coefficients
come from a finite-element mesh (Eq 16), the surface is sampled on a contact
grid of finite element size, and each curve is a mean over a finite number of
random surfaces. The runners here measure each of them against its cost, on
the quantities the figures show: the normalized stiffness ``k_P = (L / A_n)
dF/dd`` (Eq 33), the real area fraction and the peak pressure, at a few
nominal pressures P. Every sweep is a contact job
(:func:`roughcontact.contact.cell.sweep_cell`).

1. :func:`solver_speed_vs_error` -- wall time, iterations and matrix products
   of the ``"steepest"`` and ``"cg"`` solvers per tolerance, and their
   relative error at equal approach against the ``"exact"`` solution (block
   principal pivoting, machine precision) of the same surfaces and approaches.
2. :func:`mesh_errors` -- the mesh presets' cost and error, read from the
   influence-convergence table (:func:`roughcontact.reports.convergence.influence_convergence`)
   rather than recomputed; :data:`FALLBACK_MESH_ERRORS` when no table exists.
3. :func:`grid_study` -- the same statistics on coarser and finer contact
   grids over the same nominal area, and the change of k_P, real area and peak
   pressure at equal P against the finest grid.
4. :func:`surfaces_per_cell` / :func:`band_vs_count` -- half-width of the 95 %
   confidence band of the mean against the number of surfaces, by
   subsampling one set of solved surfaces (no re-solve).

All timings are wall-clock seconds of single calls on whatever machine runs
them; on a shared machine they vary with its load (the tables' ``attrs``
record it, :func:`~roughcontact.reports.speed.machine.describe_machine`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd
import scipy.stats

from roughcontact.contact import aggregate, nondim
from roughcontact.contact.cell import aggregate_sweep, nondim_pressure, sweep_cell
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.reports.speed.machine import describe_machine
from roughcontact.study.jobs import BATCH_SIZE
from roughcontact.study.presets import FALLBACK_MESH_ERRORS
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import derive_seeds, generate_many

__all__ = [
    "DEFAULT_CELLS",
    "DEFAULT_COUNTS",
    "DEFAULT_TOLERANCES",
    "REFERENCE_STIFFNESS_TOL",
    "REFERENCE_TOL",
    "SOLVER_QUANTITIES",
    "band_vs_count",
    "grid_study",
    "mesh_errors",
    "solver_speed_vs_error",
    "surfaces_per_cell",
]

log = logging.getLogger("roughcontact.speed")

#: Quantities compared between a solver and the exact solution at equal approach:
#: column prefix -> (NondimSweep attribute, description). Relative errors are
#: dimensionless, so they hold for every sigma and E (Eq 28-32).
SOLVER_QUANTITIES = MappingProxyType({
    "load": ("nominal_pressure", "load F = P A_n at the prescribed approach"),
    "real_area": ("real_area_fraction", "real contact area fraction"),
    "max_pressure": ("max_pressure", "largest element pressure"),
    "k_P": ("stiffness", "normalized stiffness k_P (Eq 33), tangent at the contact set"),
})

#: Default statistics cells of the solver study: Gaussian and negatively skewed.
DEFAULT_CELLS = ((0.0, 3.0), (-0.8, 4.0))
#: Surface counts of the sampling study (the paper used 60).
DEFAULT_COUNTS = (5, 10, 20, 40, 60, 120)
#: Solver tolerances of the report: steepest descent stops at 1e-8 (at 1e-10 it
#: needs minutes per cell at 60 x 60 on the paper's mesh).
DEFAULT_TOLERANCES = MappingProxyType({"cg": (1e-4, 1e-6, 1e-8, 1e-10, 1e-12),
                                       "steepest": (1e-4, 1e-6, 1e-8)})
#: Tolerances of the exact reference: KKT residual and stiffness CG residual.
REFERENCE_TOL = 1e-12
REFERENCE_STIFFNESS_TOL = 1e-10


# ---------------------------------------------------------------------------
# Shared pieces


def _cell_key(skew: float, kurt: float) -> str:
    """Name of a statistics cell (skewness, kurtosis) in seeds and messages, e.g. ``sk0_ku3``."""
    return f"sk{float(skew):g}_ku{float(kurt):g}"


def _cell_heights(grid, size, b: float, skew: float, kurt: float, count: int, seed: int,
                  tag: str, spectrum: Mapping | None = None) -> np.ndarray:
    """``count`` surfaces of one cell in units of sigma, shape (count, ny, nx).

    Exponential ACF (Eq 1) with 10 % correlation length ``b`` [m], periodic
    filter of the pipeline; seeds from ``derive_seeds(seed, tag|cell, count)``.
    ``spectrum``: :class:`SurfaceSpec` fields replacing the ACF (e.g.
    ``acf="self-affine"``, ``hurst``, ``rolloff_wavelength``,
    ``cutoff_wavelength``); ``b`` is then unused.
    """
    if spectrum:
        spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), sigma=1.0, skew=float(skew),
                           kurt=float(kurt), **spectrum)
    else:
        spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), corr_length=(b, b), sigma=1.0,
                           skew=float(skew), kurt=float(kurt))
    seeds = derive_seeds(seed, f"{tag}|{_cell_key(skew, kurt)}", count)
    return generate_many(spec, seeds)


def _timed_sweep(unit_influence, heights, geometry: BlockGeometry, pressure_end: float,
                 steps: int, **options) -> tuple[nondim.NondimSweep, float]:
    """One :func:`~roughcontact.contact.cell.sweep_cell` and its wall time [s].

    ``options`` go to ``sweep_cell``; callers pass ``precision`` explicitly
    (the sweep's default is "mixed", the exact reference needs "double").
    """
    start = time.perf_counter()
    sweep = sweep_cell(unit_influence, heights, geometry, pressure_end, steps, **options)
    return sweep, time.perf_counter() - start


def _nearest_steps(nominal_pressure: np.ndarray, level: float) -> np.ndarray:
    """Per surface, the step whose (positive) P is nearest ``level`` in log P."""
    with np.errstate(divide="ignore"):
        distance = np.abs(np.log(np.where(nominal_pressure > 0.0, nominal_pressure, np.nan))
                          - math.log(level))
    distance = np.where(np.isfinite(distance), distance, np.inf)
    return np.argmin(distance, axis=1)


def _relative_error(value: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``|value / reference - 1|``; 0 where both are 0, inf where only the reference is."""
    value = np.asarray(value, dtype=float)
    reference = np.asarray(reference, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        error = np.abs(value / reference - 1.0)
    error = np.where((reference == 0.0) & (value == 0.0), 0.0, error)
    return np.where((reference == 0.0) & (value != 0.0), np.inf, error)


# ---------------------------------------------------------------------------
# 1. Solver


def solver_speed_vs_error(
    unit_influence,
    geometry: BlockGeometry,
    cells: Sequence[tuple[float, float]] = DEFAULT_CELLS,
    *,
    surfaces: int = 4,
    sigma: float = 24.5e-6,
    b: float = 1e-3,
    pressures: Sequence[float] = (0.3e6, 1e6, 3e6),
    tolerances: Sequence[float] | Mapping = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12),
    methods: Sequence[str] = ("steepest", "cg"),
    precision: str = "mixed",
    steps: int = 30,
    stiffness_tol: float = 1e-6,
    max_iter: int | Mapping | None = None,
    seed: int = 2006,
    label: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Wall time and error of each solver and tolerance against the exact solution.

    For each cell ``(skew, kurt)``, ``surfaces`` surfaces (exponential ACF,
    Eq 1, 10 % correlation length ``b``, sampled on ``geometry.grid`` over
    ``geometry.size``; seeds ``derive_seeds(seed, "speed_vs_error|<cell>")``)
    are swept over the pipeline's approach grid
    (:func:`roughcontact.contact.cell.approach_grid`, ``steps`` geometric
    approaches up to one that carries ``max(pressures)`` on every surface)
    with :func:`roughcontact.contact.cell.sweep_cell`, exactly as a contact job
    does (all surfaces in one batch, warm starts and tangent predictor
    between steps, tangent stiffness at every step). The reference is
    ``method="exact"`` (block principal pivoting) at KKT tolerance
    ``REFERENCE_TOL`` with the stiffness CG at ``REFERENCE_STIFFNESS_TOL``;
    every other run uses ``stiffness_tol`` (the pipeline's 1e-6), so the k_P
    error of a tight solve is floored near it.

    Errors are taken at equal approach (the same problem): for each pressure
    level in ``pressures`` and each surface, the step whose exact nominal
    pressure is nearest the level (in log P); the columns ``<q>_error`` hold
    the largest ``|q / q_exact - 1|`` over the surfaces, for q = load (F, or P
    at equal approach), real_area (real area fraction), max_pressure and k_P
    (Eq 33). All are dimensionless, so they hold for every sigma and E
    (Eq 28-32); ``sigma`` and ``geometry.E`` only place the pressure levels.

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator
        ``E * C`` [m] of ``geometry``
        (:func:`roughcontact.elasticity.influence.unit_modulus_influence`).
    geometry : BlockGeometry
        Plan size [m], thickness L [m], grid and E [Pa] of that matrix.
    cells : sequence of (skew, kurt)
        Height statistics (Eq 4-5).
    surfaces : int
        Surfaces per cell.
    sigma, b : float
        Height standard deviation and ACF correlation length [m].
    pressures : sequence of float
        Nominal pressures P [Pa] at which the errors are read.
    tolerances : sequence of float, or dict method -> sequence
        KKT tolerances (:mod:`roughcontact.contact`) of each method (a dict
        gives each method its own; a method missing from it is skipped).
    methods : sequence of str
        Methods compared; ``"exact"`` may be included (errors ~0: the
        reference solves the same problem).
    precision : {"mixed", "double"}
        Precision of the iterative solvers (the pipeline's default: mixed).
    steps : int
        Approaches per sweep (the pipeline's default: 30).
    stiffness_tol : float
        Relative residual of the stiffness CG of the compared runs.
    max_iter : int, dict or None
        Iteration limit per solve, or a dict method -> limit; None: the
        solver's default. A run that hits it reports ``converged_fraction < 1``.
    seed : int
        Study seed of the surfaces.
    label : str, optional
        Name of the influence operator, stored in column ``influence``.
    progress : callable, optional
        Called with a one-line message after each run.

    Returns
    -------
    pandas.DataFrame
        One row per (cell, method, tol, pressure level), the exact reference
        included (``method="exact"``, ``tol=REFERENCE_TOL``, ``reference=True``).
        Columns: ``influence``, ``grid_x``, ``grid_y``, ``skew``, ``kurt``,
        ``surfaces``, ``steps``, ``method``, ``tol``, ``precision``,
        ``reference``, ``pressure_Pa`` (level), ``pressure_at_step_Pa`` (mean
        exact P at the compared steps), ``real_area_exact`` (mean exact area
        fraction there), ``wall_s`` (the whole sweep of the cell: all
        surfaces, all steps), ``solves``, ``iterations_per_solve``,
        ``matvecs_per_solve`` (exact: pivots + 2), ``converged_fraction``,
        ``max_residual``, ``load_error``, ``real_area_error``,
        ``max_pressure_error``, ``k_P_error``, ``reference_wall_s``,
        ``final_real_area_exact`` (mean exact area fraction at the last step).
    """
    if surfaces < 1:
        raise ValueError(f"surfaces must be >= 1, got {surfaces!r}")
    levels = np.asarray(pressures, dtype=float)
    if levels.ndim != 1 or levels.size == 0 or (levels <= 0).any():
        raise ValueError("pressures must be positive nominal pressures [Pa]")
    label = label or (geometry.mesh if isinstance(geometry.mesh, str) else "custom")
    say = progress or (lambda message: log.info("%s", message))
    end = nondim_pressure(levels.max(), thickness=geometry.thickness, E=geometry.E,
                          sigma=sigma)
    rows = []
    for skew, kurt in cells:
        heights = _cell_heights(geometry.grid, geometry.size, b, skew, kurt, surfaces, seed,
                                "speed_vs_error")
        reference, reference_s = _timed_sweep(
            unit_influence, heights, geometry, end, steps, method="exact", tol=REFERENCE_TOL,
            precision="double", stiffness_tol=REFERENCE_STIFFNESS_TOL, max_iter=None)
        if not reference.converged.all():
            log.warning("exact reference did not converge on %d steps of cell %s",
                        int((~reference.converged).sum()), _cell_key(skew, kurt))
        say(f"{label} {_cell_key(skew, kurt)}: exact reference {reference_s:.1f} s, "
            f"final contact {100 * reference.real_area_fraction[:, -1].mean():.2f} %")
        P_ref = reference.nominal_pressure * geometry.E * sigma / geometry.thickness
        chosen = {level: _nearest_steps(P_ref, level) for level in levels}
        runs = [("exact", REFERENCE_TOL, True, reference, reference_s)]
        for method in methods:
            own = tolerances.get(method, ()) if isinstance(tolerances, Mapping) else tolerances
            for tol in own:
                limit = max_iter.get(method) if isinstance(max_iter, Mapping) else max_iter
                nd, seconds = _timed_sweep(
                    unit_influence, heights, geometry, end, steps, method=method,
                    tol=float(tol), precision="double" if method == "exact" else precision,
                    stiffness_tol=stiffness_tol, max_iter=limit)
                runs.append((method, float(tol), False, nd, seconds))
                say(f"{label} {_cell_key(skew, kurt)}: {method} tol {tol:.0e} {seconds:.1f} s, "
                    f"{nd.iterations.mean():.0f} iterations per solve, "
                    f"{100 * nd.converged.mean():.0f} % converged")
        surface_index = np.arange(surfaces)
        for method, tol, is_reference, nd, seconds in runs:
            base = {
                "influence": label, "grid_x": geometry.grid[0], "grid_y": geometry.grid[1],
                "skew": float(skew), "kurt": float(kurt), "surfaces": surfaces, "steps": steps,
                "method": method, "tol": tol,
                "precision": "double" if method == "exact" else precision,
                "reference": is_reference, "wall_s": seconds, "solves": nd.iterations.size,
                "iterations_per_solve": float(nd.iterations.mean()),
                "matvecs_per_solve": float(nd.matvecs.mean()),
                "converged_fraction": float(nd.converged.mean()),
                "max_residual": float(np.nanmax(nd.residual)),
                "reference_wall_s": reference_s,
                "final_real_area_exact": float(reference.real_area_fraction[:, -1].mean()),
            }
            for level in levels:
                at = (surface_index, chosen[level])
                row = base | {
                    "pressure_Pa": float(level),
                    "pressure_at_step_Pa": float(P_ref[at].mean()),
                    "real_area_exact": float(reference.real_area_fraction[at].mean()),
                }
                for name, (attribute, _) in SOLVER_QUANTITIES.items():
                    error = _relative_error(getattr(nd, attribute)[at],
                                            getattr(reference, attribute)[at])
                    row[f"{name}_error"] = float(np.max(error))
                rows.append(row)
    table = pd.DataFrame(rows)
    table.attrs.update(
        comparison="relative error at equal approach against method='exact' "
                   f"(tol {REFERENCE_TOL:g}, stiffness tol {REFERENCE_STIFFNESS_TOL:g}); "
                   "largest over surfaces at the step nearest each pressure level",
        stiffness_tol=stiffness_tol, sigma=sigma, b=b, seed=seed, machine=describe_machine())
    return table


# ---------------------------------------------------------------------------
# 2. Mesh (read, not recomputed)


def mesh_errors(convergence_csv=None, hybrid_csv=None) -> pd.DataFrame:
    """Cost and largest contact-quantity error of each mesh preset.

    Reads the tidy table of :func:`roughcontact.reports.convergence.influence_convergence`
    (``results/benchmarks/influence_convergence.csv``): per mesh the build
    time, peak memory, and the largest |relative error| over its pressures
    of k_P (Eq 33), real area fraction and peak pressure against its
    reference mesh, plus the signed range of each. ``hybrid_csv`` (the
    benchmark ``influence_hybrid.csv``, long format ``operator, seconds,
    peak_gb, quantity, value``) adds the hybrid half-space + coarse-FE
    operators. Without a table, :data:`FALLBACK_MESH_ERRORS` is used
    (``source`` says which).

    Returns
    -------
    pandas.DataFrame
        Columns ``mesh``, ``build_s``, ``peak_memory_GB``, ``k_P_error``,
        ``real_area_error``, ``max_pressure_error`` (largest |relative
        error|), ``k_P_range``, ``real_area_range``, ``max_pressure_range``
        (signed min..max as text), ``reference``, ``source``.
    """
    rows = []
    if convergence_csv is not None and Path(convergence_csv).exists():
        table = pd.read_csv(convergence_csv)
        table = table[table["kind"] != "richardson"]
        names = {"k_P": "k_P_Pa_error", "real_area": "real_area_fraction_error",
                 "max_pressure": "max_pressure_Pa_error"}
        for mesh, group in table.groupby("mesh", sort=False):
            row = {"mesh": mesh, "build_s": float(group["build_s"].iloc[0]),
                   "peak_memory_GB": float(group["peak_memory_GB"].iloc[0])}
            for name, column in names.items():
                values = group[column].to_numpy(float)
                row[f"{name}_error"] = float(np.nanmax(np.abs(values)))
                row[f"{name}_range"] = (f"{100 * np.nanmin(values):+.1f}..."
                                        f"{100 * np.nanmax(values):+.1f} %")
            row["reference"] = str(group["reference"].iloc[0])
            row["source"] = str(convergence_csv)
            rows.append(row)
    else:
        for mesh, values in FALLBACK_MESH_ERRORS.items():
            rows.append({"mesh": mesh, **values, "reference": "converged",
                         "source": "FALLBACK_MESH_ERRORS"})
    if hybrid_csv is not None and Path(hybrid_csv).exists():
        hybrid = pd.read_csv(hybrid_csv)
        hybrid = hybrid[hybrid["operator"].str.startswith("hybrid")]
        for operator, group in hybrid.groupby("operator", sort=False):
            row = {"mesh": operator, "build_s": float(group["seconds"].iloc[0]),
                   "peak_memory_GB": float(group["peak_gb"].iloc[0])}
            for name, prefix in (("k_P", "k_P_Pa_error_at"),
                                 ("real_area", "real_area_fraction_error_at"),
                                 ("max_pressure", "max_pressure_Pa_error_at")):
                values = group.loc[group["quantity"].str.startswith(prefix),
                                   "value"].to_numpy(float)
                row[f"{name}_error"] = float(np.nanmax(np.abs(values)))
                row[f"{name}_range"] = (f"{100 * np.nanmin(values):+.1f}..."
                                        f"{100 * np.nanmax(values):+.1f} %")
            row["reference"] = "converged"
            row["source"] = str(hybrid_csv)
            rows.append(row)
    return pd.DataFrame(rows)


# ---------------------------------------------------------------------------
# 3. Contact grid


def _grid_influence(geometry: BlockGeometry, influence: str, coarsening: int):
    if influence == "hybrid":
        # matrix-free (the same operator as the dense hybrid matrix, without its
        # 8 n^2 bytes)
        coarse = operators.coarsened_side(geometry.grid[0], coarsening)
        return operators.block_operator(geometry, coarse_grid=(coarse, coarse))
    if influence == "halfspace":
        return halfspace_influence(geometry.grid, geometry.size, 1.0, geometry.nu)
    if influence == "halfspace_fft":
        return operators.halfspace_operator(geometry.grid, geometry.size, geometry.nu)
    if influence == "fe":
        return unit_modulus_influence(geometry)
    raise ValueError("influence must be 'hybrid', 'halfspace', 'halfspace_fft' or 'fe', "
                     f"got {influence!r}")


def grid_study(
    cells: Sequence[tuple[float, float]] = ((0.0, 3.0),),
    *,
    grids: Sequence[int] = (30, 60, 120),
    size: float = 9e-3,
    thickness: float = 10e-3,
    E: float = 5.11e8,
    nu: float = 0.0,
    base: str = "clamped",
    influence: str = "hybrid",
    mesh: str = "refined",
    coarsening: int = 2,
    surfaces: int = 4,
    sigma: float = 24.5e-6,
    b: float = 1e-3,
    pressures: Sequence[float] = (0.3e6, 1e6, 3e6),
    pairing: str = "nested",
    method: str = "cg",
    tol: float = 1e-8,
    precision: str = "mixed",
    steps: int = 30,
    seed: int = 2006,
    progress: Callable[[str], None] | None = None,
    spectrum: Mapping | None = None,
) -> pd.DataFrame:
    """k_P, real area and peak pressure of the same statistics on several contact grids.

    A square block ``size`` x ``size`` [m], ``thickness`` L [m], meshed with
    ``g`` x ``g`` contact elements for each ``g`` in ``grids``. The influence
    coefficients come from

    - ``"hybrid"`` (default): the matrix-free
      :class:`roughcontact.elasticity.operators.BlockOperator` (equal to
      :func:`roughcontact.elasticity.influence.hybrid_unit_modulus_influence`) with
      ``mesh`` (default ``"refined"``) on a grid ``coarsening`` times coarser,
      at most ``operators.COARSE_MAX`` per side (no dense matrix, so 256 x 256
      fits): Love's near field plus the finite-body correction, within
      1.2 % of the converged preset in k_P, area and peak pressure at
      60 x 60 for about 3 s; the refined finite-element model itself at
      120 x 120 would be four times the 60 x 60 model (about 0.5 M dofs).
    - ``"halfspace"``: Love's half-space (no finite-body bulk: k_P about
      11-17 % high at 60 x 60, fine for the *change* between grids only).
    - ``"halfspace_fft"``: the same Love half-space, matrix-free
      (:func:`roughcontact.elasticity.operators.halfspace_operator`, FFT
      convolution, no n^2 matrix), for grids of 240 x 240 and more.
    - ``"fe"``: :func:`~roughcontact.elasticity.influence.unit_modulus_influence` with ``mesh``.

    Surfaces (exponential ACF, Eq 1; ``sigma``, ``b``): with
    ``pairing="nested"`` (default) ``surfaces`` surfaces are generated on the
    finest grid and every coarser grid point-samples them (every k-th point:
    the same random field, the same statistics, a coarser grid), so the change
    between grids is the discretization alone; with ``"independent"`` each
    grid gets its own surfaces (seeds per grid) and the change also holds
    sampling noise (see the ``*_half_width`` columns). ``spectrum``, a mapping
    of :class:`~roughcontact.surfaces.synthetic.SurfaceSpec` fields such as
    ``{"acf": "self-affine", "hurst": 0.8, "rolloff_wavelength": 3e-3,
    "cutoff_wavelength": 0.6e-3}``, replaces the exponential ACF (``b`` is then
    unused): with the cut-off resolved, real area and peak pressure converge
    with the grid, which they do not for Eq 1. Each grid is swept as a
    contact job (:func:`roughcontact.contact.cell.sweep_cell`, ``method``, ``tol``,
    ``precision``, ``steps``) and averaged at equal P
    (:func:`roughcontact.contact.cell.aggregate_sweep`).

    Returns
    -------
    pandas.DataFrame
        One row per (cell, grid, pressure): ``skew``, ``kurt``, ``grid``,
        ``element_size_m``, ``influence_model``, ``pairing``, ``build_s``
        (influence), ``solve_s`` (all surfaces), ``surfaces``,
        ``converged_fraction``, ``pressure_Pa``, ``k_P_Pa``,
        ``k_P_half_width_Pa``, ``real_area_fraction``,
        ``real_area_half_width``, ``max_pressure_Pa``,
        ``max_pressure_half_width_Pa`` (95 % band of the mean), and
        ``k_P_change``, ``real_area_change``, ``max_pressure_change``: the
        relative change ``q / q_finest - 1`` against the finest grid.
    """
    grids = sorted(int(g) for g in grids)
    finest = grids[-1]
    if pairing not in ("nested", "independent"):
        raise ValueError(f"pairing must be 'nested' or 'independent', got {pairing!r}")
    if pairing == "nested" and any(finest % g for g in grids):
        raise ValueError(f"nested pairing needs every grid to divide the finest, got {grids}")
    say = progress or (lambda message: log.info("%s", message))
    model = (f"hybrid ({mesh}, coarsening {coarsening})" if influence == "hybrid"
             else (influence if influence.startswith("halfspace") else f"fe ({mesh})"))
    levels = np.asarray(pressures, dtype=float)
    rows = []
    fine_heights = {}
    if pairing == "nested":
        for skew, kurt in cells:
            fine_heights[(skew, kurt)] = _cell_heights((finest, finest), (size, size), b, skew,
                                                       kurt, surfaces, seed, "grid_study",
                                                       spectrum)
    for g in reversed(grids):
        geometry = BlockGeometry(size=(size, size), thickness=thickness, grid=(g, g), E=E,
                                 nu=nu, base=base, mesh=mesh)
        start = time.perf_counter()
        unit = _grid_influence(geometry, influence, coarsening)
        build_s = time.perf_counter() - start
        for skew, kurt in cells:
            if pairing == "nested":
                k = finest // g
                heights = fine_heights[(skew, kurt)][:, ::k, ::k]
                heights = heights / heights.std(axis=(1, 2), keepdims=True)
            else:
                heights = _cell_heights((g, g), (size, size), b, skew, kurt, surfaces, seed,
                                        f"grid_study|{g}", spectrum)
            end = nondim_pressure(levels.max(), thickness=thickness, E=E, sigma=sigma)
            nd, solve_s = _timed_sweep(unit, heights, geometry, end, steps, method=method,
                                       tol=tol, precision=precision, stiffness_tol=1e-6,
                                       max_iter=None)
            _, frame = aggregate_sweep(nd, sigma, E, levels)
            say(f"grid {g} x {g} {_cell_key(skew, kurt)}: influence {build_s:.1f} s, "
                f"sweep {solve_s:.1f} s")
            for _, agg in frame.iterrows():
                rows.append({
                    "skew": float(skew), "kurt": float(kurt), "grid": g,
                    "element_size_m": size / g, "influence_model": model, "pairing": pairing,
                    "build_s": build_s, "solve_s": solve_s, "surfaces": surfaces,
                    "converged_fraction": float(nd.converged.mean()),
                    "pressure_Pa": float(agg["nominal_pressure"]),
                    "k_P_Pa": agg["normalized_stiffness_mean"],
                    "k_P_half_width_Pa": agg["normalized_stiffness_half_width"],
                    "real_area_fraction": agg["real_area_fraction_mean"],
                    "real_area_half_width": agg["real_area_fraction_half_width"],
                    "max_pressure_Pa": agg["max_pressure_mean"],
                    "max_pressure_half_width_Pa": agg["max_pressure_half_width"],
                })
        del unit
    table = pd.DataFrame(rows).sort_values(["skew", "kurt", "grid", "pressure_Pa"],
                                           ignore_index=True)
    keys = ["skew", "kurt", "pressure_Pa"]
    finest_rows = table[table["grid"] == finest].set_index(keys)
    for name, column in (("k_P", "k_P_Pa"), ("real_area", "real_area_fraction"),
                         ("max_pressure", "max_pressure_Pa")):
        reference = finest_rows[column].reindex(pd.MultiIndex.from_frame(table[keys]))
        table[f"{name}_change"] = table[column].to_numpy() / reference.to_numpy() - 1.0
    table.attrs.update(influence_model=model, pairing=pairing, method=method, tol=tol,
                       spectrum=dict(spectrum or {}),
                       machine=describe_machine())
    return table


# ---------------------------------------------------------------------------
# 4. Surfaces per cell


def band_vs_count(
    physical: nondim.PhysicalSweep,
    pressures: Sequence[float],
    counts: Sequence[int] = DEFAULT_COUNTS,
    *,
    draws: int = 200,
    confidence: float = 0.95,
    seed: int = 0,
) -> pd.DataFrame:
    """Half-width of the confidence band of the cell mean against the surface count.

    From one solved set of m surfaces (no re-solve): each surface's k_P,
    real area fraction and peak pressure are interpolated at ``pressures``
    (:func:`roughcontact.contact.aggregate.surface_curves`, a power law between
    steps), then for each count c <= m, ``draws`` random subsets of c surfaces (without
    replacement; one subset when c = m) give the Student-t half-width
    ``t_{(1+c)/2, c-1} s / sqrt(c)`` of the band of
    :func:`~roughcontact.contact.aggregate.aggregate_cell`.
    Reported: the mean half-width over the subsets, and relative to the mean
    of all m surfaces. Counts above m are skipped.

    Returns
    -------
    pandas.DataFrame
        One row per (count, pressure): ``count``, ``pressure_Pa``, and for q in
        k_P (Pa), real_area (fraction), max_pressure (Pa): ``<q>_mean`` (all m
        surfaces), ``<q>_half_width`` and ``<q>_relative_half_width``;
        ``draws``, ``surfaces_solved``.
    """
    levels = np.asarray(pressures, dtype=float)
    rng = np.random.default_rng(seed)
    quantities = {"k_P": "normalized_stiffness", "real_area": "real_area_fraction",
                  "max_pressure": "max_pressure"}
    samples = {name: aggregate.surface_curves(physical, levels, q)
               for name, q in quantities.items()}
    m = physical.nominal_pressure.shape[0]
    t_factor = scipy.stats.t.ppf(0.5 * (1.0 + confidence), np.arange(1, m + 1) - 1)
    rows = []
    for count in sorted(int(c) for c in counts):
        if count < 2 or count > m:
            continue
        n_draws = 1 if count == m else int(draws)
        subsets = np.stack([rng.choice(m, size=count, replace=False) for _ in range(n_draws)])
        for j, level in enumerate(levels):
            row = {"count": count, "pressure_Pa": float(level), "draws": n_draws,
                   "surfaces_solved": m}
            for name, values in samples.items():
                column = values[:, j]
                picked = column[subsets]  # (draws, count)
                finite = np.isfinite(picked)
                n = finite.sum(axis=1)
                std = np.array([np.std(p[f], ddof=1) if f.sum() > 1 else np.nan
                                for p, f in zip(picked, finite, strict=True)])
                half = np.where(n > 1, t_factor[np.maximum(n - 1, 0)] * std / np.sqrt(n),
                                np.nan)
                mean_all = float(np.nanmean(column))
                row[f"{name}_mean"] = mean_all
                row[f"{name}_half_width"] = float(np.nanmean(half))
                row[f"{name}_relative_half_width"] = float(np.nanmean(half)) / abs(mean_all)
            rows.append(row)
    table = pd.DataFrame(rows)
    table.attrs.update(confidence=confidence, draws=draws, surfaces_solved=m)
    return table


def surfaces_per_cell(
    unit_influence,
    geometry: BlockGeometry,
    cell: tuple[float, float] = (0.0, 3.0),
    *,
    surfaces: int = 120,
    counts: Sequence[int] = DEFAULT_COUNTS,
    sigma: float = 24.5e-6,
    b: float = 1e-3,
    pressures: Sequence[float] = (0.3e6, 1e6, 3e6),
    method: str = "cg",
    tol: float = 1e-8,
    precision: str = "mixed",
    steps: int = 30,
    batch_size: int = BATCH_SIZE,
    draws: int = 200,
    seed: int = 2006,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Solve ``surfaces`` surfaces of one cell once, then :func:`band_vs_count`.

    Surfaces as in :func:`solver_speed_vs_error` (seeds
    ``derive_seeds(seed, "surfaces_per_cell|<cell>")``), swept like a contact
    job (batches of ``batch_size``). Adds columns ``skew``, ``kurt`` and
    ``solve_s`` (all surfaces).
    """
    skew, kurt = cell
    heights = _cell_heights(geometry.grid, geometry.size, b, skew, kurt, surfaces, seed,
                            "surfaces_per_cell")
    end = nondim_pressure(max(pressures), thickness=geometry.thickness, E=geometry.E,
                          sigma=sigma)
    nd, solve_s = _timed_sweep(unit_influence, heights, geometry, end, steps, method=method,
                               tol=tol, precision=precision, batch_size=batch_size)
    (progress or (lambda message: log.info("%s", message)))(
        f"{_cell_key(skew, kurt)}: {surfaces} surfaces swept in {solve_s:.1f} s")
    table = band_vs_count(nondim.to_physical(nd, sigma, geometry.E), pressures, counts,
                          draws=draws, seed=seed)
    table.insert(0, "kurt", float(kurt))
    table.insert(0, "skew", float(skew))
    table["solve_s"] = solve_s
    return table


