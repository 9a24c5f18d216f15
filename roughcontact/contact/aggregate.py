"""Per-cell statistics of force-deflection sweeps on a common nominal-pressure axis.

The paper averages 60 surfaces per set of statistics at equal nominal
pressure P (Figs 7, 9, 11-14 of Kumar, Sadeghi & Krousgrill 2006). Each
surface's sweep is solved at prescribed approaches, so its P values differ
from surface to surface; :func:`aggregate_cell` interpolates every surface's
curves onto one pressure axis and reports mean and Student-t confidence
band per pressure level. :func:`mean_plane_modulus` fits the bulk modulus
``E_u = P L / d_b`` of Eq 36-44.

Interpolation: piecewise linear in ``log P`` and ``log q`` (a power law
between two solved steps), over the converged steps with ``P > 0`` of one
surface; exact for quantities that follow a power law of P, such as the
mean-plane deflection ``d_b = P L / E_u`` (Eq 36), so the averaged curves
keep Eq 36 to rounding at every level. A surface whose values of a quantity
are not all positive is interpolated linearly in ``q`` instead. The
asperity deflection is not interpolated on its own: it is ``d - d_b`` of the
interpolated approach and mean-plane deflection, so ``d = d_a + d_b`` (Eq 45)
holds at every level too. A pressure level outside a surface's solved range
``[P_first, P_last]`` is never extrapolated: that surface is left out there
(the ``*_count`` columns say how many surfaces a value rests on; a count of
0 gives NaN).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.special

from roughcontact.contact.curves import PhysicalSweep
from roughcontact.contact.result import INTERFACE_UNITS

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "COVERAGE",
    "DISTRIBUTION_QUANTITIES",
    "COUNTER_QUANTITIES",
    "INTERFACE_QUANTITIES",
    "QUANTITIES",
    "SPACINGS",
    "Quantity",
    "aggregate_cell",
    "coverage",
    "covered_range",
    "interpolate",
    "mean_plane_modulus",
    "modulus_summary",
    "pressure_axis",
    "probe_quantities",
    "quantities",
    "statistics",
    "surface_curves",
]


class Quantity(NamedTuple):
    """How an aggregated quantity is read from a :class:`PhysicalSweep`.

    ``unit`` and ``meaning`` (symbol and equation of Kumar et al. 2006);
    ``flags``: the convergence flags a step needs to be used; ``difference``:
    for a quantity averaged as the difference of two averaged curves (so that
    the relation holds at every level), their names; ``quantile``: for a point of a
    stored distribution, the sweep's quantile array and its probability
    (:mod:`roughcontact.contact.interface`); ``ratio``: for a quantity averaged as
    the ratio of two surfaces' curves, their names; ``state``: a yes/no state of each
    step (e.g. still leaking), read at a level from the surface's step nearest in
    log P, not interpolated (its mean is then the share of surfaces in that state).
    """

    unit: str
    meaning: str
    flags: tuple[str, ...] = ("converged",)
    difference: tuple[str, str] | None = None
    quantile: tuple[str, float] | None = None
    ratio: tuple[str, str] | None = None
    state: bool = False


#: Aggregated quantities, by name.
QUANTITIES = {
    "normalized_stiffness": Quantity(
        "Pa", "k_P = (L / A_n) dF/dd, tangent at fixed contact set (Eq 33)",
        flags=("converged", "stiffness_converged")),
    "approach": Quantity("m", "d, total deflection (rigid approach)"),
    "mean_plane_deflection": Quantity("m", "d_b, mean of u (Eq 35)"),
    "asperity_deflection": Quantity("m", "d_a = d - d_b (Eq 45)",
                                    difference=("approach", "mean_plane_deflection")),
    "real_area_fraction": Quantity("1", "real contact area / nominal area"),
    "max_pressure": Quantity("Pa", "largest element pressure"),
    "plastic_area_fraction": Quantity(
        "1", "elements at the hardness cap / all elements (0 if elastic)"),
    "plastic_load_fraction": Quantity("1", "load on elements at the cap / load (0 if elastic)"),
}
#: Aggregated interface quantities (:mod:`roughcontact.contact.interface`), by name: in the
#: table when the sweep recorded them (every contact job of the study does).
INTERFACE_QUANTITIES = {name: Quantity(INTERFACE_UNITS[name], meaning) for name, meaning in (
    ("spot_count", "N_s, contact spots (4-connected clusters of elements in contact)"),
    ("mean_spot_area", "A_c / N_s, mean area of a contact spot"),
    ("perimeter", "P', contact/non-contact interface length on the grid (Manhattan "
                  "perimeter)"),
    ("corrected_real_area_fraction", "(A' - c_P P' dx) / A_n, real area corrected by its "
                                     "perimeter (Yastrebov et al. 2017)"),
    ("mean_gap", "mean interfacial separation, mean of u + f - d"),
)}
#: Points of the spot-area and gap distributions averaged like the other quantities
#: (the contact files keep every quantile of
#: :data:`~roughcontact.contact.interface.SPOT_PROBABILITIES` and ``GAP_PROBABILITIES``).
DISTRIBUTION_QUANTITIES = {
    "median_spot_area": Quantity("m^2", "median spot area (by number of spots)",
                                 quantile=("spot_area_quantiles", 0.5)),
    "largest_spot_area": Quantity("m^2", "area of the largest spot",
                                  quantile=("spot_area_quantiles", 1.0)),
    "gap_p10": Quantity("m", "gap exceeded on 90 % of the nominal area",
                        quantile=("gap_quantiles", 0.1)),
    "gap_median": Quantity("m", "median gap over the nominal area",
                           quantile=("gap_quantiles", 0.5)),
    "gap_p90": Quantity("m", "gap exceeded on 10 % of the nominal area",
                        quantile=("gap_quantiles", 0.9)),
}
#: Of a pair of elastic bodies (:mod:`roughcontact.contact.counterface`): which body
#: deflects. In the table when the sweep recorded the counter body's deflection.
COUNTER_QUANTITIES = {
    "counter_deflection": Quantity("m", "d_b2, mean-plane deflection of the counter body, "
                                        "mean of C2 p"),
    "body_deflection": Quantity("m", "d_b1 = d_b - d_b2, mean-plane deflection of the "
                                     "first body",
                                difference=("mean_plane_deflection", "counter_deflection")),
    "counter_share": Quantity("1", "d_b2 / d_b, the counter body's share of the mean-plane "
                                   "compliance under the contact pressure",
                              ratio=("counter_deflection", "mean_plane_deflection")),
}


#: Spacings of :func:`pressure_axis`: name -> ``f(first, last, n)``.
SPACINGS = {"log": np.geomspace, "linear": np.linspace}

INTERPOLATION = ("piecewise linear in log(P) and log(q) (linear in q where q <= 0) over "
                 "converged steps, no extrapolation; d_a = d - d_b of the interpolated curves")


def pressure_axis(P_min: float, P_max: float, n: int, spacing: str = "log") -> np.ndarray:
    """Nominal-pressure levels [Pa] from ``P_min`` to ``P_max`` inclusive.

    Parameters
    ----------
    P_min, P_max : float
        First and last level [Pa], ``0 < P_min < P_max``.
    n : int
        Number of levels, at least 2.
    spacing : {"log", "linear"}
        Geometric (equal ratios, the natural axis of Figs 7, 12, 13) or equal steps.
    """
    try:
        low, high = float(P_min), float(P_max)
    except (TypeError, ValueError):
        raise ValueError(
            f"P_min and P_max must be numbers [Pa], got {P_min!r}, {P_max!r}"
        ) from None
    if not (np.isfinite(low) and np.isfinite(high) and 0.0 < low < high):
        raise ValueError(f"need 0 < P_min < P_max (finite, Pa), got {P_min!r}, {P_max!r}")
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    if spacing not in SPACINGS:
        raise ValueError(f"spacing must be one of {tuple(SPACINGS)}, got {spacing!r}")
    return SPACINGS[spacing](low, high, int(n))


def _check_sweep(sweep) -> PhysicalSweep:
    if not isinstance(sweep, PhysicalSweep):
        raise TypeError(
            "sweep_physical must be a roughcontact.contact.curves.PhysicalSweep (from "
            f"to_physical or PhysicalSweep.from_contact_sweep), got {type(sweep).__name__}"
        )
    return sweep


def probe_quantities(sweep: PhysicalSweep) -> dict:
    """The aggregated columns of the sweep's probes (:mod:`roughcontact.contact.probes`),
    by name in their order: each :class:`~roughcontact.contact.probes.Column`'s unit and
    meaning, a yes/no column read as a ``state``."""
    return {column.name: Quantity(column.unit, column.meaning, state=column.state)
            for column in sweep.probe_columns.specs}


def quantities(sweep: PhysicalSweep) -> dict:
    """The quantities :func:`aggregate_cell` averages for ``sweep``: :data:`QUANTITIES`, and
    :data:`INTERFACE_QUANTITIES` (and the distribution and counter-body ones) when the
    sweep recorded them, and last its probes' columns (:func:`probe_quantities`)."""
    probed = probe_quantities(sweep)
    if sweep.mean_gap is None:
        return {**QUANTITIES, **probed}
    counter = {} if sweep.counter_deflection is None else COUNTER_QUANTITIES
    if sweep.gap_quantiles is None:
        return {**QUANTITIES, **INTERFACE_QUANTITIES, **counter, **probed}
    return {**QUANTITIES, **INTERFACE_QUANTITIES, **DISTRIBUTION_QUANTITIES, **counter,
            **probed}


