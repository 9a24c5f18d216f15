"""The exact generator: every realisation has exactly the target height moments.

Beyond the paper: iterative amplitude-adjusted Fourier transform (IAAFT,
Schreiber & Schmitz 1996) as used for rough surfaces by Perez-Rafols &
Almqvist (2019), Tribol. Int. 131, 591-604. Each surface is a permutation of
one height set (:func:`target_heights`: the Johnson law fitted directly to
the surface's (Sk, Ku), its quantiles corrected so that their sample moments
are exact), ordered so that its Fourier amplitudes come close to the target
spectrum's (:func:`exact_target_amplitude`). Not limited by the Fig 2 bound
of the filter; periodic surfaces only. :func:`generate_exact` is also
``synthetic.generate_many(..., method="exact")``.

Heights in metres; surface arrays have shape ``(ny, nx)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from roughcontact.surfaces import johnson
from roughcontact.surfaces.memory import MAX_GENERATION_BYTES, check_memory
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.spectra import apply_filter, filter_kernel, white_noise

#: Largest |error| of the standardized sample moments (mean, variance, Sk, Ku) of
#: :func:`target_heights` before scaling: the Newton correction stops below it.
HEIGHT_MOMENT_TOL = 1e-12
#: Default relative improvement of the spectral error per round below which
#: :func:`generate_exact` stops (stagnation).
EXACT_STAGNATION_RTOL = 1e-2


@dataclass(frozen=True)
class ExactResult:
    """Diagnostics of :func:`generate_exact`.

    Attributes
    ----------
    spectral_error : float
        Relative L2 distance between the realised Fourier amplitudes ``|Z|``
        and the target ``A`` of the zero-mean surface (DC term excluded):
        ``||(|Z| - A)|| / ||A||`` over the whole 2-D spectrum, dimensionless.
    iterations : int
        Amplitude / rank adjustment rounds made.
    converged : bool
        True when the iterations stopped because the spectral error stopped
        improving (relative gain below ``rtol`` over one round) or the ranking
        stopped changing; False when ``max_iter`` was reached first.
    """

    spectral_error: float
    iterations: int
    converged: bool


def _standard_height_set(skew: float, kurt: float, n: int) -> np.ndarray:
    """Sorted set of ``n`` numbers whose sample moments are (0, 1, skew, kurt).

    Starts from the target Johnson law's midpoint quantiles at probabilities
    ``(k + 1/2) / n``, standardized (zero mean, unit population standard
    deviation). Those alone have a kurtosis biased low (the tails beyond the
    outermost quantiles are cut: -3.8 % at (Sk, Ku) = (-1.5, 7), -35 % at
    (0, 20) for n = 3600), so the set is corrected by Gauss-Newton steps of
    minimum Euclidean norm on the four equations
    ``mean(x^j) = (0, 1, Sk, Ku)_j``, j = 1..4 (each step is a cubic
    polynomial in the current values: the tails move most), halved until the
    residual decreases, until the largest residual is below
    :data:`HEIGHT_MOMENT_TOL`; the set is then standardized again and sorted.
    Moments do not depend on the order, so sorting changes none of them.

    Raises
    ------
    FloatingPointError
        If the corrected set misses the moments by more than 1e-9.
    """
    curve = johnson.fit(skew, kurt)
    x = curve.transform(special.ndtri((np.arange(n) + 0.5) / n))
    x = (x - x.mean()) / x.std()
    target = np.array([0.0, 1.0, skew, kurt])

    def residual(y):
        y2 = y * y
        return np.array([y.mean(), y2.mean(), np.dot(y2, y) / n, np.dot(y2, y2) / n]) - target

    r = residual(x)
    for _ in range(50):
        if np.max(np.abs(r)) < HEIGHT_MOMENT_TOL:
            break
        x2 = x * x
        jac = np.stack([np.ones(n), 2 * x, 3 * x2, 4 * x2 * x]) / n
        step = -jac.T @ np.linalg.lstsq(jac @ jac.T, r, rcond=1e-14)[0]
        t = 1.0
        while True:
            y = x + t * step
            ry = residual(y)
            if np.linalg.norm(ry) < np.linalg.norm(r) or t < 1e-6:
                break
            t *= 0.5
        x, r = y, ry
    x = np.sort((x - x.mean()) / x.std())
    r = residual(x)
    if not np.max(np.abs(r)) < 1e-9:
        raise FloatingPointError(
            f"target_heights: could not give {n} heights the sample moments Sk = {skew:g}, "
            f"Ku = {kurt:g} (residual {np.max(np.abs(r)):.3g})"
        )
    return x


def target_heights(spec: SurfaceSpec) -> np.ndarray:
    """Sorted heights [m] whose sample moments are exactly the targets.

    The n = nx ny heights have zero mean, population standard deviation
    (1/n normalisation, as :func:`statistics.height_stats`) ``spec.sigma``, skewness
    ``spec.skew`` and kurtosis ``spec.kurt`` to rounding (about 1e-13). They
    are the Johnson law's (fitted directly to (Sk, Ku) of the surface)
    quantiles at probabilities (k + 1/2)/n, corrected so that the discrete
    set's own moments hit the targets (:func:`_standard_height_set`).
    """
    n = spec.grid[0] * spec.grid[1]
    return _standard_height_set(spec.skew, spec.kurt, n) * spec.sigma


def _half_spectrum_weights(shape) -> np.ndarray:
    """Multiplicity of each ``rfft2`` column in the full 2-D spectrum (1 or 2)."""
    nx = shape[1]
    weights = np.full(nx // 2 + 1, 2.0)
    weights[0] = 1.0
    if nx % 2 == 0:
        weights[-1] = 1.0
    return weights


def exact_target_amplitude(spec: SurfaceSpec) -> np.ndarray:
    """Target Fourier amplitude ``A`` of a zero-mean unit-variance surface, rfft2 layout.

    ``A = sqrt(n S_z)`` from the filter's transfer function (Eq 9-11) on the
    surface grid, with the DC term set to zero (every realisation has zero
    mean) and the rest rescaled so that Parseval gives unit variance:
    ``sum_full |A|^2 = n^2``. Dimensionless (heights in units of sigma).
    Shape ``(ny, nx // 2 + 1)``.
    """
    ny, nx = spec.shape
    n = nx * ny
    power = filter_kernel(spec).transfer[:, : nx // 2 + 1] ** 2
    power[0, 0] = 0.0
    total = float(np.sum(power * _half_spectrum_weights(spec.shape)))
    return np.sqrt(power * (n * n / total))


def generate_exact(
    spec: SurfaceSpec, seed: int, max_iter: int = 100, *, rtol: float = EXACT_STAGNATION_RTOL,
    max_bytes: float = MAX_GENERATION_BYTES,
) -> tuple[np.ndarray, ExactResult]:
    """Surface with exactly the target height moments and a matched spectrum (IAAFT).

    Iterative amplitude-adjusted Fourier transform after Schreiber & Schmitz
    (1996) as used for surfaces by Perez-Rafols & Almqvist (2019). Starts from
    a Gaussian filtered surface (Eq 9-11) rank-ordered onto
    :func:`target_heights`, then alternately (1) imposes the target Fourier
    amplitude ``A`` of :func:`exact_target_amplitude`, keeping the phases, and
    (2) rank-orders the result onto the height set. The relative spectral
    error ``e = ||(|Z| - A)|| / ||A||`` of each rank-ordered surface is
    measured; the iterations stop when a round improves it by less than
    ``rtol`` relatively (``e_new > (1 - rtol) e_old``: stagnation), when the
    ranking no longer changes, or after ``max_iter`` rounds. The surface with
    the smallest error is returned.

    Every realisation is a permutation of :func:`target_heights`, so its
    sample mean is zero and its sample sigma, Sk and Ku (1/n normalisation,
    :func:`statistics.height_stats`) equal the targets to rounding; it is not limited by
    the Fig 2 bound. The spectrum is matched as closely as the rank constraint
    allows. On a periodic grid a zero-mean surface's sample ACF is the target
    ACF minus its mean over the domain, so its 10 % lag is somewhat shorter
    than b (0.953 b for b = L/9, exponential ACF). Periodic surfaces only.
    Refuses with :class:`memory.SurfaceTooLarge`, before allocating, when
    :func:`memory.estimate_generation_bytes` exceeds ``max_bytes`` [bytes]
    (default :data:`MAX_GENERATION_BYTES`). Whether the spectrum suits the
    grid is the caller's to check once for all its seeds
    (:func:`~roughcontact.surfaces.spectra.check_domain`; ``generate_many``
    and the workflow do).

    Parameters
    ----------
    spec : SurfaceSpec
    seed : int
        Seed of the initial Gaussian white noise; same seed, same bits.
    max_iter : int
        Cap on the rounds.
    rtol : float
        Stagnation tolerance on the relative spectral error per round.

    Returns
    -------
    z : ndarray (ny, nx)
        Heights [m].
    info : ExactResult
    """
    if not spec.periodic:
        raise ValueError(
            "method='exact' generates periodic surfaces only; set periodic=True in the spec"
        )
    check_memory(spec, 1, "exact", max_bytes)
    heights = target_heights(spec) / spec.sigma
    target_amp = exact_target_amplitude(spec)
    kern = filter_kernel(spec)
    start = apply_filter(spec, kern, white_noise(seed, spec.shape))
    z, info = _iaaft(spec.shape, heights, target_amp, start, int(max_iter), float(rtol))
    return z * spec.sigma, info


def _iaaft(shape, heights, target_amp, start, max_iter, rtol):
    """The IAAFT rounds of :func:`generate_exact` on unit-sigma arrays."""
    weights = _half_spectrum_weights(shape)
    norm = math.sqrt(float(np.sum(weights * target_amp**2)))

    def rank(values):
        order = np.argsort(values, axis=None)
        flat = np.empty(values.size)
        flat[order] = heights
        return flat.reshape(shape), order

    def error(spectrum):
        diff = np.abs(spectrum) - target_amp
        return math.sqrt(float(np.sum(weights * diff * diff))) / norm

    z, order = rank(start)
    spectrum = np.fft.rfft2(z)
    err = error(spectrum)
    best, best_err = z, err
    converged = False
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - iteration count is reported
        magnitude = np.abs(spectrum)
        phase = np.divide(spectrum, magnitude, out=np.ones_like(spectrum), where=magnitude > 0)
        z, new_order = rank(np.fft.irfft2(target_amp * phase, s=shape))
        spectrum = np.fft.rfft2(z)
        new_err = error(spectrum)
        if new_err < best_err:
            best, best_err = z, new_err
        if np.array_equal(new_order, order) or new_err > (1.0 - rtol) * err:
            converged = True
            break
        order, err = new_order, new_err
    return best, ExactResult(best_err, it, converged)


