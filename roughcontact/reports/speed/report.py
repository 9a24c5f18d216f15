"""The speed-against-error report from scratch: the Snakemake rule ``speed_vs_error``.

:func:`speed_vs_error_report` runs the experiments
(:mod:`roughcontact.reports.speed.experiments`), decides
(:mod:`roughcontact.reports.speed.recommend`), renders
(:mod:`roughcontact.reports.speed.render`) and writes this run's accuracy
presets (:func:`write_presets`) for comparison with the stored ones
(``python -m roughcontact.study.presets --compare``).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import pandas as pd
import yaml

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.hybrid import hybrid_unit_modulus_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.reports.speed.experiments import (
    DEFAULT_CELLS,
    DEFAULT_COUNTS,
    DEFAULT_TOLERANCES,
    REFERENCE_TOL,
    mesh_errors,
    solver_speed_vs_error,
    surfaces_per_cell,
)
from roughcontact.reports.speed.grid import grid_study
from roughcontact.reports.speed.machine import describe_machine
from roughcontact.reports.speed.recommend import derive_presets, recommend
from roughcontact.reports.speed.render import write_report
from roughcontact.reports.speed.sweeps import reporter
from roughcontact.study.presets import load_presets
from roughcontact.study.provenance import atomic_path, git_commit
from roughcontact.units import MM, MPA, UM

__all__ = ["PRESETS_NAME", "speed_vs_error_report", "write_presets"]

#: File name of this run's accuracy presets, beside the Markdown report by default.
PRESETS_NAME = "accuracy_presets.yaml"


def _build_influence(geometry: BlockGeometry, name: str):
    """``E C`` [m] of ``geometry`` for mesh ``name`` ("hybrid:<preset>", "halfspace" or a
    mesh preset) and the geometry carrying that mesh name (the half-space has none)."""
    if name == "halfspace":
        return halfspace_influence(geometry.grid, geometry.size, 1.0, geometry.nu), geometry
    geometry = dataclasses.replace(geometry, mesh=name.split(":", 1)[-1])
    if name.startswith("hybrid:"):
        return hybrid_unit_modulus_influence(geometry, coarsening=2), geometry
    return unit_modulus_influence(geometry), geometry


def write_presets(path: str | os.PathLike, presets: Mapping) -> None:
    """Write accuracy presets (:func:`~roughcontact.reports.speed.recommend.derive_presets`)
    as YAML to ``path``, atomically, under a header naming the commit and machine."""
    header = (f"# Accuracy presets measured by the speed-against-error report (commit "
              f"{git_commit()}, {describe_machine()}).\n"
              "# Structure and settings of config/accuracy_presets.yaml; numbers this run "
              "did not measure are the stored ones.\n"
              "# Drift against the stored file: python -m roughcontact.study.presets "
              f"--compare {Path(path).name}\n")
    with atomic_path(path) as tmp:
        Path(tmp).write_text(header + yaml.safe_dump(presets, sort_keys=False, width=100))


def _spectrum_note(spectrum: Mapping | None) -> str:
    """How the grid study's surfaces differ from the exponential ACF, for the notes."""
    if not spectrum:
        return ""
    if spectrum.get("acf") == "psd":
        rows = spectrum["psd"]
        return (f", spectrum: a tabulated isotropic PSD ({len(rows)} rows, q "
                f"{rows[0][0] * MM:.4g}-{rows[-1][0] * MM:.4g} 1/mm) in place of the ACF")
    fields = ", ".join(f"{k} {v:g}" for k, v in spectrum.items() if isinstance(v, float))
    return f", spectrum: {spectrum.get('acf')} ({fields}) in place of the ACF"


def _solver_tables(geometry: BlockGeometry, meshes: Sequence[str], cells,
                   **options) -> pd.DataFrame:
    """:func:`solver_speed_vs_error` on the influence of each of ``meshes``, stacked (the
    first table's ``attrs``); ``options`` (``progress`` among them) go to it."""
    tables = []
    for name in meshes:
        unit, geom = _timed_influence(geometry, name, options["progress"])
        tables.append(solver_speed_vs_error(unit, geom, cells, label=name, **options))
        del unit
    table = pd.concat(tables, ignore_index=True)
    table.attrs.update(tables[0].attrs)
    return table


