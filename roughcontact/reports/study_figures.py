"""The figures drawn from the studies they list (``figures.<name>.studies``): two
rough, elastic bodies (Eq 17-18) and the leakage through the contact gap.

Each reads several studies' aggregate tables (and, for the leakage, their
sidecars' percolation thresholds), checked against the SHA-256 their sidecars
record (:func:`roughcontact.reports.plotting.load_aggregates`), and draws one
row of panels per study with the bands of
:func:`roughcontact.reports.plotting.plot_band`.
"""

from __future__ import annotations

from roughcontact.reports.plotting import load_aggregates, plot_band
from roughcontact.study.counter_records import NO_COUNTER_BODY, counter_name

#: Files per study of a figure's ``aggregate_files`` (``rules/common.smk``:
#: ``get_figure_aggregates``): table, moduli, sidecar, validity.
AGGREGATE_FILES = 4


def load_studies(paths, names) -> dict:
    """The aggregate tables of several studies by name (:func:`load_aggregates` of each
    :data:`AGGREGATE_FILES` paths of ``paths``, in the order of ``names``)."""
    paths, names = list(paths), list(names)
    if len(paths) != AGGREGATE_FILES * len(names):
        raise ValueError(f"{len(paths)} aggregate files for {len(names)} studies "
                         f"({', '.join(names)}): expected {AGGREGATE_FILES} each")
    return {name: load_aggregates(paths[AGGREGATE_FILES * k:AGGREGATE_FILES * (k + 1)])[0]
            for k, name in enumerate(names)}


def stiffness_unit(values) -> tuple[float, str]:
    """Scale and unit of a stiffness or pressure [Pa] on an axis: MPa, or GPa where the
    values exceed 10 GPa (a steel block's k_P)."""
    import numpy as np

    return (1e-9, "GPa") if np.nanmax(np.asarray(values, dtype=float)) > 1e10 else (1e-6, "MPa")


def _counter_modelled(cell) -> bool:
    """Whether a cell's counter body was modelled (its share reported): not the rigid
    smooth flat, and not a counter body the contact job treated as rigid."""
    return "counter_share_count" in cell and bool((cell["counter_share_count"] > 0).any())


def two_bodies_label(cell) -> str:
    """Legend text of a cell of a two-bodies study (its rows of an aggregate table): its
    counter body (its ``counter`` column:
    :func:`~roughcontact.study.counter_records.counter_name`), and whether the contact
    job treated it as rigid (below ``rigid_share``: no share reported)."""
    label = counter_name(cell.iloc[0])
    if label != NO_COUNTER_BODY.name and not _counter_modelled(cell):
        label += " (treated as rigid)"
    return label


def plot_two_bodies(tables):
    """Two rough, elastic bodies (Eq 17-18): each counter body of a study beside the
    rigid smooth flat, against nominal pressure P [MPa] (log axis).

    ``tables``: study name -> aggregate table, one row of panels each. Columns:
    normalized stiffness k_P (MPa, or GPa where it exceeds 10 GPa), real area
    [%] (log axis), mean gap [µm], and each body's share of the mean-plane
    deflection d_b [%]: the counter body's (``counter_share``, solid) and the
    first body's (1 - ``counter_share``, dashed with crosses: visible where the
    two are equal), both with the 95 % band of
    ``counter_share`` (:func:`fraction_band`). One curve with its band per cell
    (:func:`plot_band`), labelled by :func:`two_bodies_label`; the rigid smooth
    flat in black, a counter body not modelled (treated as rigid) without a
    share. The panels of a row share their P axis; the first names the study
    and its first body.
    Returns the figure.
    """
    import matplotlib.pyplot as plt

    names = list(tables)
    fig, axes = plt.subplots(len(names), 4, figsize=(19.0, 4.3 * len(names)), squeeze=False,
                             sharex="row")
    for row_axes, name in zip(axes, names, strict=True):
        table = tables[name]
        scale, unit = stiffness_unit(table["normalized_stiffness_mean"])
        panels = [("normalized_stiffness", scale, f"normalized stiffness $k_P$ [{unit}]"),
                  ("real_area_fraction", 100.0, "real contact area $A_r / A_n$ [%]"),
                  ("mean_gap", 1e6, r"mean gap $\bar g$ [µm]")]
        colors = iter(f"C{k}" for k in range(10))
        for _, cell in table.groupby("cell", sort=True):
            label = two_bodies_label(cell)
            color = "k" if label == NO_COUNTER_BODY.name else next(colors)
            for ax, (quantity, y_scale, _) in zip(row_axes, panels, strict=False):
                plot_band(ax, cell, quantity, y_scale=y_scale, label=label, color=color)
            if _counter_modelled(cell):
                body = cell.assign(body_share_mean=1.0 - cell["counter_share_mean"],
                                   body_share_half_width=cell["counter_share_half_width"],
                                   body_share_count=cell["counter_share_count"])
                plot_band(row_axes[3], cell, "counter_share", y_scale=100.0, color=color,
                          band="fraction", label=label)
                plot_band(row_axes[3], body, "body_share", y_scale=100.0, color=color,
                          band="fraction", linestyle="--").set(marker="x", markersize=4)
        _finish_two_bodies_row(row_axes, panels, name, table)
    fig.tight_layout()
    return fig


