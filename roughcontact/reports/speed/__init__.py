"""Speed against error of the numerical choices: solver, mesh, contact grid, surface count.

Every result of the study (Figs 7, 9-14 of Kumar, Sadeghi & Krousgrill 2006)
carries four numerical errors besides the physics (solver tolerance on Eq 27,
finite-element mesh of Eq 16, contact grid, number of random surfaces). This
package measures each against its cost on k_P (Eq 33), the real area
fraction and the peak pressure, recommends the cheapest settings within a
tolerance and re-measures the accuracy presets. One module per job, imported
one way (``report`` -> ``experiments``, ``grid``, ``recommend``, ``render`` ->
``sweeps``, ``machine``):

- :mod:`~roughcontact.reports.speed.experiments` -- the runners:
  :func:`solver_speed_vs_error` (what it compares: :class:`SolverComparison`),
  :func:`mesh_errors`, :func:`surfaces_per_cell`, :func:`band_vs_count`;
- :mod:`~roughcontact.reports.speed.grid` -- the contact-grid runner,
  :func:`grid_study` (its influence models and pairing: :class:`GridOptions`);
- :mod:`~roughcontact.reports.speed.sweeps` -- what the runners share: a
  cell's surfaces (:class:`CellSurfaces`) and a timed contact sweep
  (:class:`SweepSettings`), records the caller builds once;
- :mod:`~roughcontact.reports.speed.recommend` -- decisions from their
  tables: :func:`recommend`, :func:`derive_presets`;
- :mod:`~roughcontact.reports.speed.render` -- figures, Markdown and the tidy
  CSV: :func:`write_report`;
- :mod:`~roughcontact.reports.speed.machine` -- the machine a timing was taken on;
- :mod:`~roughcontact.reports.speed.report` -- :func:`speed_vs_error_report`,
  the Snakemake entry point (its records: :class:`ReportFiles`,
  :class:`SpeedSpecimen`, :class:`SpeedOptions` and
  :class:`~roughcontact.study.config.SpeedReportSettings`), and
  :func:`write_presets`.

The runners on a small block, for instance::

    from roughcontact.elasticity.influence import BlockGeometry
    from roughcontact.reports.speed import CellSurfaces, SweepSettings, grid_study

    table = grid_study(BlockGeometry(size=(1.8e-3, 1.8e-3), thickness=2e-3),
                       grids=(6, 12), surfaces=2, generator=CellSurfaces(b=0.3e-3),
                       sweep=SweepSettings(pressures=(1e6,), steps=8))
"""

from roughcontact.reports.speed.experiments import (
    SOLVER_QUANTITIES,
    SolverComparison,
    band_vs_count,
    mesh_errors,
    solver_speed_vs_error,
    surfaces_per_cell,
)
from roughcontact.reports.speed.grid import GridOptions, grid_study
from roughcontact.reports.speed.recommend import derive_presets, recommend
from roughcontact.reports.speed.render import write_report
from roughcontact.reports.speed.report import (
    ReportFiles,
    SpeedOptions,
    SpeedSpecimen,
    speed_vs_error_report,
    write_presets,
)
from roughcontact.reports.speed.sweeps import CellSurfaces, SweepSettings
from roughcontact.study.presets import ACCURACY_PRESETS, FALLBACK_MESH_ERRORS

__all__ = [
    "ACCURACY_PRESETS",
    "FALLBACK_MESH_ERRORS",
    "SOLVER_QUANTITIES",
    "CellSurfaces",
    "GridOptions",
    "ReportFiles",
    "SolverComparison",
    "SpeedOptions",
    "SpeedSpecimen",
    "SweepSettings",
    "band_vs_count",
    "derive_presets",
    "grid_study",
    "mesh_errors",
    "recommend",
    "solver_speed_vs_error",
    "speed_vs_error_report",
    "surfaces_per_cell",
    "write_presets",
    "write_report",
]
