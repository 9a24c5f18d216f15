"""Figure code of the notebooks and reports: atomic saving, tables, curves, panels.

Every file is written under a temporary name beside it and renamed when
complete (:func:`roughcontact.study.provenance.atomic_path`); the temporaries
that killed writers left are removed first
(:func:`roughcontact.reports.execution.remove_stale_temporaries`).
"""

from __future__ import annotations

import os
from pathlib import Path

from roughcontact.errors import StoredFileError
from roughcontact.hashes import file_sha256
from roughcontact.reports.execution import remove_stale_temporaries
from roughcontact.study.provenance import atomic_path

#: Mantissas whose minor ticks keep their labels, tried in turn until the labels of a
#: log axis no longer overlap (the last: major labels only).
MINOR_LABELS = ((2, 3, 5), (2, 5), (3,), ())


def drawn_tick_labels(axis, renderer) -> list:
    """Window extents of the non-empty tick labels ``axis`` draws (ticks within its view),
    in their order along the axis."""
    low, high = sorted(axis.get_view_interval())
    boxes = []
    for tick in axis.get_major_ticks() + axis.get_minor_ticks():
        if not low <= tick.get_loc() <= high:
            continue
        for label in (tick.label1, tick.label2):
            if label.get_visible() and label.get_text():
                boxes.append((tick.get_loc(), label.get_window_extent(renderer)))
    return [box for _, box in sorted(boxes, key=lambda item: item[0])]