_ALL = {**QUANTITIES, **INTERFACE_QUANTITIES, **DISTRIBUTION_QUANTITIES, **COUNTER_QUANTITIES}


def _quantity(sweep: PhysicalSweep, quantity: str) -> Quantity:
    """How ``quantity`` is read: one of :data:`_ALL`, or a column of the sweep's probes."""
    return _ALL[quantity] if quantity in _ALL else probe_quantities(sweep)[quantity]


def _values(sweep: PhysicalSweep, quantity: str) -> np.ndarray:
    """The (m, k) values of ``quantity``: a field or probe column of the sweep, or a point
    of one of its stored distributions."""
    source = _quantity(sweep, quantity).quantile
    if source is None:
        return np.asarray(sweep.column(quantity), dtype=float)
    from roughcontact.contact.interface import GAP_PROBABILITIES, SPOT_PROBABILITIES

    name, probability = source
    probabilities = SPOT_PROBABILITIES if name == "spot_area_quantiles" else GAP_PROBABILITIES
    return np.asarray(getattr(sweep, name), dtype=float)[..., probabilities.index(probability)]


def _usable(sweep: PhysicalSweep, quantity: str) -> np.ndarray:
    """(m, k) mask of steps a quantity may be interpolated from."""
    P = sweep.nominal_pressure
    mask = np.isfinite(P) & (P > 0.0)
    for flag in _quantity(sweep, quantity).flags:
        mask &= getattr(sweep, flag)
    return mask & np.isfinite(_values(sweep, quantity))


