"""Where the elastic model stops: the share of a solution above a hardness, with no extra solve.

The contact problem of Kumar, Sadeghi & Krousgrill (2006) is purely elastic.
Where element pressures exceed the hardness ``H`` of the softer material, an
elastic-perfectly-plastic body would saturate at ``p = H`` and carry the
excess elsewhere (the capped solve, ``hardness=`` of
:func:`roughcontact.contact.solve`). Whether that matters for a quoted
number can be read off the elastic solution itself, for any ``H`` chosen
after the solve, from a compact record of each solution's pressure
distribution:

*pressure profile*
    the element pressures sorted in decreasing order, ``p_(1) >= p_(2) >=
    ...``, kept at the ranks of :func:`rank_grid` (every rank up to
    :data:`EXACT_RANKS`, then geometric with ratio :data:`RANK_RATIO`, ending at
    ``n``; 140-260 numbers for 60 x 60 to 256 x 256 elements);
*load profile*
    the share of the total load carried by the ``r`` most loaded elements,
    ``sum_{i <= r} p_(i) / sum p``, at the same ranks.

For a threshold ``t`` (:func:`fractions_above`) the count ``N`` of elements
with ``p > t`` lies between two stored ranks ``r_a < r_b`` with ``p_(r_a) > t
>= p_(r_b)``; it is interpolated linearly in pressure between them, exact
where ``r_b = r_a + 1`` (at most :data:`EXACT_RANKS` elements above ``t``) and
otherwise off by less than ``r_b - r_a - 1`` elements, below
``RANK_RATIO - 1`` (5 %) of ``N``. The load share above ``t`` is the load
profile interpolated linearly in rank at ``N``, and the excess load
``sum (p - t)_+ / sum p`` (what a cap at ``t`` must carry elsewhere) is that
share less ``N t / sum p``.

In the dimensionless form of :mod:`roughcontact.contact.nondim` the
threshold of a hardness ``H`` [Pa] is ``H L / (E sigma)``: one stored sweep
answers for every (sigma, E, H).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "EXACT_RANKS",
    "RANK_RATIO",
    "fractions_above",
    "pressure_profile",
    "rank_grid",
]

#: Ranks kept one by one: up to this many elements above a threshold are counted exactly.
EXACT_RANKS = 128
#: Ratio of successive kept ranks beyond :data:`EXACT_RANKS`.
RANK_RATIO = 1.05


def rank_grid(n: int, exact: int = EXACT_RANKS, ratio: float = RANK_RATIO) -> np.ndarray:
    """Ranks (1-based, strictly increasing, the last one ``n``) of a pressure profile.

    Every rank up to ``exact``, then ``ceil(exact ratio^i)`` until ``n``, which
    is always the last rank (so the profile ends at the smallest pressure and
    the load share at 1).
    """
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ValueError(f"n must be a positive integer (elements), got {n!r}")
    if not ratio > 1.0:
        raise ValueError(f"ratio must be above 1, got {ratio!r}")
    n = int(n)
    ranks = list(range(1, min(n, exact) + 1))
    value = float(exact)
    while ranks[-1] < n:
        value *= ratio
        ranks.append(min(n, max(ranks[-1] + 1, int(np.ceil(value)))))
    return np.asarray(ranks, dtype=np.int64)


def pressure_profile(pressure: np.ndarray, ranks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pressure and load profiles of solutions at ``ranks`` (module docstring).

    Parameters
    ----------
    pressure : ndarray, (..., n)
        Element pressures, non-negative (any unit); the last axis is the elements.
    ranks : ndarray of int, (R,)
        From :func:`rank_grid` for this ``n``.

    Returns
    -------
    values : ndarray, (..., R)
        ``p_(r)``, the ``r``-th largest pressure (unit of ``pressure``).
    shares : ndarray, (..., R)
        Share of the total load on the ``r`` most loaded elements [-] (0
        where no element is loaded).
    """
    p = np.asarray(pressure, dtype=float)
    index = np.asarray(ranks) - 1
    ordered = -np.sort(-p, axis=-1)
    cumulative = np.cumsum(ordered, axis=-1)
    total = cumulative[..., -1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        shares = np.where(total > 0.0, cumulative[..., index] / total, 0.0)
    return ordered[..., index], shares


def fractions_above(ranks: np.ndarray, values: np.ndarray, shares: np.ndarray,
                    real_area_fraction: np.ndarray, mean_pressure: np.ndarray,
                    threshold: float) -> dict[str, np.ndarray]:
    """Shares of a solution above a pressure ``threshold``, from its profiles.

    Parameters
    ----------
    ranks : ndarray of int, (R,)
        The ranks of the profiles (:func:`rank_grid`; the last is ``n``).
    values, shares : ndarray, (..., R)
        Pressure and load profiles (:func:`pressure_profile`).
    real_area_fraction : ndarray, (...)
        Fraction of the ``n`` elements in contact (``p > 0``) of each solution.
    mean_pressure : ndarray, (...)
        Mean element pressure of each solution, in the unit of ``values``
        (the nominal pressure; ``n`` times it is the total).
    threshold : float
        Pressure ``t`` in the unit of ``values``, positive.

    Returns
    -------
    dict of ndarray, (...)
        ``elements_above``: count ``N`` of elements with ``p > t`` (interpolated,
        see the module docstring); ``area_above``: ``N`` over the elements in
        contact [-]; ``load_above``: share of the load on them [-];
        ``excess_load``: ``sum (p - t)_+ / sum p`` [-]. All 0 where nothing is
        above ``t`` or nothing is in contact.
    """
    t = float(threshold)
    if not (np.isfinite(t) and t > 0.0):
        raise ValueError(f"threshold must be a finite positive pressure, got {threshold!r}")
    r = np.asarray(ranks, dtype=float)
    v = np.asarray(values, dtype=float)
    c = np.asarray(shares, dtype=float)
    n = r[-1]
    above = np.count_nonzero(v > t, axis=-1)            # stored ranks above t
    a = np.clip(above - 1, 0, r.size - 1)[..., None]    # last stored rank above t
    b = np.clip(above, 0, r.size - 1)[..., None]        # first stored rank at or below t
    r_a, r_b = r[a], r[b]
    v_a = np.take_along_axis(v, a, -1)
    v_b = np.take_along_axis(v, b, -1)
    c_a = np.take_along_axis(c, a, -1)
    c_b = np.take_along_axis(c, b, -1)
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.where(v_a > v_b, (v_a - t) / (v_a - v_b), 0.0)
        count = np.clip(r_a + fraction * (r_b - r_a), r_a, np.maximum(r_b - 1.0, r_a))
        load = c_a + np.where(r_b > r_a, (count - r_a) / (r_b - r_a), 0.0) * (c_b - c_a)
    count, load = count[..., 0], load[..., 0]
    none = above == 0
    count = np.where(none, 0.0, np.where(above == r.size, n, count))
    load = np.where(none, 0.0, np.where(above == r.size, 1.0, load))
    total = n * np.asarray(mean_pressure, dtype=float)
    contact = np.rint(np.asarray(real_area_fraction, dtype=float) * n)
    with np.errstate(invalid="ignore", divide="ignore"):
        area = np.where(contact > 0.0, count / contact, 0.0)
        excess = np.where(total > 0.0, np.maximum(load - count * t / total, 0.0), 0.0)
    return {"elements_above": count, "area_above": np.minimum(area, 1.0),
            "load_above": load, "excess_load": excess}
