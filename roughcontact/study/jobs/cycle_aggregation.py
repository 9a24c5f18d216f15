"""The cycles' aggregation: a study's loops in SI units, averaged step by step and per cycle.

Each capped cell's cycle file (:mod:`roughcontact.study.jobs.cycle_storage`, checked to
have been solved for the cell's cycle job) is taken to SI units for the cell's sigma
and E (:func:`~roughcontact.contact.cycles.cycle_to_physical`, Eq 28-32). Under load
control every surface of a cell sits at the same nominal pressure at every step, so
the surfaces are averaged step by step, with 95 % Student-t bands
(:func:`~roughcontact.contact.aggregate.statistics`), into

- ``<study>.cycles.csv``: one row per cell and step, with its cycle and leg
  (loading, unloading, reloading; :func:`~roughcontact.contact.cycles.legs`): the
  approach, the real and plastic area fractions, the permanent set (the residual
  approach once unloaded), the plastic depth ``V_p / A_n``, the stiffness per nominal
  area ``k_P = (dF/dd) / A_n`` and the probes' columns (and what each probe's study
  record adds: the seal's leak rate);
- ``<study>.cycles_summary.csv``: one row per cell and cycle
  (:func:`~roughcontact.contact.cycles.cycle_summary`): the residual approach at the
  cycle's end, the energy the loop dissipated and the plastic work per nominal area,
  the unloading-to-loading stiffness ratio at half the peak, the share of surfaces
  shaken down, and every per-step quantity at half the peak on the cycle's rise and
  on its fall (``rise_*``, ``fall_*``: a seal pressed once, at the same load);
- ``<study>.cycles.json``: units, the cells, the loading path, the solver's
  statistics per cell, provenance and the tables' SHA-256.

Unconverged steps (flagged by the job with the surface's later steps) are left out and
counted.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from roughcontact.contact import aggregate
from roughcontact.contact.cycles import cycle_summary, cycle_to_physical, legs
from roughcontact.hashes import file_sha256
from roughcontact.study.contact_records import StudyCell, study_columns
from roughcontact.study.cycle_records import LoadingSettings
from roughcontact.study.jobs.aggregation import check_probes, json_value, with_probe_columns
from roughcontact.study.jobs.cycle_storage import read_cycle
from roughcontact.study.probes import StudyProbe
from roughcontact.study.provenance import NO_RUN, RunInfo, atomic_path, provenance
from roughcontact.units import MPA

__all__ = ["STEP_QUANTITIES", "SUMMARY_QUANTITIES", "aggregate_cycles", "cell_tables"]

log = logging.getLogger(__name__)

#: The quantities of the table per step: name -> (unit, meaning).
STEP_QUANTITIES = {
    "approach": ("m", "d, rigid approach from the original surface's first touch"),
    "real_area_fraction": ("1", "A / A_n, share of elements with p > 0"),
    "plastic_area_fraction": ("1", "share of elements at the cap, p = H"),
    "permanent_set": ("m", "min(f + w) - min(f): the approach at which the flattened "
                           "surface first touches (the residual approach once unloaded)"),
    "plastic_depth": ("m", "V_p / A_n, the plastic volume per nominal area"),
    "normalized_stiffness": ("Pa/m", "k_P = (dF/dd) / A_n, tangent on the elements in "
                                     "contact below the cap"),
}
#: The quantities of the table per cycle: name -> (unit, meaning).
SUMMARY_QUANTITIES = {
    "residual_approach": ("m", "permanent set at the cycle's end"),
    "dissipated_energy": ("J/m^2", "the work of the load over the cycle per nominal area, "
                                   "sum 1/2 (P_i + P_i+1) (d_i+1 - d_i): the loop's area, "
                                   "dissipated, where the cycle ends at the load it began "
                                   "at (every cycle unloading to no load; from the second "
                                   "on with unload_to > 0, where the first also holds the "
                                   "elastic energy stored at its end)"),
    "plastic_work": ("J/m^2", "H times the plastic volume the cycle added, per nominal "
                              "area"),
    "unloading_stiffness_ratio": ("1", "unloading over loading tangent at half the peak"),
    "shaken_down": ("1", "share of surfaces whose cycle added no plastic volume"),
}


def _stats(name: str, samples: np.ndarray) -> dict:
    """``name``'s mean, half width and count columns of ``samples`` ``(m, k)``."""
    mean, half_width, count = aggregate.statistics(samples)
    return {f"{name}_mean": mean, f"{name}_half_width": half_width, f"{name}_count": count}


