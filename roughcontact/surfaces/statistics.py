"""Sample statistics of height maps: moments, autocorrelation, spectral moments.

The quantities the generators target and the study reports, for generated
and measured surfaces alike: the sample moments of heights (Eq 2-5 of Kumar,
Sadeghi & Krousgrill 2006, :func:`height_stats`), the sample autocorrelation
function (:func:`autocorrelation_map`) and its 10 % decay lags, the
correlation lengths of Eq 1 (:func:`correlation_length`). Beyond the paper,
the statistics the contact literature uses, of a plain height map
(:func:`spectral_moments`, :class:`SpectralMoments`): Nayak's spectral
moments m0, m2, m4, the rms gradient h'_rms, the rms curvature h''_rms and
Nayak's parameter alpha, by Fourier or finite-difference derivatives. Heights
and lengths in metres; arrays ``(ny, nx)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

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


# --------------------------------------------------------------------------- spectral moments


@dataclass(frozen=True)
class SpectralMoments:
    """Spectral moments, rms gradient and curvature, Nayak parameter of a height map.

    ``<.>`` is the mean over the surface; ``grad h`` and ``lap h`` are the
    gradient and the Laplacian of the heights h(x, y). For an isotropic
    surface ``m0``, ``m2`` and ``m4`` are Nayak's (1971) moments of a profile
    in any direction; for any surface they are those moments averaged over
    the directions of the plane (rotation invariant).

    Attributes
    ----------
    m0 : float
        Variance of the heights ``<(h - <h>)^2>`` [m^2], sigma^2 (Eq 3).
    m2 : float
        Mean square slope of a profile, averaged over directions,
        ``<|grad h|^2> / 2`` [-]; Nayak's ``m2 = <(dh/dx)^2>``.
    m4 : float
        Mean square second derivative of a profile, averaged over directions,
        ``(3/8) <(lap h)^2>`` [1/m^2]; Nayak's ``m4 = <(d2h/dx2)^2>``.
    rms_gradient : float
        ``h'_rms = sqrt(<|grad h|^2>) = sqrt(2 m2)`` [-].
    rms_slope_x, rms_slope_y : float
        ``sqrt(<(dh/dx)^2>)``, ``sqrt(<(dh/dy)^2>)`` [-], along each axis.
    rms_curvature : float
        ``h''_rms = sqrt(<(lap h / 2)^2>) = sqrt(2 m4 / 3)`` [1/m]: the rms of
        the mean curvature ``(kappa_1 + kappa_2) / 2 ~ lap h / 2`` (small slopes).
    nayak_alpha : float
        Nayak's bandwidth parameter ``alpha = m0 m4 / m2^2`` [-]: 3/2 for a
        single wavelength, more the wider the spectrum (at least 3/2 for a
        periodic map: Cauchy-Schwarz on ``<|grad h|^2>^2 <= m0 <(lap h)^2>``).
        NaN where ``m2 = 0``.
    """

    m0: float
    m2: float
    m4: float
    rms_gradient: float
    rms_slope_x: float
    rms_slope_y: float
    rms_curvature: float
    nayak_alpha: float

    @classmethod
    def from_mean_squares(cls, m0: float, slope_x: float, slope_y: float,
                          laplacian: float) -> SpectralMoments:
        """The record from ``m0`` [m^2], ``<(dh/dx)^2>``, ``<(dh/dy)^2>`` [-] and
        ``<(lap h)^2>`` [1/m^2]."""
        m2 = 0.5 * (slope_x + slope_y)
        m4 = 0.375 * laplacian
        alpha = m0 * m4 / m2**2 if m2 > 0 else math.nan
        return cls(m0=float(m0), m2=float(m2), m4=float(m4),
                   rms_gradient=math.sqrt(slope_x + slope_y),
                   rms_slope_x=math.sqrt(slope_x), rms_slope_y=math.sqrt(slope_y),
                   rms_curvature=0.5 * math.sqrt(laplacian), nayak_alpha=float(alpha))


def spectral_moments(z, size, *, derivative: str = "fourier",
                     periodic: bool = True) -> SpectralMoments:
    """Spectral moments, h'_rms, h''_rms and Nayak's alpha of a height map (ny, nx).

    Parameters
    ----------
    z : array (ny, nx)
        Heights [m], row-major over y then x; the mean does not enter.
    size : (Lx, Ly) or float
        Side lengths [m]; the spacing is ``(Lx / nx, Ly / ny)``.
    derivative : {"fourier", "difference"}
        "fourier" (periodic only): exact derivatives of the trigonometric
        interpolant of the heights, by Parseval over the FFT bins:
        ``<(dh/dx)^2> = sum qx^2 |Z|^2 / N^2``, ``<(lap h)^2> = sum |q|^4
        |Z|^2 / N^2``, ``q = 2 pi k / L``. The Nyquist mode of an even axis,
        ``a (-1)^i``, is the real interpolant ``a cos(pi x / dx)``: its first
        derivative along that axis is zero at every grid point, its second
        is ``-(pi / dx)^2`` times it, so odd derivatives drop it and even
        ones keep it (S. G. Johnson 2011, "Notes on FFT-based
        differentiation", MIT; ``scipy.fftpack.diff`` drops it from both).
        SurfaceTopography's ``moment_power_spectrum`` keeps it in both; the
        two agree wherever the spectrum has no power at the Nyquist
        wavenumber (a resolved cut-off).
        "difference": the stencils of SurfaceTopography's defaults, forward
        differences ``(h[i+1] - h[i]) / dx`` for the slopes and the five-point
        Laplacian; second order in the spacing for these mean squares.
    periodic : bool
        Whether the map tiles the plane. False ("difference" only): each
        stencil is used where it lies inside the map, the slopes on the
        ``(ny - 1, nx - 1)`` points with both forward neighbours and the
        Laplacian on the ``(ny - 2, nx - 2)`` interior points, as
        SurfaceTopography does for a non-periodic topography.

    Returns
    -------
    SpectralMoments
        ``m0`` [m^2], ``m2`` [-], ``m4`` [1/m^2], ``rms_gradient`` [-],
        ``rms_slope_x``, ``rms_slope_y`` [-], ``rms_curvature`` [1/m] and
        ``nayak_alpha`` [-].

    Notes
    -----
    Conventions. ``h'_rms = <|grad h|^2>^(1/2)`` over both directions
    (Persson 2006, Surf. Sci. Rep. 61, 201; SurfaceTopography's
    ``rms_gradient``); ``h''_rms = <(lap h / 2)^2>^(1/2)``, the rms mean
    curvature (Jacobs, Junge & Pastewka 2017, Surf. Topogr. Metrol. Prop. 5,
    013001; SurfaceTopography's ``rms_curvature_from_area``, which is its
    ``rms_laplacian`` / 2). The moments are Nayak's (1971, J. Lubr. Technol.
    93, 398, after Longuet-Higgins 1957) profile moments ``m0, m2, m4``
    averaged over directions: for an isotropic surface ``m20 = m02 = m2``,
    ``m40 = m04 = 3 m22 = m4``, so ``<|grad h|^2> = 2 m2`` and
    ``<(lap h)^2> = m40 + 2 m22 + m04 = (8/3) m4``; averaging a profile's
    ``m2(theta)``, ``m4(theta)`` over directions gives these for any surface.
    SurfaceTopography's ``moment_power_spectrum(order)`` gives the areal
    moments ``M`` instead: ``M2 = <|grad h|^2> = 2 m2``, ``M4 = <(lap h)^2> =
    (8/3) m4`` (and ``M0`` includes the mean), so ``alpha = (3/2) M0 M4 /
    M2^2``.
    """
    z = np.asarray(z, dtype=float)
    if z.ndim != 2 or min(z.shape) < 3:
        raise ValueError(f"z must be a height map (ny, nx) with at least 3 points per side; "
                         f"got shape {z.shape}")
    if not np.all(np.isfinite(z)):
        raise ValueError("z has non-finite heights; fill them first "
                         "(roughcontact.surfaces.preparation.fill_missing)")
    lengths = tuple(float(v) for v in as_pair(size, "size"))
    if not all(math.isfinite(v) and v > 0 for v in lengths):
        raise ValueError(f"size must be positive and finite [m]; got {size!r}")
    mean_squares = _MEAN_SQUARES.get((derivative, bool(periodic)))
    if mean_squares is None:
        raise ValueError(f"derivative must be one of {DERIVATIVES}, and 'fourier' needs "
                         f"periodic=True; got derivative={derivative!r}, periodic={periodic!r}")
    spacing = (lengths[0] / z.shape[1], lengths[1] / z.shape[0])
    m0 = float(np.mean((z - z.mean()) ** 2))
    return SpectralMoments.from_mean_squares(m0, *mean_squares(z, spacing))


def _fourier_mean_squares(z: np.ndarray, spacing) -> tuple[float, float, float]:
    """``<(dh/dx)^2>``, ``<(dh/dy)^2>``, ``<(lap h)^2>`` of the trigonometric interpolant.

    Parseval over the half spectrum of a real FFT: each column but the first
    (and the Nyquist column of an even nx) stands for itself and its mirror.
    """
    ny, nx = z.shape
    power = np.abs(np.fft.rfft2(z)) ** 2 / z.size**2
    power[:, 1:(nx + 1) // 2] *= 2.0
    qx = 2.0 * math.pi * np.fft.rfftfreq(nx, spacing[0])
    qy = 2.0 * math.pi * np.fft.fftfreq(ny, spacing[1])
    qx2, qy2 = qx**2, qy**2
    laplacian = float(np.sum(power * (qx2[None, :] + qy2[:, None]) ** 2))
    if nx % 2 == 0:
        qx2[-1] = 0.0  # odd derivatives of the Nyquist mode vanish at the grid points
    if ny % 2 == 0:
        qy2[ny // 2] = 0.0
    slope_x = float(np.sum(power * qx2[None, :]))
    slope_y = float(np.sum(power * qy2[:, None]))
    return slope_x, slope_y, laplacian


def _difference_mean_squares(z: np.ndarray, spacing, periodic: bool):
    """``<(dh/dx)^2>``, ``<(dh/dy)^2>``, ``<(lap h)^2>`` by finite differences.

    Periodic maps are extended by wrapping, so every point has its stencil.
    """
    dx, dy = spacing
    first = np.pad(z, ((0, 1), (0, 1)), mode="wrap") if periodic else z
    slope_x = np.diff(first, axis=1)[:-1] / dx
    slope_y = np.diff(first, axis=0)[:, :-1] / dy
    second = np.pad(z, 1, mode="wrap") if periodic else z
    laplacian = (np.diff(second, 2, axis=1)[1:-1] / dx**2
                 + np.diff(second, 2, axis=0)[:, 1:-1] / dy**2)
    return (float(np.mean(slope_x**2)), float(np.mean(slope_y**2)),
            float(np.mean(laplacian**2)))


#: Derivatives of :func:`spectral_moments`.
DERIVATIVES = ("fourier", "difference")
#: The mean squares of each (derivative, periodic): ``(z, spacing) -> (<hx^2>, <hy^2>,
#: <(lap h)^2>)``.
_MEAN_SQUARES = {
    ("fourier", True): _fourier_mean_squares,
    ("difference", True): functools.partial(_difference_mean_squares, periodic=True),
    ("difference", False): functools.partial(_difference_mean_squares, periodic=False),
}
