"""The speed-against-error report from scratch: the Snakemake rule ``speed_vs_error``.

:func:`speed_vs_error_report` runs the experiments
(:mod:`roughcontact.reports.speed.experiments`), decides
(:mod:`roughcontact.reports.speed.recommend`), renders
(:mod:`roughcontact.reports.speed.render`) and writes this run's accuracy
presets (:func:`write_presets`) for comparison with the stored ones
(``python -m roughcontact.study.presets --compare``). It takes four records:
the configured :class:`~roughcontact.study.config.SpeedReportSettings`, the
:class:`SpeedSpecimen` it measures on, the :class:`SpeedOptions` it measures
and the :class:`ReportFiles` it reads and writes::

    from roughcontact.reports.speed import ReportFiles, speed_vs_error_report

    speed_vs_error_report(ReportFiles("speed.md", "speed.csv", "speed.png"))
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import pandas as pd
import yaml

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.hybrid import hybrid_unit_modulus_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.reports.speed.experiments import (
    DEFAULT_CELLS,
    REFERENCE_TOL,
    REPORT_COMPARISON,
    SolverComparison,
    mesh_errors,
    solver_speed_vs_error,
    surfaces_per_cell,
)
from roughcontact.reports.speed.grid import grid_study
from roughcontact.reports.speed.machine import describe_machine
from roughcontact.reports.speed.recommend import derive_presets, recommend
from roughcontact.reports.speed.render import write_report
from roughcontact.reports.speed.sweeps import (
    DEFAULT_SURFACES,
    CellSurfaces,
    SweepSettings,
    reporter,
)
from roughcontact.study.config import SpeedReportSettings
from roughcontact.study.presets import load_presets
from roughcontact.study.provenance import atomic_path, git_commit
from roughcontact.units import MM, MPA, UM

__all__ = [
    "PRESETS_NAME",
    "ReportFiles",
    "SpeedOptions",
    "SpeedSpecimen",
    "speed_vs_error_report",
    "write_presets",
]

#: File name of this run's accuracy presets, beside the Markdown report by default.
PRESETS_NAME = "accuracy_presets.yaml"
#: The report's settings by default: the schema's (``reports.speed_vs_error``).
DEFAULT_SETTINGS = SpeedReportSettings()


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


@dataclass(frozen=True)
class ReportFiles:
    """Where the speed-against-error report reads and writes.

    Attributes
    ----------
    md, csv : path-like
        The Markdown report and the tidy CSV of every table.
    png : path-like or sequence of two
        One six-panel figure, or two (solver; grid and surface count).
    presets : path-like, optional
        This run's accuracy presets (default: :data:`PRESETS_NAME` beside ``md``).
    mesh_table : path-like, optional
        The influence-convergence CSV (:func:`mesh_errors`; None or missing:
        :data:`~roughcontact.study.presets.FALLBACK_MESH_ERRORS`).
    hybrid_table : path-like, optional
        The benchmark's ``influence_hybrid.csv`` (None: no hybrid rows).
    """

    md: str | os.PathLike
    csv: str | os.PathLike
    png: str | os.PathLike | Sequence[str | os.PathLike]
    presets: str | os.PathLike | None = None
    mesh_table: str | os.PathLike | None = None
    hybrid_table: str | os.PathLike | None = None

    def presets_path(self) -> Path:
        """Where this run's accuracy presets go: ``presets``, else beside ``md``."""
        return Path(self.md).with_name(PRESETS_NAME) if self.presets is None else Path(self.presets)


@dataclass(frozen=True)
class SpeedSpecimen:
    """The block, material and surfaces the speed-against-error report measures on.

    Attributes
    ----------
    size : float
        Side of the square block, the nominal contact area [m].
    thickness : float
        Block thickness L [m] (clamped base).
    E, nu : float
        Young's modulus [Pa] and Poisson's ratio.
    grid : int
        Contact elements per side of the solver and surface-count studies.
    cells : sequence of (skew, kurt)
        Statistics cells (Eq 4-5) of the solver study; the first one is also
        that of the grid and surface-count studies.
    generator : CellSurfaces
        How their surfaces are generated (sigma, b [m], seed).

    The defaults are the paper's block (Table 1: 9 mm x 9 mm x 10 mm, E = 511
    MPa, nu = 0, 60 x 60) and :data:`DEFAULT_CELLS`.
    """

    size: float = 9e-3
    thickness: float = 10e-3
    E: float = 5.11e8
    nu: float = 0.0
    grid: int = 60
    cells: Sequence[tuple[float, float]] = DEFAULT_CELLS
    generator: CellSurfaces = DEFAULT_SURFACES

    @classmethod
    def of_block(cls, block: BlockGeometry, **fields) -> SpeedSpecimen:
        """The specimen of ``block``'s first side and grid, L, E and nu, and ``fields``
        (``cells``, ``generator``); its base and mesh are not used (the report's block
        is clamped and each experiment chooses its mesh)."""
        return cls(size=block.size[0], thickness=block.thickness, E=block.E, nu=block.nu,
                   grid=block.grid[0], **fields)

    def geometry(self) -> BlockGeometry:
        """The clamped square block on ``grid`` x ``grid`` elements (its mesh is replaced
        by each experiment's)."""
        return BlockGeometry(size=(self.size, self.size), thickness=self.thickness,
                             grid=(self.grid, self.grid), E=self.E, nu=self.nu)