def _finish_two_bodies_row(row_axes, panels, name: str, table) -> None:
    """Labels, scales, legends and the title of one row of :func:`plot_two_bodies`."""
    from matplotlib.lines import Line2D

    for ax, (_, _, ylabel) in zip(row_axes, panels, strict=False):
        ax.set_ylabel(ylabel)
    row_axes[1].set_yscale("log")
    share = row_axes[3]
    share.set(ylabel="share of the mean-plane deflection $d_b$ [%]", ylim=(-3.0, 103.0))
    if not share.lines:
        share.text(0.5, 0.5, "no counter body modelled", transform=share.transAxes,
                   ha="center", va="center", color="0.4")
    handles = share.get_legend_handles_labels()[0] + [
        Line2D([], [], color="0.3", label="counter body"),
        Line2D([], [], color="0.3", linestyle="--", marker="x", markersize=4,
               label="first body")]
    share.legend(handles=handles, fontsize=7)
    for ax in row_axes:
        ax.set(xscale="log", xlabel="nominal pressure $P$ [MPa]")
        ax.grid(True, which="both", alpha=0.3)
    first = {column: ", ".join(f"{v:g}" if isinstance(v, float) else str(v)
                               for v in dict.fromkeys(table[column]))
             for column in ("sigma_um", "E_MPa", "nu", "thickness_mm", "mesh")}
    row_axes[0].set_title(
        f"{name}: first body $\\sigma$ = {first['sigma_um']} µm, $E$ = {first['E_MPa']} "
        f"MPa, $\\nu$ = {first['nu']}, {first['thickness_mm']} mm {first['mesh']} mesh",
        fontsize=9, loc="left")
    row_axes[0].legend(fontsize=7)


#: Dapp et al. 2012 (PRL 108, 244301): the real area fraction at which the free space of a
#: randomly rough contact stops percolating, nearly independent of the surface [-].
DAPP_THRESHOLD = 0.42
#: The end of the real-area axis of :func:`plot_leakage` [-]: past the thresholds (about
#: 0.42), where every flow factor is 0.
AREA_AXIS_END = 0.6
#: Line style of each flow direction in :func:`plot_leakage`.
DIRECTION_STYLES = {"x": "-", "y": "--"}


def flow_directions(table) -> tuple[str, ...]:
    """The flow directions an aggregate table has the leak rate of (the ``_mean`` column of
    :data:`~roughcontact.transport.probe.LEAK_RATE` along each), in the order x, y; none
    for a study solved without the flow."""
    from roughcontact.transport.probe import LEAK_RATE, column_name

    return tuple(d for d in DIRECTION_STYLES if f"{column_name(LEAK_RATE, d)}_mean" in table)


