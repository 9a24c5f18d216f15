"""Plan-time checks of a study's measured surface: is it a height map, are its values meant?

A measured map enters the plan with its statistics (:class:`MeasuredCell`),
so what would make its contact results meaningless is seen before any job:

- *noise*: heights uncorrelated from one grid point to the next (the 10 %
  autocorrelation lag shorter than one spacing, :data:`MIN_CORRELATION_SPACINGS`)
  are not a height map that resolves its surface: a file read in a wrong
  format or channel, or random bytes;
- *sigma out of range* (:data:`~roughcontact.study.plan.body_checks.PLAUSIBLE`): a
  measured sigma is not typed by the user, so the advice is about the unit
  the heights were read in (``height_unit``, or the file's own), and only for
  a map that passed the noise check (a unit that scales noise into range
  does not make it a surface).

Both belong to the plausibility check (``plausibility_check: true``, the
default), which stops the plan with every message before any job; it judges the
measured map of a study and of a counter body alike
(:func:`~roughcontact.study.plan.body_checks.body_problems`).
"""

from __future__ import annotations

import math

from roughcontact.study.codec import in_unit
from roughcontact.study.records import MeasuredCell
from roughcontact.surfaces.readers import HEIGHT_UNITS
from roughcontact.units import MM, UM

#: A measured map whose autocorrelation falls to 10 % within fewer grid spacings than
#: this is uncorrelated from one point to the next (white noise: about 0.9 spacing).
MIN_CORRELATION_SPACINGS = 1.0


def noise_message(where: str, surface: MeasuredCell) -> str | None:
    """Why a measured map looks like noise (:data:`MIN_CORRELATION_SPACINGS`), or None;
    ``where`` the configuration key of its import (``sweeps.pad.surface``,
    ``counterface.surface.measured``)."""
    spacing = [s / g for s, g in zip(surface.size, surface.grid, strict=True)]
    lags = [b / h for b, h in zip(surface.corr_length, spacing, strict=True)]
    if not any(math.isfinite(lag) and lag < MIN_CORRELATION_SPACINGS for lag in lags):
        return None
    source = surface.source
    resampled = source.decimate is not None or source.resample_grid is not None
    why = (f"a contact grid coarser than the surface's correlation ({where}.decimate or "
           f"{where}.resample_grid: take a finer one)" if resampled else
           f"random values, or a file read in a wrong format or channel ({where}.format, "
           f"{where}.channel)")
    (bx, by), (dx, dy) = (in_unit(v, MM) for v in surface.corr_length), \
        (in_unit(v, MM) for v in spacing)
    return (f"{where}: the heights of {source.file} are uncorrelated from one grid point to "
            f"the next: their autocorrelation falls to 10 % within {min(lags):.2g} grid "
            f"spacings (b = {bx:.3g} x {by:.3g} mm on a spacing of {dx:.3g} x {dy:.3g} mm), "
            f"which is noise, not a height map that resolves its surface: {why}. Check the "
            "file; no height unit makes noise a surface")


def measured_sigma_message(where: str, surface: MeasuredCell, low: float, high: float) -> str:
    """Why a measured sigma [um] outside ``low``-``high`` is suspect, and what to check
    (``where``: the key of its import).

    A unit that brings it into range is named only for a file that does not
    carry its own unit (``height_unit`` is then the configuration's).
    """
    sigma_um = in_unit(surface.sigma, UM)
    unit = surface.source.height_unit
    text = (f"{where}: the measured sigma of {surface.source.file} is {sigma_um:g} um, "
            f"outside {low:g}-{high:g} um")
    if unit is None:
        return (text + ", with the heights in the unit the file states: check that the file "
                f"is the height map meant ({where}.channel selects another data channel)")
    metres = HEIGHT_UNITS[unit]
    fits = [(other, sigma_um * HEIGHT_UNITS[other] / metres) for other in HEIGHT_UNITS
            if other != unit and low <= sigma_um * HEIGHT_UNITS[other] / metres <= high]
    advice = "; ".join(f"if its heights are in {other}, set {where}.height_unit: {other} "
                       f"(sigma {value:.4g} um)" for other, value in fits)
    return (text + f" with its heights read in {unit} ({where}.height_unit: {unit})"
            + (f": {advice}" if advice else ": check the file"))


def measured_problems(where: str, surface: MeasuredCell,
                      sigma_range: tuple[float, float]) -> list[str]:
    """Messages for a measured map (a study's or a counter body's, imported as ``where``
    says): noise, or else a measured sigma [um] outside ``sigma_range``."""
    noise = noise_message(where, surface)
    if noise is not None:
        return [noise]
    low, high = sigma_range
    if low <= in_unit(surface.sigma, UM) <= high:
        return []
    return [measured_sigma_message(where, surface, low, high)]


__all__ = [
    "MIN_CORRELATION_SPACINGS",
    "measured_problems",
    "measured_sigma_message",
    "noise_message",
]
