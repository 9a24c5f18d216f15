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
  :func:`solver_speed_vs_error`, :func:`mesh_errors`,
  :func:`surfaces_per_cell`, :func:`band_vs_count`;
- :mod:`~roughcontact.reports.speed.grid` -- the contact-grid runner,
  :func:`grid_study`;
- :mod:`~roughcontact.reports.speed.sweeps` -- what the runners share: a
  cell's surfaces and a timed contact sweep;
- :mod:`~roughcontact.reports.speed.recommend` -- decisions from their
  tables: :func:`recommend`, :func:`derive_presets`;
- :mod:`~roughcontact.reports.speed.render` -- figures, Markdown and the tidy
  CSV: :func:`write_report`;
- :mod:`~roughcontact.reports.speed.machine` -- the machine a timing was taken on;
- :mod:`~roughcontact.reports.speed.report` -- :func:`speed_vs_error_report`,
  the Snakemake entry point, and :func:`write_presets`.
"""

from roughcontact.reports.speed.experiments import (
    SOLVER_QUANTITIES,
    band_vs_count,
    mesh_errors,
    solver_speed_vs_error,
    surfaces_per_cell,
)
from roughcontact.reports.speed.grid import grid_study
from roughcontact.reports.speed.recommend import derive_presets, recommend
from roughcontact.reports.speed.render import write_report
from roughcontact.reports.speed.report import speed_vs_error_report, write_presets
from roughcontact.study.presets import ACCURACY_PRESETS, FALLBACK_MESH_ERRORS

__all__ = [
    "ACCURACY_PRESETS",
    "FALLBACK_MESH_ERRORS",
    "SOLVER_QUANTITIES",
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
