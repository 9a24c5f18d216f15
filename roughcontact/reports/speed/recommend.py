"""Decisions of the speed-against-error report: recommended settings and accuracy presets.

Pure functions of the experiment tables (:mod:`roughcontact.reports.speed.experiments`):

- :func:`recommend` -- per component (mesh, contact grid, solver, surface
  count), the cheapest option within a tolerance on k_P (Eq 33) and real area.
- :func:`derive_presets` -- the accuracy presets of ``config/accuracy_presets.yaml``
  (:mod:`roughcontact.study.presets`) with every number this run measured
  replaced by its measurement; the report writes them to
  ``results/reports/accuracy_presets.yaml``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np
import pandas as pd

__all__ = ["CHOOSERS", "FALLBACK_KEYS", "MESH_ERROR_KEYS", "PRESET_DIGITS", "derive_presets",
           "recommend"]

#: Significant digits of the measured relative errors [-] and costs written to the presets.
PRESET_DIGITS = 3


def _pick(candidates: pd.DataFrame, cost: str, meets: pd.Series):
    """Cheapest row meeting the tolerance, else the most accurate row (meets=False)."""
    good = candidates[meets]
    if len(good):
        return good.sort_values(cost, kind="stable").iloc[0], True, int(len(good))
    worst = candidates[["k_P_error", "real_area_error"]].max(axis=1)
    return candidates.loc[worst.idxmin()], False, 0


def _within(frame: pd.DataFrame, share: float, tol_kP: float, tol_area: float) -> pd.Series:
    """Rows whose k_P and real-area errors are within ``share`` of the tolerances."""
    return (frame["k_P_error"] <= share * tol_kP) & (frame["real_area_error"] <= share * tol_area)


def _choice(component: str, choice: str, cost: float, cost_unit: str, k_P_error: float,
            real_area_error: float, meets, options_meeting: int, note: str) -> dict:
    """One row of the recommendation table."""
    return {"component": component, "choice": choice, "cost": cost, "cost_unit": cost_unit,
            "k_P_error": k_P_error, "real_area_error": real_area_error, "meets": bool(meets),
            "options_meeting": options_meeting, "note": note}


def _mesh_choice(mesh_table: pd.DataFrame, share: float, tol_kP: float, tol_area: float) -> dict:
    """Cheapest mesh to build within tolerance of its reference (:func:`mesh_errors`)."""
    mesh = mesh_table.reset_index(drop=True)
    row, ok, count = _pick(mesh, "build_s", _within(mesh, share, tol_kP, tol_area))
    return _choice("mesh", row["mesh"], float(row["build_s"]), "s to build E*C (60 x 60)",
                   float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
                   f"error against the {row.get('reference', 'converged')} preset "
                   f"(p_max error {100 * float(row['max_pressure_error']):.1f} %)"
                   + ("" if ok else "; no mesh meets the tolerance"))


def _grid_choice(grid_table: pd.DataFrame, share: float, tol_kP: float, tol_area: float) -> dict:
    """Cheapest contact grid coarser than the finest within tolerance of it (:func:`grid_study`);
    else the finest, not shown converged (its own error unknown)."""
    grid = grid_table.groupby("grid").agg(
        k_P_error=("k_P_change", lambda s: float(np.nanmax(np.abs(s)))),
        real_area_error=("real_area_change", lambda s: float(np.nanmax(np.abs(s)))),
        cost=("build_s", "first"), solve_s=("solve_s", "sum"),
        surfaces=("surfaces", "first")).reset_index()
    grid["cost"] = grid["cost"] + grid["solve_s"]
    finest = int(grid["grid"].max())
    coarser = grid[grid["grid"] < finest].sort_values("grid")
    per_quantity = []
    for column, name, tol in (("k_P_error", "k_P", tol_kP), ("real_area_error", "area", tol_area)):
        good = coarser[coarser[column] <= share * tol]
        per_quantity.append(f"{name} alone: {int(good['grid'].iloc[0])} per side"
                            if len(good) else f"{name} alone: none coarser than {finest}")
    detail = "; ".join(f"{int(r['grid'])}: k_P {100 * r['k_P_error']:.1f} %, area "
                       f"{100 * r['real_area_error']:.0f} %" for _, r in coarser.iterrows())
    note = f"change against the finest grid ({finest}: {detail}); " + ", ".join(per_quantity)
    meets = _within(coarser, share, tol_kP, tol_area)
    if len(coarser) and meets.any():
        row, ok, count = _pick(coarser, "cost", meets)
        k_error, a_error = float(row["k_P_error"]), float(row["real_area_error"])
    else:
        row, ok, count = grid[grid["grid"] == finest].iloc[0], False, 0
        k_error = a_error = math.nan
        note += ("; no coarser grid is within the tolerance of the finest, whose own "
                 "error is not measured: the grid is not shown converged")
    return _choice("grid", f"{int(row['grid'])} per side", float(row["cost"]),
                   "s (influence + sweeps)", k_error, a_error, ok, count, note)


def _solver_choice(solver_table: pd.DataFrame, share: float, tol_kP: float,
                   tol_area: float) -> dict:
    """Cheapest solver setting within tolerance of the exact solution, every step converged
    (:func:`solver_speed_vs_error`; cost: the summed sweeps of the measured cells)."""
    keys = ["influence", "method", "tol", "precision"]
    solver = solver_table.groupby(keys, sort=False).agg(
        k_P_error=("k_P_error", "max"), real_area_error=("real_area_error", "max"),
        load_error=("load_error", "max"), cost=("wall_s", "sum"),
        converged=("converged_fraction", "min")).reset_index()
    solver = solver.drop_duplicates(keys)
    meets = _within(solver, share, tol_kP, tol_area) & (solver["converged"] >= 1.0)
    row, ok, count = _pick(solver, "cost", meets)
    return _choice("solver", f"{row['method']} tol {row['tol']:.0e} ({row['precision']}, "
                   f"{row['influence']})", float(row["cost"]), "s (sweeps of all measured cells)",
                   float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
                   "against the exact solution at equal approach (load error "
                   f"{float(row['load_error']):.1e})"
                   + ("" if ok else "; none meets the tolerance"))


def _count_choice(count_table: pd.DataFrame, share: float, tol_kP: float,
                  tol_area: float) -> dict:
    """Fewest surfaces per cell whose relative 95 % half-width is within tolerance
    (:func:`band_vs_count`)."""
    counts = count_table.groupby("count").agg(
        k_P_error=("k_P_relative_half_width", "max"),
        real_area_error=("real_area_relative_half_width", "max")).reset_index()
    counts["cost"] = counts["count"].astype(float)
    row, ok, count = _pick(counts, "cost", _within(counts, share, tol_kP, tol_area))
    solved = int(count_table["surfaces_solved"].max())
    return _choice("surfaces", f"{int(row['count'])} per cell", float(row["count"]), "surfaces",
                   float(row["k_P_error"]), float(row["real_area_error"]), ok, count,
                   f"relative 95 % half-width of the cell mean (subsets of {solved} solved "
                   "surfaces)" + ("" if ok else f"; more than {int(row['count'])} surfaces needed"))


#: Components of the recommendation, in its order: name -> chooser of one row from the
#: component's table, its share of the tolerance and the tolerances on k_P and real area.
CHOOSERS = MappingProxyType({"mesh": _mesh_choice, "grid": _grid_choice,
                             "solver": _solver_choice, "surfaces": _count_choice})


def _combined(rows: list[dict], tol_kP: float, tol_area: float) -> dict:
    """The chosen components' known errors added up (a bound for independent errors)."""
    k_sum = float(np.nansum([r["k_P_error"] for r in rows]))
    a_sum = float(np.nansum([r["real_area_error"] for r in rows]))
    unknown = [r["component"] for r in rows
               if not (np.isfinite(r["k_P_error"]) and np.isfinite(r["real_area_error"]))]
    return _choice("combined", "the choices above", math.nan, "", k_sum, a_sum,
                   all(r["meets"] for r in rows) and k_sum <= tol_kP and a_sum <= tol_area, 0,
                   "sum of the components' errors (worst case of independent errors)"
                   + (f"; without {', '.join(unknown)} (unknown)" if unknown else ""))