#: The columns of an aggregate table that may tell a study's cells apart beside their
#: (Sk, Ku), with the unit a legend gives each.
_LABEL_COLUMNS = (("counter", ""), ("sigma_um", " µm"), ("b_mm", " mm"), ("E_MPa", " MPa"),
                  ("nu", ""), ("size_mm", " mm"), ("thickness_mm", " mm"), ("mesh", ""),
                  ("cap_MPa", " MPa"))


def _shown_value(column: str, value, unit: str) -> str:
    text = f"{value:g}" if isinstance(value, float) else str(value)
    names = {"counter": "against", "sigma_um": "σ", "b_mm": "b", "E_MPa": "E",
             "nu": "ν", "size_mm": "L", "thickness_mm": "block", "mesh": "mesh",
             "cap_MPa": "cap"}
    return f"{names[column]} {text}{unit}"


def cell_labels(table, study: str) -> dict:
    """Legend text of each cell of a study of the leakage figure (its rows of an aggregate
    ``table``), by cell: the ``study``'s name and the cell's (Sk, Ku), then each column
    that differs between the study's cells (the counter body, sigma, b, E, ...), and a
    measured surface's source (the start of its ``label``, ``measured <file>``); a cell
    its columns do not tell apart from another gets its index. Two studies of equal moments, or a
    measured map and its twin, thus never share a label."""
    import pandas as pd

    first = table.drop_duplicates("cell").sort_values("cell").set_index("cell")
    varying = [(c, unit) for c, unit in _LABEL_COLUMNS
               if c in first and first[c].astype(str).nunique() > 1]
    labels = {}
    for cell, row in first.iterrows():
        parts = [f"Sk = {row['skew']:g}, Ku = {row['kurt']:g}"]
        parts += [_shown_value(c, row[c], unit) for c, unit in varying
                  if not (isinstance(row[c], float) and pd.isna(row[c]))]
        source = str(row.get("label", ""))
        if source.startswith("measured ") and ": " in source:
            parts.insert(0, source.split(": ", 1)[0])
        labels[cell] = f"{study}: {', '.join(parts)}"
    texts = list(labels.values())
    return {cell: text if texts.count(text) == 1 else f"{text} (cell {cell})"
            for cell, text in labels.items()}


def load_percolation(paths, names) -> dict:
    """The percolation thresholds of several studies by name (the sidecar's
    ``flow.percolation`` of each :data:`AGGREGATE_FILES` paths of ``paths``, as a table
    per study: one row per cell and flow direction; the sidecar checked as by
    :func:`load_aggregates`). A study solved without the flow has none to draw: refused,
    naming its sidecar (the workflow refuses such a figure when it is planned)."""
    import pandas as pd

    paths, names = list(paths), list(names)
    found = {}
    for k, name in enumerate(names):
        files = paths[AGGREGATE_FILES * k:AGGREGATE_FILES * (k + 1)]
        meta = load_aggregates(files)[2]
        if "flow" not in meta:
            raise ValueError(f"{files[2]}: study {name!r} was solved without the flow "
                             f"(flow.enabled: false), so it has no percolation thresholds "
                             f"to draw; solve it with the flow on")
        rows = meta["flow"]["percolation"]
        found[name] = pd.DataFrame(rows).astype({key: float for key in _THRESHOLD_KEYS
                                                 if rows})
    return found


#: The numbers of a percolation threshold (None in the sidecar where not found).
_THRESHOLD_KEYS = ("area", "area_low", "area_high", "pressure_MPa", "pressure_low_MPa",
                   "pressure_high_MPa")


def load_pressure_drops(paths, names) -> dict:
    """The pressure drop [MPa] across the seal of several studies by name (the sidecar's
    ``flow.pressure_drop_Pa`` of each :data:`AGGREGATE_FILES` paths of ``paths``; the
    sidecar checked as by :func:`load_aggregates`); a study solved without the flow has
    none."""
    paths, names = list(paths), list(names)
    found = {}
    for k, name in enumerate(names):
        meta = load_aggregates(paths[AGGREGATE_FILES * k:AGGREGATE_FILES * (k + 1)])[2]
        if "flow" in meta:
            found[name] = meta["flow"]["pressure_drop_Pa"] / 1e6
    return found


