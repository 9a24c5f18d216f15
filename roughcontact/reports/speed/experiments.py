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
3. :func:`~roughcontact.reports.speed.grid.grid_study` (its own module) -- the
   same statistics on coarser and finer contact grids over the same nominal
   area, and the change of k_P, real area and peak pressure at equal P
   against the finest grid.
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
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pandas as pd
import scipy.stats

from roughcontact.contact import aggregate, nondim
from roughcontact.contact.cell import SWEEP_OPTIONS
from roughcontact.contact.curves import NondimSweep, PhysicalSweep
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.reports.speed.machine import describe_machine
from roughcontact.reports.speed.sweeps import (
    DEFAULT_SURFACES,
    DEFAULT_SWEEP,
    CellSurfaces,
    SweepSettings,
    cell_key,
    reporter,
    timed_sweep,
)
from roughcontact.study.jobs.contact import BATCH_SIZE
from roughcontact.study.presets import FALLBACK_MESH_ERRORS

__all__ = [
    "DEFAULT_CELLS",
    "DEFAULT_COUNTS",
    "DEFAULT_TOLERANCES",
    "REFERENCE_STIFFNESS_TOL",
    "REPORT_COMPARISON",
    "REFERENCE_TOL",
    "SOLVER_QUANTITIES",
    "SolverComparison",
    "band_vs_count",
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
    "k_P": ("normalized_stiffness",
            "normalized stiffness k_P (Eq 33), tangent at the contact set"),
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
# Solver errors at equal approach


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

#: How the solver table's errors are taken (its ``attrs["comparison"]``).
SOLVER_COMPARISON = (f"relative error at equal approach against method='exact' (tol "
                     f"{REFERENCE_TOL:g}, stiffness tol {REFERENCE_STIFFNESS_TOL:g}); largest "
                     "over surfaces at the step nearest each pressure level")
#: Methods solved in one precision whatever the study's: the exact reference, in double.
FIXED_PRECISION = MappingProxyType({"exact": "double"})


def _positive_levels(pressures: Sequence[float]) -> np.ndarray:
    """``pressures`` [Pa] as an array, checked to be a non-empty list of positive values."""
    levels = np.asarray(pressures, dtype=float)
    if levels.ndim != 1 or levels.size == 0 or (levels <= 0).any():
        raise ValueError("pressures must be positive nominal pressures [Pa]")
    return levels


class _Run(NamedTuple):
    """One sweep of the solver study: its settings, result and wall time [s]."""

    method: str
    tol: float
    precision: str
    reference: bool
    sweep: NondimSweep
    seconds: float


def _reference_run(sweep: Callable, name: str, cell: str, say: Callable[[str], None]) -> _Run:
    """The exact solution of one cell's sweep (block principal pivoting, ``REFERENCE_TOL``).

    ``sweep`` is :func:`timed_sweep` bound to the cell's surfaces and approaches.
    """
    result, seconds = sweep(SWEEP_OPTIONS.with_(method="exact", tol=REFERENCE_TOL,
                                                precision="double",
                                                stiffness_tol=REFERENCE_STIFFNESS_TOL,
                                                max_iter=None))
    if not result.converged.all():
        log.warning("exact reference did not converge on %d steps of cell %s",
                    int((~result.converged).sum()), cell)
    say(f"{name} {cell}: exact reference {seconds:.1f} s, "
        f"final contact {100 * result.real_area_fraction[:, -1].mean():.2f} %")
    return _Run("exact", REFERENCE_TOL, "double", True, result, seconds)


@dataclass(frozen=True)
class SolverComparison:
    """What :func:`solver_speed_vs_error` compares against the exact solution.

    Attributes
    ----------
    methods : sequence of str
        Methods compared; ``"exact"`` may be included (errors ~0).
    tolerances : sequence of float, or mapping method -> sequence
        Dimensionless KKT tolerances (Eq 27) of every method, or of each (a
        method missing is skipped).
    max_iter : int, mapping method -> int, or None
        Iteration limit per solve (None: the solver's); a run that hits it
        reports ``converged_fraction < 1``.
    stiffness_tol : float
        Residual of the stiffness CG of every compared run, which floors a
        tight solve's k_P error.

    The defaults: steepest descent and CG at 1e-4 ... 1e-12; the report
    compares at :data:`DEFAULT_TOLERANCES` (:data:`REPORT_COMPARISON`).
    """

    methods: Sequence[str] = ("steepest", "cg")
    tolerances: Sequence[float] | Mapping = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    max_iter: int | Mapping | None = None
    stiffness_tol: float = 1e-6

    def runs(self, precision: str) -> list[tuple[str, float, str, int | None]]:
        """``(method, tol, precision, max_iter)`` of every run, in order: the iterative
        methods in ``precision``, those of :data:`FIXED_PRECISION` in theirs."""
        runs = []
        for method in self.methods:
            own = (self.tolerances.get(method, ()) if isinstance(self.tolerances, Mapping)
                   else self.tolerances)
            limit = (self.max_iter.get(method) if isinstance(self.max_iter, Mapping)
                     else self.max_iter)
            runs += [(method, float(tol), FIXED_PRECISION.get(method, precision), limit)
                     for tol in own]
        return runs


#: The comparison of the speed-against-error report: :data:`DEFAULT_TOLERANCES`.
REPORT_COMPARISON = SolverComparison(tolerances=DEFAULT_TOLERANCES)


def _compared_runs(sweep: Callable, name: str, say: Callable[[str], None],
                   comparison: SolverComparison, precision: str) -> list[_Run]:
    """One run per method and tolerance of ``comparison``, the iterative ones in ``precision``."""
    runs = []
    for method, tol, own_precision, limit in comparison.runs(precision):
        result, seconds = sweep(SWEEP_OPTIONS.with_(method=method, tol=tol,
                                                    precision=own_precision,
                                                    stiffness_tol=comparison.stiffness_tol,
                                                    max_iter=limit))
        runs.append(_Run(method, tol, own_precision, False, result, seconds))
        say(f"{name}: {method} tol {tol:.0e} {seconds:.1f} s, "
            f"{result.iterations.mean():.0f} iterations per solve, "
            f"{100 * result.converged.mean():.0f} % converged")
    return runs


def _solver_rows(run: _Run, reference: _Run, levels: np.ndarray, chosen: Mapping,
                 P_ref: np.ndarray, fields: Mapping) -> list[dict]:
    """Rows of one run: its cost, and its errors against ``reference`` at each level.

    ``chosen``: per level, each surface's step nearest it (:func:`_nearest_steps`
    of the reference's nominal pressures ``P_ref`` [Pa]); ``fields``: the
    columns the cell's rows share.
    """
    result, exact = run.sweep, reference.sweep
    base = dict(fields) | {
        "method": run.method, "tol": run.tol, "precision": run.precision,
        "reference": run.reference, "wall_s": run.seconds, "solves": result.iterations.size,
        "iterations_per_solve": float(result.iterations.mean()),
        "matvecs_per_solve": float(result.matvecs.mean()),
        "converged_fraction": float(result.converged.mean()),
        "max_residual": float(np.nanmax(result.residual)),
        "reference_wall_s": reference.seconds,
        "final_real_area_exact": float(exact.real_area_fraction[:, -1].mean()),
    }
    surface_index = np.arange(P_ref.shape[0])
    rows = []
    for level in levels:
        at = (surface_index, chosen[level])
        row = base | {"pressure_Pa": float(level), "pressure_at_step_Pa": float(P_ref[at].mean()),
                      "real_area_exact": float(exact.real_area_fraction[at].mean())}
        for name, (attribute, _) in SOLVER_QUANTITIES.items():
            error = _relative_error(getattr(result, attribute)[at], getattr(exact, attribute)[at])
            row[f"{name}_error"] = float(np.max(error))
        rows.append(row)
    return rows


def _solver_cell(sweep: Callable, fields: Mapping, levels: np.ndarray,
                 geometry: BlockGeometry, sigma: float, say: Callable[[str], None],
                 compared: tuple[SolverComparison, str]) -> list[dict]:
    """The rows of one cell: its exact reference and every compared run, each at every level.

    ``sweep`` is :func:`timed_sweep` bound to the cell's surfaces and approaches;
    ``compared`` the comparison and the precision of its iterative runs.
    """
    name, cell = fields["influence"], cell_key(fields["skew"], fields["kurt"])
    reference = _reference_run(sweep, name, cell, say)
    P_ref = reference.sweep.nominal_pressure * geometry.E * sigma / geometry.thickness
    chosen = {level: _nearest_steps(P_ref, level) for level in levels}
    runs = [reference, *_compared_runs(sweep, f"{name} {cell}", say, *compared)]
    return [row for run in runs
            for row in _solver_rows(run, reference, levels, chosen, P_ref, fields)]


def solver_speed_vs_error(
    unit_influence, geometry: BlockGeometry, cells: Sequence[tuple[float, float]] = DEFAULT_CELLS,
    *, surfaces: int = 4, generator: CellSurfaces = DEFAULT_SURFACES,
    sweep: SweepSettings = DEFAULT_SWEEP, comparison: SolverComparison = SolverComparison(),
    label: str | None = None, progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Wall time and error of each solver and tolerance against the exact solution.

    Per cell, ``surfaces`` surfaces of ``generator`` (:class:`CellSurfaces`:
    std sigma and 10 % correlation length b [m] on ``geometry``'s grid; seeds
    ``derive_seeds(seed, "speed_vs_error|<cell>")``) are swept as a contact
    job sweeps them (:func:`roughcontact.contact.cell.sweep_cell`: the
    ``steps`` geometric approaches of ``sweep`` up to one carrying its largest
    pressure on every surface, warm starts, tangent stiffness): first by the
    reference, ``method="exact"`` (block principal pivoting at
    ``REFERENCE_TOL``, stiffness CG at ``REFERENCE_STIFFNESS_TOL``), then by
    each method of ``comparison`` at each of its tolerances (in
    ``sweep.precision``). Errors at equal approach: per pressure level of
    ``sweep`` and surface, the step whose exact P is nearest the level in log
    P; ``<q>_error`` is the largest ``|q / q_exact - 1|`` over the surfaces for
    q in :data:`SOLVER_QUANTITIES`, dimensionless (Eq 28-32).

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator
        ``E * C`` [m] of ``geometry`` (plan size [m], L [m], grid, E [Pa]).
    cells : sequence of (skew, kurt)
        Height statistics (Eq 4-5).
    surfaces : int
        Surfaces per cell.
    generator, sweep, comparison
        :class:`CellSurfaces`, :class:`SweepSettings` (its ``pressures`` [Pa]
        where the errors are read, ``steps`` and the ``precision`` of the
        iterative solvers; its method and tol unused) and
        :class:`SolverComparison` (methods, tolerances, iteration limits).
    label, progress
        Name of the influence operator (column ``influence``); a callable
        given a line after each run.

    Returns
    -------
    pandas.DataFrame
        One row per (cell, method, tol, pressure level), the reference included
        (``method="exact"``, ``tol=REFERENCE_TOL``, ``reference=True``):
        ``influence``, ``grid_x``, ``grid_y``, ``skew``, ``kurt``, ``surfaces``,
        ``steps``, ``method``, ``tol``, ``precision``, ``reference``, ``wall_s``
        (the cell's whole sweep), ``solves``, ``iterations_per_solve``,
        ``matvecs_per_solve`` (exact: pivots + 2), ``converged_fraction``,
        ``max_residual``, ``reference_wall_s``, ``final_real_area_exact`` (at
        the last step), ``pressure_Pa`` (level), ``pressure_at_step_Pa``,
        ``real_area_exact`` (exact means at the compared steps), ``<q>_error``.
    """
    if surfaces < 1:
        raise ValueError(f"surfaces must be >= 1, got {surfaces!r}")
    levels = _positive_levels(sweep.pressures)
    label = label or (geometry.mesh if isinstance(geometry.mesh, str) else "custom")
    say = reporter(progress)
    end = sweep.end(geometry, generator.sigma)
    rows = []
    for skew, kurt in cells:
        heights = generator.heights(geometry.grid, geometry.size, (skew, kurt), surfaces,
                                    "speed_vs_error")
        fields = {"influence": label, "grid_x": geometry.grid[0], "grid_y": geometry.grid[1],
                  "skew": float(skew), "kurt": float(kurt), "surfaces": surfaces,
                  "steps": sweep.steps}
        rows += _solver_cell(
            partial(timed_sweep, unit_influence, heights, geometry, end, sweep.steps), fields,
            levels, geometry, generator.sigma, say, (comparison, sweep.precision))
    table = pd.DataFrame(rows)
    table.attrs.update(comparison=SOLVER_COMPARISON, stiffness_tol=comparison.stiffness_tol,
                       sigma=generator.sigma, b=generator.b, seed=generator.seed,
                       machine=describe_machine())
    return table


# ---------------------------------------------------------------------------
# 2. Mesh (read, not recomputed)


def _error_summary(name: str, values: np.ndarray) -> dict:
    """``<name>_error`` (largest |relative error|) and ``<name>_range`` (signed min...max
    as text, in %) of one quantity's relative errors [-]."""
    return {f"{name}_error": float(np.nanmax(np.abs(values))),
            f"{name}_range": (f"{100 * np.nanmin(values):+.1f}..."
                              f"{100 * np.nanmax(values):+.1f} %")}


#: Quantities of the mesh table -> their error columns of the influence-convergence table.
CONVERGENCE_ERRORS = MappingProxyType({"k_P": "k_P_Pa_error",
                                       "real_area": "real_area_fraction_error",
                                       "max_pressure": "max_pressure_Pa_error"})


def _convergence_rows(path) -> list[dict]:
    """The mesh rows of an influence-convergence table (extrapolated rows left out)."""
    table = pd.read_csv(path)
    table = table[table["kind"] != "richardson"]
    rows = []
    for mesh, group in table.groupby("mesh", sort=False):
        row = {"mesh": mesh, "build_s": float(group["build_s"].iloc[0]),
               "peak_memory_GB": float(group["peak_memory_GB"].iloc[0])}
        for name, column in CONVERGENCE_ERRORS.items():
            row |= _error_summary(name, group[column].to_numpy(float))
        rows.append(row | {"reference": str(group["reference"].iloc[0]), "source": str(path)})
    return rows


def _hybrid_rows(path) -> list[dict]:
    """The hybrid operators' rows of the benchmark's long table ``influence_hybrid.csv``."""
    hybrid = pd.read_csv(path)
    hybrid = hybrid[hybrid["operator"].str.startswith("hybrid")]
    rows = []
    for operator, group in hybrid.groupby("operator", sort=False):
        row = {"mesh": operator, "build_s": float(group["seconds"].iloc[0]),
               "peak_memory_GB": float(group["peak_gb"].iloc[0])}
        for name, prefix in CONVERGENCE_ERRORS.items():
            at = group["quantity"].str.startswith(f"{prefix}_at")
            row |= _error_summary(name, group.loc[at, "value"].to_numpy(float))
        rows.append(row | {"reference": "converged", "source": str(path)})
    return rows


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
    if convergence_csv is not None and Path(convergence_csv).exists():
        rows = _convergence_rows(convergence_csv)
    else:
        rows = [{"mesh": mesh, **values, "reference": "converged",
                 "source": "FALLBACK_MESH_ERRORS"} for mesh, values in FALLBACK_MESH_ERRORS.items()]
    if hybrid_csv is not None and Path(hybrid_csv).exists():
        rows += _hybrid_rows(hybrid_csv)
    return pd.DataFrame(rows)


# ---------------------------------------------------------------------------
# 4. Surfaces per cell


def band_vs_count(
    physical: PhysicalSweep,
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
    unit_influence, geometry: BlockGeometry, cell: tuple[float, float] = (0.0, 3.0), *,
    surfaces: int = 120, counts: Sequence[int] = DEFAULT_COUNTS,
    generator: CellSurfaces = DEFAULT_SURFACES, sweep: SweepSettings = DEFAULT_SWEEP,
    batch_size: int = BATCH_SIZE, draws: int = 200,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Solve ``surfaces`` surfaces of one cell once, then :func:`band_vs_count`.

    Surfaces of ``generator`` as in :func:`solver_speed_vs_error` (seeds
    ``derive_seeds(seed, "surfaces_per_cell|<cell>")``), swept like a contact
    job (``sweep``: its method, tol, precision and steps; batches of
    ``batch_size``), read at ``sweep.pressures`` [Pa] and subsampled to each of
    ``counts`` (``draws`` subsets each). Adds columns ``skew``, ``kurt`` and
    ``solve_s`` (all surfaces).
    """
    skew, kurt = cell
    heights = generator.heights(geometry.grid, geometry.size, cell, surfaces, "surfaces_per_cell")
    nd, solve_s = timed_sweep(unit_influence, heights, geometry,
                              sweep.end(geometry, generator.sigma), sweep.steps,
                              SWEEP_OPTIONS.with_(method=sweep.method, tol=sweep.tol,
                                                  precision=sweep.precision,
                                                  batch_size=batch_size))
    reporter(progress)(f"{cell_key(skew, kurt)}: {surfaces} surfaces swept in {solve_s:.1f} s")
    table = band_vs_count(nondim.to_physical(nd, generator.sigma, geometry.E), sweep.pressures,
                          counts, draws=draws, seed=generator.seed)
    table.insert(0, "kurt", float(kurt))
    table.insert(0, "skew", float(skew))
    table["solve_s"] = solve_s
    return table
