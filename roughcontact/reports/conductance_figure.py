"""The conductance figure: h_c, the constriction's h_s against the correlations, the bulk.

The aggregates of the studies a ``conductance`` figure lists (each solved with the
``conductance`` section on, :mod:`roughcontact.study.conductance_settings`) and the
rms profile slope of each cell's surfaces
(:func:`~roughcontact.transport.conduction.correlations.rms_profile_slope`, from its
surface file) give, per cell and level, ``h_c``, ``h_s`` and the correlation of the
cell: Mikic's elastic one, or for a capped cell Cooper, Mikic and Yovanovich's plastic
one with its cap as the microhardness
(:mod:`roughcontact.transport.conduction.correlations`; ``k_s = 2 k`` against the
perfectly conducting flat, ``E* = E / (1 - nu^2)``).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from roughcontact.transport.conduction.correlations import (
    cmy_plastic,
    harmonic_conductivity,
    mikic_elastic,
    rms_profile_slope,
)
from roughcontact.transport.conduction.probe import (
    BULK_SHARE,
    CONDUCTANCE_PER_AREA,
    CONSTRICTION_PER_AREA,
)

__all__ = ["conductance_answers", "conductance_at", "load_conductivities", "load_slopes",
           "plot_conductance", "with_correlations"]

MPA, UM = 1e6, 1e-6


def load_conductivities(paths, names) -> dict:
    """The body's and the counter body's thermal conductivities [W/(m K)] of several
    studies by name (the sidecar's ``conductance.conductivity`` and
    ``counter_conductivity``, inf for a perfectly conducting counter face, of each
    study's aggregate files ``paths``, checked as by
    :func:`~roughcontact.reports.plotting.load_aggregates`); a study solved without a
    conductivity is refused, naming it."""
    from roughcontact.reports.plotting import load_aggregates
    from roughcontact.reports.study_figures import AGGREGATE_FILES

    paths, names = list(paths), list(names)
    found = {}
    for k, name in enumerate(names):
        meta = load_aggregates(paths[AGGREGATE_FILES * k:AGGREGATE_FILES * (k + 1)])[2]
        conductivity = (meta.get("conductance") or {}).get("conductivity")
        if conductivity is None:
            raise ValueError(f"study {name} was solved without a thermal conductivity "
                             "(its sidecar has no conductance.conductivity): set "
                             "conductance.enabled: true and conductance.conductivity_W_mK")
        counter = meta["conductance"].get("counter_conductivity")
        found[name] = (float(conductivity), math.inf if counter is None else float(counter))
    return found


def load_slopes(surface_files, cells) -> dict:
    """Surface cell key -> the rms profile slope per unit rms height [1/m] of its
    surfaces (``surface_files`` and their cells' params ``cells``, in one order; each
    file checked to have been made for its cell)."""
    from roughcontact.study.jobs.storage import read_surfaces
    from roughcontact.study.records import surface_cell_from_params

    slopes = {}
    for path, params in zip(surface_files, cells, strict=True):
        cell = surface_cell_from_params(params)
        heights = read_surfaces(path, cell=params)["heights"]  # unit rms height
        spacing = tuple(s / n for s, n in zip(cell.size, cell.grid, strict=True))
        slopes[cell.key] = rms_profile_slope(heights, spacing)
    return slopes


def with_correlations(table: pd.DataFrame, slopes: dict, conductivity: float,
                      counter_conductivity: float = math.inf) -> pd.DataFrame:
    """A study's aggregate ``table`` with each cell's slope ``m`` [-] (its surfaces'
    :func:`load_slopes` times its sigma), the correlation's ``h`` [W/(m^2 K)] at each
    level (``correlation``: Mikic's elastic one, CMY's plastic one for a capped cell)
    and ``h_s`` over it (``h_s_ratio``); ``conductivity`` the body's and
    ``counter_conductivity`` the counter face's [W/(m K)] (inf: a perfect conductor)."""
    rows = []
    k_s = harmonic_conductivity(conductivity, counter_conductivity)
    for _, cell in table.groupby("cell", sort=False):
        first = cell.iloc[0]
        sigma = first["sigma_um"] * UM
        slope = slopes[first["contact_key"].split("__")[0]] * sigma
        pressure = cell["nominal_pressure"].to_numpy(dtype=float)
        cap = first.get("cap_MPa", math.nan)
        if cap is not None and np.isfinite(cap):
            h, name = cmy_plastic(pressure, k_s, slope, sigma, cap * MPA), "CMY plastic"
        else:
            modulus = first["E_MPa"] * MPA / (1.0 - first["nu"] ** 2)
            h, name = mikic_elastic(pressure, k_s, slope, sigma, modulus), "Mikic elastic"
        rows.append(cell.assign(slope=slope, correlation_h=h, correlation=name,
                                h_s_ratio=cell[f"{CONSTRICTION_PER_AREA}_mean"] / h))
    return pd.concat(rows)


