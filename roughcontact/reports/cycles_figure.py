"""The cycles figure: loading, unloading and reloading of the listed studies' capped cells.

Each study's cycles' tables (``<study>.cycles.csv``, one row per cell and load step,
and ``<study>.cycles_summary.csv``, one row per cell and cycle:
:mod:`roughcontact.study.jobs.cycle_aggregation`), checked against the SHA-256 their
sidecar ``<study>.cycles.json`` records, give one row of panels per study:

- nominal pressure [MPa] against the approach [um] of each cell, the band the 95 %
  confidence interval of the mean approach at each step's pressure (under load control
  every surface sits at the same nominal pressure at every step);
- the stiffness per nominal area k_P [MPa/um] against nominal pressure;
- where the study was solved with the flow, the leak rate [m^3/s, log] against nominal
  pressure, the levels at which the fluid would open the faces (the tables'
  ``faces_open``) marked; else the permanent set [um] against load step.

In every panel the first loading is solid, each unloading dashed and each reloading
dotted (:data:`LEG_STYLES`); each leg's curve starts at the last step of the leg before
it, so that a loop is drawn closed. The answers (:func:`cycles_answers`) give per cell
the residual approach after the first cycle, the unloading-to-loading stiffness ratio at
half the peak, the energy each cycle dissipated beside its plastic work, the share of
surfaces shaken down in the second cycle and, with the flow on, the leak rate at half the
peak on loading and on unloading.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from roughcontact.reports.plotting import check_sha256, positive_band
from roughcontact.reports.study_figures import cell_labels, flow_directions
from roughcontact.study.flow_settings import FACES_OPEN
from roughcontact.study.layout import CYCLE_EXTENSIONS
from roughcontact.transport.probe import LEAK_RATE, column_name
from roughcontact.units import MPA, UM

__all__ = ["CYCLE_FILES", "LEG_STYLES", "cycle_numbers", "cycles_answers", "leg_segments",
           "load_cycles", "plot_cycles"]

#: Files per study of the figure's ``aggregate_files``: the table per step, the table per
#: cycle and their sidecar (:data:`~roughcontact.study.layout.CYCLE_EXTENSIONS`).
CYCLE_FILES = len(CYCLE_EXTENSIONS)
#: The line style of each leg of a cycle.
LEG_STYLES = {"loading": "-", "unloading": "--", "reloading": ":"}
#: Line widths by leg: a reloading that retraces the unloading (an elastic cycle) is drawn
#: wider, on top, so that its dots show on the dashes.
LEG_WIDTHS = {"loading": 1.5, "unloading": 1.5, "reloading": 2.5}
#: k_P [Pa/m] in MPa/um.
MPA_PER_UM = MPA / UM


def load_cycles(paths, names) -> dict:
    """The cycles' tables of several studies by name: ``(steps, summary)``, the table per
    step and the table per cycle of each :data:`CYCLE_FILES` paths of ``paths`` (in the
    order of ``names``), each checked against the SHA-256 its sidecar records
    (:class:`~roughcontact.errors.StoredFileError` if edited or damaged)."""
    paths, names = list(paths), list(names)
    if len(paths) != CYCLE_FILES * len(names):
        raise ValueError(f"{len(paths)} cycle files for {len(names)} studies "
                         f"({', '.join(names)}): expected {CYCLE_FILES} each")
    found = {}
    for k, name in enumerate(names):
        table_path, summary_path, meta_path = paths[CYCLE_FILES * k:CYCLE_FILES * (k + 1)]
        meta = json.loads(Path(meta_path).read_text())
        check_sha256(table_path, meta, "table_sha256", meta_path)
        check_sha256(summary_path, meta, "summary_sha256", meta_path)
        found[name] = (pd.read_csv(table_path), pd.read_csv(summary_path))
    return found


def leg_segments(rows: pd.DataFrame, joined: bool = True) -> list[tuple[str, pd.DataFrame]]:
    """A cell's rows of the table per step cut into its legs, in step order: ``(leg,
    rows)``; ``joined``: each leg's rows from the last step of the leg before it (a loop
    drawn closed; not for a tangent such as k_P, which jumps where the load turns)."""
    rows = rows.sort_values("step")
    run = (rows["leg"] != rows["leg"].shift()) | (rows["cycle"] != rows["cycle"].shift())
    starts = list(np.flatnonzero(run.to_numpy())) + [len(rows)]
    return [(rows["leg"].iloc[start], rows.iloc[max(start - int(joined), 0):end])
            for start, end in zip(starts[:-1], starts[1:], strict=True)]


def _stat(rows: pd.DataFrame, quantity: str, scale: float = 1.0):
    """Mean and 95 % half width of ``quantity`` times ``scale``, and the mask of the steps
    that rest on at least one surface."""
    ok = rows[f"{quantity}_count"].to_numpy() > 0
    mean = rows[f"{quantity}_mean"].to_numpy(dtype=float) * scale
    half = np.nan_to_num(rows[f"{quantity}_half_width"].to_numpy(dtype=float)) * scale
    return mean, half, ok


def _line(leg: str) -> dict:
    """The line style and width of ``leg`` (:data:`LEG_STYLES`, :data:`LEG_WIDTHS`)."""
    return {"ls": LEG_STYLES[leg], "lw": LEG_WIDTHS[leg], "zorder": 2.5 if leg == "reloading"
            else 2}


def _draw_loop(ax, rows, color, style: dict, label) -> None:
    """Panel (a): nominal pressure against the approach, the approach's band across."""
    approach, half, ok = _stat(rows, "approach", 1 / UM)
    pressure = rows["nominal_pressure"].to_numpy(dtype=float)[ok] / MPA
    ax.plot(approach[ok], pressure, color=color, label=label, **style)
    ax.fill_betweenx(pressure, approach[ok] - half[ok], approach[ok] + half[ok],
                     color=color, alpha=0.15, lw=0)


