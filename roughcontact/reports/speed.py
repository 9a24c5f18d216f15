"""Speed against error of the numerical choices: solver, mesh, contact grid, surface count.

Every result of the study (Figs 7, 9-14 of Kumar, Sadeghi & Krousgrill 2006)
carries four numerical errors besides the physics: the contact solver stops
at a tolerance (Eq 27 solved to a KKT residual), the influence coefficients
come from a finite-element mesh (Eq 16), the surface is sampled on a contact
grid of finite element size, and each curve is a mean over a finite number of
random surfaces. This module measures each of them against its cost, on the
quantities the figures show: the normalized stiffness ``k_P = (L / A_n)
dF/dd`` (Eq 33), the real area fraction and the peak pressure, at a few
nominal pressures P, and recommends the cheapest settings that meet a stated
tolerance.

1. :func:`solver_speed_vs_error` -- wall time, iterations and matrix products
   of the ``"steepest"`` and ``"cg"`` solvers per tolerance, and their
   relative error at equal approach against the ``"exact"`` solution (block
   principal pivoting, machine precision) of the same surfaces and approaches.
2. :func:`mesh_errors` -- the mesh presets' cost and error, read from the
   influence-convergence table (:func:`roughcontact.convergence.influence_convergence`)
   rather than recomputed; :data:`FALLBACK_MESH_ERRORS` when no table exists.
3. :func:`grid_study` -- the same statistics on coarser and finer contact
   grids over the same nominal area, and the change of k_P, real area and peak
   pressure at equal P against the finest grid.
4. :func:`surfaces_per_cell` / :func:`band_vs_count` -- half-width of the 95 %
   confidence band of the mean against the number of surfaces, by
   subsampling one set of solved surfaces (no re-solve).
5. :func:`recommend` -- per component, the cheapest option within tolerance.
6. :func:`write_report` / :func:`speed_vs_error_report` -- Markdown, tidy CSV
   and PNG, written atomically.

All timings are wall-clock seconds of single calls on whatever machine runs
them; on a shared machine they vary with its load (the report records the
load average before and after).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import platform
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd
import scipy.stats

from roughcontact.contact import aggregate, nondim
from roughcontact.contact.cell import approach_grid, nondim_pressure
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import (
    BlockGeometry,
    hybrid_unit_modulus_influence,
    unit_modulus_influence,
)
from roughcontact.study.jobs import BATCH_SIZE
from roughcontact.study.presets import ACCURACY_PRESETS, FALLBACK_MESH_ERRORS
from roughcontact.study.provenance import atomic_path, git_commit
from roughcontact.surfaces.synthetic import SurfaceSpec, derive_seeds, generate_many

__all__ = [
    "ACCURACY_PRESETS",
    "FALLBACK_MESH_ERRORS",
    "SOLVER_QUANTITIES",
    "band_vs_count",
    "grid_study",
    "mesh_errors",
    "recommend",
    "solver_speed_vs_error",
    "speed_vs_error_report",
    "surfaces_per_cell",
    "write_report",
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
    return f"sk{float(skew):g}_ku{float(kurt):g}"


def _cell_heights(grid, size, b: float, skew: float, kurt: float, count: int, seed: int,
                  tag: str) -> np.ndarray:
    """``count`` surfaces of one cell in units of sigma, shape (count, ny, nx).

    Exponential ACF (Eq 1) with 10 % correlation length ``b`` [m], periodic
    filter of the pipeline; seeds from ``derive_seeds(seed, tag|cell, count)``.
    """
    spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), corr_length=(b, b), sigma=1.0,
                       skew=float(skew), kurt=float(kurt))
    seeds = derive_seeds(seed, f"{tag}|{_cell_key(skew, kurt)}", count)
    return generate_many(spec, seeds)


def _pressure_end(pressures, geometry: BlockGeometry, sigma: float) -> float:
    """Non-dimensional pressure ``P L / (E sigma)`` the sweep must reach."""
    return nondim_pressure(np.max(pressures), thickness=geometry.thickness, E=geometry.E,
                           sigma=sigma)


def _solve(unit_influence, heights, geometry: BlockGeometry, approaches, *, method: str,
           tol: float, precision: str, stiffness_tol: float, max_iter):
    """One timed :func:`roughcontact.nondim.solve_cell` of all surfaces (one batch)."""
    start = time.perf_counter()
    nd = nondim.solve_cell(unit_influence, heights, thickness=geometry.thickness,
                           element_area=geometry.element_area, approaches=approaches,
                           method=method, tol=tol, max_iter=max_iter,
                           stiffness_tol=stiffness_tol, precision=precision)
    return nd, time.perf_counter() - start


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


def _is_reference(column: pd.Series) -> np.ndarray:
    """The ``reference`` flags as booleans (also after a CSV round trip: "True"/"False")."""
    return column.astype(str).str.lower().isin(("true", "1", "1.0")).to_numpy()


def _machine() -> str:
    load = os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3
    return (f"{platform.machine()}, {os.cpu_count()} cores, load average {load[0]:.2f}, "
            f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")


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
    (:func:`roughcontact.pipeline.sweep_approaches`, ``steps`` geometric
    approaches up to one that carries ``max(pressures)`` on every surface)
    with :func:`roughcontact.nondim.solve_cell`, exactly as a contact job
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
        ``E * C`` [m] of ``geometry`` (:func:`roughcontact.influence.unit_modulus_influence`).
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
    rows = []
    for skew, kurt in cells:
        heights = _cell_heights(geometry.grid, geometry.size, b, skew, kurt, surfaces, seed,
                                "speed_vs_error")
        approaches = approach_grid(heights, _pressure_end(levels, geometry, sigma),
                                               steps)
        reference, reference_s = _solve(unit_influence, heights, geometry, approaches,
                                        method="exact", tol=REFERENCE_TOL, precision="double",
                                        stiffness_tol=REFERENCE_STIFFNESS_TOL, max_iter=None)
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
                nd, seconds = _solve(unit_influence, heights, geometry, approaches,
                                     method=method, tol=float(tol),
                                     precision="double" if method == "exact" else precision,
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
        stiffness_tol=stiffness_tol, sigma=sigma, b=b, seed=seed, machine=_machine())
    return table


# ---------------------------------------------------------------------------
# 2. Mesh (read, not recomputed)


def mesh_errors(convergence_csv=None, hybrid_csv=None) -> pd.DataFrame:
    """Cost and largest contact-quantity error of each mesh preset.

    Reads the tidy table of :func:`roughcontact.convergence.influence_convergence`
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
    if influence == "fe":
        return unit_modulus_influence(geometry)
    raise ValueError(f"influence must be 'hybrid', 'halfspace' or 'fe', got {influence!r}")


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
) -> pd.DataFrame:
    """k_P, real area and peak pressure of the same statistics on several contact grids.

    A square block ``size`` x ``size`` [m], ``thickness`` L [m], meshed with
    ``g`` x ``g`` contact elements for each ``g`` in ``grids``. The influence
    coefficients come from

    - ``"hybrid"`` (default): the matrix-free
      :class:`roughcontact.operators.BlockOperator` (equal to
      :func:`roughcontact.influence.hybrid_unit_modulus_influence`) with
      ``mesh`` (default ``"refined"``) on a grid ``coarsening`` times coarser,
      at most ``operators.COARSE_MAX`` per side (no dense matrix, so 256 x 256
      fits): Love's near field plus the finite-body correction, within
      1.2 % of the converged preset in k_P, area and peak pressure at
      60 x 60 for about 3 s; the refined finite-element model itself at
      120 x 120 would be four times the 60 x 60 model (about 0.5 M dofs).
    - ``"halfspace"``: Love's half-space (no finite-body bulk: k_P about
      11-17 % high at 60 x 60, fine for the *change* between grids only).
    - ``"fe"``: :func:`~roughcontact.influence.unit_modulus_influence` with ``mesh``.

    Surfaces (exponential ACF, Eq 1; ``sigma``, ``b``): with
    ``pairing="nested"`` (default) ``surfaces`` surfaces are generated on the
    finest grid and every coarser grid point-samples them (every k-th point:
    the same random field, the same statistics, a coarser grid), so the change
    between grids is the discretization alone; with ``"independent"`` each
    grid gets its own surfaces (seeds per grid) and the change also holds
    sampling noise (see the ``*_half_width`` columns). Each grid is swept as a
    contact job (:func:`roughcontact.nondim.solve_cell`, ``method``, ``tol``,
    ``precision``, ``steps``) and averaged at equal P
    (:func:`roughcontact.aggregate.aggregate_cell`).

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
             else (influence if influence == "halfspace" else f"fe ({mesh})"))
    levels = np.asarray(pressures, dtype=float)
    rows = []
    fine_heights = {}
    if pairing == "nested":
        for skew, kurt in cells:
            fine_heights[(skew, kurt)] = _cell_heights((finest, finest), (size, size), b, skew,
                                                       kurt, surfaces, seed, "grid_study")
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
                                        f"grid_study|{g}")
            approaches = approach_grid(heights,
                                                   _pressure_end(levels, geometry, sigma), steps)
            nd, solve_s = _solve(unit, heights, geometry, approaches, method=method, tol=tol,
                                 precision=precision, stiffness_tol=1e-6, max_iter=None)
            frame = aggregate.aggregate_cell(nondim.to_physical(nd, sigma, E), levels)
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
                       machine=_machine())
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
    (:func:`roughcontact.aggregate.surface_curves`, a power law between
    steps), then for each count c <= m, ``draws`` random subsets of c surfaces (without
    replacement; one subset when c = m) give the Student-t half-width
    ``t_{(1+c)/2, c-1} s / sqrt(c)`` of the band of :func:`~roughcontact.aggregate.aggregate_cell`.
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
    approaches = approach_grid(heights, _pressure_end(pressures, geometry, sigma),
                                           steps)
    start = time.perf_counter()
    nd = nondim.solve_cell(unit_influence, heights, thickness=geometry.thickness,
                           element_area=geometry.element_area, approaches=approaches,
                           method=method, tol=tol, precision=precision, batch_size=batch_size)
    solve_s = time.perf_counter() - start
    (progress or (lambda message: log.info("%s", message)))(
        f"{_cell_key(skew, kurt)}: {surfaces} surfaces swept in {solve_s:.1f} s")
    table = band_vs_count(nondim.to_physical(nd, sigma, geometry.E), pressures, counts,
                          draws=draws, seed=seed)
    table.insert(0, "kurt", float(kurt))
    table.insert(0, "skew", float(skew))
    table["solve_s"] = solve_s
    return table


# ---------------------------------------------------------------------------
# 5. Recommendation


def _pick(candidates: pd.DataFrame, cost: str, meets: pd.Series):
    """Cheapest row meeting the tolerance, else the most accurate row (meets=False)."""
    good = candidates[meets]
    if len(good):
        return good.sort_values(cost, kind="stable").iloc[0], True, int(len(good))
    worst = candidates[["k_P_error", "real_area_error"]].max(axis=1)
    return candidates.loc[worst.idxmin()], False, 0


def recommend(solver_table: pd.DataFrame | None, mesh_table: pd.DataFrame | None,
              grid_table: pd.DataFrame | None, count_table: pd.DataFrame | None, *,
              tol_kP: float = 0.02, tol_area: float = 0.05,
              shares: dict | None = None) -> pd.DataFrame:
    """Cheapest mesh, contact grid, solver tolerance and surface count within tolerance.

    Each component is judged against its share of the tolerance on the
    relative error of k_P (Eq 33) and of the real area fraction (``shares``:
    component -> fraction, default 1, i.e. each component alone may use the
    whole tolerance), using the largest error over the measured cells and
    pressures:

    - mesh (:func:`mesh_errors`): |error| against the converged preset;
      cost = build time. The reference has error 0 by definition.
    - grid (:func:`grid_study`): |change| against the finest grid; cost =
      influence build + sweep time. Only coarser grids are candidates (the
      finest has change 0 by definition); when none is within tolerance the
      finest is listed with ``meets=False`` and unknown (NaN) error: the grid
      is not shown converged. The note names, per quantity, the coarsest grid
      within tolerance of the finest.
    - solver (:func:`solver_speed_vs_error`): error against the exact
      solution, every step converged; cost = summed sweep wall time of the
      measured cells. The exact method itself (error 0) is a candidate.
    - surfaces (:func:`band_vs_count`): relative 95 % half-width of the cell
      mean; cost = the count.

    A final ``combined`` row adds the chosen components' known errors (a
    bound if they are independent and of unknown sign); its ``meets`` needs
    every component to meet its share and the sum to be within the
    tolerance. When no option of a component meets it, the most accurate one
    is listed with ``meets=False``.

    Returns
    -------
    pandas.DataFrame
        Columns ``component``, ``choice``, ``cost``, ``cost_unit``,
        ``k_P_error``, ``real_area_error``, ``meets``, ``options_meeting``,
        ``note``; ``attrs["text"]`` is a plain-language summary.
    """
    shares = dict(shares or {})
    rows = []

    def add(component, choice, cost, unit, k_error, a_error, meets, count, note):
        rows.append({"component": component, "choice": choice, "cost": cost,
                     "cost_unit": unit, "k_P_error": k_error, "real_area_error": a_error,
                     "meets": bool(meets), "options_meeting": count, "note": note})

    def within(frame, component):
        share = float(shares.get(component, 1.0))
        return ((frame["k_P_error"] <= share * tol_kP)
                & (frame["real_area_error"] <= share * tol_area))

    if mesh_table is not None and len(mesh_table):
        mesh = mesh_table.reset_index(drop=True)
        row, ok, count = _pick(mesh, "build_s", within(mesh, "mesh"))
        add("mesh", row["mesh"], float(row["build_s"]), "s to build E*C (60 x 60)",
            float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
            f"error against the {row.get('reference', 'converged')} preset "
            f"(p_max error {100 * float(row['max_pressure_error']):.1f} %)"
            + ("" if ok else "; no mesh meets the tolerance"))
    if grid_table is not None and len(grid_table):
        grid = grid_table.groupby("grid").agg(
            k_P_error=("k_P_change", lambda s: float(np.nanmax(np.abs(s)))),
            real_area_error=("real_area_change", lambda s: float(np.nanmax(np.abs(s)))),
            cost=("build_s", "first"), solve_s=("solve_s", "sum"),
            surfaces=("surfaces", "first")).reset_index()
        grid["cost"] = grid["cost"] + grid["solve_s"]
        finest = int(grid["grid"].max())
        coarser = grid[grid["grid"] < finest].sort_values("grid")
        share = float(shares.get("grid", 1.0))
        per_quantity = []
        for column, name, tol in (("k_P_error", "k_P", tol_kP),
                                  ("real_area_error", "area", tol_area)):
            good = coarser[coarser[column] <= share * tol]
            per_quantity.append(f"{name} alone: {int(good['grid'].iloc[0])} per side"
                                if len(good) else f"{name} alone: none coarser than {finest}")
        detail = "; ".join(
            f"{int(r['grid'])}: k_P {100 * r['k_P_error']:.1f} %, area "
            f"{100 * r['real_area_error']:.0f} %" for _, r in coarser.iterrows())
        note = f"change against the finest grid ({finest}: {detail}); " + ", ".join(per_quantity)
        meets = within(coarser, "grid")
        if len(coarser) and meets.any():
            row, ok, count = _pick(coarser, "cost", meets)
            k_error, a_error = float(row["k_P_error"]), float(row["real_area_error"])
        else:
            row, ok, count = grid[grid["grid"] == finest].iloc[0], False, 0
            k_error = a_error = math.nan
            note += ("; no coarser grid is within the tolerance of the finest, whose own "
                     "error is not measured: the grid is not shown converged")
        add("grid", f"{int(row['grid'])} per side", float(row["cost"]),
            "s (influence + sweeps)", k_error, a_error, ok, count, note)
    if solver_table is not None and len(solver_table):
        keys = ["influence", "method", "tol", "precision"]
        solver = solver_table.groupby(keys, sort=False).agg(
            k_P_error=("k_P_error", "max"), real_area_error=("real_area_error", "max"),
            load_error=("load_error", "max"), cost=("wall_s", "sum"),
            converged=("converged_fraction", "min")).reset_index()
        solver = solver.drop_duplicates(keys)
        meets = within(solver, "solver") & (solver["converged"] >= 1.0)
        row, ok, count = _pick(solver, "cost", meets)
        add("solver", f"{row['method']} tol {row['tol']:.0e} ({row['precision']}, "
            f"{row['influence']})", float(row["cost"]), "s (sweeps of all measured cells)",
            float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
            f"against the exact solution at equal approach (load error "
            f"{float(row['load_error']):.1e})" + ("" if ok else "; none meets the tolerance"))
    if count_table is not None and len(count_table):
        counts = count_table.groupby("count").agg(
            k_P_error=("k_P_relative_half_width", "max"),
            real_area_error=("real_area_relative_half_width", "max")).reset_index()
        counts["cost"] = counts["count"].astype(float)
        row, ok, count = _pick(counts, "cost", within(counts, "surfaces"))
        solved = int(count_table["surfaces_solved"].max())
        add("surfaces", f"{int(row['count'])} per cell", float(row["count"]), "surfaces",
            float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
            f"relative 95 % half-width of the cell mean (subsets of {solved} solved surfaces)"
            + ("" if ok else f"; more than {int(row['count'])} surfaces needed"))
    if rows:
        k_sum = float(np.nansum([r["k_P_error"] for r in rows]))
        a_sum = float(np.nansum([r["real_area_error"] for r in rows]))
        unknown = [r["component"] for r in rows
                   if not (np.isfinite(r["k_P_error"]) and np.isfinite(r["real_area_error"]))]
        add("combined", "the choices above", math.nan, "", k_sum, a_sum,
            all(r["meets"] for r in rows) and k_sum <= tol_kP and a_sum <= tol_area, 0,
            "sum of the components' errors (worst case of independent errors)"
            + (f"; without {', '.join(unknown)} (unknown)" if unknown else ""))
    table = pd.DataFrame(rows)
    lines = [f"Tolerance: k_P within {100 * tol_kP:g} %, real area within {100 * tol_area:g} %"
             + (f" (shares {shares})." if shares else ", each component alone.")]
    for r in rows:
        status = "meets" if r["meets"] else "does NOT meet"
        lines.append(f"- {r['component']}: {r['choice']} ({status} it; k_P "
                     f"{100 * r['k_P_error']:.2g} %, area {100 * r['real_area_error']:.2g} %). "
                     f"{r['note']}.")
    table.attrs.update(tol_kP=tol_kP, tol_area=tol_area, shares=shares, text="\n".join(lines))
    return table


# ---------------------------------------------------------------------------
# 6. Report


def _plot_solver(axes, solver_table: pd.DataFrame) -> None:
    from matplotlib.ticker import NullFormatter

    compared = solver_table[~_is_reference(solver_table["reference"])]
    keys = ["influence", "skew", "kurt", "method", "tol"]
    worst = compared.groupby(keys, sort=False).agg(
        wall_s=("wall_s", "first"), load_error=("load_error", "max"),
        real_area_error=("real_area_error", "max"), k_P_error=("k_P_error", "max")).reset_index()
    floor = 1e-16  # an error of exactly 0 is drawn here
    for ax, column, title in zip(axes, ("load_error", "k_P_error", "real_area_error"),
                                 ("load F at equal approach", "k_P (Eq 33)", "real area"),
                                 strict=True):
        for k, ((influence, skew, kurt, method), group) in enumerate(
                worst.groupby(["influence", "skew", "kurt", "method"], sort=False)):
            ax.plot(group["wall_s"], np.maximum(group[column], floor),
                    marker="o" if method == "cg" else ("s" if method == "steepest" else "^"),
                    linestyle="-" if method == "cg" else "--", color=f"C{k}",
                    label=f"{method}, {influence}, Sk {skew:g} Ku {kurt:g}")
            for _, r in group.iterrows():
                ax.annotate(f"{r['tol']:.0e}", (r["wall_s"], max(r[column], floor)),
                            fontsize=6, alpha=0.7)
        for ref_s in solver_table.loc[_is_reference(solver_table["reference"]),
                                      "wall_s"].unique():
            ax.axvline(ref_s, color="grey", linewidth=0.6, linestyle=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("wall time of one cell's sweep [s] (dotted: exact)")
        ax.set_ylabel("largest |relative error| vs exact (0 drawn at 1e-16)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6)


def _plot_counts(ax, count_table: pd.DataFrame) -> None:
    for k, (level, group) in enumerate(count_table.groupby("pressure_Pa")):
        for name, style in (("k_P", "-"), ("real_area", "--")):
            ax.plot(group["count"], 100 * group[f"{name}_relative_half_width"], style,
                    marker="o", color=f"C{k}",
                    label=f"{'k_P' if name == 'k_P' else 'area'}, P = {level / 1e6:g} MPa")
    counts = np.sort(count_table["count"].unique())
    first = count_table[count_table["count"] == counts[0]]
    start = 100 * first["real_area_relative_half_width"].max()
    ax.plot(counts, start * np.sqrt((counts[0] - 1) / (counts - 1)), ":", color="grey",
            label="~ 1/sqrt(n)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("surfaces per cell")
    ax.set_ylabel("95 % half-width of the mean [% of mean]")
    ax.set_title("band half-width against surface count")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)


def _plot_grid(ax, grid_table: pd.DataFrame) -> None:
    for k, (level, group) in enumerate(grid_table.groupby("pressure_Pa")):
        group = group.groupby("grid").mean(numeric_only=True).reset_index()
        ax.plot(group["grid"], 100 * group["k_P_change"], "-o", color=f"C{k}",
                label=f"k_P, P = {level / 1e6:g} MPa")
        ax.plot(group["grid"], 100 * group["real_area_change"], "--s", color=f"C{k}",
                label=f"area, P = {level / 1e6:g} MPa")
    from matplotlib.ticker import NullFormatter

    ax.set_xscale("log")
    grids = sorted(int(g) for g in grid_table["grid"].unique())
    ax.set_xticks(grids, [str(g) for g in grids])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.axhline(0.0, color="grey", linewidth=0.6)
    ax.set_xlabel("contact elements per side")
    ax.set_ylabel("change against the finest grid [%]")
    ax.set_title("contact-grid convergence")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)


def _save_figures(png_paths, solver_table, grid_table, count_table) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from roughcontact.reports.plotting import save_figure

    paths = [png_paths] if isinstance(png_paths, str | os.PathLike) else list(png_paths)
    if not paths:
        return
    if len(paths) == 1:
        fig = Figure(figsize=(15, 9), layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(2, 3)
        solver_axes, grid_ax, count_ax = axes[0], axes[1, 0], axes[1, 1]
        axes[1, 2].axis("off")
        figures = [(fig, paths[0])]
    else:
        fig = Figure(figsize=(15, 4.8), layout="constrained")
        FigureCanvasAgg(fig)
        solver_axes = fig.subplots(1, 3)
        other = Figure(figsize=(10, 4.8), layout="constrained")
        FigureCanvasAgg(other)
        grid_ax, count_ax = other.subplots(1, 2)
        figures = [(fig, paths[0]), (other, paths[1])]
    if solver_table is not None and len(solver_table):
        _plot_solver(solver_axes, solver_table)
    if grid_table is not None and len(grid_table):
        _plot_grid(grid_ax, grid_table)
    else:
        grid_ax.axis("off")
    if count_table is not None and len(count_table):
        _plot_counts(count_ax, count_table)
    else:
        count_ax.axis("off")
    for figure, path in figures:
        figure.suptitle("Speed against error: solver tolerance, contact grid, surfaces per cell")
        save_figure(figure, path)


def _markdown_table(frame: pd.DataFrame, columns: Sequence[str], floatfmt: str = ".3g") -> str:
    present = [c for c in columns if c in frame]
    return frame[present].to_markdown(index=False, floatfmt=floatfmt)


def _presets_table(presets) -> pd.DataFrame:
    return pd.DataFrame([{"preset": name, **dict(values)} for name, values in presets.items()])


def write_report(solver_table: pd.DataFrame | None, mesh_table: pd.DataFrame | None,
                 grid_table: pd.DataFrame | None, count_table: pd.DataFrame | None,
                 recommendation: pd.DataFrame, md_path, csv_path, png_paths=(), *,
                 presets=ACCURACY_PRESETS, notes: Sequence[str] = ()) -> None:
    """Markdown report, combined tidy CSV and PNG figure(s), each written atomically.

    The Markdown has the sections ``# Speed against error``, ``## Recommendation``
    (``recommendation`` and its ``attrs["text"]``), ``## How it was measured``
    (``notes`` and the tables' ``attrs``), ``## Solver``, ``## Mesh``,
    ``## Contact grid``, ``## Surfaces per cell`` and ``## Accuracy presets``.
    The CSV stacks all tables with a ``table`` column (solver, mesh, grid,
    surfaces, recommendation) over the union of their columns. ``png_paths``:
    one path (one six-panel figure) or two (solver; grid and surface count).
    """
    tables = {"solver": solver_table, "mesh": mesh_table, "grid": grid_table,
              "surfaces": count_table, "recommendation": recommendation}
    tidy = pd.concat([frame.assign(table=name) for name, frame in tables.items()
                      if frame is not None and len(frame)], ignore_index=True, sort=False)
    tidy = tidy[["table"] + [c for c in tidy.columns if c != "table"]]
    with atomic_path(csv_path) as tmp:
        tidy.to_csv(tmp, index=False)

    out = ["# Speed against error", ""]
    out += [f"Commit {git_commit()}, machine: {_machine()} (at writing). Every error is a "
            "relative error; timings are wall-clock on a shared machine and vary with its load.",
            ""]
    out += ["## Recommendation", "", recommendation.attrs.get("text", ""), "",
            _markdown_table(recommendation, ["component", "choice", "cost", "cost_unit",
                                             "k_P_error", "real_area_error", "meets",
                                             "options_meeting"]), ""]
    out += ["## How it was measured", ""]
    out += [f"- {note}" for note in notes]
    for name, frame in tables.items():
        if frame is not None and frame.attrs:
            attrs = {k: v for k, v in frame.attrs.items() if k != "text"}
            if attrs:
                out.append(f"- {name}: " + "; ".join(f"{k} = {v}" for k, v in attrs.items()))
    out.append("")
    out += ["## Solver", ""]
    if solver_table is not None and len(solver_table):
        out += ["Largest error over surfaces at each pressure level; `wall_s` is the whole "
                "sweep of one cell (all surfaces and steps).", ""]
        out.append(_markdown_table(solver_table, [
            "influence", "skew", "kurt", "method", "tol", "pressure_Pa", "real_area_exact",
            "wall_s", "iterations_per_solve", "matvecs_per_solve", "converged_fraction",
            "load_error", "real_area_error", "max_pressure_error", "k_P_error"]))
    else:
        out.append("Not measured.")
    out += ["", "## Mesh", ""]
    if mesh_table is not None and len(mesh_table):
        out.append(_markdown_table(mesh_table, [
            "mesh", "build_s", "peak_memory_GB", "k_P_error", "real_area_error",
            "max_pressure_error", "k_P_range", "real_area_range", "max_pressure_range",
            "source"]))
    else:
        out.append("Not measured.")
    out += ["", "## Contact grid", ""]
    if grid_table is not None and len(grid_table):
        out.append(_markdown_table(grid_table, [
            "skew", "kurt", "grid", "element_size_m", "build_s", "solve_s", "pressure_Pa",
            "k_P_Pa", "k_P_half_width_Pa", "real_area_fraction", "real_area_half_width",
            "max_pressure_Pa", "k_P_change", "real_area_change", "max_pressure_change"]))
    else:
        out.append("Not measured.")
    out += ["", "## Surfaces per cell", ""]
    if count_table is not None and len(count_table):
        out.append(_markdown_table(count_table, [
            "skew", "kurt", "count", "pressure_Pa", "k_P_mean", "k_P_half_width",
            "k_P_relative_half_width", "real_area_mean", "real_area_half_width",
            "real_area_relative_half_width", "max_pressure_relative_half_width"]))
    else:
        out.append("Not measured.")
    out += ["", "## Accuracy presets", "",
            "`roughcontact.speed.ACCURACY_PRESETS` (errors: relative, of the cell means; "
            "None where not measured).", "", _markdown_table(_presets_table(presets), [
                "preset", "mesh", "grid_per_9mm", "method", "tol", "precision", "surfaces",
                "k_P_error", "real_area_error", "max_pressure_error", "solver_k_P_error",
                "grid_change_k_P", "grid_change_real_area", "sampling_k_P",
                "sampling_real_area"]), ""]
    with atomic_path(md_path) as tmp:
        Path(tmp).write_text("\n".join(out) + "\n")
    _save_figures(png_paths, solver_table, grid_table, count_table)


def speed_vs_error_report(
    out_md,
    out_csv,
    out_png,
    *,
    grid: int = 60,
    surfaces: int = 4,
    cells: Sequence[tuple[float, float]] = DEFAULT_CELLS,
    solver_meshes: Sequence[str] = ("paper",),
    methods: Sequence[str] = ("steepest", "cg"),
    tolerances: Sequence[float] | Mapping = DEFAULT_TOLERANCES,
    max_iter: int | Mapping | None = None,
    precision: str = "mixed",
    steps: int = 30,
    grids: Sequence[int] = (30, 60, 120),
    grid_surfaces: int | None = None,
    count_surfaces: int = 120,
    counts: Sequence[int] = DEFAULT_COUNTS,
    count_mesh: str = "hybrid:refined",
    size: float = 9e-3,
    thickness: float = 10e-3,
    E: float = 5.11e8,
    nu: float = 0.0,
    sigma: float = 24.5e-6,
    b: float = 1e-3,
    pressures: Sequence[float] = (0.3e6, 1e6, 3e6),
    mesh_table_path=None,
    hybrid_table_path=None,
    tol_kP: float = 0.02,
    tol_area: float = 0.05,
    seed: int = 2006,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Run every measurement from scratch and write the report (the Snakemake entry point).

    1. :func:`solver_speed_vs_error` on a ``grid`` x ``grid`` block of
       ``size`` x ``size`` x ``thickness`` [m] (the paper's 60 x 60, 9 mm,
       10 mm by default) for each mesh preset in ``solver_meshes`` (built
       here; "hybrid:<preset>" for the hybrid operator), ``surfaces`` per cell.
    2. :func:`mesh_errors` from ``mesh_table_path`` (the influence-convergence
       CSV) and ``hybrid_table_path``, or :data:`FALLBACK_MESH_ERRORS`.
    3. :func:`grid_study` over ``grids`` (hybrid refined influence, nested
       surfaces, the first cell, ``grid_surfaces`` or ``surfaces`` surfaces).
    4. :func:`surfaces_per_cell`: ``count_surfaces`` surfaces of the first cell
       on ``count_mesh`` at ``grid``, subsampled to ``counts``.
    5. :func:`recommend` for ``tol_kP``, ``tol_area``; :func:`write_report`.

    ``out_png`` is one path or a list of two. Returns the tables (keys
    solver, mesh, grid, surfaces, recommendation).

    Cost with the workflow's settings (grids 30-240; measured 2026-11-24, 2
    cores, one BLAS thread): 401 s and a peak resident set of 1.4 GB (the
    coarse "refined" models of the hybrid operators, 60 x 60 at most):
    solver study about 240 s (two cells), grid study 83 s (240 x 240: 15 s
    influence + 35 s sweep; 120 x 120: 15 s + 15 s), 120 surfaces 70 s.
    """
    say = progress or (lambda message: log.info("%s", message))
    started = time.perf_counter()
    before = _machine()
    geometry = BlockGeometry(size=(size, size), thickness=thickness, grid=(grid, grid), E=E,
                             nu=nu)

    def build(name: str):
        geom = dataclasses.replace(geometry, mesh=name.split(":", 1)[-1])
        start = time.perf_counter()
        if name.startswith("hybrid:"):
            unit = hybrid_unit_modulus_influence(geom, coarsening=2)
        elif name == "halfspace":
            unit = halfspace_influence(geom.grid, geom.size, 1.0, geom.nu)
        else:
            unit = unit_modulus_influence(geom)
        say(f"influence {name} {grid} x {grid}: {time.perf_counter() - start:.1f} s")
        return unit, geom

    solver_tables = []
    for name in solver_meshes:
        unit, geom = build(name)
        solver_tables.append(solver_speed_vs_error(
            unit, geom, cells, surfaces=surfaces, sigma=sigma, b=b, pressures=pressures,
            tolerances=tolerances, methods=methods, precision=precision, steps=steps,
            max_iter=max_iter, seed=seed, label=name, progress=say))
        del unit
    solver_table = pd.concat(solver_tables, ignore_index=True)
    solver_table.attrs.update(solver_tables[0].attrs)
    mesh_table = mesh_errors(mesh_table_path, hybrid_table_path)
    grid_table = grid_study(cells[:1], grids=grids, size=size, thickness=thickness, E=E, nu=nu,
                            surfaces=grid_surfaces or surfaces, sigma=sigma, b=b,
                            pressures=pressures, precision=precision, steps=steps, seed=seed,
                            progress=say)
    unit, geom = build(count_mesh)
    count_table = surfaces_per_cell(unit, geom, cells[0], surfaces=count_surfaces,
                                    counts=counts, sigma=sigma, b=b, pressures=pressures,
                                    precision=precision, steps=steps, seed=seed, progress=say)
    count_table.attrs["influence"] = count_mesh
    del unit
    recommendation = recommend(solver_table, mesh_table, grid_table, count_table,
                               tol_kP=tol_kP, tol_area=tol_area)
    notes = [
        f"Block {size * 1e3:g} mm x {size * 1e3:g} mm, L = {thickness * 1e3:g} mm, "
        f"E = {E:g} Pa, nu = {nu:g}, clamped base; surfaces: exponential ACF (Eq 1), "
        f"sigma = {sigma * 1e6:g} um, b = {b * 1e3:g} mm, periodic filter; cells "
        f"{', '.join(f'(Sk {s:g}, Ku {k:g})' for s, k in cells)}; seed {seed}.",
        f"Pressures {', '.join(f'{p / 1e6:g}' for p in pressures)} MPa; each sweep is a "
        f"contact job: {steps} geometric approaches (pipeline.sweep_approaches), "
        f"solve_cell with tangent stiffness, warm starts, precision {precision}.",
        f"Solver: {surfaces} surfaces per cell on {grid} x {grid}, influence "
        f"{', '.join(solver_meshes)}; errors at equal approach against method 'exact' "
        f"(block principal pivoting, tol {REFERENCE_TOL:g}); its cost is the "
        "'exact' row (reference=True).",
        "Mesh: read from the influence-convergence table (not recomputed).",
        f"Grid: {', '.join(str(g) for g in grids)} per side, influence "
        f"{grid_table.attrs.get('influence_model')}, chosen because the refined "
        "finite-element model at 120 x 120 needs about 4 times the dofs of 60 x 60 and the "
        "hybrid is within 1.2 % of the converged preset at 60 x 60; surfaces "
        f"{grid_table.attrs.get('pairing')} (the finest grid point-sampled).",
        f"Surfaces per cell: {count_surfaces} surfaces of cell {cells[0]} on {count_mesh} "
        f"at {grid} x {grid}, solved once; random subsets per count.",
        f"Total wall time {time.perf_counter() - started:.0f} s; machine before: {before}; "
        f"after: {_machine()}.",
    ]
    write_report(solver_table, mesh_table, grid_table, count_table, recommendation, out_md,
                 out_csv, out_png, notes=notes)
    return {"solver": solver_table, "mesh": mesh_table, "grid": grid_table,
            "surfaces": count_table, "recommendation": recommendation}