def _timed_influence(geometry: BlockGeometry, name: str, say):
    """:func:`_build_influence`, its wall time said in a line."""
    start = time.perf_counter()
    unit, geom = _build_influence(geometry, name)
    say(f"influence {name} {geometry.grid[0]} x {geometry.grid[1]}: "
        f"{time.perf_counter() - start:.1f} s")
    return unit, geom


def _notes(grid_table: pd.DataFrame, *, size, thickness, E, nu, sigma, b, cells, seed,
           pressures, steps, precision, surfaces, grid, solver_meshes, grids, spectrum,
           count_surfaces, count_mesh, started: float, before: str) -> list[str]:
    """How each part of the report was measured, a line each (``## How it was measured``)."""
    return [
        f"Block {size / MM:g} mm x {size / MM:g} mm, L = {thickness / MM:g} mm, "
        f"E = {E:g} Pa, nu = {nu:g}, clamped base; surfaces: exponential ACF (Eq 1), "
        f"sigma = {sigma / UM:g} um, b = {b / MM:g} mm, periodic filter; cells "
        f"{', '.join(f'(Sk {s:g}, Ku {k:g})' for s, k in cells)}; seed {seed}.",
        f"Pressures {', '.join(f'{p / MPA:g}' for p in pressures)} MPa; each sweep is a "
        f"contact job: {steps} geometric approaches (contact.cell.approach_grid), "
        f"contact.cell.sweep_cell with tangent stiffness, warm starts, precision "
        f"{precision}.",
        f"Solver: {surfaces} surfaces per cell on {grid} x {grid}, influence "
        f"{', '.join(solver_meshes)}; errors at equal approach against method 'exact' "
        f"(block principal pivoting, tol {REFERENCE_TOL:g}); its cost is the "
        "'exact' row (reference=True).",
        "Mesh: read from the influence-convergence table (not recomputed).",
        f"Grid: {', '.join(str(g) for g in grids)} per side, influence "
        f"{grid_table.attrs.get('influence_model')}, chosen because the refined "
        "finite-element model at 120 x 120 needs about 4 times the dofs of 60 x 60 and the "
        "hybrid is within 1.2 % of the converged preset at 60 x 60; surfaces "
        f"{grid_table.attrs.get('pairing')} (the finest grid point-sampled)"
        f"{_spectrum_note(spectrum)}.",
        f"Surfaces per cell: {count_surfaces} surfaces of cell {cells[0]} on {count_mesh} "
        f"at {grid} x {grid}, solved once; random subsets per count.",
        f"Total wall time {time.perf_counter() - started:.0f} s; machine before: {before}; "
        f"after: {describe_machine()}.",
    ]