def _draw_against_pressure(ax, rows, quantity: str, scale: float, color, style: dict) -> None:
    """Panels (b) and (c): ``quantity`` against nominal pressure with its band (in log
    space for the leak rate, whose axis is log; its levels of no leak left out)."""
    mean, half, ok = _stat(rows, quantity, scale)
    log = ax.get_yscale() == "log"
    if log:
        ok &= mean > 0
    pressure = rows["nominal_pressure"].to_numpy(dtype=float)[ok] / MPA
    low, high = (positive_band(mean[ok], half[ok]) if log
                 else (mean[ok] - half[ok], mean[ok] + half[ok]))
    ax.plot(pressure, mean[ok], color=color, **style)
    ax.fill_between(pressure, low, high, color=color, alpha=0.15, lw=0)


def _mark_open(ax, rows, quantity: str) -> None:
    """Panel (c) with the flow: a grey cross on each step of a cell at which the faces
    would open (the table's ``faces_open``), once per step."""
    if FACES_OPEN not in rows:
        return
    mean, _, ok = _stat(rows, quantity)
    opened = ok & (mean > 0) & rows[FACES_OPEN].to_numpy(dtype=bool)
    ax.plot(rows["nominal_pressure"].to_numpy(dtype=float)[opened] / MPA, mean[opened], "x",
            color="grey", ms=6, zorder=3)


def _draw_set(ax, rows, color, style: dict) -> None:
    """Panel (c) without the flow: the permanent set against load step."""
    mean, half, ok = _stat(rows, "permanent_set", 1 / UM)
    step = rows["step"].to_numpy()[ok]
    ax.plot(step, mean[ok], color=color, **style)
    ax.fill_between(step, mean[ok] - half[ok], mean[ok] + half[ok], color=color, alpha=0.15,
                    lw=0)


def _draw_cell(row_axes, rows, color, label, direction) -> None:
    for leg, segment in leg_segments(rows, joined=False):
        _draw_against_pressure(row_axes[1], segment, "normalized_stiffness", 1 / MPA_PER_UM,
                               color, _line(leg))
    for k, (leg, segment) in enumerate(leg_segments(rows)):
        style = _line(leg)
        _draw_loop(row_axes[0], segment, color, style, label if k == 0 else None)
        if direction is None:
            _draw_set(row_axes[2], segment, color, style)
        else:
            _draw_against_pressure(row_axes[2], segment, column_name(LEAK_RATE, direction),
                                   1.0, color, style)
    if direction is not None:
        _mark_open(row_axes[2], rows, column_name(LEAK_RATE, direction))


def _finish_row(row_axes, name: str, table, direction) -> None:
    from matplotlib.lines import Line2D

    loops, stiffness, right = row_axes
    loops.set(xlabel="approach d [µm]", ylabel="nominal pressure P [MPa]",
              title=f"{name}: nominal pressure against approach")
    stiffness.set(xlabel="nominal pressure P [MPa]", ylabel="k_P = (dF/dd) / A_n [MPa/µm]",
                  title=f"{name}: stiffness per nominal area")
    keys = [Line2D([], [], color="k", label=leg, **_line(leg)) for leg in LEG_STYLES
            if leg in set(table["leg"])]
    if direction is None:
        right.set(xlabel="load step", ylabel="permanent set [µm]",
                  title=f"{name}: permanent set (residual approach)")
        for end in table.groupby("cycle")["step"].max().to_numpy()[:-1]:
            right.axvline(end, color="grey", lw=0.8)
    else:
        right.set(yscale="log", xlabel="nominal pressure P [MPa]",
                  ylabel=f"leak rate Q along {direction} [m³/s]",
                  title=f"{name}: leak rate, loading against unloading")
        if FACES_OPEN in table and table[FACES_OPEN].astype(bool).any():
            right.plot([], [], "x", color="grey", label="faces open (Δp > P)")
            right.legend(fontsize=7, loc="upper right")
    for ax in row_axes:
        ax.grid(True, alpha=0.3)
    loops.legend(fontsize=7, loc="upper left")
    stiffness.legend(handles=keys, fontsize=7, loc="lower right")