def _summary(rows: list[dict], tol_kP: float, tol_area: float, shares: dict) -> str:
    """The recommendation in plain language, a line per component."""
    lines = [f"Tolerance: k_P within {100 * tol_kP:g} %, real area within {100 * tol_area:g} %"
             + (f" (shares {shares})." if shares else ", each component alone.")]
    for r in rows:
        status = "meets" if r["meets"] else "does NOT meet"
        lines.append(f"- {r['component']}: {r['choice']} ({status} it; k_P "
                     f"{100 * r['k_P_error']:.2g} %, area {100 * r['real_area_error']:.2g} %). "
                     f"{r['note']}.")
    return "\n".join(lines)


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
    tables = {"mesh": mesh_table, "grid": grid_table, "solver": solver_table,
              "surfaces": count_table}
    rows = [choose(tables[name], float(shares.get(name, 1.0)), tol_kP, tol_area)
            for name, choose in CHOOSERS.items()
            if tables[name] is not None and len(tables[name])]
    if rows:
        rows.append(_combined(rows, tol_kP, tol_area))
    table = pd.DataFrame(rows)
    table.attrs.update(tol_kP=tol_kP, tol_area=tol_area, shares=shares,
                       text=_summary(rows, tol_kP, tol_area, shares))
    return table


# ---------------------------------------------------------------------------
# Accuracy presets