def speed_vs_error_report(
    out_md, out_csv, out_png, *, grid: int = 60, surfaces: int = 4,
    cells: Sequence[tuple[float, float]] = DEFAULT_CELLS,
    solver_meshes: Sequence[str] = ("paper",), methods: Sequence[str] = ("steepest", "cg"),
    tolerances: Sequence[float] | Mapping = DEFAULT_TOLERANCES,
    max_iter: int | Mapping | None = None, precision: str = "mixed", steps: int = 30,
    grids: Sequence[int] = (30, 60, 120), grid_surfaces: int | None = None,
    spectrum: Mapping | None = None, count_surfaces: int = 120,
    counts: Sequence[int] = DEFAULT_COUNTS, count_mesh: str = "hybrid:refined",
    size: float = 9e-3, thickness: float = 10e-3, E: float = 5.11e8, nu: float = 0.0,
    sigma: float = 24.5e-6, b: float = 1e-3, pressures: Sequence[float] = (0.3e6, 1e6, 3e6),
    mesh_table_path=None, hybrid_table_path=None, tol_kP: float = 0.02,
    tol_area: float = 0.05, seed: int = 2006, out_presets=None,
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
       surfaces, the first cell, ``grid_surfaces`` or ``surfaces`` surfaces),
       with ``spectrum`` (:class:`~roughcontact.surfaces.spec.SurfaceSpec`
       fields such as ``acf="self-affine"``; None: the exponential ACF) in
       place of the exponential ACF where given.
    4. :func:`surfaces_per_cell`: ``count_surfaces`` surfaces of the first cell
       on ``count_mesh`` at ``grid``, subsampled to ``counts``.
    5. :func:`~roughcontact.reports.speed.recommend.recommend` for ``tol_kP``,
       ``tol_area``; :func:`~roughcontact.reports.speed.render.write_report`.
    6. :func:`~roughcontact.reports.speed.recommend.derive_presets` from the
       stored ``config/accuracy_presets.yaml``, written to ``out_presets``
       (default: ``accuracy_presets.yaml`` beside ``out_md``).

    ``out_png`` is one path or a list of two. Returns the tables (keys
    solver, mesh, grid, surfaces, recommendation).

    Cost with the workflow's settings (grids 30-240; measured 2026-11-24, 2
    cores, one BLAS thread): 401 s and a peak resident set of 1.4 GB (the
    coarse "refined" models of the hybrid operators, 60 x 60 at most):
    solver study about 240 s (two cells), grid study 83 s (240 x 240: 15 s
    influence + 35 s sweep; 120 x 120: 15 s + 15 s), 120 surfaces 70 s.
    """
    say, started, before = reporter(progress), time.perf_counter(), describe_machine()
    geometry = BlockGeometry(size=(size, size), thickness=thickness, grid=(grid, grid), E=E,
                             nu=nu)
    common = dict(sigma=sigma, b=b, pressures=pressures, precision=precision, steps=steps,
                  seed=seed, progress=say)
    solver_table = _solver_tables(geometry, solver_meshes, cells, surfaces=surfaces,
                                  tolerances=tolerances, methods=methods, max_iter=max_iter,
                                  **common)
    mesh_table = mesh_errors(mesh_table_path, hybrid_table_path)
    grid_table = grid_study(cells[:1], grids=grids, size=size, thickness=thickness, E=E, nu=nu,
                            surfaces=grid_surfaces or surfaces, spectrum=spectrum, **common)
    unit, geom = _timed_influence(geometry, count_mesh, say)
    count_table = surfaces_per_cell(unit, geom, cells[0], surfaces=count_surfaces,
                                    counts=counts, **common)
    count_table.attrs["influence"] = count_mesh
    del unit
    recommendation = recommend(solver_table, mesh_table, grid_table, count_table,
                               tol_kP=tol_kP, tol_area=tol_area)
    notes = _notes(grid_table, size=size, thickness=thickness, E=E, nu=nu, sigma=sigma, b=b,
                   cells=cells, seed=seed, pressures=pressures, steps=steps,
                   precision=precision, surfaces=surfaces, grid=grid,
                   solver_meshes=solver_meshes, grids=grids, spectrum=spectrum,
                   count_surfaces=count_surfaces, count_mesh=count_mesh, started=started,
                   before=before)
    presets = derive_presets(solver_table, mesh_table, grid_table, count_table, load_presets())
    out_presets = Path(out_md).with_name(PRESETS_NAME) if out_presets is None else out_presets
    write_report(solver_table, mesh_table, grid_table, count_table, recommendation, out_md,
                 out_csv, out_png, notes=notes, presets=presets["accuracy_presets"],
                 presets_caption=f"this run's, `{Path(out_presets).name}` (stored ones where "
                                 "not measured; compare with `python -m "
                                 "roughcontact.study.presets --compare`)")
    write_presets(out_presets, presets)
    return {"solver": solver_table, "mesh": mesh_table, "grid": grid_table,
            "surfaces": count_table, "recommendation": recommendation}
