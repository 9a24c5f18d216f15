"""Rendering of the speed-against-error report: figures, Markdown and the tidy CSV.

:func:`write_report` writes the tables of
:mod:`roughcontact.reports.speed.experiments` and the decisions of
:mod:`roughcontact.reports.speed.recommend` as a Markdown report, one tidy CSV
and one or two PNG figures, each atomically.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from roughcontact.reports.plotting import save_figure
from roughcontact.reports.speed.machine import describe_machine
from roughcontact.study.presets import ACCURACY_PRESETS
from roughcontact.study.provenance import atomic_path, git_commit
from roughcontact.units import MPA

__all__ = ["write_report"]


def _is_reference(column: pd.Series) -> np.ndarray:
    """The ``reference`` flags as booleans (also after a CSV round trip: "True"/"False")."""
    return column.astype(str).str.lower().isin(("true", "1", "1.0")).to_numpy()


#: Marker and line style of each solver method's curves; :data:`OTHER_METHOD_STYLE` for others.
METHOD_STYLES = MappingProxyType({"cg": {"marker": "o", "linestyle": "-"},
                                  "steepest": {"marker": "s", "linestyle": "--"}})
OTHER_METHOD_STYLE = MappingProxyType({"marker": "^", "linestyle": "--"})


def _plot_solver(axes, solver_table: pd.DataFrame) -> None:
    compared = solver_table[~_is_reference(solver_table["reference"])]
    keys = ["influence", "skew", "kurt", "method", "tol"]
    worst = compared.groupby(keys, sort=False).agg(
        wall_s=("wall_s", "first"), load_error=("load_error", "max"),
        real_area_error=("real_area_error", "max"), k_P_error=("k_P_error", "max")).reset_index()
    floor = 1e-16  # an error of exactly 0 is drawn here
    for ax, column, title in zip(axes, ("load_error", "k_P_error", "real_area_error"),
                                 ("load F at equal approach", "k_P (Eq 33)", "real area"),
                                 strict=True):
        for k, ((influence, skew, kurt, method), group) in enumerate(
                worst.groupby(["influence", "skew", "kurt", "method"], sort=False)):
            ax.plot(group["wall_s"], np.maximum(group[column], floor),
                    **METHOD_STYLES.get(method, OTHER_METHOD_STYLE), color=f"C{k}",
                    label=f"{method}, {influence}, Sk {skew:g} Ku {kurt:g}")
            for _, r in group.iterrows():
                ax.annotate(f"{r['tol']:.0e}", (r["wall_s"], max(r[column], floor)),
                            fontsize=6, alpha=0.7)
        for ref_s in solver_table.loc[_is_reference(solver_table["reference"]),
                                      "wall_s"].unique():
            ax.axvline(ref_s, color="grey", linewidth=0.6, linestyle=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("wall time of one cell's sweep [s] (dotted: exact)")
        ax.set_ylabel("largest |relative error| vs exact (0 drawn at 1e-16)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6)


def _plot_counts(ax, count_table: pd.DataFrame) -> None:
    for k, (level, group) in enumerate(count_table.groupby("pressure_Pa")):
        for name, label, style in (("k_P", "k_P", "-"), ("real_area", "area", "--")):
            ax.plot(group["count"], 100 * group[f"{name}_relative_half_width"], style,
                    marker="o", color=f"C{k}", label=f"{label}, P = {level / MPA:g} MPa")
    counts = np.sort(count_table["count"].unique())
    first = count_table[count_table["count"] == counts[0]]
    start = 100 * first["real_area_relative_half_width"].max()
    ax.plot(counts, start * np.sqrt((counts[0] - 1) / (counts - 1)), ":", color="grey",
            label="~ 1/sqrt(n)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("surfaces per cell")
    ax.set_ylabel("95 % half-width of the mean [% of mean]")
    ax.set_title("band half-width against surface count")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)


def _plot_grid(ax, grid_table: pd.DataFrame) -> None:
    for k, (level, group) in enumerate(grid_table.groupby("pressure_Pa")):
        group = group.groupby("grid").mean(numeric_only=True).reset_index()
        ax.plot(group["grid"], 100 * group["k_P_change"], "-o", color=f"C{k}",
                label=f"k_P, P = {level / MPA:g} MPa")
        ax.plot(group["grid"], 100 * group["real_area_change"], "--s", color=f"C{k}",
                label=f"area, P = {level / MPA:g} MPa")
    ax.set_xscale("log")
    grids = sorted(int(g) for g in grid_table["grid"].unique())
    ax.set_xticks(grids, [str(g) for g in grids])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.axhline(0.0, color="grey", linewidth=0.6)
    ax.set_xlabel("contact elements per side")
    ax.set_ylabel("change against the finest grid [%]")
    ax.set_title("contact-grid convergence")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)


def _save_figures(png_paths, solver_table, grid_table, count_table) -> None:
    paths = [png_paths] if isinstance(png_paths, str | os.PathLike) else list(png_paths)
    if not paths:
        return
    if len(paths) == 1:
        fig = Figure(figsize=(15, 9), layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(2, 3)
        solver_axes, grid_ax, count_ax = axes[0], axes[1, 0], axes[1, 1]
        axes[1, 2].axis("off")
        figures = [(fig, paths[0])]
    else:
        fig = Figure(figsize=(15, 4.8), layout="constrained")
        FigureCanvasAgg(fig)
        solver_axes = fig.subplots(1, 3)
        other = Figure(figsize=(10, 4.8), layout="constrained")
        FigureCanvasAgg(other)
        grid_ax, count_ax = other.subplots(1, 2)
        figures = [(fig, paths[0]), (other, paths[1])]
    if solver_table is not None and len(solver_table):
        _plot_solver(solver_axes, solver_table)
    if grid_table is not None and len(grid_table):
        _plot_grid(grid_ax, grid_table)
    else:
        grid_ax.axis("off")
    if count_table is not None and len(count_table):
        _plot_counts(count_ax, count_table)
    else:
        count_ax.axis("off")
    for figure, path in figures:
        figure.suptitle("Speed against error: solver tolerance, contact grid, surfaces per cell")
        save_figure(figure, path)


def _markdown_table(frame: pd.DataFrame, columns: Sequence[str], floatfmt: str = ".3g") -> str:
    present = [c for c in columns if c in frame]
    return frame[present].to_markdown(index=False, floatfmt=floatfmt)


def _presets_table(presets: Mapping) -> pd.DataFrame:
    return pd.DataFrame([{"preset": name, **dict(values)} for name, values in presets.items()])


#: Longest attribute value written in full in the notes (a tabulated PSD is cut).
ATTR_TEXT_LIMIT = 200


def _attr_text(value) -> str:
    """A table attribute for the notes, cut to :data:`ATTR_TEXT_LIMIT` characters."""
    text = str(value)
    if len(text) <= ATTR_TEXT_LIMIT:
        return text
    return f"{text[:ATTR_TEXT_LIMIT]} ... ({len(text)} characters)"


#: Columns of the recommendation shown in the report.
RECOMMENDATION_COLUMNS = ("component", "choice", "cost", "cost_unit", "k_P_error",
                          "real_area_error", "meets", "options_meeting")
#: Sections of the report's tables, in order: (title, table name, text before the
#: table or None, columns shown).
TABLE_SECTIONS = (
    ("Solver", "solver",
     "Largest error over surfaces at each pressure level; `wall_s` is the whole sweep of one "
     "cell (all surfaces and steps).",
     ("influence", "skew", "kurt", "method", "tol", "pressure_Pa", "real_area_exact", "wall_s",
      "iterations_per_solve", "matvecs_per_solve", "converged_fraction", "load_error",
      "real_area_error", "max_pressure_error", "k_P_error")),
    ("Mesh", "mesh", None,
     ("mesh", "build_s", "peak_memory_GB", "k_P_error", "real_area_error", "max_pressure_error",
      "k_P_range", "real_area_range", "max_pressure_range", "source")),
    ("Contact grid", "grid", None,
     ("skew", "kurt", "grid", "element_size_m", "build_s", "solve_s", "pressure_Pa", "k_P_Pa",
      "k_P_half_width_Pa", "real_area_fraction", "real_area_half_width", "max_pressure_Pa",
      "k_P_change", "real_area_change", "max_pressure_change")),
    ("Surfaces per cell", "surfaces", None,
     ("skew", "kurt", "count", "pressure_Pa", "k_P_mean", "k_P_half_width",
      "k_P_relative_half_width", "real_area_mean", "real_area_half_width",
      "real_area_relative_half_width", "max_pressure_relative_half_width")),
)
#: Columns of the accuracy presets shown in the report.
PRESET_COLUMNS = ("preset", "mesh", "grid_per_9mm", "method", "tol", "precision", "surfaces",
                  "k_P_error", "real_area_error", "max_pressure_error", "solver_k_P_error",
                  "grid_change_k_P", "grid_change_real_area", "sampling_k_P",
                  "sampling_real_area")


def _head(recommendation: pd.DataFrame) -> list[str]:
    """Title, provenance and the ``## Recommendation`` section (lines of Markdown)."""
    return ["# Speed against error", "",
            f"Commit {git_commit()}, machine: {describe_machine()} (at writing). Every error is a "
            "relative error; timings are wall-clock on a shared machine and vary with its load.",
            "", "## Recommendation", "", recommendation.attrs.get("text", ""), "",
            _markdown_table(recommendation, RECOMMENDATION_COLUMNS), ""]