#: Mesh-table columns stored per preset (relative errors [-] against the converged mesh).
MESH_ERROR_KEYS = ("k_P_error", "real_area_error", "max_pressure_error")
#: Mesh-table columns stored per mesh in ``fallback_mesh_errors`` (s, GB, relative errors).
FALLBACK_KEYS = ("build_s", "peak_memory_GB", *MESH_ERROR_KEYS)


def _rounded(value) -> float:
    """``value`` to :data:`PRESET_DIGITS` significant digits, as a plain float."""
    return float(f"{float(value):.{PRESET_DIGITS}g}")


def _fill(stored: Mapping, measured: Mapping) -> dict:
    """``stored`` with the finite ``measured`` values of its own keys (rounded).

    Keys ``stored`` lacks are dropped, so the structure stays the stored one;
    a value the run could not measure (NaN) keeps the stored number.
    """
    fresh = dict(stored)
    for key, value in measured.items():
        if key in fresh and value is not None and math.isfinite(float(value)):
            fresh[key] = _rounded(value)
    return fresh


def _largest(values) -> float:
    """Largest |value| (NaN when there is none)."""
    values = np.abs(np.asarray(values, dtype=float))
    return float(np.nanmax(values)) if np.isfinite(values).any() else math.nan


def _measured_meshes(mesh_table: pd.DataFrame | None) -> dict[str, pd.Series]:
    """Rows of :func:`~roughcontact.reports.speed.experiments.mesh_errors` that were
    measured (not the stored fallback) against the "converged" preset, as the stored
    numbers are, by mesh name."""
    if mesh_table is None or not len(mesh_table):
        return {}
    measured = mesh_table[(mesh_table["source"].astype(str) != "FALLBACK_MESH_ERRORS")
                          & (mesh_table["reference"].astype(str) == "converged")]
    return {str(row["mesh"]): row for _, row in measured.iterrows()}


def _solver_errors(solver_table: pd.DataFrame | None, method: str, tol: float,
                   precision: str | None) -> dict:
    """Largest k_P and real-area error against the exact solution at ``method``/``tol``.

    Over every measured influence, cell and pressure; the rows at the preset's
    ``precision`` when the table has them, else those at the report's.
    """
    if solver_table is None or not len(solver_table):
        return {}
    rows = solver_table[(solver_table["method"] == method)
                        & np.isclose(solver_table["tol"].astype(float), float(tol),
                                     rtol=1e-9, atol=0.0)]
    if "precision" in rows and (rows["precision"] == precision).any():
        rows = rows[rows["precision"] == precision]
    if not len(rows):
        return {}
    return {"solver_k_P_error": _largest(rows["k_P_error"]),
            "solver_real_area_error": _largest(rows["real_area_error"])}