def _increasing(P: np.ndarray) -> np.ndarray:
    """Mask of the points strictly above every earlier point (keeps P monotone)."""
    previous = np.maximum.accumulate(np.concatenate(([-np.inf], P[:-1])))
    return P > previous


def surface_curves(sweep_physical: PhysicalSweep, pressures, quantity: str) -> np.ndarray:
    """Each surface's ``quantity`` interpolated onto ``pressures``, (m, len(pressures)).

    A power law (linear in ``log P`` and ``log q``; linear in ``q`` for a
    surface with a value ``q <= 0``) between the surface's usable steps
    (contact solve converged, and for ``normalized_stiffness`` the stiffness solve too;
    ``P > 0``; ``P`` strictly increasing along the steps, later steps that do
    not raise ``P`` are dropped). NaN outside the surface's usable range
    (no extrapolation) and for a surface without usable steps. The asperity
    deflection is the difference of the approach's and the mean-plane
    deflection's curves (Eq 45).
    """
    sweep = _check_sweep(sweep_physical)
    known = quantities(sweep)
    if quantity not in known:
        raise ValueError(f"quantity must be one of {tuple(known)}, got {quantity!r}")
    difference = known[quantity].difference
    if difference is not None:  # e.g. d_a = d - d_b (Eq 45) at every level
        first, second = difference
        return (surface_curves(sweep, pressures, first)
                - surface_curves(sweep, pressures, second))
    ratio = known[quantity].ratio
    if ratio is not None:  # e.g. the counter body's share d_b2 / d_b
        first, second = ratio
        with np.errstate(invalid="ignore", divide="ignore"):
            return (surface_curves(sweep, pressures, first)
                    / surface_curves(sweep, pressures, second))
    levels = np.asarray(pressures, dtype=float)
    if levels.ndim != 1 or not np.isfinite(levels).all() or (levels <= 0.0).any():
        raise ValueError("pressures must be a 1-d array of finite positive levels [Pa]")
    read = _nearest if known[quantity].state else _interpolate
    return read(sweep.nominal_pressure, _values(sweep, quantity), _usable(sweep, quantity),
                levels)


