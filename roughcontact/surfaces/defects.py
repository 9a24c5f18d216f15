"""Defects of a measured height map: holes, spikes and dropouts, found to advise on them.

Instruments leave two kinds of defect that the import must not use silently:

- *holes*: points the instrument marked undefined, or left out of a point
  list. Where they gather at the edges, a window without them
  (:func:`largest_complete_window`) is the fix (``crop_mm``), not filling.
- *spikes and dropouts*: single points or small clusters far from every
  height the surface has (:func:`find_spikes`): farther than
  :data:`SPIKE_ROBUST_SIGMAS` robust standard deviations (1.4826 times the
  median absolute deviation, which a handful of such points does not move)
  from the median height. A Gaussian surface has such a point once in
  10^23; the heavy-tailed measurements of SurfaceTopography's test
  collection reach 9.3 (a Gwyddion export) and the plateau-honed example
  8.4, while its Digital Surf file (dropouts: Ku 596 on the 1.5 mm window),
  the Sensofar file (Ku 9.2) and the MetroPro file (5 spikes, Ku 52) have
  points at 14 to 110. They are reported where leaving them out changes the
  kurtosis by more than :data:`SPIKE_KURTOSIS_CHANGE`.

Arrays are ``(ny, nx)``; heights in any unit.
"""

from __future__ import annotations

import math

import numpy as np

#: Points farther than this many robust standard deviations from the median are spikes.
SPIKE_ROBUST_SIGMAS = 10.0
#: Spikes are reported when leaving them out changes the kurtosis by more than this
#: fraction of its value without them.
SPIKE_KURTOSIS_CHANGE = 0.25
#: Largest mask searched point by point for a window without holes; larger masks are
#: searched in blocks (a block with a hole counts as a hole: the window found is
#: then somewhat smaller than the largest).
_WINDOW_SEARCH_POINTS = 1_000_000


def _largest_rectangle(bad: np.ndarray) -> tuple[int, int, int, int, int]:
    """``(area, ix0, iy0, nx, ny)`` of the largest rectangle of False cells of ``bad``
    (the histogram method: per row, the heights of the good runs above it, and the
    largest rectangle under that histogram by a stack)."""
    ny, nx = bad.shape
    heights = np.zeros(nx + 1, dtype=np.int64)  # a zero sentinel at the end
    best = (0, 0, 0, 0, 0)
    for iy in range(ny):
        heights[:nx] = np.where(bad[iy], 0, heights[:nx] + 1)
        stack: list[int] = []
        for ix in range(nx + 1):
            while stack and heights[stack[-1]] >= heights[ix]:
                height = int(heights[stack.pop()])
                left = stack[-1] + 1 if stack else 0
                if height * (ix - left) > best[0]:
                    best = (height * (ix - left), left, iy - height + 1, ix - left, height)
            stack.append(ix)
    return best


def largest_complete_window(missing: np.ndarray) -> tuple[int, int, int, int] | None:
    """The largest axis-parallel window without missing points, ``(ix0, iy0, nx, ny)``
    in points, or None where there is none (every point missing).

    Masks of more than :data:`_WINDOW_SEARCH_POINTS` points are searched in
    square blocks (any missing point makes its block missing), which gives a
    window without missing points, at most a block per side smaller than the
    largest.
    """
    missing = np.asarray(missing, dtype=bool)
    ny, nx = missing.shape
    block = max(1, math.ceil(math.sqrt(missing.size / _WINDOW_SEARCH_POINTS)))
    if block > 1:
        my, mx = -(-ny // block), -(-nx // block)
        padded = np.ones((my * block, mx * block), dtype=bool)
        padded[:ny, :nx] = missing
        coarse = padded.reshape(my, block, mx, block).any(axis=(1, 3))
    else:
        coarse = missing
    area, ix0, iy0, wx, wy = _largest_rectangle(coarse)
    if area == 0:
        return None
    return ix0 * block, iy0 * block, wx * block, wy * block


def find_spikes(heights: np.ndarray) -> np.ndarray:
    """Mask of the spikes and dropouts of ``heights``: points farther than
    :data:`SPIKE_ROBUST_SIGMAS` robust standard deviations from the median height
    (NaN points are never spikes)."""
    z = np.asarray(heights, dtype=float)
    known = z[np.isfinite(z)]
    if known.size == 0:
        return np.zeros(z.shape, dtype=bool)
    median = float(np.median(known))
    robust = 1.4826 * float(np.median(np.abs(known - median)))
    if not robust > 0:
        return np.zeros(z.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        return np.abs(z - median) > SPIKE_ROBUST_SIGMAS * robust


def kurtosis(values: np.ndarray) -> float:
    """Pearson kurtosis of the finite ``values`` (1/N moments, as Eq 5)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    d = v - v.mean()
    m2 = float(np.mean(d * d))
    return float(np.mean(d**4)) / m2**2 if m2 > 0 else math.nan


def spikes_matter(heights: np.ndarray, spikes: np.ndarray) -> tuple[bool, float, float]:
    """Whether the ``spikes`` change the kurtosis by more than
    :data:`SPIKE_KURTOSIS_CHANGE`, with the kurtosis with and without them."""
    with_them = kurtosis(heights)
    without = kurtosis(np.asarray(heights)[~spikes])
    matter = bool(spikes.any()) and abs(with_them - without) > SPIKE_KURTOSIS_CHANGE * without
    return matter, with_them, without


__all__ = [
    "SPIKE_KURTOSIS_CHANGE",
    "SPIKE_ROBUST_SIGMAS",
    "find_spikes",
    "kurtosis",
    "largest_complete_window",
    "spikes_matter",
]
