"""The aggregation job: a study's contact results in SI units, averaged per nominal pressure.

An *aggregation* turns the contact results of a figure's (or sweep's) cells
into SI curves for each cell's sigma and E (Eq 28-32) and averages them on a
common nominal-pressure axis (:mod:`roughcontact.contact.aggregate`), into
CSV tables for people with a JSON sidecar; an elastic cell checked against a
hardness gets its validity table (the share of its real area and load above
it, from the stored solutions: no extra solve). What a study adds to the columns of
the probes its contact jobs recorded (the flow's leak rate and percolation
thresholds) comes from each probe's study-side record
(:class:`~roughcontact.study.probes.StudyProbe`).
"""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from roughcontact.contact import aggregate, plausibility
from roughcontact.contact import cell as cell_module
from roughcontact.errors import StoredFileError
from roughcontact.hashes import file_sha256
from roughcontact.study.codec import in_unit
from roughcontact.study.contact_records import StudyCell, study_columns
from roughcontact.study.jobs.storage import read_contact
from roughcontact.study.probes import StudyProbe
from roughcontact.study.provenance import NO_RUN, RunInfo, atomic_path, provenance
from roughcontact.units import MPA

log = logging.getLogger(__name__)


def validity_rows(cell: StudyCell, nd, levels) -> list[pd.DataFrame]:
    """The validity tables of an elastic cell (one per hardness it is checked against),
    with ``flagged``.

    ``levels`` [Pa]; each table is :func:`roughcontact.contact.cell.validity_table`
    with ``hardness_MPa`` and ``flagged`` (the mean share of the real area or
    of the load above H exceeds the cell's ``hardness_threshold``).
    """
    if cell.hardness is not None:
        return []
    threshold = cell.hardness_threshold
    out = []
    for H in cell.checked_hardness:
        frame = cell_module.validity_table(nd, cell.height_scale, cell.E, H, levels)
        flagged = ((frame["area_above_mean"] > threshold)
                   | (frame["load_above_mean"] > threshold))
        out.append(frame.drop(columns="hardness").assign(
            hardness_MPa=in_unit(H, MPA), threshold=threshold, flagged=flagged))
    return out


def validity_summary(frame: pd.DataFrame) -> dict:
    """Per cell and hardness: the lowest flagged pressure level [MPa] and the largest shares."""
    flagged = frame[frame["flagged"]]
    return {
        "first_flagged_MPa": (float(flagged["nominal_pressure"].min() / MPA)
                              if len(flagged) else None),
        "max_area_above": float(frame["area_above_mean"].max()),
        "max_load_above": float(frame["load_above_mean"].max()),
        "max_excess_load": float(frame["excess_load_mean"].max()),
    }


#: Columns of a study's validity table, in order (also its header when no cell names a
#: hardness).
VALIDITY_COLUMNS = ("cell", "label", "contact_key", "hardness_MPa", "threshold",
                    "nominal_pressure", *(f"{q}_{s}" for q in cell_module.VALIDITY_QUANTITIES
                                          for s in ("mean", "half_width", "count")), "flagged")


class _CellTables(NamedTuple):
    """The aggregation of one study cell: its part of each table and of the sidecar."""

    rows: pd.DataFrame  # one row per pressure level
    moduli: pd.DataFrame  # one row per surface
    summary: dict  # the mean-plane modulus and convergence summary
    validity: list  # one table per hardness it is checked against
    checks: list  # their summaries
    probed: dict  # probe kind -> its rows of the sidecar (e.g. the percolation thresholds)