def overlapping_labels(fig) -> list[tuple]:
    """The pairs of tick labels of ``fig`` that overlap once drawn: ``(axes index, "x" or
    "y", first box, second box)``."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    found = []
    for index, ax in enumerate(fig.axes):
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            boxes = drawn_tick_labels(axis, renderer)
            found += [(index, name, a, b) for k, a in enumerate(boxes) for b in boxes[k + 1:]
                      if a.overlaps(b)]
    return found


def tidy_log_ticks(fig) -> None:
    """Keep the tick labels of every log axis of ``fig`` from overlapping.

    Matplotlib labels the minor ticks of a log axis spanning less than a
    decade or two (``2x10^-1 3x10^-1 4x10^-1 ...``); on a narrow panel they
    run into each other. Each such axis keeps the labels of fewer mantissas
    (:data:`MINOR_LABELS`) until none overlap, then, if the major labels
    still do, fewer major ticks. Lays the figure out once, and again after
    each round of changes, without rendering it (a third less time than a
    draw on a 6-panel figure); call it once the layout is set
    (:func:`save_figure` does).
    """
    from matplotlib.ticker import LogLocator

    steps = {}  # axis -> the next step to take on it
    while True:
        fig.draw_without_rendering()  # the layout and the labels' text, no pixels
        renderer = fig.canvas.get_renderer()
        crowded = [axis for ax in fig.axes for axis in (ax.xaxis, ax.yaxis)
                   if axis.get_scale() == "log" and _overlap(drawn_tick_labels(axis, renderer))]
        crowded = [axis for axis in crowded if steps.get(axis, 0) < len(MINOR_LABELS) + 3]
        if not crowded:
            return
        for axis in crowded:
            step = steps.get(axis, 0)
            if step < len(MINOR_LABELS):
                axis.set_minor_formatter(_MantissaFormatter(MINOR_LABELS[step]))
            else:  # major labels only, and still crowded: fewer decades labelled
                axis.set_major_locator(LogLocator(numticks=8 - 2 * (step - len(MINOR_LABELS))))
            steps[axis] = step + 1


def _overlap(boxes) -> bool:
    """Whether any two neighbouring boxes (in order along the axis) overlap."""
    return any(a.overlaps(b) for a, b in zip(boxes, boxes[1:], strict=False))


def _mantissa_formatter():
    """The class of :class:`_MantissaFormatter`, made on first use (matplotlib stays an
    import of the figures only)."""
    import math

    from matplotlib.ticker import LogFormatterSciNotation

    class MantissaFormatter(LogFormatterSciNotation):
        """Labels of the minor ticks whose mantissa is in ``keep`` (all of them
        labelled, none of the others), major ticks as usual."""

        def __init__(self, keep):
            super().__init__(labelOnlyBase=False, minor_thresholds=(math.inf, math.inf))
            self.keep = frozenset(keep)

        def __call__(self, x, pos=None):
            if x <= 0:
                return ""
            mantissa = round(x / 10 ** math.floor(math.log10(x) + 1e-9), 6)
            keep = mantissa == 1 or mantissa in self.keep
            return super().__call__(x, pos) if keep else ""

    return MantissaFormatter


def _MantissaFormatter(keep):  # noqa: N802 - stands for the class
    return _mantissa_formatter()(keep)


def save_figure(fig, *paths, dpi: int = 150) -> None:
    """Save a matplotlib figure to each path (format from the suffix), atomically, with
    the tick labels of its log axes kept apart (:func:`tidy_log_ticks`)."""
    tidy_log_ticks(fig)
    for path in paths:
        path = Path(path)
        remove_stale_temporaries(path)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=path.suffix.lstrip("."))


def save_table(frame, path: str | os.PathLike) -> None:
    """Write a table as CSV (no index), atomically; stale temporaries removed first."""
    remove_stale_temporaries(path)
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False)


def draw_table(frame, *, title: str | None = None, fontsize: float = 9):
    """A figure holding ``frame`` as a table; headers and cells may use mathtext.

    The cells show ``frame`` as it is (format the numbers as strings first);
    each column is as wide as its widest entry. Returns the figure.
    """
    import matplotlib.pyplot as plt

    rows, columns = frame.shape
    fig, ax = plt.subplots(figsize=(1.0 * columns, 0.3 * (rows + 1)))
    ax.axis("off")
    table = ax.table(cellText=frame.astype(str).to_numpy(), colLabels=list(frame.columns),
                     cellLoc="center", loc="upper center")
    table.auto_set_font_size(False)
    table.set_fontsize(fontsize)
    table.auto_set_column_width(list(range(columns)))
    for (row, _), cell in table.get_celld().items():
        cell.set_height(1.0 / (rows + 1))
        cell.PAD = 0.4
        if row == 0:
            cell.set_facecolor("0.9")
    if title:
        ax.set_title(title, fontsize=fontsize + 1)
    return fig


def surface_moments(files, sigma_um: float, cells=None):
    """Realised moments of the first surface of each surface file, a row each.

    Columns ``file``, ``sigma_um`` (the stored unit std times ``sigma_um``
    [µm]), ``skew`` and ``kurt``: what the 3-D panels of
    :func:`draw_surfaces` show. With ``cells`` (each file's cell, its
    ``params()``), each file must have been made for its cell. Returns a
    pandas DataFrame.
    """
    import pandas as pd

    from roughcontact.study.jobs.storage import read_surfaces

    rows = []
    files = list(files)
    for path, cell in zip(files, [None] * len(files) if cells is None else cells, strict=True):
        stats = read_surfaces(path, count=1, cell=cell)["stats"]
        rows.append({"file": str(path), "sigma_um": stats["sigma"][0] * sigma_um,
                     "skew": stats["skew"][0], "kurt": stats["kurt"][0]})
    return pd.DataFrame(rows, columns=["file", "sigma_um", "skew", "kurt"])


def draw_surfaces(files, sigma_um: float, titles, *, columns: int = 3, cells=None):
    """3-D views of the first surface of each surface file, ``columns`` per row.

    Heights [µm] are the stored unit heights times ``sigma_um``; plan
    coordinates in mm. ``titles`` (one per file, may hold line breaks and
    mathtext) go above the panels with room kept for them. With ``cells``
    (each file's cell, its ``params()``), each file must have been made for
    its cell. Returns the figure.
    """
    import matplotlib.pyplot as plt
    import numpy as np

    from roughcontact.study.jobs.storage import read_surfaces

    files = list(files)
    columns = max(1, min(columns, len(files)))
    rows = -(-len(files) // columns)
    fig = plt.figure(figsize=(4.2 * columns, 4.0 * rows))
    cells = [None] * len(files) if cells is None else cells
    for k, (path, title, cell) in enumerate(zip(files, titles, cells, strict=True)):
        data = read_surfaces(path, count=1, cell=cell)
        spec = data["spec"]
        z = data["heights"][0] * sigma_um
        ny, nx = z.shape
        x = (np.arange(nx) + 0.5) * spec["size"][0] / nx * 1e3
        y = (np.arange(ny) + 0.5) * spec["size"][1] / ny * 1e3
        X, Y = np.meshgrid(x, y)
        ax = fig.add_subplot(rows, columns, k + 1, projection="3d")
        ax.plot_surface(X, Y, z, cmap="viridis", linewidth=0, antialiased=False,
                        rstride=1, cstride=1)
        ax.set(xlabel="$x$ [mm]", ylabel="$y$ [mm]")
        ax.set_zlabel("$z$ [µm]", labelpad=8)
        ax.set_box_aspect(None, zoom=0.9)
        ax.set_title(title, fontsize=10, pad=0, y=1.0)
    fig.subplots_adjust(left=0.0, right=0.95, bottom=0.03, top=0.9, wspace=0.05, hspace=0.2)
    return fig


def check_sha256(path, meta: dict, key: str, meta_path) -> None:
    """Raise :class:`~roughcontact.errors.StoredFileError` unless ``path`` has the SHA-256
    that the sidecar ``meta`` (read from ``meta_path``) records under ``key``."""
    if meta.get(key) != file_sha256(path):
        raise StoredFileError(
            f"{path}: does not match the SHA-256 in {meta_path} (changed or damaged after "
            f"the aggregation, or written by an older version); delete it and run the "
            "workflow again to rebuild it", path)


def load_aggregates(paths) -> tuple:
    """The aggregate table, per-surface moduli and sidecar of a study (``aggregate_files``).

    Both tables are checked against the SHA-256 their sidecar records: an edited
    or damaged table raises :class:`~roughcontact.errors.StoredFileError`.
    """
    import json

    import pandas as pd

    table_path, moduli_path, meta_path = paths[:3]
    meta = json.loads(Path(meta_path).read_text())
    for path, key in ((table_path, "table_sha256"), (moduli_path, "moduli_sha256")):
        check_sha256(path, meta, key, meta_path)
    return pd.read_csv(table_path), pd.read_csv(moduli_path), meta


def load_validity(paths):
    """The validity table of a study (``aggregate_files``; 4th path), checked against
    the SHA-256 its sidecar records; an empty table if the study has none."""
    import json

    import pandas as pd

    if len(paths) < 4:
        return pd.DataFrame()
    meta_path, path = paths[2], paths[3]
    check_sha256(path, json.loads(Path(meta_path).read_text()), "validity_sha256", meta_path)
    return pd.read_csv(path)


def curve_style(row) -> dict:
    """Legend label (Sk, Ku; "capped at H" for a capped cell) and line style of a cell's
    curve (dashed when capped), from a row of an aggregate table."""
    import math

    label = f"Sk = {row['skew']:g}, Ku = {row['kurt']:g}"
    cap = row.get("cap_MPa", float("nan"))
    if cap is not None and not math.isnan(cap):
        return {"label": f"{label}, capped at {cap:g} MPa", "linestyle": "--"}
    return {"label": label, "linestyle": "-"}


def mark_hardness(ax, validity, cells) -> float | None:
    """Shade where any of ``cells`` is flagged in ``validity`` (:func:`load_validity`).

    From the lowest flagged nominal pressure [MPa] of those cells to the right
    edge, with a note naming the hardness and threshold; nothing without a
    flagged level. Returns that pressure [MPa] or None.
    """
    if validity is None or len(validity) == 0:
        return None
    part = validity[validity["cell"].isin(list(cells)) & validity["flagged"].astype(bool)]
    if part.empty:
        return None
    first = part.loc[part["nominal_pressure"].idxmin()]
    x = float(first["nominal_pressure"]) / 1e6
    ax.axvspan(x, ax.get_xlim()[1], color="tab:red", alpha=0.08, linewidth=0)
    ax.axvline(x, color="tab:red", linestyle=":", linewidth=1)
    ax.text(x, 0.02, f" > {100 * first['threshold']:g} % of area or load\n above "
            f"H = {first['hardness_MPa']:g} MPa", transform=ax.get_xaxis_transform(),
            color="tab:red", fontsize=7, va="bottom")
    return x


#: How the figures draw bands (for captions and notes).
BAND_NOTE = ("bands: 95 % confidence interval of the mean, drawn in log space (in logit "
             "space for fractions), so that they stay within the quantity's range")


#: Largest half width of :func:`positive_band` in log space (e^50 either way).
MAX_LOG_BAND = 50.0


def positive_band(mean, half_width):
    """Lower and upper ends [unit of ``mean``] of the band of a positive quantity.

    The aggregate tables give the Student-t interval ``mean +- half_width``
    (95 %), symmetric. For a positive quantity averaged over few surfaces with
    a large scatter its lower end falls below zero (n = 4: t = 3.18 times the
    standard error), a value the quantity cannot take, and on a log axis the
    band then has no lower edge. The mean of a positive, right-skewed quantity
    scatters more upwards than downwards; the interval transformed to log
    space (delta method: standard error of ``log(mean)`` = standard error /
    mean) says so: ``mean * exp(-+ half_width / mean)``, positive,
    asymmetric, and ``mean -+ half_width`` to first order when the band is
    narrow (``half_width / mean = 0.1``: -9.5 % / +10.5 %). A zero mean (every
    surface zero: no scatter) gives a zero band; a NaN half width (a single
    surface) none.

    Parameters
    ----------
    mean, half_width : array_like
        Means and 95 % half widths of the table (``<quantity>_mean`` and
        ``<quantity>_half_width``), non-negative.

    Returns
    -------
    (ndarray, ndarray)
        Lower and upper ends.
    """
    import numpy as np

    mean = np.asarray(mean, dtype=float)
    ratio = np.divide(np.nan_to_num(np.asarray(half_width, dtype=float)), mean,
                      out=np.zeros_like(mean), where=mean > 0)
    # a half width many times its mean (a leak rate where most surfaces have sealed)
    # would overflow exp: a band of e^50 either way is already off every axis
    ratio = np.minimum(ratio, MAX_LOG_BAND)
    return mean * np.exp(-ratio), mean * np.exp(ratio)


def fraction_band(mean, half_width):
    """Lower and upper ends of the band of a fraction (a share in [0, 1]).

    As :func:`positive_band`, in logit space: ``logit(mean) -+ half_width /
    (mean (1 - mean))``, mapped back; within (0, 1), ``mean -+ half_width``
    to first order. A mean of 0 or 1 (no scatter) gives a zero band.
    """
    import numpy as np

    mean = np.asarray(mean, dtype=float)
    inside = (mean > 0) & (mean < 1)
    spread = np.divide(np.nan_to_num(np.asarray(half_width, dtype=float)), mean * (1 - mean),
                       out=np.zeros_like(mean), where=inside)
    logit = np.log(np.where(inside, mean, 0.5) / np.where(inside, 1 - mean, 0.5))

    def back(value):
        return np.where(inside, 1.0 / (1.0 + np.exp(-value)), mean)

    return back(logit - spread), back(logit + spread)


#: The band of each kind of quantity (:func:`plot_band`).
BANDS = {"positive": positive_band, "fraction": fraction_band}


def plot_band(ax, frame, quantity: str, *, y_scale: float = 1.0, label=None, color=None,
              linestyle="-", band: str | None = None):
    """Mean curve of ``quantity`` against nominal pressure [MPa] with its confidence band.

    ``frame`` holds one cell's rows of an aggregate table. The quantities of
    the tables are positive (stiffness, pressures, deflections) or fractions
    (``*_fraction``, shares above a hardness): their band is drawn in log
    space (:func:`positive_band`) or logit space (:func:`fraction_band`), so
    that it stays in their range; ``band`` names the kind (``"positive"``,
    ``"fraction"``; default by the name of ``quantity``). Levels that rest on
    no surface are left out; a level resting on fewer surfaces than the cell
    has is drawn with a hollow marker, so a thin band there is not mistaken
    for a tight one. Returns the line.
    """
    count = frame[f"{quantity}_count"].to_numpy()
    ok = count > 0
    x = frame["nominal_pressure"].to_numpy()[ok] / 1e6
    mean = frame[f"{quantity}_mean"].to_numpy()[ok]
    kind = band or ("fraction" if quantity.endswith("_fraction") else "positive")
    low, high = BANDS[kind](mean, frame[f"{quantity}_half_width"].to_numpy()[ok])
    y, low, high = mean * y_scale, low * y_scale, high * y_scale
    (line,) = ax.plot(x, y, label=label, color=color, linestyle=linestyle)
    ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, linewidth=0)
    partial = count[ok] < frame["surfaces"].to_numpy()[ok]
    if partial.any():
        ax.plot(x[partial], y[partial], "o", mfc="none", color=line.get_color(), ms=4)
    return line


def plot_by_mesh(table, validity, quantity: str, *, y_scale: float, ylabel: str, title: str,
                 log_y: bool = False):
    """One panel per mesh of ``quantity`` against nominal pressure [MPa] (Figs 7, 12, 13).

    Each panel holds the mesh's cells of the aggregate table ``table``, one
    curve with its band per cell (:func:`plot_band`, styled by
    :func:`curve_style`), log P axis (and log ``quantity`` when ``log_y``),
    shaded where ``validity`` (:func:`load_validity`) flags a cell above the
    hardness (:func:`mark_hardness`); titled ``"<title> (<mesh> mesh)"``,
    ``ylabel`` on the first panel, which shares its y axis with the others.
    Returns the figure.
    """
    import matplotlib.pyplot as plt

    meshes = list(dict.fromkeys(table["mesh"]))
    fig, axes = plt.subplots(1, len(meshes), figsize=(5.2 * len(meshes), 4.2), squeeze=False,
                             sharey=True)
    for ax, mesh in zip(axes[0], meshes, strict=True):
        part = table[table["mesh"] == mesh]
        for _, cell in part.groupby("cell", sort=True):
            plot_band(ax, cell, quantity, y_scale=y_scale, **curve_style(cell.iloc[0]))
        ax.set_xscale("log")
        if log_y:
            ax.set_yscale("log")
        mark_hardness(ax, validity, part["cell"].unique())
        ax.set_xlabel("nominal pressure $P$ [MPa]")
        ax.set_title(f"{title} ({mesh} mesh)", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0][0].set_ylabel(ylabel)
    fig.tight_layout()
    return fig


def _draw_cells(ax, table, quantity: str, *, y_scale: float, label: str) -> None:
    """One curve with its band per cell of ``table`` (:func:`plot_band`), labelled
    ``label.format(**row)`` with the cell's first row; log P axis and grid."""
    for _, cell in table.groupby("cell", sort=True):
        plot_band(ax, cell, quantity, y_scale=y_scale, label=label.format(**cell.iloc[0]))
    ax.set(xscale="log", xlabel="nominal pressure $P$ [MPa]")
    ax.grid(True, which="both", alpha=0.3)


def plot_cells(table, quantity: str, *, y_scale: float, ylabel: str, title: str, label: str,
               legend_fontsize: float | None = None):
    """``quantity`` of every cell of ``table`` against nominal pressure [MPa], one panel.

    One curve with its band per cell (:func:`plot_band`), labelled
    ``label.format(**row)`` with the cell's first row of the aggregate table
    (e.g. ``"$b$ = {b_mm:g} mm"``); log P axis. Returns the figure.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.4, 4.2))
    _draw_cells(ax, table, quantity, y_scale=y_scale, label=label)
    ax.set(ylabel=ylabel, title=title)
    ax.legend(fontsize=legend_fontsize)
    fig.tight_layout()
    return fig


def plot_cells_panels(table, panels, *, label: str, title: str, columns: int | None = None):
    """Several quantities of every cell of ``table`` against nominal pressure [MPa], one
    panel each, ``columns`` to a row (default: all in one row) (as :func:`plot_cells`).

    ``panels`` holds ``(quantity, y_scale, ylabel, log_y)`` per panel; the
    legend is on the first panel, ``title`` above all. Returns the figure.
    """
    import matplotlib.pyplot as plt

    columns = len(panels) if columns is None else int(columns)
    rows = -(-len(panels) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(5.0 * columns, 4.2 * rows), squeeze=False)
    flat = axes.ravel()
    for ax, (quantity, y_scale, ylabel, log_y) in zip(flat, panels, strict=False):
        _draw_cells(ax, table, quantity, y_scale=y_scale, label=label)
        ax.set(ylabel=ylabel, yscale="log" if log_y else "linear")
    for ax in flat[len(panels):]:
        ax.set_visible(False)
    flat[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def cells_at_pressures(table, quantities, pressures, *, by: str):
    """Mean and 95 % half width of each quantity for every cell of an aggregate table,
    at the nominal-pressure levels nearest ``pressures`` [Pa], side by side.

    One row per (quantity, level), columns ``<by>=<value> mean`` and ``... half
    width`` per cell (``by`` a column of the table naming its cells, e.g.
    ``b_mm``), then ``spread``, the largest minus the smallest mean relative
    to their average, and ``separated``: whether the two extremes differ by
    more than the 95 % half width of their difference, sqrt(h1^2 + h2^2)
    (independent cells). Values in the table's units (SI).
    """
    import numpy as np
    import pandas as pd

    levels = np.unique(table["nominal_pressure"])
    rows = []
    for quantity in quantities:
        for target in pressures:
            level = levels[np.argmin(np.abs(np.log(levels / target)))]
            at = table[table["nominal_pressure"] == level].sort_values(by)
            mean = at[f"{quantity}_mean"].to_numpy()
            half = at[f"{quantity}_half_width"].to_numpy()
            row = {"quantity": quantity, "nominal_pressure": level}
            for value, m, h in zip(at[by], mean, half, strict=True):
                name = f"{value:g}" if isinstance(value, int | float | np.number) else value
                row |= {f"{by}={name} mean": m, f"{by}={name} half width": h}
            low, high = np.argmin(mean), np.argmax(mean)
            row["spread"] = (mean[high] - mean[low]) / np.mean(mean)
            row["separated"] = bool(mean[high] - mean[low]
                                    > np.hypot(half[high], half[low]))
            rows.append(row)
    return pd.DataFrame(rows)


#: The quantities :func:`measured_against_twin` compares: (column, unit, scale) with the
#: unit None for MPa, or GPa where the values exceed 10 GPa.
_MEASURED_QUANTITIES = (("normalized_stiffness", None, 1.0), ("real_area_fraction", "%", 100.0),
                        ("max_pressure", None, 1.0))


def measured_against_twin(table, source: dict, levels: int = 4) -> str:
    """The measured surface's k_P, real area and peak pressure beside its synthetic twin's
    (mean +- 95 % half width, and their ratio) at ``levels`` nominal pressures spread over
    an aggregate table, a line each; the measured values alone where the study has no
    twin (``compare_synthetic: false``). ``source`` names each cell's source
    (``"measured"`` or another name for the twin) by cell index.
    """
    import numpy as np

    all_levels = np.unique(table["nominal_pressure"])
    picks = all_levels[np.linspace(0, len(all_levels) - 1, levels).round().astype(int)]
    measured = [i for i, name in source.items() if name == "measured"][0]
    twins = [i for i, name in source.items() if name != "measured"]
    rows = [] if twins else ["no synthetic twin (compare_synthetic: false): the measured "
                             "surface alone"]
    for quantity, unit, scale in _MEASURED_QUANTITIES:
        if unit is None:
            big = np.nanmax(table[f"{quantity}_mean"]) > 1e10
            scale, unit = (1e-9, "GPa") if big else (1e-6, "MPa")
        for level in picks:
            at = table[table["nominal_pressure"] == level].set_index("cell")
            value = at.loc[measured, f"{quantity}_mean"] * scale
            line = f"{quantity:22s} P = {level / 1e6:7.3g} MPa: measured {value:9.4g}"
            if twins:
                twin, half = (at.loc[twins[0], f"{quantity}_{k}"] * scale
                              for k in ("mean", "half_width"))
                line += f", twin {twin:9.4g} +- {half:7.2g} {unit}; ratio {value / twin:.3f}"
            rows.append(line if twins else f"{line} {unit}")
    return "\n".join(rows)


def describe_study(table) -> str:
    """:func:`study_note` and the labels of the study's cells, one per line."""
    return "\n".join([study_note(table), "cells:",
                      *(f"   {label}" for label in table["label"].unique())])


def study_note(table) -> str:
    """One line for a caption: surfaces per cell, confidence, unconverged solves."""
    cells = table.drop_duplicates("cell")
    bad = int(cells["unconverged_steps"].sum())
    return (f"{int(cells['surfaces'].min())}-{int(cells['surfaces'].max())} surfaces per "
            f"curve; {BAND_NOTE}; unconverged solves excluded: {bad}")