def plot_cycles(studies: dict):
    """The figure of ``studies`` (name -> ``(steps, summary)``, :func:`load_cycles`): one
    row of three panels per study (module docstring); returns the figure."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(studies), 3, figsize=(15.0, 4.6 * len(studies)),
                             squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for row_axes, (name, (table, _)) in zip(axes, studies.items(), strict=True):
        directions = flow_directions(table)
        direction = directions[0] if directions else None
        if direction is not None:
            row_axes[2].set_yscale("log")
        labels = cell_labels(table, name)
        for k, (cell, rows) in enumerate(table.groupby("cell", sort=True)):
            _draw_cell(row_axes, rows, colors[k % len(colors)], labels[cell], direction)
        _finish_row(row_axes, name, table, direction)
    fig.tight_layout()
    return fig


def _summary_value(row, quantity: str, scale: float = 1.0) -> tuple[float, float]:
    return (float(row[f"{quantity}_mean"]) * scale,
            float(np.nan_to_num(row[f"{quantity}_half_width"])) * scale)


def cycle_numbers(studies: dict) -> pd.DataFrame:
    """Each cell's numbers per cycle (its rows of the table per cycle), for the notebook
    and the answers: ``study``, ``cell``, ``label``, ``cycle``, ``half_peak_MPa``, the
    residual approach [um], the unloading-to-loading stiffness ratio, the dissipated
    energy and the plastic work [J/m^2], the share shaken down, each with its 95 % half
    width (``_pm``), and with the flow the leak rate at half the peak on the rise and on
    the fall [m^3/s] (``leak_rise``, ``leak_fall``, ``_pm``) along the first direction."""
    rows = []
    for name, (table, summary) in studies.items():
        labels = cell_labels(table, name)
        directions = flow_directions(table)
        leak = column_name(LEAK_RATE, directions[0]) if directions else None
        for _, row in summary.sort_values(["cell", "cycle"]).iterrows():
            found = {"study": name, "cell": row["cell"], "label": labels[row["cell"]],
                     "cycle": int(row["cycle"]), "half_peak_MPa": row["half_peak_MPa"]}
            for quantity, short, scale in (("residual_approach", "residual_um", 1 / UM),
                                           ("unloading_stiffness_ratio", "stiffness_ratio", 1),
                                           ("dissipated_energy", "dissipated", 1),
                                           ("plastic_work", "plastic_work", 1),
                                           ("shaken_down", "shaken_down", 1)):
                found[short], found[f"{short}_pm"] = _summary_value(row, quantity, scale)
            if leak is not None:
                found["leak_rise"], found["leak_rise_pm"] = _summary_value(row, f"rise_{leak}")
                found["leak_fall"], found["leak_fall_pm"] = _summary_value(row, f"fall_{leak}")
            rows.append(found)
    return pd.DataFrame(rows)


def _pm(mean: float, half: float, unit: str = "") -> str:
    return f"{mean:.3g} ± {half:.2g}{' ' + unit if unit else ''}"


def _cell_sentence(cell: pd.DataFrame, direction) -> str:
    first = cell.iloc[0]
    parts = [f"residual approach after cycle 1 "
             f"{_pm(first.residual_um, first.residual_um_pm, 'µm')}",
             f"unloading over loading stiffness at half the peak ({first.half_peak_MPa:.3g} "
             f"MPa) {_pm(first.stiffness_ratio, first.stiffness_ratio_pm)}",
             "energy dissipated per cycle " + ", ".join(
                 f"{_pm(r.dissipated, r.dissipated_pm, 'J/m²')} (plastic work "
                 f"{_pm(r.plastic_work, r.plastic_work_pm, 'J/m²')}) in cycle {r.cycle}"
                 for r in cell.itertuples())]
    second = cell[cell["cycle"] == 2]
    if len(second):
        shaken = second.iloc[0]
        parts.append(f"shaken down in cycle 2: {100 * shaken.shaken_down:.3g} ± "
                     f"{100 * shaken.shaken_down_pm:.2g} % of the surfaces")
    if direction is not None:
        ratio = (f"{first.leak_fall / first.leak_rise:.3g}" if first.leak_rise > 0
                 else "undefined: no leak on loading")
        parts.append(f"leak rate along {direction} at half the peak "
                     f"{_pm(first.leak_rise, first.leak_rise_pm, 'm³/s')} on loading, "
                     f"{_pm(first.leak_fall, first.leak_fall_pm, 'm³/s')} on unloading "
                     f"(unloading over loading {ratio})")
    return f"{first.label}: {'; '.join(parts)}."


def cycles_answers(studies: dict) -> str:
    """The report's sentences (reStructuredText, one paragraph per cell): the numbers of
    :func:`cycle_numbers`, means with their 95 % half widths."""
    numbers = cycle_numbers(studies)
    lines = []
    for (name, _), cell in numbers.groupby(["study", "cell"], sort=False):
        directions = flow_directions(studies[name][0])
        lines.append(_cell_sentence(cell, directions[0] if directions else None))
    return "\n\n".join(lines) + "\n"