def _plausibility(cell: StudyCell, frame: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """The table with its ``plausibility`` column
    (:func:`~roughcontact.contact.plausibility.plausibility_flags`), and the cell's
    reasons (:func:`~roughcontact.contact.plausibility.implausible`, logged as a warning)."""
    n = cell.geometry.grid[0] * cell.geometry.grid[1]
    flags = plausibility.plausibility_flags(frame, n, cell.E, cell.geometry.nu)
    reasons = plausibility.implausible(frame, n, cell.E, cell.geometry.nu)
    if reasons:
        log.warning("cell %s: results outside physical plausibility: %s; see its rows' "
                    "plausibility column (a block too thick for its patch, or a mesh too "
                    "coarse, gives this)", cell.label, "; ".join(reasons))
    units = {**frame.attrs["units"], "plausibility": "-"}
    frame = frame.assign(plausibility=flags)
    frame.attrs["units"] = units
    return frame, reasons


def _with_pressure_in_mpa(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with ``nominal_pressure_MPa`` beside ``nominal_pressure`` [Pa]: the unit the
    configuration, the figures and the sidecar speak (``nominal_pressure`` unchanged)."""
    units = {**frame.attrs["units"], "nominal_pressure_MPa": "MPa"}
    frame = frame.copy()
    frame.insert(frame.columns.get_loc("nominal_pressure") + 1, "nominal_pressure_MPa",
                 [in_unit(p, MPA) for p in frame["nominal_pressure"]])
    frame.attrs["units"] = units
    return frame


def with_probe_columns(frame: pd.DataFrame, probes: tuple) -> pd.DataFrame:
    """The table with the columns each study-side probe record adds (the flow's leak
    rate; none without probes)."""
    for record in probes:
        columns, units = record.table_columns(frame)
        units = {**frame.attrs["units"], **units}
        frame = frame.assign(**columns)
        frame.attrs["units"] = units
    return frame


def _shown(probes) -> str:
    """The probes of a message: each one's settings under its kind, or none."""
    return str({probe.kind: probe.params() for probe in probes}) if probes else "no probe"


def check_probes(path, stored: tuple, probes: tuple, geometry) -> None:
    """The contact file of a job on ``geometry`` must have recorded the probes the
    configuration asks for."""
    wanted = tuple(record.job_probe(geometry) for record in probes)
    if stored != wanted:
        raise StoredFileError(
            f"{path}: solved with {_shown(stored)}, but the configuration asks for "
            f"{_shown(wanted)}; delete it and run the workflow again to solve it with the "
            "configured probes", path)


def _aggregate_cell(index: int, cell: StudyCell, columns: dict, path, levels: int,
                    probes: tuple[StudyProbe, ...] = ()) -> _CellTables:
    """Aggregate one cell's contact file at ``levels`` nominal pressures over its range,
    labelled with its ``columns`` (:func:`~roughcontact.study.contact_records.study_columns`;
    with what the study-side records of its ``probes`` add: the flow's leak rate and
    percolation thresholds, where the flow is on)."""
    nd, attrs = read_contact(path, job=cell.job.params())  # solved for this cell's job
    check_probes(path, nd.probe_columns.probes, probes, cell.job.geometry)
    key, label = cell.contact_key, cell.label
    axis = aggregate.pressure_axis(*cell.pressure_range, levels)
    physical, frame = cell_module.aggregate_sweep(nd, cell.height_scale, cell.E, axis,
                                                  hardness=cell.hardness)
    frame, implausible = _plausibility(cell, frame)
    frame = with_probe_columns(_with_pressure_in_mpa(frame), probes)
    labels = {"cell": index, "label": label, "contact_key": key, **columns}
    probed = {record.kind: record.cell_rows(physical, {"cell": index, "label": label,
                                                       "contact_key": key})
              for record in probes}
    if cell.hardness is not None or cell.checked_hardness:
        labels["cap_MPa"] = float("nan") if cell.hardness is None else in_unit(cell.hardness,
                                                                               MPA)
    validity, checks = [], []
    for part in validity_rows(cell, nd, axis):
        validity.append(part.assign(cell=index, label=label, contact_key=key))
        summary = validity_summary(part)
        checks.append({"cell": index, "label": label,
                       "hardness_MPa": float(part["hardness_MPa"].iloc[0]),
                       "threshold": float(part["threshold"].iloc[0]), **summary})
        if summary["first_flagged_MPa"] is not None:
            log.warning("cell %s: above the hardness %g MPa from P = %.3g MPa (share of "
                        "real area up to %.3g, of load up to %.3g; threshold %g): the "
                        "elastic model overstates pressures there", label,
                        checks[-1]["hardness_MPa"], summary["first_flagged_MPa"],
                        summary["max_area_above"], summary["max_load_above"],
                        checks[-1]["threshold"])
    per_surface = aggregate.mean_plane_modulus(physical)
    unconverged = int(attrs["unconverged_steps"])
    summary = {**labels,
               **{k: float(v) for k, v in aggregate.modulus_summary(per_surface, cell.E).items()},
               "unconverged_steps": unconverged, "worst_residual": float(attrs["worst_residual"]),
               "implausible": implausible, **cell.counterface.summary(attrs, cell.height_scale)}
    if unconverged:
        log.warning("cell %s: %d unconverged steps excluded", key, unconverged)
    for reason in aggregate.COVERAGE[2:]:
        short = frame["nominal_pressure"][frame["coverage"] == reason] / MPA
        if len(short):
            log.warning("cell %s: %d pressure levels (%.4g-%.4g MPa) have no values: %s; "
                        "their rows are NaN with count 0", label, len(short), short.min(),
                        short.max(), reason)
    return _CellTables(frame.assign(**labels), per_surface.assign(seed=attrs["seeds"], **labels),
                       summary, validity, checks, probed)


def aggregate_study(cells: list[StudyCell], contact_paths: dict, levels: int, table_path,
                    moduli_path, meta_path, run: RunInfo = NO_RUN, validity_path=None,
                    probes: tuple[StudyProbe, ...] = ()) -> pd.DataFrame:
    """Aggregate a figure's or sweep's cells into CSV tables with a JSON sidecar.

    ``contact_paths`` maps a contact key to its file. The table has one row per
    cell and pressure level (:func:`roughcontact.contact.aggregate.aggregate_cell`
    columns plus the cell's parameters, as
    :func:`~roughcontact.study.contact_records.study_columns` gives them: with counter
    bodies, each cell's ``counter``); the moduli table one row per cell and surface
    (E_u, Eq 36) with the cell summary in the sidecar; the nominal pressure is in Pa
    (``nominal_pressure``) and in MPa (``nominal_pressure_MPa``). Unconverged
    solves are excluded by the aggregation and counted in both. With
    ``validity_path``, the validity table (:func:`validity_rows`: the share of
    each elastic cell's real area and load above each hardness it names, no
    extra solve; header only without a hardness) is written there, its
    flagged cells summarised in the sidecar. ``probes``: the study-side records of the
    probes the contact files must have recorded
    (:func:`~roughcontact.study.probes.study_probes`); the table has their columns and
    what each record adds (with the flow on, :mod:`roughcontact.study.flow_settings`:
    the leak rate of its seal and, per level, whether the pressure drop would open the
    faces, ``faces_open``), and the sidecar each record's entry under its kind
    (each cell's percolation thresholds).
    """
    parts = [_aggregate_cell(index, cell, columns, contact_paths[cell.contact_key], levels,
                             probes)
             for index, (cell, columns) in enumerate(zip(cells, study_columns(cells),
                                                         strict=True))]
    table = pd.concat([part.rows for part in parts], ignore_index=True)
    with atomic_path(table_path) as tmp:
        table.to_csv(tmp, index=False)
    with atomic_path(moduli_path) as tmp:
        pd.concat([part.moduli for part in parts], ignore_index=True).to_csv(tmp, index=False)
    meta = {
        "description": "aggregates of the contact study; one row per cell and nominal "
                       "pressure level; mean, 95 % Student-t half width and surface count "
                       "per quantity",
        "units": parts[0].rows.attrs["units"] if parts else {},
        "interpolation": aggregate.INTERPOLATION,
        "cells": [cell.params() for cell in cells],
        "mean_plane_modulus": [part.summary for part in parts],
        **provenance(run),  # with the config hash
        # what the figures check before they read the tables
        "table_sha256": file_sha256(table_path),
        "moduli_sha256": file_sha256(moduli_path),
    }
    for record in probes:
        meta[record.kind] = record.sidecar([
            {name: json_value(value) for name, value in row.items()}
            for part in parts for row in part.probed[record.kind]])
    if validity_path is not None:
        meta |= _write_validity([frame for part in parts for frame in part.validity],
                                [check for part in parts for check in part.checks],
                                validity_path)
    with atomic_path(meta_path) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=1, default=float))
    return table


def json_value(value):
    """A value of the strict-JSON sidecar: None for NaN."""
    return None if isinstance(value, float) and not math.isfinite(value) else value


def _write_validity(frames: list, checks: list, path) -> dict:
    """Write a study's validity table; returns its entries of the sidecar."""
    frame = (pd.concat(frames, ignore_index=True) if frames
             else pd.DataFrame(columns=list(VALIDITY_COLUMNS)))
    with atomic_path(path) as tmp:
        frame[list(VALIDITY_COLUMNS)].to_csv(tmp, index=False)
    return {
        "validity": {
            "description": "share of each elastic cell's real contact area and load above "
                           "the hardness (from the stored solutions, no extra solve); flagged "
                           "where a mean share exceeds the threshold",
            "checks": checks,
            "flagged_cells": sorted({c["cell"] for c in checks
                                     if c["first_flagged_MPa"] is not None}),
        },
        "validity_sha256": file_sha256(path),
    }


__all__ = [
    "VALIDITY_COLUMNS",
    "aggregate_study",
    "validity_rows",
    "validity_summary",
]