def interpolate(sweep_physical: PhysicalSweep, values, pressures) -> np.ndarray:
    """Per-step ``values`` (m, k) of a sweep interpolated onto ``pressures`` [Pa], (m, levels).

    As :func:`surface_curves` for a quantity the sweep does not hold (e.g. a
    share above a hardness, :func:`roughcontact.contact.cell.validity_table`):
    over the converged steps with finite values, no extrapolation.
    """
    sweep = _check_sweep(sweep_physical)
    values = np.asarray(values, dtype=float)
    if values.shape != sweep.nominal_pressure.shape:
        raise ValueError(f"values must have the sweep's shape {sweep.nominal_pressure.shape}, "
                         f"got {values.shape}")
    levels = np.asarray(pressures, dtype=float)
    if levels.ndim != 1 or not np.isfinite(levels).all() or (levels <= 0.0).any():
        raise ValueError("pressures must be a 1-d array of finite positive levels [Pa]")
    usable = _usable(sweep, "approach") & np.isfinite(values)
    return _interpolate(sweep.nominal_pressure, values, usable, levels)


def _per_surface(nominal_pressure, values, usable, levels, read) -> np.ndarray:
    """Each surface's ``values`` (m, k) read at ``levels`` by ``read(log P, y, log
    level)`` over its usable steps (``P`` strictly increasing), NaN outside their range
    (no extrapolation) and for a surface without usable steps."""
    out = np.full((values.shape[0], levels.size), np.nan)
    for j in range(values.shape[0]):
        P = nominal_pressure[j, usable[j]]
        y = values[j, usable[j]]
        if P.size == 0:
            continue
        keep = _increasing(P)
        P, y = P[keep], y[keep]
        inside = (levels >= P[0]) & (levels <= P[-1])
        out[j, inside] = read(np.log(P), y, np.log(levels[inside]))
    return out


def _power_law(log_p, y, x) -> np.ndarray:
    """Linear in log P and log y between the steps (linear in y where some y <= 0)."""
    if (y > 0.0).all():
        return np.exp(np.interp(x, log_p, np.log(y)))
    return np.interp(x, log_p, y)


def _nearest_step(log_p, y, x) -> np.ndarray:
    """The value at the step nearest in log P (a state: no interpolation)."""
    below = np.clip(np.searchsorted(log_p, x, side="right") - 1, 0, log_p.size - 1)
    above = np.minimum(below + 1, log_p.size - 1)
    return y[np.where((log_p[above] - x) < (x - log_p[below]), above, below)]


def _interpolate(nominal_pressure, values, usable, levels) -> np.ndarray:
    return _per_surface(nominal_pressure, values, usable, levels, _power_law)


def _nearest(nominal_pressure, values, usable, levels) -> np.ndarray:
    """Each surface's value at its usable step nearest in log P to each level."""
    return _per_surface(nominal_pressure, values, usable, levels, _nearest_step)


def statistics(samples: np.ndarray, confidence: float = 0.95):
    """Mean, Student-t half-width and count per column, ignoring NaN."""
    finite = np.isfinite(samples)
    count = finite.sum(axis=0)
    filled = np.where(finite, samples, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(count > 0, filled.sum(axis=0) / count, np.nan)
        deviation = np.where(finite, samples - mean, 0.0)
        variance = np.where(count > 1, (deviation**2).sum(axis=0) / (count - 1), np.nan)
        # Student-t quantile (what scipy.stats.t.ppf computes, without importing scipy.stats)
        t = scipy.special.stdtrit(np.maximum(count - 1, 1), 0.5 * (1.0 + confidence))
        half_width = np.where(count > 1, t * np.sqrt(variance / count), np.nan)
    return mean, half_width, count


def _check_confidence(confidence) -> float:
    """``confidence`` as a float in (0, 1)."""
    try:
        confidence = float(confidence)
    except (TypeError, ValueError):
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}") from None
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    return confidence


def _quantity_columns(sweep: PhysicalSweep, levels: np.ndarray, confidence: float):
    """The ``nominal_pressure`` column and each quantity's mean, half-width and count
    at ``levels`` [Pa] (:func:`aggregate_cell`), and their units."""
    columns = {"nominal_pressure": levels}
    units = {"nominal_pressure": "Pa"}
    for quantity, spec in quantities(sweep).items():
        samples = surface_curves(sweep, levels, quantity)
        mean, half_width, count = statistics(samples, confidence)
        columns[f"{quantity}_mean"] = mean
        columns[f"{quantity}_half_width"] = half_width
        columns[f"{quantity}_count"] = count
        units.update({f"{quantity}_mean": spec.unit, f"{quantity}_half_width": spec.unit,
                      f"{quantity}_count": "1"})
    return columns, units


