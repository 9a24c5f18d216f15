"""Where every output of a study lives: the ``results/`` layout, in one place.

The workflow's rules, the plan, the jobs and the audit take their paths from
here (relative to the working directory, Snakemake's ``--directory``); a file's
name is its record's key (:mod:`roughcontact.study.records`), so a changed
parameter is a new file. Under :data:`ROOT`:

- ``surfaces/<cell key>.h5``: a surface cell's heights (units of sigma);
- ``influence/<geometry key>.h5``, ``influence/pairs/<pair key>.h5`` and
  ``influence/choices/<geometry key>.json``: influence models, pairs of them summed
  once, and the choices of ``operator: auto``;
- ``contact/<job key>.h5``: a contact job's non-dimensional sweep;
- ``aggregates/<study>.<ext>`` for each of :data:`AGGREGATE_EXTENSIONS`: a study's
  tables and their sidecar;
- ``figures/<figure>.<ext>``, ``audit/``, ``reports/``, ``grid_convergence/``,
  ``logs/`` (mirroring the outputs) and ``benchmarks/``.
"""

from __future__ import annotations

__all__ = ["AGGREGATE_EXTENSIONS", "ROOT", "aggregate", "aggregates", "choice", "contact",
           "figure", "grid_contact", "grid_surfaces", "influence", "pair", "report",
           "surfaces"]

#: The folder of every output, relative to the working directory.
ROOT = "results"
#: The files of a study's aggregates: the table, the mean-plane moduli, the JSON sidecar
#: and the validity table, in this order.
AGGREGATE_EXTENSIONS = ("csv", "moduli.csv", "json", "validity.csv")


def surfaces(key: str) -> str:
    """A surface cell's file."""
    return f"{ROOT}/surfaces/{key}.h5"


def influence(key: str) -> str:
    """A geometry's influence file."""
    return f"{ROOT}/influence/{key}.h5"


def pair(key: str) -> str:
    """A pair of influence models summed once."""
    return f"{ROOT}/influence/pairs/{key}.h5"


def choice(key: str) -> str:
    """The choice of an ``operator: auto`` geometry."""
    return f"{ROOT}/influence/choices/{key}.json"


def contact(key: str) -> str:
    """A contact job's file."""
    return f"{ROOT}/contact/{key}.h5"


def aggregate(study: str, extension: str) -> str:
    """One of a study's aggregate files (``extension`` of :data:`AGGREGATE_EXTENSIONS`)."""
    return f"{ROOT}/aggregates/{study}.{extension}"


def aggregates(study: str) -> list[str]:
    """A study's aggregate files, in the order of :data:`AGGREGATE_EXTENSIONS`."""
    return [aggregate(study, extension) for extension in AGGREGATE_EXTENSIONS]


def figure(name: str, extension: str) -> str:
    """A figure's file (png, pdf, the executed notebook ipynb, or a table's csv)."""
    return f"{ROOT}/figures/{name}.{extension}"


def report(name: str) -> str:
    """A report's file (``speed_vs_error.md``, ``influence_convergence.csv``, ...)."""
    return f"{ROOT}/reports/{name}"


def grid_surfaces(grid: int) -> str:
    """The grid-convergence study's surfaces on ``grid``."""
    return f"{ROOT}/grid_convergence/surfaces_{grid}.h5"


def grid_contact(grid: int) -> str:
    """The grid-convergence study's contact sweep on ``grid``."""
    return f"{ROOT}/grid_convergence/contact_{grid}.h5"
