"""Contact results outside physical plausibility, read off a cell's aggregated table.

The elastic contact model gives numbers for any input; two kinds of result
say that the model, its mesh or the block behind it went wrong, whatever the
solver's residual:

- a peak element pressure above :data:`MAX_PRESSURE_OVER_E_STAR` times the
  contact modulus ``E* = E / (1 - nu^2)`` (a strain of that order: no elastic
  model holds there; the paper's mesh, locally too stiff, stays below 3.2 E*
  over the paper's whole study);
- a contact carried by fewer than :data:`MIN_CONTACT_ELEMENTS` elements at
  the highest nominal pressure of the cell (one or two asperity tips on
  single elements: the real area and the peak pressure are those of the
  discretization; a 10 mm block under a 0.1 mm patch put 4 of 4096 elements
  in contact at 24 E*; the paper's study has at least 23 at the highest
  pressure of each cell, the quick study 9.7).

:func:`plausibility_flags` gives a sentence per table row (``"ok"`` where
none applies), :func:`implausible` the cell's summary: the aggregation
writes the first as the ``plausibility`` column and logs the second, the
audit flags a cell with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from roughcontact.units import MPA

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "MAX_PRESSURE_OVER_E_STAR",
    "MIN_CONTACT_ELEMENTS",
    "implausible",
    "plausibility_flags",
]

#: Largest plausible peak element pressure, in units of E* = E / (1 - nu^2).
MAX_PRESSURE_OVER_E_STAR = 10.0
#: Fewest elements in contact, at a cell's highest nominal pressure, of a resolved contact.
MIN_CONTACT_ELEMENTS = 5


def _contact_modulus(E: float, nu: float) -> float:
    return E / (1.0 - nu * nu)


def _highest_contact(frame: pd.DataFrame, n_elements: int) -> tuple[float, float] | None:
    """(nominal pressure [Pa], mean elements in contact) at the highest level with values."""
    valued = frame[frame["real_area_fraction_count"] > 0]
    if valued.empty:
        return None
    top = valued.iloc[int(np.argmax(valued["nominal_pressure"].to_numpy()))]
    return float(top["nominal_pressure"]), float(top["real_area_fraction_mean"]) * n_elements


def plausibility_flags(frame: pd.DataFrame, n_elements: int, E: float,
                       nu: float) -> np.ndarray:
    """Per row of an :func:`~roughcontact.contact.aggregate.aggregate_cell` table: ``"ok"``,
    or why the row is implausible (``"p_max 24 E*"``; ``"4 of 4096 elements in contact at
    the highest pressure"`` on every row of a cell whose contact stays unresolved).

    ``n_elements`` the contact elements of the grid, ``E`` [Pa] and ``nu`` the
    material's (the cell's).
    """
    ratio = frame["max_pressure_mean"].to_numpy(float) / _contact_modulus(E, nu)
    flags = [[f"p_max {r:.3g} E*"] if r > MAX_PRESSURE_OVER_E_STAR else [] for r in ratio]
    top = _highest_contact(frame, n_elements)
    if top is not None and top[1] < MIN_CONTACT_ELEMENTS:
        for row in flags:
            row.append(f"{top[1]:.3g} of {n_elements} elements in contact at the highest "
                       "pressure")
    return np.array(["; ".join(row) or "ok" for row in flags], dtype=object)


def implausible(frame: pd.DataFrame, n_elements: int, E: float, nu: float) -> list[str]:
    """Why a cell's results are implausible, as sentences with their pressures (none:
    plausible); the table as in :func:`plausibility_flags`."""
    out = []
    ratio = frame["max_pressure_mean"].to_numpy(float) / _contact_modulus(E, nu)
    high = np.nan_to_num(ratio) > MAX_PRESSURE_OVER_E_STAR
    if high.any():
        first = float(frame["nominal_pressure"].to_numpy(float)[high].min())
        out.append(f"peak pressure up to {np.nanmax(ratio):.3g} E* (E* = E / (1 - nu^2)), "
                   f"above {MAX_PRESSURE_OVER_E_STAR:g} E* from P = {first / MPA:.3g} MPa")
    top = _highest_contact(frame, n_elements)
    if top is not None and top[1] < MIN_CONTACT_ELEMENTS:
        out.append(f"{top[1]:.3g} of {n_elements} elements in contact at the highest "
                   f"pressure P = {top[0] / MPA:.3g} MPa (fewer than {MIN_CONTACT_ELEMENTS}: "
                   "the contact is not resolved)")
    return out