def aggregate_cell(sweep_physical: PhysicalSweep, pressures, *,
                   confidence: float = 0.95) -> pd.DataFrame:
    """Mean and confidence band over the surfaces of a cell at each nominal pressure.

    Every surface's curves are interpolated onto ``pressures`` by
    :func:`surface_curves` (linear in log P, no extrapolation, unconverged
    steps excluded), then at each level the mean over the surfaces that
    cover it, the half-width ``t_{(1+c)/2, n-1} s / sqrt(n)`` of the
    two-sided Student-t confidence interval of that mean (``s`` the sample
    standard deviation, ``n`` the count; NaN for ``n < 2``) and ``n`` are
    reported.

    Parameters
    ----------
    sweep_physical : PhysicalSweep
        SI sweep of the cell (:func:`roughcontact.contact.nondim.to_physical`).
    pressures : array_like
        Nominal-pressure levels [Pa], positive (:func:`pressure_axis`).
    confidence : float
        Confidence level of the band, in (0, 1).

    Returns
    -------
    pandas.DataFrame
        One row per level: ``nominal_pressure`` [Pa]; for each quantity ``q`` of
        :func:`quantities` (``QUANTITIES``, and the interface, distribution and
        counter-body ones and the probe columns the sweep recorded; units in
        ``frame.attrs["units"]``)
        ``q_mean``, ``q_half_width`` (same unit) and ``q_count`` (surfaces used:
        fewer where the level lies outside some surfaces' swept range, 0 with NaN
        values outside all); ``coverage`` (:func:`coverage`: why a count is
        short); ``surfaces`` (m); ``unconverged_steps`` and
        ``unconverged_stiffness_steps``, the cell's totals (repeated on every row)
        of steps excluded because the contact solve, respectively only the
        stiffness solve (from k_P), did not converge. ``frame.attrs`` holds
        ``units``, ``confidence``, ``interpolation``, ``sigma``, ``E``,
        ``thickness`` and ``nominal_area``.
    """
    sweep = _check_sweep(sweep_physical)
    confidence = _check_confidence(confidence)
    levels = np.asarray(pressures, dtype=float)
    m = sweep.nominal_pressure.shape[0]
    columns, units = _quantity_columns(sweep, levels, confidence)
    columns["coverage"] = coverage(sweep, levels)
    columns["surfaces"] = np.full(levels.size, m)
    columns["unconverged_steps"] = np.full(levels.size, int((~sweep.converged).sum()))
    columns["unconverged_stiffness_steps"] = np.full(
        levels.size, int((sweep.converged & ~sweep.stiffness_converged).sum()))
    units.update(coverage="-", surfaces="1", unconverged_steps="1",
                 unconverged_stiffness_steps="1")
    import pandas as pd

    frame = pd.DataFrame(columns)
    frame.attrs.update(units=units, confidence=confidence, interpolation=INTERPOLATION,
                       sigma=sweep.sigma, E=sweep.E, thickness=sweep.thickness,
                       nominal_area=sweep.nominal_area)
    return frame


#: Values of the ``coverage`` column of :func:`aggregate_cell`.
COVERAGE = ("all surfaces", "some surfaces", "below the first solved step",
            "above the last solved step", "no converged step")


def coverage(sweep_physical: PhysicalSweep, pressures) -> np.ndarray:
    """Per level of ``pressures`` [Pa], which surfaces' converged steps reach it
    (:data:`COVERAGE`): every surface, some, or none because the level lies below
    every surface's first solved step or above every surface's last one."""
    sweep = _check_sweep(sweep_physical)
    levels = np.asarray(pressures, dtype=float)
    usable = _usable(sweep, "approach")
    P = np.where(usable, sweep.nominal_pressure, np.nan)
    out = np.full(levels.size, COVERAGE[4], dtype=object)
    rows = usable.any(axis=1)
    if not rows.any():
        return out
    first = np.nanmin(P[rows], axis=1)
    last = np.nanmax(P[rows], axis=1)
    inside = (levels[:, None] >= first[None, :]) & (levels[:, None] <= last[None, :])
    full = inside.all(axis=1) & rows.all()
    out[inside.any(axis=1)] = COVERAGE[1]
    out[full] = COVERAGE[0]
    out[~inside.any(axis=1) & (levels < first.min())] = COVERAGE[2]
    out[~inside.any(axis=1) & (levels > last.max())] = COVERAGE[3]
    return out