def plot_leakage(tables, thresholds, pressure_drops=None):
    """Will the seal leak? The flow through the contact gap of each study, one row of
    four panels per study, one colour per cell (legend: :func:`cell_labels`, the study's
    name and what tells its cells apart), the flow along x solid and along y dashed.

    ``tables``: study name -> aggregate table with the flow columns
    (:func:`flow_directions`); ``thresholds``: study name -> its percolation
    thresholds (:func:`load_percolation`); ``pressure_drops``: study name -> the
    pressure drop across its seal [MPa] (:func:`load_pressure_drops`), whose levels
    below it (the tables' ``faces_open``: the fluid would lift the faces apart) are
    shaded grey and hatched in the panels against P. Panels:

    (a) the leak rate of the seal along ``d`` [m^3/s] against nominal
        pressure P [MPa], both log, with its band (:func:`plot_band`): the
        levels of a positive mean only (the leak rate is 0 once every surface
        has sealed, which a log axis cannot show); each cell's sealing pressure
        along the first direction (the sidecar's ``pressure_MPa``) a dash-dotted
        line in its colour;
    (b) the flow factor phi = K / mean(g)^3 along ``d`` against P; its legend
        explains the marks (hollow markers: a level resting on fewer surfaces
        than the cell has, :func:`plot_band`; the open faces; the sealing
        pressure);
    (c) the flow factor against the real area fraction up to
        :data:`AREA_AXIS_END`, the cells' mean curves (log, where > 0: the
        approach to sealing), each cell's percolation threshold along x (the
        first direction) a vertical line in its colour with its 95 % band
        (``area_low`` to ``area_high``) shaded (along y a dotted line), and
        :data:`DAPP_THRESHOLD` grey dashed;
    (d) the share of surfaces still leaking along ``d`` [%] against P, with its
        band (:func:`fraction_band`), each cell's sealing pressure a dash-dotted
        line with its 95 % band shaded, its numbers in the legend
        (:func:`sealing_text`).

    The columns are named by :func:`roughcontact.transport.probe.column_name`.

    Returns the figure.
    """
    import matplotlib.pyplot as plt

    names = list(tables)
    fig, axes = plt.subplots(len(names), 4, figsize=(19.0, 4.4 * len(names)), squeeze=False)
    for row_axes, name in zip(axes, names, strict=True):
        table = tables[name]
        directions = flow_directions(table)
        labels = cell_labels(table, name)
        found = thresholds.get(name)
        sealing = []
        for (cell, rows), color in zip(table.groupby("cell", sort=True),
                                       (f"C{k}" for k in range(10)), strict=False):
            for d in directions:
                _draw_flow_cell(row_axes, rows, d, color,
                                labels[cell] if d == directions[0] else None)
            _mark_thresholds(row_axes[2], found, cell, color, directions)
            sealing += _mark_sealing(row_axes, found, cell, color, directions, labels[cell])
        drop = (pressure_drops or {}).get(name)
        _shade_open_faces(row_axes, table, drop)
        _finish_leakage_row(row_axes, name, table, directions)
        _leakage_keys(row_axes, directions, drop, sealing)
    fig.tight_layout()
    return fig


def sealing_text(found) -> str:
    """A cell's sealing pressure as the figure's legend and caption give it: the nominal
    pressure [MPa] at which half its surfaces have sealed and its 95 % band (a
    percolation threshold's row, :func:`load_percolation`), 3 significant digits; a band
    open at one end (too few surfaces sealed inside the swept range to bound it) says
    "above" or "below"; a pressure not found says so."""
    import math

    def shown(key: str) -> str | None:
        value = found.get(key)
        return None if value is None or not math.isfinite(float(value)) else \
            f"{float(value):.3g}"

    pressure, low, high = (shown(key) for key in ("pressure_MPa", "pressure_low_MPa",
                                                  "pressure_high_MPa"))
    if pressure is None:
        return "not sealed inside the swept range"
    band = (f"{low}-{high}" if low and high else f"above {low}" if low
            else f"below {high}" if high else "unbounded")
    return f"{pressure} MPa (95 %: {band})"