def _per_step(physical, probes, area: float) -> dict[str, np.ndarray]:
    """Every per-step quantity of an SI cycle, ``(m, k)`` by name: :data:`STEP_QUANTITIES`
    and the probes' columns."""
    return {"approach": physical.approach,
            "real_area_fraction": physical.real_area_fraction,
            "plastic_area_fraction": physical.plastic_area_fraction,
            "permanent_set": physical.permanent_set,
            "plastic_depth": physical.plastic_volume / area,
            "normalized_stiffness": physical.contact_stiffness / area,
            **{name: probes[name] for name in probes}}


def _table(values: dict, pressure, probes: tuple, columns: dict) -> pd.DataFrame:
    """A table of the statistics of ``values`` (name -> ``(m, k)``) at nominal
    ``pressure`` [Pa] ``(k,)``, with what the study ``probes`` add and ``columns``."""
    frame = pd.DataFrame({"nominal_pressure": pressure,
                          "nominal_pressure_MPa": np.asarray(pressure) / MPA,
                          **{k: v for name, samples in values.items()
                             for k, v in _stats(name, samples).items()}})
    frame.attrs["units"] = {}
    frame = with_probe_columns(frame, probes)
    return frame.assign(**columns)


def _at_pressure(values: np.ndarray, pressure: np.ndarray, steps: np.ndarray,
                 level: float) -> np.ndarray:
    """Each surface's value ``(m,)`` at the nominal pressure ``level`` along the leg
    ``steps`` (load control: one pressure per step for every surface), linear in P."""
    order = steps[np.argsort(pressure[steps])]
    p = pressure[order]
    upper = int(np.clip(np.searchsorted(p, level), 1, len(p) - 1))
    weight = (level - p[upper - 1]) / (p[upper] - p[upper - 1])
    return (1 - weight) * values[:, order[upper - 1]] + weight * values[:, order[upper]]


def _summary(physical, per_step: dict, probes: tuple, columns: dict, area: float,
             cycle: np.ndarray, leg: np.ndarray) -> pd.DataFrame:
    """The table per cycle of an SI cycle (module docstring), its steps' ``cycle`` and
    ``leg`` (:func:`~roughcontact.contact.cycles.legs`)."""
    summary = cycle_summary(physical)
    pressure = np.asarray(physical.path.values)
    rows = []
    for c in range(summary["peak_load"].shape[1]):
        peak = float(np.max(pressure[cycle == c + 1]))
        own = {"residual_approach": summary["permanent_set"][:, c:c + 1],
               "dissipated_energy": summary["dissipated"][:, c:c + 1] / area,
               "plastic_work": summary["plastic_work"][:, c:c + 1] / area,
               "unloading_stiffness_ratio": summary["unloading_stiffness_ratio"][:, c:c + 1],
               "shaken_down": summary["shaken_down"][:, c:c + 1].astype(float)}
        row = _table(own, [peak / 2], (), {})
        row.insert(0, "cycle", c + 1)
        row.insert(1, "peak_pressure_MPa", peak / MPA)
        row = row.rename(columns={"nominal_pressure_MPa": "half_peak_MPa"}).drop(
            columns="nominal_pressure")
        for name, steps in (("rise", (cycle == c + 1) & (leg != "unloading")),
                            ("fall", (cycle == c + 1) & (leg == "unloading"))):
            steps = np.flatnonzero(steps)
            if c > 0 or name == "fall":  # a leg from the turn before it
                steps = np.concatenate([[steps[0] - 1], steps])
            at = {q: _at_pressure(v, pressure, steps, peak / 2)[:, None]
                  for q, v in per_step.items()}
            part = _table(at, [peak / 2], probes, {}).drop(
                columns=["nominal_pressure", "nominal_pressure_MPa"])
            row = pd.concat([row, part.add_prefix(f"{name}_")], axis=1)
        rows.append(row.assign(**columns))
    return pd.concat(rows, ignore_index=True)


