"""Where every output of a study lives: the ``results/`` layout, in one place.

The workflow's rules, the plan, the jobs and the audit take their paths from
here (relative to the working directory, Snakemake's ``--directory``); a file's
name is its record's key (:mod:`roughcontact.study.records`), so a changed
parameter is a new file. Under :data:`ROOT`:

- ``surfaces/<cell key>.h5``: a surface cell's heights (units of sigma);
- ``influence/<geometry key>.h5``, ``influence/pairs/<pair key>.h5``,
  ``influence/choices/<geometry key>.json`` and ``influence/thermal/<block key>.h5``:
  influence models, pairs of them summed once, the choices of ``operator: auto`` and
  the blocks' thermal influences (the conductance's);
- ``contact/<job key>.h5``: a contact job's non-dimensional sweep;
- ``cycles/<cycle job key>.h5``: a cycle job's non-dimensional loading path (the
  ``loading`` section's);
- ``aggregates/<study>.<ext>`` for each of :data:`AGGREGATE_EXTENSIONS`: a study's
  tables and their sidecar; ``aggregates/<study>.<ext>`` for each of
  :data:`CYCLE_EXTENSIONS`: its cycles' tables and sidecar;
- ``figures/<figure>.<ext>``, ``audit/``, ``reports/``, ``grid_convergence/``,
  ``logs/`` (mirroring the outputs) and ``benchmarks/``.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["AGGREGATE_EXTENSIONS", "CYCLE_EXTENSIONS", "ROOT", "Files", "aggregate",
           "aggregates", "choice", "contact", "cycle", "cycle_aggregates", "figure",
           "grid_contact", "grid_surfaces", "influence", "pair", "report", "surfaces",
           "thermal"]

#: The folder of every output, relative to the working directory.
ROOT = "results"
#: The files of a study's aggregates: the table, the mean-plane moduli, the JSON sidecar
#: and the validity table, in this order.
AGGREGATE_EXTENSIONS = ("csv", "moduli.csv", "json", "validity.csv")
#: The files of a study's cycles (the ``loading`` section's): the table per step, the
#: table per cycle and the JSON sidecar, in this order.
CYCLE_EXTENSIONS = ("cycles.csv", "cycles_summary.csv", "cycles.json")


@dataclass(frozen=True)
class Files:
    """The files of one kind, named by their record's key:
    ``<ROOT>/<folder>/<prefix><key><suffix>``."""

    folder: str
    suffix: str = ".h5"
    prefix: str = ""

    def __call__(self, key) -> str:
        return f"{ROOT}/{self.folder}/{self.prefix}{key}{self.suffix}"


#: A surface cell's file.
surfaces = Files("surfaces")
#: A geometry's influence file.
influence = Files("influence")
#: A block's thermal influence (the conductance's).
thermal = Files("influence/thermal")
#: A pair of influence models summed once.
pair = Files("influence/pairs")
#: The choice of an ``operator: auto`` geometry.
choice = Files("influence/choices", ".json")
#: A contact job's file.
contact = Files("contact")
#: A cycle job's file.
cycle = Files("cycles")
#: A report's file, by its name with its extension (``speed_vs_error.md``, ...).
report = Files("reports", "")


def aggregate(study: str, extension: str) -> str:
    """One of a study's aggregate files (``extension`` of :data:`AGGREGATE_EXTENSIONS`)."""
    return f"{ROOT}/aggregates/{study}.{extension}"


def aggregates(study: str) -> list[str]:
    """A study's aggregate files, in the order of :data:`AGGREGATE_EXTENSIONS`."""
    return [aggregate(study, extension) for extension in AGGREGATE_EXTENSIONS]


def cycle_aggregates(study: str) -> list[str]:
    """A study's cycle files, in the order of :data:`CYCLE_EXTENSIONS`."""
    return [aggregate(study, extension) for extension in CYCLE_EXTENSIONS]


def figure(name: str, extension: str) -> str:
    """A figure's file (png, pdf, the executed notebook ipynb, or a table's csv)."""
    return f"{ROOT}/figures/{name}.{extension}"


#: The grid-convergence study's surfaces on a grid (elements per side).
grid_surfaces = Files("grid_convergence", prefix="surfaces_")
#: The grid-convergence study's contact sweep on a grid.
grid_contact = Files("grid_convergence", prefix="contact_")