def _measured(notes: Sequence[str], tables: Mapping) -> list[str]:
    """The ``## How it was measured`` section: ``notes`` and the tables' ``attrs``."""
    out = ["## How it was measured", ""] + [f"- {note}" for note in notes]
    for name, frame in tables.items():
        if frame is not None and frame.attrs:
            attrs = {k: v for k, v in frame.attrs.items() if k != "text"}
            if attrs:
                out.append(f"- {name}: " + "; ".join(f"{k} = {_attr_text(v)}"
                                                     for k, v in attrs.items()))
    return out + [""]


def _table_sections(tables: Mapping) -> list[str]:
    """One section per entry of :data:`TABLE_SECTIONS` ("Not measured." without its table)."""
    out = []
    for title, name, intro, columns in TABLE_SECTIONS:
        frame = tables[name]
        out += [f"## {title}", ""]
        if frame is not None and len(frame):
            out += ([intro, ""] if intro else []) + [_markdown_table(frame, columns)]
        else:
            out.append("Not measured.")
        out.append("")
    return out


def write_report(solver_table: pd.DataFrame | None, mesh_table: pd.DataFrame | None,
                 grid_table: pd.DataFrame | None, count_table: pd.DataFrame | None,
                 recommendation: pd.DataFrame, md_path, csv_path, png_paths=(), *,
                 presets: Mapping = ACCURACY_PRESETS, notes: Sequence[str] = (),
                 presets_caption: str = "the stored presets, `config/accuracy_presets.yaml`",
                 ) -> None:
    """Markdown report, combined tidy CSV and PNG figure(s), each written atomically.

    The Markdown has the sections ``# Speed against error``, ``## Recommendation``
    (``recommendation`` and its ``attrs["text"]``), ``## How it was measured``
    (``notes`` and the tables' ``attrs``), ``## Solver``, ``## Mesh``,
    ``## Contact grid``, ``## Surfaces per cell`` and ``## Accuracy presets``.
    The CSV stacks all tables with a ``table`` column (solver, mesh, grid,
    surfaces, recommendation) over the union of their columns. ``png_paths``:
    one path (one six-panel figure) or two (solver; grid and surface count).
    ``presets`` (name -> settings and relative errors, as
    :data:`roughcontact.study.presets.ACCURACY_PRESETS`) fill the last section,
    introduced as ``presets_caption``.
    """
    tables = {"solver": solver_table, "mesh": mesh_table, "grid": grid_table,
              "surfaces": count_table, "recommendation": recommendation}
    tidy = pd.concat([frame.assign(table=name) for name, frame in tables.items()
                      if frame is not None and len(frame)], ignore_index=True, sort=False)
    tidy = tidy[["table"] + [c for c in tidy.columns if c != "table"]]
    with atomic_path(csv_path) as tmp:
        tidy.to_csv(tmp, index=False)
    out = (_head(recommendation) + _measured(notes, tables) + _table_sections(tables)
           + ["## Accuracy presets", "",
              f"Accuracy presets: {presets_caption} (errors: relative, of the cell means; "
              "None where not measured).", "",
              _markdown_table(_presets_table(presets), PRESET_COLUMNS), ""])
    with atomic_path(md_path) as tmp:
        Path(tmp).write_text("\n".join(out) + "\n")
    _save_figures(png_paths, solver_table, grid_table, count_table)
