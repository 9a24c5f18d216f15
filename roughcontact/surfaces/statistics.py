"""Sample statistics of height maps: moments and autocorrelation.

The quantities the generators target and the study reports, for generated
and measured surfaces alike: the sample moments of heights (Eq 2-5 of Kumar,
Sadeghi & Krousgrill 2006, :func:`height_stats`), the sample autocorrelation
function (:func:`autocorrelation_map`) and its 10 % decay lags, the
correlation lengths of Eq 1 (:func:`correlation_length`). Heights and lengths
in metres; arrays ``(ny, nx)``.
"""

from __future__ import annotations

import math

import numpy as np

from roughcontact.surfaces.spec import as_pair


def height_stats(z) -> dict:
    """Sample moments of heights (Eq 2-5), over the last two axes.

    Returns a dict of arrays (or floats for one surface): ``mean`` [m],
    ``sigma`` [m], ``skew``, ``kurt`` (Pearson), with 1/(NM) normalisation.
    """
    z = np.asarray(z, dtype=float)
    mean = z.mean(axis=(-2, -1))
    dev = z - mean[..., None, None]
    dev2 = dev * dev  # products, not float powers: 20 times faster
    m2 = np.mean(dev2, axis=(-2, -1))
    m3 = np.mean(dev2 * dev, axis=(-2, -1))
    m4 = np.mean(dev2 * dev2, axis=(-2, -1))
    with np.errstate(divide="ignore", invalid="ignore"):
        skew = np.where(m2 > 0, m3 / np.where(m2 > 0, m2, 1.0) ** 1.5, np.nan)
        kurt = np.where(m2 > 0, m4 / np.where(m2 > 0, m2, 1.0) ** 2, np.nan)
    out = {"mean": mean, "sigma": np.sqrt(m2), "skew": skew, "kurt": kurt}
    if z.ndim == 2:
        out = {k: float(v) for k, v in out.items()}
    return out


def autocorrelation_map(z, periodic: bool = True) -> np.ndarray:
    """Normalised sample ACF of a surface (ny, nx), FFT order, R[0, 0] = 1.

    Periodic: circular ACF. Otherwise the linear ACF from zero-padded FFTs,
    each lag divided by its number of overlapping pairs (unbiased).
    """
    z = np.asarray(z, float)
    z = z - z.mean()
    ny, nx = z.shape
    if periodic:
        f = np.fft.fft2(z)
        acf = np.fft.ifft2(f * np.conj(f)).real / z.size
    else:
        f = np.fft.fft2(z, s=(2 * ny, 2 * nx))
        acf = np.fft.ifft2(f * np.conj(f)).real
        ones = np.fft.fft2(np.ones_like(z), s=(2 * ny, 2 * nx))
        counts = np.rint(np.fft.ifft2(ones * np.conj(ones)).real)
        with np.errstate(divide="ignore", invalid="ignore"):
            acf = np.where(counts > 0, acf / counts, 0.0)
    return acf / acf[0, 0]


def _decay_lag(profile: np.ndarray, step: float, level: float) -> float:
    below = np.nonzero(profile <= level)[0]
    if below.size == 0:
        return math.nan
    k = int(below[0])
    r0, r1 = profile[k - 1], profile[k]
    return step * (k - 1 + (r0 - level) / (r0 - r1))


def correlation_length(z, spacing, periodic: bool = True, level: float = 0.1):
    """Lags (bx, by) [m] at which the sample ACF first decays to ``level`` (10 %).

    Linear interpolation between grid lags along each axis; NaN where the ACF
    does not decay to ``level`` within half the domain.
    """
    dx, dy = as_pair(spacing, "spacing")
    acf = autocorrelation_map(z, periodic)
    ny, nx = np.shape(z)  # half the window, not of the zero-padded ACF's lags
    bx = _decay_lag(acf[0, : nx // 2 + 1], dx, level)
    by = _decay_lag(acf[: ny // 2 + 1, 0], dy, level)
    return bx, by