def cell_tables(cell: StudyCell, loading: LoadingSettings, path, probes: tuple = (),
                columns: dict | None = None) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """A cell's tables per step and per cycle (module docstring) from its cycle file
    ``path``, checked to have been solved for its cycle job (of ``loading``) with the
    study ``probes``, labelled with ``columns``; and its solver statistics."""
    job = loading.job(cell)
    nd, attrs = read_cycle(path, job=job.params())
    check_probes(path, nd.probe_columns.probes, probes, cell.job.geometry)
    lx, ly = cell.geometry.size
    area = lx * ly
    physical = cycle_to_physical(nd, cell.height_scale, cell.E, cell.geometry.thickness, area)
    per_step = _per_step(physical, nd.probe_columns.in_length(cell.height_scale), area)
    cycle, leg = legs(physical.path)
    columns = dict(columns or {}) | {"cycle_key": job.key,
                                     "cap_MPa": float(cell.hardness / MPA)}
    steps = _table(per_step, np.asarray(physical.path.values), probes, columns)
    steps.insert(0, "step", np.arange(len(cycle)))
    steps.insert(1, "cycle", cycle)
    steps.insert(2, "leg", leg)
    unconverged = int(attrs["unconverged_steps"])
    if unconverged:
        log.warning("cell %s: %d unconverged cycle steps (with their surfaces' later steps) "
                    "left out", cell.label, unconverged)
    stats = {"label": cell.label, "cycle_key": job.key, "unconverged_steps": unconverged,
             "worst_residual": float(attrs["worst_residual"]),
             "wall_seconds": float(attrs["wall_seconds"])}
    return steps, _summary(physical, per_step, probes, columns, area, cycle, leg), stats


def aggregate_cycles(cells: list[StudyCell], loading: LoadingSettings, cycle_paths: dict,
                     outputs, run: RunInfo = NO_RUN,
                     probes: tuple[StudyProbe, ...] = ()) -> pd.DataFrame:
    """Aggregate a study's capped ``cells`` along ``loading``'s path into the tables and
    sidecar ``outputs`` (``table``, ``summary``, ``meta``; module docstring) from their
    cycle files (``cycle_paths``: cycle job key -> path). Returns the table per step."""
    tables, summaries, stats = [], [], []
    for index, (cell, columns) in enumerate(zip(cells, study_columns(cells), strict=True)):
        step, summary, stat = cell_tables(cell, loading,
                                          cycle_paths[loading.job(cell).key], probes,
                                          {"cell": index, "label": cell.label, **columns})
        tables.append(step)
        summaries.append(summary)
        stats.append(stat)
    table = pd.concat(tables, ignore_index=True)
    with atomic_path(outputs.table) as tmp:
        table.to_csv(tmp, index=False)
    with atomic_path(outputs.summary) as tmp:
        pd.concat(summaries, ignore_index=True).to_csv(tmp, index=False)
    units = {name: unit for name, (unit, _) in {**STEP_QUANTITIES,
                                                 **SUMMARY_QUANTITIES}.items()}
    meta = {"description": "loading, unloading and reloading of the study's capped cells "
                           "(load control, the cap's permanent set kept): one row per cell "
                           "and step, and one per cell and cycle; mean, 95 % Student-t "
                           "half width and surface count per quantity",
            "units": {"nominal_pressure": "Pa", "nominal_pressure_MPa": "MPa", **units},
            "meanings": {name: meaning for name, (_, meaning) in
                         {**STEP_QUANTITIES, **SUMMARY_QUANTITIES}.items()},
            "loading": loading.params(), "cells": [cell.params() for cell in cells],
            "solver": [{k: json_value(v) for k, v in s.items()} for s in stats],
            **provenance(run),
            "table_sha256": file_sha256(outputs.table),
            "summary_sha256": file_sha256(outputs.summary)}
    with atomic_path(outputs.meta) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=1, default=float))
    return table