@dataclass(frozen=True)
class SpeedOptions:
    """The numerical choices the speed-against-error report measures beside its settings.

    Attributes
    ----------
    solver_meshes : sequence of str
        Influence of each solver study: a mesh preset, ``"hybrid:<preset>"``
        (the hybrid operator) or ``"halfspace"`` (default: the paper's mesh).
    comparison : SolverComparison
        Methods, tolerances and iteration limits compared against the exact
        solution (default :data:`REPORT_COMPARISON`).
    precision, steps : str, int
        Precision of the iterative solvers and approaches of every sweep (the
        pipeline's: mixed, 30).
    grid_surfaces : int, optional
        Surfaces per cell of the grid study (None: the settings' ``surfaces``).
    grid_spectrum : mapping, optional
        :class:`~roughcontact.surfaces.spec.SurfaceSpec` fields of the grid
        study's surfaces (e.g. ``acf="self-affine"``) in place of the
        specimen's ACF (None: the specimen's surfaces).
    count_mesh : str
        Influence of the surface-count study (default ``"hybrid:refined"``).
    """

    solver_meshes: Sequence[str] = ("paper",)
    comparison: SolverComparison = REPORT_COMPARISON
    precision: str = "mixed"
    steps: int = 30
    grid_surfaces: int | None = None
    grid_spectrum: Mapping | None = None
    count_mesh: str = "hybrid:refined"

    def sweep(self, pressures: Sequence[float]) -> SweepSettings:
        """The sweeps of every experiment, read at ``pressures`` [Pa] (cg at 1e-8 where one
        method is swept)."""
        return SweepSettings(pressures=tuple(pressures), steps=self.steps,
                             precision=self.precision)

    def grid_generator(self, generator: CellSurfaces) -> CellSurfaces:
        """The grid study's surfaces: ``generator``, on :attr:`grid_spectrum` where given."""
        if self.grid_spectrum is None:
            return generator
        return dataclasses.replace(generator, spectrum=self.grid_spectrum)


def _solver_tables(geometry: BlockGeometry, meshes: Sequence[str], say: Callable[[str], None],
                   study: Callable[..., pd.DataFrame]) -> pd.DataFrame:
    """``study(unit, geometry, label=name)`` (:func:`solver_speed_vs_error` bound to its
    settings) on the influence of each of ``meshes``, stacked (the first table's
    ``attrs``)."""
    tables = []
    for name in meshes:
        unit, geom = _timed_influence(geometry, name, say)
        tables.append(study(unit, geom, label=name))
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


def _notes(grid_table: pd.DataFrame, settings: SpeedReportSettings, specimen: SpeedSpecimen,
           options: SpeedOptions, started: float, before: str) -> list[str]:
    """How each part of the report was measured, a line each (``## How it was measured``):
    the records it ran on, the wall time since ``started`` and the machine ``before``."""
    size, generator, cells, grid = specimen.size, specimen.generator, specimen.cells, specimen.grid
    return [
        f"Block {size / MM:g} mm x {size / MM:g} mm, L = {specimen.thickness / MM:g} mm, "
        f"E = {specimen.E:g} Pa, nu = {specimen.nu:g}, clamped base; surfaces: exponential "
        f"ACF (Eq 1), sigma = {generator.sigma / UM:g} um, b = {generator.b / MM:g} mm, "
        f"periodic filter; cells {', '.join(f'(Sk {s:g}, Ku {k:g})' for s, k in cells)}; "
        f"seed {generator.seed}.",
        f"Pressures {', '.join(f'{p / MPA:g}' for p in settings.pressures)} MPa; each sweep "
        f"is a contact job: {options.steps} geometric approaches "
        "(contact.cell.approach_grid), contact.cell.sweep_cell with tangent stiffness, warm "
        f"starts, precision {options.precision}.",
        f"Solver: {settings.surfaces} surfaces per cell on {grid} x {grid}, influence "
        f"{', '.join(options.solver_meshes)}; errors at equal approach against method "
        f"'exact' (block principal pivoting, tol {REFERENCE_TOL:g}); its cost is the "
        "'exact' row (reference=True).",
        "Mesh: read from the influence-convergence table (not recomputed).",
        f"Grid: {', '.join(str(g) for g in settings.grids)} per side, influence "
        f"{grid_table.attrs.get('influence_model')}, chosen because the refined "
        "finite-element model at 120 x 120 needs about 4 times the dofs of 60 x 60 and the "
        "hybrid is within 1.2 % of the converged preset at 60 x 60; surfaces "
        f"{grid_table.attrs.get('pairing')} (the finest grid point-sampled)"
        f"{_spectrum_note(options.grid_spectrum)}.",
        f"Surfaces per cell: {settings.count_surfaces} surfaces of cell {cells[0]} on "
        f"{options.count_mesh} at {grid} x {grid}, solved once; random subsets per count.",
        f"Total wall time {time.perf_counter() - started:.0f} s; machine before: {before}; "
        f"after: {describe_machine()}.",
    ]