def sealing_sentence(tables, thresholds) -> str:
    """The leakage figure's answers for its caption: each cell's sealing pressure along
    each flow direction (:func:`sealing_text`), labelled by :func:`cell_labels`."""
    parts = []
    for name, table in tables.items():
        labels = cell_labels(table, name)
        found = thresholds.get(name)
        for cell, label in labels.items():
            rows = [] if found is None else [row for _, row in found.iterrows()
                                             if row["cell"] == cell]
            texts = [f"{sealing_text(row)} along {row['direction']}" for row in rows]
            if texts:
                parts.append(f"{label}: {', '.join(texts)}")
    return ("Sealing pressure (the nominal pressure at which half the surfaces have "
            "sealed, with its 95 % band): " + "; ".join(parts) + ".") if parts else ""


def open_levels_sentence(tables, drops) -> str:
    """The levels of each study at which the pressure drop across the seal exceeds the
    nominal contact pressure (the tables' ``faces_open``: the fluid would lift the faces
    apart, which the model does not load them with), in MPa; ``drops``: study name ->
    pressure drop [MPa] (:func:`load_pressure_drops`)."""
    parts = []
    for name, table in tables.items():
        opened = sorted(set(table.loc[table["faces_open"], "nominal_pressure_MPa"]))
        parts.append(f"{name}: pressure drop {drops[name]:g} MPa above P at "
                     + (", ".join(f"{p:.3g}" for p in opened) + " MPa (faces open)"
                        if opened else "no level"))
    return "; ".join(parts) + "." if parts else ""


def leakage_answers(tables, thresholds) -> str:
    """The leakage figure's numbers for the report's caption, those only the run knows:
    each cell's sealing pressure with its band (:func:`sealing_sentence`; the open levels
    the caption gives from the configuration, :mod:`roughcontact.study.plan.captions`)."""
    return sealing_sentence(tables, thresholds) + "\n"


def _mark_sealing(row_axes, thresholds, cell, color: str, directions, label: str) -> list:
    """A cell's sealing pressure along the first of ``directions`` on the panels against
    P: a dash-dotted line in its colour on (a) and (d), its 95 % band shaded on (d).
    Returns the legend entry of (d) (its numbers, :func:`sealing_text`), none where the
    thresholds have no pressure."""
    import math

    from matplotlib.lines import Line2D

    if thresholds is None or len(thresholds) == 0 or "pressure_MPa" not in thresholds:
        return []
    rows = thresholds[(thresholds["cell"] == cell)
                      & (thresholds["direction"] == directions[0])]
    if len(rows) == 0:
        return []
    found = rows.iloc[0]
    entry = Line2D([], [], color=color, linestyle="-.",
                   label=f"{label}: {sealing_text(found)}")
    if not math.isfinite(found["pressure_MPa"]):
        return [entry]
    leak, _, _, connected = row_axes
    for ax in (leak, connected):
        ax.axvline(found["pressure_MPa"], color=color, linestyle="-.", linewidth=1.0)
    low, high = found.get("pressure_low_MPa"), found.get("pressure_high_MPa")
    if low is not None and high is not None and math.isfinite(low) and math.isfinite(high):
        connected.axvspan(low, high, color=color, alpha=0.12, linewidth=0)
    return [entry]


def _shade_open_faces(row_axes, table, drop) -> None:
    """The levels at which the faces would open (the table's ``faces_open``: the pressure
    drop ``drop`` [MPa] exceeds P) shaded grey and hatched, from the first level to the
    drop, on the panels against P; nothing without a drop or such a level."""
    if drop is None or "faces_open" not in table or not table["faces_open"].astype(bool).any():
        return
    first = float(table["nominal_pressure"].min()) / 1e6
    for ax in (row_axes[0], row_axes[1], row_axes[3]):
        ax.axvspan(first, drop, facecolor="0.5", alpha=0.15, hatch="//", edgecolor="0.6",
                   linewidth=0, zorder=0)


