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


def save_figure(fig, *paths, dpi: int = 150) -> None:
    """Save a matplotlib figure to each path (format from the suffix), atomically."""
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


def surface_moments(files, sigma_um: float):
    """Realised moments of the first surface of each surface file, a row each.

    Columns ``file``, ``sigma_um`` (the stored unit std times ``sigma_um``
    [µm]), ``skew`` and ``kurt``: what the 3-D panels of
    :func:`draw_surfaces` show. Returns a pandas DataFrame.
    """
    import pandas as pd

    from roughcontact.study.storage import read_surfaces

    rows = []
    for path in files:
        stats = read_surfaces(path, count=1)["stats"]
        rows.append({"file": str(path), "sigma_um": stats["sigma"][0] * sigma_um,
                     "skew": stats["skew"][0], "kurt": stats["kurt"][0]})
    return pd.DataFrame(rows, columns=["file", "sigma_um", "skew", "kurt"])


def draw_surfaces(files, sigma_um: float, titles, *, columns: int = 3):
    """3-D views of the first surface of each surface file, ``columns`` per row.

    Heights [µm] are the stored unit heights times ``sigma_um``; plan
    coordinates in mm. ``titles`` (one per file, may hold line breaks and
    mathtext) go above the panels with room kept for them. Returns the figure.
    """
    import matplotlib.pyplot as plt
    import numpy as np

    from roughcontact.study.storage import read_surfaces

    files = list(files)
    columns = max(1, min(columns, len(files)))
    rows = -(-len(files) // columns)
    fig = plt.figure(figsize=(4.2 * columns, 4.0 * rows))
    for k, (path, title) in enumerate(zip(files, titles, strict=True)):
        data = read_surfaces(path, count=1)
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


def _check_sha256(path, meta: dict, key: str, meta_path) -> None:
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
        _check_sha256(path, meta, key, meta_path)
    return pd.read_csv(table_path), pd.read_csv(moduli_path), meta


def load_validity(paths):
    """The validity table of a study (``aggregate_files``; 4th path), checked against
    the SHA-256 its sidecar records; an empty table if the study has none."""
    import json

    import pandas as pd

    if len(paths) < 4:
        return pd.DataFrame()
    meta_path, path = paths[2], paths[3]
    _check_sha256(path, json.loads(Path(meta_path).read_text()), "validity_sha256", meta_path)
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


def plot_band(ax, frame, quantity: str, *, y_scale: float = 1.0, label=None, color=None,
              linestyle="-"):
    """Mean curve of ``quantity`` against nominal pressure [MPa] with its confidence band.

    ``frame`` holds one cell's rows of an aggregate table. Levels that rest on
    no surface are left out; a level resting on fewer surfaces than the cell
    has is drawn with a hollow marker, so a thin band there is not mistaken
    for a tight one. Returns the line.
    """
    import numpy as np

    count = frame[f"{quantity}_count"].to_numpy()
    ok = count > 0
    x = frame["nominal_pressure"].to_numpy()[ok] / 1e6
    y = frame[f"{quantity}_mean"].to_numpy()[ok] * y_scale
    hw = np.nan_to_num(frame[f"{quantity}_half_width"].to_numpy()[ok] * y_scale)
    (line,) = ax.plot(x, y, label=label, color=color, linestyle=linestyle)
    ax.fill_between(x, y - hw, y + hw, color=line.get_color(), alpha=0.2, linewidth=0)
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


def plot_cells_panels(table, panels, *, label: str, title: str):
    """Several quantities of every cell of ``table`` against nominal pressure [MPa], one
    panel each, side by side (as :func:`plot_cells`).

    ``panels`` holds ``(quantity, y_scale, ylabel, log_y)`` per panel; the
    legend is on the first panel, ``title`` above all. Returns the figure.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 4.2), squeeze=False)
    for ax, (quantity, y_scale, ylabel, log_y) in zip(axes[0], panels, strict=True):
        _draw_cells(ax, table, quantity, y_scale=y_scale, label=label)
        ax.set(ylabel=ylabel, yscale="log" if log_y else "linear")
    axes[0][0].legend(fontsize=8)
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
                row |= {f"{by}={value:g} mean": m, f"{by}={value:g} half width": h}
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
            f"curve; bands: 95 % confidence interval of the mean; unconverged solves "
            f"excluded: {bad}")