def _write(files: ReportFiles, tables: Mapping[str, pd.DataFrame], notes: list[str]) -> None:
    """The report's Markdown, CSV and figures, and this run's accuracy presets
    (:func:`derive_presets` from the stored ones), to ``files``."""
    measured = [tables[name] for name in ("solver", "mesh", "grid", "surfaces")]
    presets = derive_presets(*measured, load_presets())
    out_presets = files.presets_path()
    write_report(*measured, tables["recommendation"], files.md, files.csv, files.png,
                 notes=notes, presets=presets["accuracy_presets"],
                 presets_caption=f"this run's, `{out_presets.name}` (stored ones where "
                                 "not measured; compare with `python -m "
                                 "roughcontact.study.presets --compare`)")
    write_presets(out_presets, presets)


def speed_vs_error_report(
    files: ReportFiles, settings: SpeedReportSettings = DEFAULT_SETTINGS,
    specimen: SpeedSpecimen = SpeedSpecimen(), options: SpeedOptions = SpeedOptions(), *,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Run every measurement from scratch and write the report (the Snakemake entry point).

    ``settings`` (:class:`~roughcontact.study.config.SpeedReportSettings`, the
    ``reports.speed_vs_error`` section) say how much to measure and at which
    pressures, ``specimen`` (:class:`SpeedSpecimen`) on what, ``options``
    (:class:`SpeedOptions`) with which numerical choices, ``files``
    (:class:`ReportFiles`) where to read and write. Every sweep is
    ``options.sweep(settings.pressures)`` (:class:`SweepSettings`).

    1. :func:`solver_speed_vs_error` on the specimen's block (the paper's 60 x
       60, 9 mm, 10 mm by default) for each of ``options.solver_meshes``
       (built here; "hybrid:<preset>" for the hybrid operator),
       ``settings.surfaces`` per cell of ``specimen.cells``.
    2. :func:`mesh_errors` from ``files.mesh_table`` (the influence-convergence
       CSV) and ``files.hybrid_table``, or :data:`FALLBACK_MESH_ERRORS`.
    3. :func:`grid_study` over ``settings.grids`` (hybrid refined influence,
       nested surfaces, the first cell, ``options.grid_surfaces`` or
       ``settings.surfaces`` surfaces), on ``options.grid_spectrum`` in place
       of the exponential ACF where given.
    4. :func:`surfaces_per_cell`: ``settings.count_surfaces`` surfaces of the
       first cell on ``options.count_mesh``, subsampled to ``settings.counts``.
    5. :func:`~roughcontact.reports.speed.recommend.recommend` for
       ``settings.tol_kP``, ``settings.tol_area``;
       :func:`~roughcontact.reports.speed.render.write_report`.
    6. :func:`~roughcontact.reports.speed.recommend.derive_presets` from the
       stored ``config/accuracy_presets.yaml``, written to ``files.presets``.

    Returns the tables (keys solver, mesh, grid, surfaces, recommendation).

    Cost with the workflow's settings (grids 30-240; measured 2026-11-24, 2
    cores, one BLAS thread): 401 s and a peak resident set of 1.4 GB (the
    coarse "refined" models of the hybrid operators, 60 x 60 at most):
    solver study about 240 s (two cells), grid study 83 s (240 x 240: 15 s
    influence + 35 s sweep; 120 x 120: 15 s + 15 s), 120 surfaces 70 s.
    """
    say, started, before = reporter(progress), time.perf_counter(), describe_machine()
    geometry, generator = specimen.geometry(), specimen.generator
    sweep = options.sweep(settings.pressures)
    tables = {"solver": _solver_tables(geometry, options.solver_meshes, say, partial(
        solver_speed_vs_error, cells=specimen.cells, surfaces=settings.surfaces,
        generator=generator, sweep=sweep, comparison=options.comparison, progress=say))}
    tables["mesh"] = mesh_errors(files.mesh_table, files.hybrid_table)
    tables["grid"] = grid_study(geometry, specimen.cells[:1], grids=settings.grids,
                                surfaces=options.grid_surfaces or settings.surfaces,
                                generator=options.grid_generator(generator), sweep=sweep,
                                progress=say)
    unit, geom = _timed_influence(geometry, options.count_mesh, say)
    tables["surfaces"] = surfaces_per_cell(unit, geom, specimen.cells[0],
                                           surfaces=settings.count_surfaces,
                                           counts=settings.counts, generator=generator,
                                           sweep=sweep, progress=say)
    tables["surfaces"].attrs["influence"] = options.count_mesh
    del unit
    tables["recommendation"] = recommend(tables["solver"], tables["mesh"], tables["grid"],
                                         tables["surfaces"], tol_kP=settings.tol_kP,
                                         tol_area=settings.tol_area)
    _write(files, tables, _notes(tables["grid"], settings, specimen, options, started, before))
    return tables