def _leakage_columns(d: str) -> tuple[str, str, str]:
    """The leak rate's, the flow factor's and the still-leaking share's columns along
    ``d`` (:func:`roughcontact.transport.probe.column_name`)."""
    from roughcontact.transport.probe import CONNECTED, FACTOR, LEAK_RATE, column_name

    return tuple(column_name(quantity, d) for quantity in (LEAK_RATE, FACTOR, CONNECTED))


def _draw_flow_cell(row_axes, rows, d: str, color: str, label) -> None:
    """One cell's curves along direction ``d`` in the four panels of :func:`plot_leakage`."""
    style = {"color": color, "linestyle": DIRECTION_STYLES[d]}
    leak, factor, connected = _leakage_columns(d)
    leaking = rows[rows[f"{leak}_mean"] > 0]
    if len(leaking):
        plot_band(row_axes[0], leaking, leak, label=label, **style)
    plot_band(row_axes[1], rows, factor, **style)
    open_ = rows[(rows[f"{factor}_mean"] > 0) & (rows["real_area_fraction_count"] > 0)]
    row_axes[2].plot(open_["real_area_fraction_mean"], open_[f"{factor}_mean"], **style)
    plot_band(row_axes[3], rows, connected, y_scale=100.0, band="fraction", **style)


def _mark_thresholds(ax, thresholds, cell, color: str, directions) -> None:
    """A cell's percolation thresholds on the flow factor against real area: along the
    first of ``directions`` (x where recorded) a solid line with its 95 % band shaded,
    along the other a dotted line; none where not found."""
    import math

    if thresholds is None or len(thresholds) == 0:
        return
    for _, found in thresholds[thresholds["cell"] == cell].iterrows():
        if found["direction"] not in directions or not math.isfinite(found["area"]):
            continue
        first = found["direction"] == directions[0]
        ax.axvline(found["area"], color=color, linewidth=1.0, alpha=0.9,
                   linestyle="-" if first else ":")
        if first and math.isfinite(found["area_low"]) and math.isfinite(found["area_high"]):
            ax.axvspan(found["area_low"], found["area_high"], color=color, alpha=0.12,
                       linewidth=0)


