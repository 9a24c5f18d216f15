"""Where a contact seals: each surface's percolation point and a cell's threshold.

As the load grows, the contact spots grow and merge, and at some load the free
space between them no longer connects the inlet to the outlet: the interface
seals, and the leak stops (Dapp, Luecke, Persson & Mueser, "Self-affine elastic
contacts: percolation and leakage", Phys. Rev. Lett. 108, 244301, 2012: near a
relative contact area of 0.42 for isotropic self-affine roughness; Wang & Mueser
2021: 0.415).

*A surface's sealing point.* Along a sweep's steps (increasing load), the first
converged step whose free space is not connected
(:attr:`~roughcontact.transport.flow.FlowResult.connected`) closes a bracket with
the converged step before it, which was connected: the surface sealed between
their real areas (and loads). Its point is the bracket's midpoint in real area
and its geometric midpoint in pressure (the steps are geometric in the approach,
and the aggregation reads a state at the step nearest in log P, so the share of
surfaces still leaking at a level is the share whose point lies above it), its
resolution the bracket's width. A surface that is still connected at its last
converged step seals above its swept range (:data:`ABOVE`); one sealed at its
first step, below it (:data:`BELOW`). Steps that connect again after the first
sealed one are counted (``reopened``), not used.

*A cell's threshold.* The real area (and the nominal pressure) at which half the
surfaces have sealed: the median of the surfaces' points, those above the range
counting as larger than every point and those below as smaller, with the
distribution-free confidence interval of a median from order statistics (the
ranks ``l`` and ``n + 1 - l`` of the binomial(n, 1/2) quantiles; e.g. Conover,
*Practical Nonparametric Statistics*, 3rd ed., 1999, Sec 3.2). NaN where the
median or a bound falls outside the swept range, with the reason in ``note``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ABOVE", "BELOW", "INSIDE", "SealingPoints", "Threshold", "sealing_points",
           "threshold"]

#: Where a surface's sealing point lies relative to its swept range.
INSIDE, ABOVE, BELOW = "inside", "above", "below"


@dataclass(frozen=True)
class SealingPoints:
    """Each surface's sealing point (module docstring), (m,) arrays.

    Attributes
    ----------
    where : ndarray of str
        :data:`INSIDE`, :data:`ABOVE` or :data:`BELOW` the swept range.
    area, area_low, area_high : ndarray
        The bracket's midpoint and ends in real area fraction [-]; NaN unless inside.
    pressure, pressure_low, pressure_high : ndarray
        The same in nominal pressure [unit of the sweep's pressures].
    reopened : ndarray of int
        Converged steps after the first sealed one whose free space connects again.
    """

    where: np.ndarray
    area: np.ndarray
    area_low: np.ndarray
    area_high: np.ndarray
    pressure: np.ndarray
    pressure_low: np.ndarray
    pressure_high: np.ndarray
    reopened: np.ndarray


def sealing_points(connected, real_area, pressure, converged) -> SealingPoints:
    """The sealing point of each surface of a sweep (module docstring).

    Parameters
    ----------
    connected, converged : ndarray of bool, (m, k)
        The free space connects inlet to outlet; the contact solve converged.
    real_area, pressure : ndarray, (m, k)
        Real area fraction [-] and nominal pressure of each step (increasing load).
    """
    connected, converged = np.asarray(connected, bool), np.asarray(converged, bool)
    area, load = np.asarray(real_area, float), np.asarray(pressure, float)
    if not connected.shape == converged.shape == area.shape == load.shape or area.ndim != 2:
        raise ValueError(f"connected, real_area, pressure and converged must be (m, k) arrays "
                         f"of one shape, got {connected.shape}, {area.shape}, {load.shape}, "
                         f"{converged.shape}")
    m = area.shape[0]
    where = np.full(m, ABOVE, dtype=object)
    columns = {name: np.full(m, np.nan) for name in ("area", "area_low", "area_high",
                                                     "pressure", "pressure_low",
                                                     "pressure_high")}
    reopened = np.zeros(m, dtype=int)
    for j in range(m):
        steps = np.flatnonzero(converged[j])
        sealed = steps[~connected[j, steps]]
        if sealed.size == 0:
            continue
        first = np.searchsorted(steps, sealed[0])
        reopened[j] = int(np.count_nonzero(connected[j, steps[first:]]))
        if first == 0:
            where[j] = BELOW
            continue
        where[j] = INSIDE
        before, after = steps[first - 1], steps[first]
        for name, values in (("area", area), ("pressure", load)):
            low, high = values[j, before], values[j, after]
            columns[f"{name}_low"][j], columns[f"{name}_high"][j] = low, high
        columns["area"][j] = 0.5 * (columns["area_low"][j] + columns["area_high"][j])
        columns["pressure"][j] = math.sqrt(columns["pressure_low"][j]
                                           * columns["pressure_high"][j])
    return SealingPoints(where=where.astype(str), reopened=reopened, **columns)


@dataclass(frozen=True)
class Threshold:
    """A cell's percolation threshold (module docstring): the median of its surfaces'
    sealing points with its confidence interval, in real area fraction [-] and in
    nominal pressure; counts of surfaces inside, above and below the range."""

    area: float
    area_low: float
    area_high: float
    pressure: float
    pressure_low: float
    pressure_high: float
    surfaces: int
    sealed_inside: int
    above: int
    below: int
    confidence: float
    note: str

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def _median_ranks(n: int, confidence: float) -> tuple[int, int]:
    """1-based ranks ``(l, n + 1 - l)`` of the order statistics that bound the median
    with probability at least ``confidence`` (binomial(n, 1/2)); ``l`` may be 0 (no
    bound at that confidence)."""
    from scipy.stats import binom

    low = int(binom.ppf(0.5 * (1.0 - confidence), n, 0.5))
    # the largest l with P(B <= l - 1) <= (1 - c) / 2
    while low > 0 and binom.cdf(low - 1, n, 0.5) > 0.5 * (1.0 - confidence):
        low -= 1
    return low, n + 1 - low


def _order_statistic(values: np.ndarray, below: int, above: int, rank: int) -> tuple:
    """The ``rank``-th smallest (1-based) of ``below`` values under the range, the finite
    ``values`` and ``above`` values over it: (value, why NaN or '')."""
    n = below + values.size + above
    if rank < 1 or rank > n:
        return np.nan, "too few surfaces for the band"
    if rank <= below:
        return np.nan, "below the first step"
    if rank > below + values.size:
        return np.nan, "above the swept range"
    return float(np.sort(values)[rank - below - 1]), ""


def threshold(points: SealingPoints, confidence: float = 0.95) -> Threshold:
    """The cell's threshold of its surfaces' sealing ``points`` (module docstring)."""
    where = np.asarray(points.where)
    n = where.size
    inside = where == INSIDE
    below, above = int(np.count_nonzero(where == BELOW)), int(np.count_nonzero(where == ABOVE))
    low_rank, high_rank = _median_ranks(n, confidence)
    values, notes = {}, []
    for name in ("area", "pressure"):
        finite = np.asarray(getattr(points, name))[inside]
        sorted_ranks = ((n + 1) // 2, n // 2 + 1)  # the median: mean of these two
        middle = [_order_statistic(finite, below, above, r) for r in sorted_ranks]
        values[name] = 0.5 * (middle[0][0] + middle[1][0])
        bounds = [_order_statistic(finite, below, above, r) for r in (low_rank, high_rank)]
        values[f"{name}_low"], values[f"{name}_high"] = bounds[0][0], bounds[1][0]
        notes += [why for _, why in (*middle, *bounds) if why]
    note = "; ".join(dict.fromkeys(notes)) or "inside the swept range"
    return Threshold(**values, surfaces=n, sealed_inside=int(inside.sum()), above=above,
                     below=below, confidence=float(confidence), note=note)