def _band(ax, rows, column: str, color, scale: float = 1.0, **style):
    x = rows["nominal_pressure"] / MPA
    mean, half = rows[f"{column}_mean"] * scale, rows[f"{column}_half_width"] * scale
    line, = ax.plot(x, mean, color=color, **style)
    ax.fill_between(x, mean - half, mean + half, color=color, alpha=0.15, lw=0)
    return line


def _label(first, study: str) -> str:
    cap = first.get("cap_MPa", math.nan)
    capped = f", H {cap:g} MPa" if cap is not None and np.isfinite(cap) else ""
    return (f"{study}: Sk {first['skew']:g}, Ku {first['kurt']:g}, "
            f"L {first['thickness_mm']:g} mm{capped}")


def plot_conductance(tables: dict):
    """The figure of studies ``tables`` (name -> :func:`with_correlations` table): h_c and
    h_s with the correlation for the first study's cells, h_s over the correlation for
    every cell, the bulk's share for every cell."""
    import matplotlib.pyplot as plt

    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(15.0, 4.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    first_name = next(iter(tables))
    index = 0
    for study, table in tables.items():
        for _, cell in table.groupby("cell", sort=False):
            color = colors[index % len(colors)]
            index += 1
            top = cell.iloc[0]
            label = _label(top, study)
            if study == first_name:
                _band(left, cell, CONDUCTANCE_PER_AREA, color, 1e-3, marker="o", ms=3,
                      label=f"{label}: h_c")
                _band(left, cell, CONSTRICTION_PER_AREA, color, 1e-3, ls=":")
                left.plot(cell["nominal_pressure"] / MPA, cell["correlation_h"] * 1e-3,
                          color=color, ls="--", lw=1)
            middle.plot(cell["nominal_pressure"] / MPA, cell["h_s_ratio"], color=color,
                        marker="o", ms=3, label=f"{label} ({top['correlation']})")
            _band(right, cell, BULK_SHARE, color, marker="o", ms=3, label=label)
    left.set(xscale="log", yscale="log", xlabel="nominal pressure P [MPa]",
             ylabel="h [kW/(m² K)]",
             title=f"{first_name}: h_c (solid), h_s (dotted), correlation (dashed)")
    middle.axhline(1.0, color="grey", lw=0.8)
    middle.set(xscale="log", xlabel="nominal pressure P [MPa]",
               ylabel="h_s / correlation", title="constriction against the correlation")
    right.set(xscale="log", xlabel="nominal pressure P [MPa]", ylim=(0.0, 1.0),
              ylabel="bulk share R_bulk C", title="the bulk's share of the resistance")
    for ax in (left, middle, right):
        ax.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=7)
    middle.legend(fontsize=6)
    right.legend(fontsize=6)
    fig.tight_layout()
    return fig


def conductance_at(table: pd.DataFrame, pressures_MPa) -> pd.DataFrame:
    """Each cell's numbers at the levels nearest ``pressures_MPa``: h_c, h_s, the bulk
    share (mean and 95 % half width), the correlation and h_s over it."""
    picked = []
    for _, cell in table.groupby("cell", sort=False):
        levels = cell["nominal_pressure"].to_numpy() / MPA
        for p in pressures_MPa:
            picked.append(cell.iloc[int(np.argmin(np.abs(np.log(levels / p))))])
    frame = pd.DataFrame(picked)
    columns = {"skew": "Sk", "kurt": "Ku", "thickness_mm": "L_mm",
               "nominal_pressure_MPa": "P_MPa"}
    for column, short in ((CONDUCTANCE_PER_AREA, "h_c"), (CONSTRICTION_PER_AREA, "h_s"),
                          (BULK_SHARE, "bulk")):
        columns[f"{column}_mean"] = short
        columns[f"{column}_half_width"] = f"{short}_pm"
    columns |= {"correlation_h": "h_corr", "h_s_ratio": "h_s/h_corr"}
    return frame[list(columns)].rename(columns=columns)


def conductance_answers(tables: dict, pressures_MPa) -> str:
    """The report's sentence: each study's h_c at ``pressures_MPa`` per (Sk, Ku), with
    95 % bands (reStructuredText)."""
    lines = []
    for study, table in tables.items():
        found = conductance_at(table, pressures_MPa)
        for (skew, kurt), rows in found.groupby(["Sk", "Ku"], sort=False):
            values = "; ".join(f"{r.P_MPa:.3g} MPa: {r.h_c / 1e3:.3g} ± {r.h_c_pm / 1e3:.2g}"
                               for r in rows.itertuples())
            lines.append(f"{study}, (Sk, Ku) = ({skew:g}, {kurt:g}): h_c [kW/(m² K)] at "
                         f"{values}.")
    return "\n\n".join(lines) + "\n"
