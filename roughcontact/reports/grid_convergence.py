"""Grid convergence of real contact area, peak pressure and the area-load slope kappa.

The same self-affine surfaces with a short-wavelength cut-off, resolved on
grids of ``g`` x ``g`` elements (:mod:`roughcontact.study.jobs.grid_convergence`
makes and solves them, on the periodic elastic half-space), are compared at
fixed reduced nominal pressures ``p* = p0 / (E* h'_rms)``:

- the real area fraction ``A / A0`` and the peak pressure ``p_max`` of each
  surface at each ``p*`` (its sweep interpolated in ``log P``, as the
  study's aggregates are: :func:`roughcontact.contact.aggregate.surface_curves`),
  averaged over the surfaces with a Student-t 95 % band;
- the area-load slope ``kappa = (A / A0) / p*``, fitted per surface through
  the origin, ``kappa = sum(A p*) / sum(p*^2)`` (:func:`fit_kappa`), over
  the reduced pressures whose mean area on the finest grid lies in
  ``kappa_area`` (0.5-10 %): the same levels on every grid, so that kappa
  changes with the grid as smoothly as the areas do (a selection of steps
  by each grid's own area would move levels in and out of the fit);
- for each aggregate, Richardson's extrapolation from the three finest grids
  (refined by a constant ratio r, 2 here): the observed order
  ``p = log_r((f_4h - f_2h) / (f_2h - f_h))`` and ``f_h + (f_h - f_2h) /
  (r^p - 1)`` (:func:`roughcontact.reports.convergence.richardson`: NaN when
  the differences change sign or p lies outside [0.5, 6]), and the coarsest
  grid from which every finer grid lies within ``converged_within`` (1 %)
  of the extrapolated value (:func:`converged_grid`; of the finest grid's
  value where Richardson does not apply, which says less).

The 95 % bands are the spread of the surfaces (seeds) about their mean; the
changes from grid to grid are those of the same surfaces (paired), so they
are measured far more precisely than the bands suggest.

kappa compared with the literature: Persson's theory ``sqrt(8 / pi)`` = 1.60
(Persson 2001, J. Chem. Phys. 115, 3840), the asperity theory of Bush,
Gibson & Thomas (1975, Wear 35, 87) ``sqrt(2 pi)`` = 2.51, and numerical
studies about 2 (Hyun, Pei, Molinari & Robbins 2004, Phys. Rev. E 70,
026117; Yastrebov, Anciaux & Molinari 2015, Int. J. Solids Struct. 52, 83).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from roughcontact.contact import aggregate
from roughcontact.contact.curves import PhysicalSweep
from roughcontact.reports.convergence import richardson
from roughcontact.reports.plotting import BANDS, positive_band, save_figure
from roughcontact.study.config import GridConvergenceSettings
from roughcontact.study.jobs.grid_convergence import read_grid_contact
from roughcontact.study.provenance import atomic_path

__all__ = ["KAPPA_REFERENCES", "QUANTITIES", "converged_grid", "extrapolate", "fit_kappa",
           "grid_convergence_report", "grid_convergence_table", "kappa_levels",
           "plot_grid_convergence"]

#: kappa of the theories and simulations the study is compared with.
KAPPA_REFERENCES = {"Persson sqrt(8/pi)": math.sqrt(8.0 / math.pi),
                    "asperity theory sqrt(2 pi)": math.sqrt(2.0 * math.pi),
                    "numerical studies": 2.0}
#: Aggregates per reduced pressure, with their unit.
QUANTITIES = {"real_area_fraction": "1", "corrected_real_area_fraction": "1",
              "max_pressure": "Pa", "spot_count": "1", "mean_gap": "m"}


def fit_kappa(reduced_pressures, area: np.ndarray) -> np.ndarray:
    """kappa of each surface: ``sum(A p*) / sum(p*^2)`` over the levels where its area is
    known (not NaN), NaN with fewer than two.

    ``reduced_pressures`` (levels,) ``p* = p0 / (E* h'_rms)`` [-]; ``area`` (m, levels)
    the real area fraction of each surface there [-].
    """
    reduced = np.broadcast_to(np.asarray(reduced_pressures, dtype=float), np.shape(area))
    known = np.isfinite(area)
    with np.errstate(invalid="ignore", divide="ignore"):
        kappa = (np.where(known, area * reduced, 0.0).sum(axis=1)
                 / np.where(known, reduced**2, 0.0).sum(axis=1))
    return np.where(known.sum(axis=1) >= 2, kappa, np.nan)


def kappa_levels(levels, finest_area: np.ndarray, area_range: tuple[float, float]) -> np.ndarray:
    """Mask of the ``levels`` whose mean area over the surfaces (``finest_area`` (m, levels),
    the finest grid's) lies in ``area_range``."""
    mean = aggregate.statistics(finest_area)[0]
    return (mean >= area_range[0]) & (mean <= area_range[1])


def converged_grid(grids: Sequence[int], values: Sequence[float], reference: float,
                   within: float) -> float:
    """The coarsest grid from which every finer grid's value lies within ``within``
    (relative) of ``reference``; NaN if none does or ``reference`` is not finite."""
    if not math.isfinite(reference) or reference == 0.0:
        return math.nan
    found = math.nan
    for grid, value in sorted(zip(grids, values, strict=True), reverse=True):
        if not abs(value / reference - 1.0) <= within:
            break
        found = float(grid)
    return found


def extrapolate(grids: Sequence[int], means: Sequence[float]) -> tuple[float, float]:
    """Richardson's ``(value, observed order)`` from the three finest of ``grids``
    (ascending, elements per side) and their ``means``; NaN unless those three are
    refined by a constant ratio (:func:`~roughcontact.reports.convergence.richardson`)."""
    if len(grids) < 3:
        return math.nan, math.nan
    (g1, g2, g3), (f1, f2, f3) = grids[-3:], means[-3:]
    if not math.isclose(g3 * g1, g2 * g2):
        return math.nan, math.nan
    return richardson(f1, f2, f3, g2 / g1)


def _aggregate_rows(quantity: str, levels, per_grid: Mapping, settings) -> list[dict]:
    """Rows of one quantity at each reduced pressure (``per_grid``: grid -> (m, levels))."""
    grids = sorted(per_grid)
    rows = []
    for i, level in enumerate(levels):
        stats = {g: aggregate.statistics(per_grid[g][:, i:i + 1]) for g in grids}
        means = [float(stats[g][0][0]) for g in grids]
        value, order = extrapolate(grids, means)
        # where Richardson does not apply, the finest grid is the (weaker) reference
        reference = "extrapolated" if math.isfinite(value) else "finest grid"
        done = converged_grid(grids, means, value if math.isfinite(value) else means[-1],
                              settings.converged_within)
        previous = [math.nan, *means[:-1]]
        for g, mean, before in zip(grids, means, previous, strict=True):
            rows.append({"quantity": quantity, "unit": QUANTITIES.get(quantity, "1"),
                         "reduced_pressure": level,
                         "nominal_pressure_Pa": level * settings.pressure_scale, "grid": g,
                         "mean": mean, "half_width": float(stats[g][1][0]),
                         "surfaces": int(stats[g][2][0]), "extrapolated": value,
                         "observed_order": order,
                         "relative_to_extrapolated": mean / value - 1.0,
                         "change_from_coarser": mean / before - 1.0,
                         "converged_grid": done, "converged_against": reference})
    return rows


def grid_convergence_table(sweeps: Mapping[int, tuple[PhysicalSweep, dict]],
                           settings: GridConvergenceSettings) -> pd.DataFrame:
    """The study's table from each grid's sweep and attributes (:func:`read_grid_contact`).

    One row per (quantity, reduced pressure, grid): ``quantity``
    (``real_area_fraction``, ``corrected_real_area_fraction`` (the element count
    corrected by its perimeter, Yastrebov, Anciaux & Molinari 2017),
    ``max_pressure``, ``spot_count``, ``mean_gap``, ``kappa`` or
    ``kappa_corrected`` (kappa of the corrected area)), ``unit``,
    ``reduced_pressure`` ``p0 / (E* h'_rms)`` [-] and ``nominal_pressure_Pa``
    (NaN for kappa), ``grid``, ``mean``, ``half_width`` (95 %), ``surfaces``,
    ``extrapolated`` and ``observed_order`` (three finest grids),
    ``relative_to_extrapolated``, ``change_from_coarser`` (against the next
    coarser grid), ``converged_grid`` and ``converged_against`` (the
    extrapolated value, or the finest grid's where Richardson does not apply:
    then the finest grid is never shown to be converged), ``kappa_fit`` (the levels
    of the fit of kappa, on its rows); then per grid
    ``element_size_m``, ``points_per_cutoff`` (``lambda_s / dx``),
    ``wall_s``, ``cpu_s``, ``method`` and ``unconverged_solves``.
    """
    levels = np.asarray(settings.reduced_pressures)
    curves = {quantity: {} for quantity in QUANTITIES}
    pressures = levels * settings.pressure_scale
    for grid, (sweep, attrs) in sweeps.items():
        if not np.allclose(attrs["rms_gradient"], settings.rms_gradient, rtol=1e-9, atol=0):
            raise ValueError(f"grid {grid}: the surfaces' h'_rms differ from the study's "
                             f"{settings.rms_gradient:g}: every surface is scaled to it, so "
                             "one nominal pressure per reduced pressure serves them all")
        for quantity, per_grid in curves.items():
            per_grid[grid] = aggregate.surface_curves(sweep, pressures, quantity)
    area = curves["real_area_fraction"]
    chosen = kappa_levels(levels, area[max(area)], settings.kappa_area)
    rows = [row for quantity, per_grid in curves.items()
            for row in _aggregate_rows(quantity, levels, per_grid, settings)]
    for name, source in (("kappa", "real_area_fraction"),
                         ("kappa_corrected", "corrected_real_area_fraction")):
        kappa = {grid: fit_kappa(levels[chosen], values[:, chosen])[:, None]
                 for grid, values in curves[source].items()}
        rows += _aggregate_rows(name, [math.nan], kappa, settings)
    table = pd.DataFrame(rows)
    kappa_rows = table["quantity"].isin(["kappa", "kappa_corrected"])
    table.loc[kappa_rows, ["nominal_pressure_Pa"]] = math.nan
    table["kappa_fit"] = ""
    table.loc[kappa_rows, "kappa_fit"] = "p* = " + " ".join(f"{p:g}" for p in levels[chosen])
    per_grid = pd.DataFrame([{
        "grid": grid, "element_size_m": settings.size / grid,
        "points_per_cutoff": settings.cutoff_wavelength * grid / settings.size,
        "wall_s": float(attrs["wall_seconds"]), "cpu_s": float(attrs["cpu_seconds"]),
        "method": attrs["method"], "unconverged_solves": int((~sweep.converged).sum())}
        for grid, (sweep, attrs) in sweeps.items()])
    return table.merge(per_grid, on="grid", how="left")


def _plot_levels(ax, table: pd.DataFrame, quantity: str, scale: float, ylabel: str,
                 style: str = "o-", label: str = "") -> None:
    """One curve per reduced pressure against the grid, 95 % band, extrapolated dashed."""
    rows = table[table["quantity"] == quantity]
    for i, (level, part) in enumerate(rows.groupby("reduced_pressure", sort=True)):
        color = f"C{i}"
        band = BANDS["fraction" if quantity.endswith("_fraction") else "positive"]
        low, high = band(part["mean"], part["half_width"])
        ax.plot(part["grid"], part["mean"] * scale, style, color=color,
                label=f"$p^*$ = {level:.3g}{label}")
        ax.fill_between(part["grid"], low * scale, high * scale, color=color, alpha=0.2)
        extrapolated = part["extrapolated"].iloc[0] * scale
        if math.isfinite(extrapolated):
            ax.axhline(extrapolated, color=color, ls="--", lw=0.8)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("grid (elements per side)")
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, ncol=2)


def _plot_changes(ax, table: pd.DataFrame, within: float) -> None:
    """|f / f_extrapolated - 1| of every aggregate against the grid, and the 1 % line."""
    for i, (quantity, marker) in enumerate((("real_area_fraction", "o"),
                                            ("corrected_real_area_fraction", "D"),
                                            ("max_pressure", "s"), ("kappa", "^"))):
        rows = table[table["quantity"] == quantity]
        for level, part in rows.groupby("reduced_pressure", dropna=False, sort=True):
            label = quantity if level == rows["reduced_pressure"].min() or \
                quantity == "kappa" else None
            ax.plot(part["grid"], part["relative_to_extrapolated"].abs(), marker=marker,
                    color=f"C{i}", alpha=0.7, label=label)
    ax.axhline(within, color="k", ls=":", lw=0.8)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("grid (elements per side)")
    ax.set_ylabel("|value / extrapolated - 1|")
    ax.legend(fontsize=7)


def _plot_kappa(ax, table: pd.DataFrame) -> None:
    """kappa per grid with its 95 % band over the surfaces, and the literature's values."""
    for quantity, fmt, label in (("kappa", "o-", "element count"),
                                 ("kappa_corrected", "D:", "corrected area")):
        rows = table[table["quantity"] == quantity]
        low, high = positive_band(rows["mean"], rows["half_width"])
        ax.errorbar(rows["grid"], rows["mean"], yerr=[rows["mean"] - low, high - rows["mean"]],
                    fmt=fmt, color="k", capsize=3, label=f"{label} (95 % band, log space)")
    for (name, value), style in zip(KAPPA_REFERENCES.items(), ("--", "-.", ":"), strict=True):
        ax.axhline(value, ls=style, color="C3", lw=0.9)
        ax.annotate(f"{name} = {value:.2f}", (rows["grid"].min(), value), fontsize=7,
                    va="bottom")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("grid (elements per side)")
    ax.set_ylabel(r"$\kappa = (A / A_0) \,/\, (p_0 / (E^* h'_\mathrm{rms}))$")
    ax.legend(fontsize=7, loc="lower right")


def plot_grid_convergence(table: pd.DataFrame, path_png: str | os.PathLike,
                          within: float = 0.01) -> Figure:
    """Four panels: real area (and corrected by its perimeter), peak pressure (over E*
    h'_rms), kappa (of both areas), changes; PNG.

    Bands of the 95 % intervals drawn in log (logit) space
    (:func:`roughcontact.reports.plotting.positive_band`); returns the figure."""
    fig = Figure(figsize=(11, 8.5))
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    scale = table.attrs.get("pressure_scale", 1.0)
    _plot_levels(axes[0, 0], table, "real_area_fraction", 1.0, r"real area fraction $A / A_0$")
    _plot_levels(axes[0, 0], table, "corrected_real_area_fraction", 1.0,
                 r"real area fraction $A / A_0$ (diamonds: corrected by the perimeter)",
                 style="D:", label=", corrected")
    _plot_levels(axes[0, 1], table, "max_pressure", 1.0 / scale,
                 r"$p_\max / (E^* h'_\mathrm{rms})$")
    _plot_kappa(axes[1, 0], table)
    _plot_changes(axes[1, 1], table, within)
    fig.suptitle("Grid convergence on the periodic half-space: the same self-affine surfaces "
                 "on every grid (dashed: Richardson extrapolation)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path_png)
    return fig


def grid_convergence_report(contact_paths: Sequence, csv_path, png_path) -> pd.DataFrame:
    """Read the study's contact files (one per grid), write the table (CSV) and figure (PNG).

    Every file must belong to the same study (equal ``params`` and seeds) and
    match its content hash (:func:`~roughcontact.study.jobs.grid_convergence.read_grid_contact`);
    otherwise ValueError naming the file. Returns the table
    (:func:`grid_convergence_table`).
    """
    sweeps, params, seeds = {}, None, None
    for path in contact_paths:
        sweep, attrs = read_grid_contact(path)
        if params is None:
            params, seeds = attrs["params"], attrs["seeds"]
        elif attrs["params"] != params or attrs["seeds"] != seeds:
            raise ValueError(f"{path}: made with other settings or seeds than "
                             f"{contact_paths[0]}; rebuild it")
        sweeps[int(attrs["grid"])] = (sweep, attrs)
    settings = GridConvergenceSettings.from_section(json.loads(params))
    table = grid_convergence_table(dict(sorted(sweeps.items())), settings)
    table.attrs["pressure_scale"] = settings.pressure_scale
    with atomic_path(csv_path) as tmp:
        table.to_csv(tmp, index=False)
    plot_grid_convergence(table, png_path, settings.converged_within)
    return table