def _finish_leakage_row(row_axes, name: str, table, directions) -> None:
    """Labels, scales, legends and the title of one row of :func:`plot_leakage`."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    leak, factor, area, connected = row_axes
    leak.set(yscale="log", ylabel="leak rate $Q$ [m$^3$/s] (where > 0)")
    factor.set(ylabel=r"flow factor $\phi = K / \bar g^3$")
    connected.set(ylabel="surfaces still leaking [%]", ylim=(-3.0, 103.0))
    for ax in (leak, factor, connected):
        ax.set(xscale="log", xlabel="nominal pressure $P$ [MPa]")
    for ax in (leak, connected):  # one P axis: the leak rate's ends where it reaches 0
        ax.sharex(factor)
    area.set(xlabel="real contact area fraction $A_r / A_n$", yscale="log",
             ylabel=f"{factor.get_ylabel()} (where > 0)", xlim=(0.0, AREA_AXIS_END))
    area.axvline(DAPP_THRESHOLD, color="0.5", linestyle="--", linewidth=1.2)
    for ax in (leak, factor, connected):
        ax.grid(True, which="both", alpha=0.3)
    area.grid(True, alpha=0.3)  # major only: its log axis spans many decades
    key = [Line2D([], [], color="0.3", linestyle=DIRECTION_STYLES[d], label=f"along {d}")
           for d in directions]
    key += [Line2D([], [], color="0.3", linewidth=1.0,
                   label=f"percolation threshold ({directions[0]})"),
            Patch(color="0.3", alpha=0.2, label="its 95 % band")]
    key += [Line2D([], [], color="0.3", linestyle=":", label=f"percolation threshold ({d})")
            for d in directions[1:]]
    key.append(Line2D([], [], color="0.5", linestyle="--",
                      label=f"Dapp et al. 2012: {DAPP_THRESHOLD:g}"))
    area.legend(handles=key, fontsize=7)
    first = {column: ", ".join(f"{v:g}" for v in dict.fromkeys(table[column]))
             for column in ("sigma_um", "E_MPa", "b_mm")}
    leak.set_title(f"{name}: $\\sigma$ = {first['sigma_um']} µm, $b$ = {first['b_mm']} mm, "
                   f"$E$ = {first['E_MPa']} MPa", fontsize=9, loc="left")


def _leakage_keys(row_axes, directions, drop, sealing) -> None:
    """The legends of one row of :func:`plot_leakage` that name the cells and explain
    every mark: the cells on (a), the marks on (b), the sealing pressures on (d)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    leak, factor, _, connected = row_axes
    leak.legend(fontsize=7)
    marks = [Line2D([], [], color="0.3", marker="o", mfc="none", linestyle="none", ms=4,
                    label="hollow: a level on fewer surfaces than the cell has")]
    if drop is not None and any(p.get_hatch() for p in factor.patches):
        marks.append(Patch(facecolor="0.5", alpha=0.15, hatch="//", edgecolor="0.6",
                           label=f"faces would open: pressure drop {drop:g} MPa > P "
                                 "(fluid pressure not on the faces)"))
    if sealing:
        marks.append(Line2D([], [], color="0.3", linestyle="-.",
                            label=f"sealing pressure ({directions[0]}): half the surfaces "
                                  "sealed; band in (d)"))
        connected.legend(handles=sealing, fontsize=6, title=f"sealing pressure "
                         f"({directions[0]})", title_fontsize=7)
    factor.legend(handles=marks, fontsize=7)


def leak_rates_at(table, pressures):
    """Each cell's leak rate, flow factor, share of surfaces still leaking and mean gap at
    the nominal-pressure levels nearest ``pressures`` [Pa], per flow direction of the
    aggregate table (:func:`flow_directions`): one row per (cell, level), mean and 95 %
    half width, in the table's units (SI; the pressure in MPa)."""
    import numpy as np
    import pandas as pd

    levels = np.unique(table["nominal_pressure"])
    picks = [levels[np.argmin(np.abs(np.log(levels / p)))] for p in pressures]
    rows = []
    for _, cell in table.groupby("cell", sort=True):
        for level in dict.fromkeys(picks):
            at = cell[cell["nominal_pressure"] == level].iloc[0]
            row = {"Sk": at["skew"], "Ku": at["kurt"], "P_MPa": level / 1e6,
                   "mean_gap": at["mean_gap_mean"]}
            for d in flow_directions(table):
                for quantity in _leakage_columns(d):
                    row[f"{quantity}_mean"] = at[f"{quantity}_mean"]
                    row[f"{quantity}_half_width"] = at[f"{quantity}_half_width"]
            rows.append(row)
    return pd.DataFrame(rows)


def leakage_pressures(table) -> list[float]:
    """Three nominal pressures [Pa] to report a leakage study at: its lowest level every
    surface of every cell reached, its highest level at which some cell still leaks, and the level
    between them nearest their geometric mean (fewer where they coincide)."""
    import numpy as np

    every = table.groupby("nominal_pressure")["coverage"].agg(
        lambda coverage: bool((coverage == "all surfaces").all()))
    full = table[table["nominal_pressure"].isin(every.index[every.to_numpy()])]
    leak = [f"{_leakage_columns(d)[0]}_mean" for d in flow_directions(table)]
    levels = np.unique(full["nominal_pressure"])
    leaking = np.unique(full.loc[(full[leak] > 0).any(axis=1), "nominal_pressure"])
    low, high = levels[0], (leaking[-1] if len(leaking) else levels[-1])
    middle = levels[np.argmin(np.abs(np.log(levels / np.sqrt(low * high))))]
    return list(dict.fromkeys([float(low), float(middle), float(high)]))