def covered_range(sweep_physical: PhysicalSweep) -> tuple[float, float]:
    """Nominal-pressure range [Pa] covered by every surface's converged steps.

    ``(max_j P_first_j, min_j P_last_j)``: a :func:`pressure_axis` inside it
    gives full counts (for all but the stiffness, which may lose a few steps
    more). Raises ``ValueError`` if the surfaces' ranges do not overlap.
    """
    sweep = _check_sweep(sweep_physical)
    usable = _usable(sweep, "approach")
    P = np.where(usable, sweep.nominal_pressure, np.nan)
    if not usable.any(axis=1).all():
        raise ValueError("some surfaces have no converged step with P > 0")
    low, high = float(np.nanmax(np.nanmin(P, axis=1))), float(np.nanmin(np.nanmax(P, axis=1)))
    if not low < high:
        raise ValueError(
            f"the surfaces' pressure ranges do not overlap: {low:.6g} >= {high:.6g} Pa"
        )
    return low, high


def mean_plane_modulus(sweep_physical: PhysicalSweep,
                       thickness: float | None = None) -> pd.DataFrame:
    """Apparent bulk modulus ``E_u = P L / d_b`` of each surface (Eq 36-44).

    Fits ``P = s d_b`` by least squares through the origin over the
    surface's converged steps with ``P > 0``: ``s = sum(P d_b) / sum(d_b^2)``
    and ``E_u = s L``. For nu = 0 and a block whose influence rows sum to
    ``L/E`` (Eq 38), ``d_b = P L / E`` exactly and ``E_u = E``.

    Parameters
    ----------
    sweep_physical : PhysicalSweep
    thickness : float, optional
        ``L`` [m]; default ``sweep_physical.thickness``.

    Returns
    -------
    pandas.DataFrame
        One row per surface: ``surface``, ``mean_plane_modulus`` (E_u [Pa]),
        ``linearity_residual`` (``max |P - s d_b| / max P`` [-], 0 for an
        exactly linear response), ``steps_used``. NaN where no step is usable.
    """
    sweep = _check_sweep(sweep_physical)
    length = sweep.thickness if thickness is None else float(thickness)
    if not (np.isfinite(length) and length > 0.0):
        raise ValueError(f"thickness must be a finite positive length [m], got {thickness!r}")
    usable = _usable(sweep, "mean_plane_deflection")
    m = usable.shape[0]
    modulus = np.full(m, np.nan)
    residual = np.full(m, np.nan)
    for j in range(m):
        P = sweep.nominal_pressure[j, usable[j]]
        d_b = sweep.mean_plane_deflection[j, usable[j]]
        if P.size == 0 or not (d_b**2).sum() > 0.0:
            continue
        slope = (P * d_b).sum() / (d_b**2).sum()
        modulus[j] = slope * length
        residual[j] = np.abs(P - slope * d_b).max() / P.max()
    import pandas as pd

    frame = pd.DataFrame({"surface": np.arange(m), "mean_plane_modulus": modulus,
                          "linearity_residual": residual, "steps_used": usable.sum(axis=1)})
    frame.attrs.update(units={"mean_plane_modulus": "Pa", "linearity_residual": "1"},
                       thickness=length)
    return frame


def modulus_summary(per_surface: pd.DataFrame, E: float) -> pd.Series:
    """Per-cell summary of :func:`mean_plane_modulus` against the true modulus ``E`` [Pa].

    Returns a Series with ``surfaces`` (with a finite E_u), ``mean``, ``std``
    (ddof 1), ``min``, ``max`` [Pa], ``relative_deviation`` (``mean / E - 1``),
    ``max_relative_deviation`` (``max |E_u / E - 1|``) and
    ``max_linearity_residual``.
    """
    E = float(E)
    if not (np.isfinite(E) and E > 0.0):
        raise ValueError(f"E must be a finite positive modulus [Pa], got {E!r}")
    values = per_surface["mean_plane_modulus"].to_numpy(dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        raise ValueError("no surface has a finite mean-plane modulus")
    import pandas as pd

    return pd.Series({
        "surfaces": values.size,
        "mean": values.mean(),
        "std": values.std(ddof=1) if values.size > 1 else np.nan,
        "min": values.min(),
        "max": values.max(),
        "relative_deviation": values.mean() / E - 1.0,
        "max_relative_deviation": np.abs(values / E - 1.0).max(),
        "max_linearity_residual": per_surface["linearity_residual"].max(),
    })