def _grid_changes(grid_table: pd.DataFrame | None, element_size: float | None) -> dict:
    """Largest |change| of k_P and real area at ``element_size`` [m] against the finest grid.

    Empty when that element size was not measured or is the finest (whose
    change is 0 by definition, not a measurement).
    """
    if grid_table is None or not len(grid_table) or element_size is None:
        return {}
    sizes = grid_table["element_size_m"].astype(float)
    rows = grid_table[np.isclose(sizes, float(element_size), rtol=1e-6, atol=0.0)]
    if not len(rows) or np.isclose(float(element_size), sizes.min(), rtol=1e-6, atol=0.0):
        return {}
    return {"grid_change_k_P": _largest(rows["k_P_change"]),
            "grid_change_real_area": _largest(rows["real_area_change"])}


def _sampling(count_table: pd.DataFrame | None, surfaces: int | None) -> dict:
    """Largest relative 95 % half-width of the cell mean with ``surfaces`` surfaces."""
    if count_table is None or not len(count_table) or surfaces is None:
        return {}
    rows = count_table[count_table["count"] == int(surfaces)]
    if not len(rows):
        return {}
    return {"sampling_k_P": _largest(rows["k_P_relative_half_width"]),
            "sampling_real_area": _largest(rows["real_area_relative_half_width"])}


def derive_presets(solver_table: pd.DataFrame | None, mesh_table: pd.DataFrame | None,
                   grid_table: pd.DataFrame | None, count_table: pd.DataFrame | None,
                   stored: Mapping) -> dict:
    """The accuracy presets with this run's measurements in place of the stored numbers.

    ``stored`` is the content of ``config/accuracy_presets.yaml``
    (:func:`roughcontact.study.presets.load_presets`: sections
    ``accuracy_presets`` and ``fallback_mesh_errors``). The result has exactly
    its sections, names and keys; per preset the settings (``mesh``,
    ``grid_per_9mm``, ``element_size_m``, ``method``, ``tol``, ``precision``,
    ``surfaces``) and texts are kept, and of the numbers those the tables
    measure are replaced (largest |value| over cells and pressures, rounded to
    :data:`PRESET_DIGITS` significant digits; all relative, dimensionless):

    - ``k_P_error``, ``real_area_error``, ``max_pressure_error``: the row of
      the preset's ``mesh`` in ``mesh_table``
      (:func:`~roughcontact.reports.speed.experiments.mesh_errors`), when it
      was read from an influence-convergence table (not the fallback) whose
      reference is the "converged" preset;
    - ``solver_k_P_error``, ``solver_real_area_error``: ``solver_table`` at
      the preset's ``method`` and ``tol`` (error against the exact solution at
      equal approach);
    - ``grid_change_k_P``, ``grid_change_real_area``: ``grid_table`` at the
      preset's ``element_size_m`` [m] against the finest grid (when a finer
      one was measured);
    - ``sampling_k_P``, ``sampling_real_area``: ``count_table`` at the
      preset's ``surfaces`` (relative 95 % half-width of the cell mean);
    - ``fallback_mesh_errors``: ``build_s`` [s], ``peak_memory_GB`` [GB] and
      the three mesh errors of each stored mesh found in ``mesh_table``.

    Every other value keeps the stored one.
    """
    meshes = _measured_meshes(mesh_table)
    presets = {}
    for name, preset in stored["accuracy_presets"].items():
        measured = {}
        if preset.get("mesh") in meshes:
            measured.update({key: meshes[preset["mesh"]][key] for key in MESH_ERROR_KEYS})
        if "method" in preset and "tol" in preset:
            measured.update(_solver_errors(solver_table, preset["method"], preset["tol"],
                                           preset.get("precision")))
        measured.update(_grid_changes(grid_table, preset.get("element_size_m")))
        measured.update(_sampling(count_table, preset.get("surfaces")))
        presets[name] = _fill(preset, measured)
    fallback = {}
    for mesh, values in stored["fallback_mesh_errors"].items():
        row = meshes.get(mesh)
        fallback[mesh] = _fill(values, {} if row is None else {k: row[k] for k in FALLBACK_KEYS})
    return {"accuracy_presets": presets, "fallback_mesh_errors": fallback}
