"""Which white-noise moments give the target surface moments (Eq 12-15, and a correction).

The filter of :mod:`roughcontact.surfaces.spectra` carries the skewness and
kurtosis of i.i.d. white noise over to the surface through its transfer
factors S3, S4 (Eq 12-13 of Kumar, Sadeghi & Krousgrill 2006):

- :func:`moment_transfer`, :func:`input_moments` (Eq 12-13 inverted) and
  :func:`fit_input` (the Johnson law of the white noise);
- the reachable region: :func:`kurt_min` (Eq 15, Fig 2), :func:`lognormal_line`
  and :func:`input_family` (Fig 1).

Eq 12-13 hold for the infinite process; a finite window's sample moments are
biased. :func:`calibrate_filter` finds the process moments whose windows have
the target sample moments in expectation (:func:`expected_sample_moments`,
estimated over fixed-seed surfaces); :func:`sample_bound` is Fig 2's bound for
a window's expected sample moments. Moments are dimensionless (Pearson
kurtosis, normal = 3).
"""

from __future__ import annotations

import functools
import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from roughcontact.errors import InfeasibleMoments
from roughcontact.surfaces import johnson
from roughcontact.surfaces.spec import SurfaceSpec, mm_text
from roughcontact.surfaces.spectra import (
    CircularValidFilter,
    apply_filter,
    filter_kernel,
    noise_shape,
)
from roughcontact.surfaces.statistics import height_stats

log = logging.getLogger(__name__)


# --------------------------------------------------------------------------- moment transfer


def moment_transfer(spec: SurfaceSpec) -> tuple[float, float]:
    """Skewness and kurtosis transfer factors (S3, S4) of the filter (Eq 12-13).

    ``S3 = sum h^3 / (sum h^2)^(3/2)`` and ``S4 = sum h^4 / (sum h^2)^2``, so
    that ``Sk_z = S3 Sk_x`` and ``Ku_z - 3 = S4 (Ku_x - 3)`` for i.i.d. input.
    They depend on the ACF shape and on b/dx only.
    """
    h = filter_kernel(spec).weights
    s2 = float(np.sum(h**2))
    return float(np.sum(h**3) / s2**1.5), float(np.sum(h**4) / s2**2)


def kurt_min(spec: SurfaceSpec, skew=None):
    """Smallest reachable surface kurtosis at skewness ``skew`` (Fig 2).

    The white noise must satisfy Ku_x >= Sk_x^2 + 1 (Eq 15); through Eq 12-13
    this gives ``Ku_z,min = 3 + S4 (Sk_z^2 / S3^2 - 2)``. Vectorised in
    ``skew``; defaults to ``spec.skew``. Depends on the grid spacing through
    b/dx (the filter's S3, S4).
    """
    s3, s4 = moment_transfer(spec)
    skew = spec.skew if skew is None else np.asarray(skew, dtype=float)
    return 3.0 + s4 * (skew**2 / s3**2 - 2.0)


def reachable(kurt: float) -> str:
    """A bound on the kurtosis as advice: rounded up to 2 decimals and 0.01 above it, so
    the value written is reached (a bound rounded down, or the bound itself, would be
    refused again)."""
    return f"{math.ceil(kurt * 100.0 + 1e-9) / 100.0 + 0.01:.2f}"


def _transfer_to_input(skew, kurt, s3, s4):
    """Eq 12-13 inverted: the white noise's (Sk_x, Ku_x) for surface moments (skew, kurt)."""
    return skew / s3, 3.0 + (kurt - 3.0) / s4


def input_moments(spec: SurfaceSpec) -> tuple[float, float]:
    """Skewness and kurtosis (Sk_x, Ku_x) of the white noise before filtering.

    Inverts Eq 12-13. Raises :class:`InfeasibleMoments` when the target lies
    below :func:`kurt_min` for this grid and ACF.
    """
    absolute = spec.skew**2 + 1.0
    s3, s4 = moment_transfer(spec)
    if spec.kurt < absolute:
        kmin = 3.0 + s4 * (spec.skew**2 / s3**2 - 2.0)
        raise InfeasibleMoments(
            f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is below the absolute limit "
            f"Ku >= Sk^2 + 1 = {absolute:g} (Eq 14): no distribution has these moments, "
            f"and the filter for a {spec.acf} ACF with corr_length = "
            f"{mm_text(spec.corr_length)} mm on this grid reaches at this skewness a "
            f"kurtosis of at least {kmin:.4f} (Eq 15 with Eq 12-13). Raise kurt to at least "
            f"{reachable(kmin)}, or use method='exact', which is limited only by "
            f"Ku >= Sk^2 + 1."
        )
    skew_x, kurt_x = _transfer_to_input(spec.skew, spec.kurt, s3, s4)
    limit = skew_x**2 + 1.0
    if kurt_x < limit - 1e-12 * max(1.0, limit):
        kmin = 3.0 + s4 * (limit - 3.0)
        raise InfeasibleMoments(
            f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is not reachable with a linear "
            f"filter for a {spec.acf} ACF with corr_length = {mm_text(spec.corr_length)} mm on a "
            f"{spec.grid[0]} x {spec.grid[1]} grid over {mm_text(spec.size)} mm "
            f"(b/dx = {spec.corr_length[0] / spec.spacing[0]:.3g}): the minimum kurtosis at this "
            f"skewness is {kmin:.4f} (Eq 15 with Eq 12-13). Raise kurt to at least "
            f"{reachable(kmin)}, "
            "shorten the correlation length relative to the grid spacing, or use "
            "method='exact', which is limited only by Ku >= Sk^2 + 1."
        )
    return float(skew_x), float(max(kurt_x, limit))


def input_family(spec: SurfaceSpec, skew, kurt):
    """Johnson family of the white noise needed for surface moments (skew, kurt).

    Maps (Sk_z, Ku_z) to (Sk_x, Ku_x) through Eq 12-13 and classifies with
    :func:`roughcontact.surfaces.johnson.family_of` (the regions of Fig 1). Vectorised.
    """
    s3, s4 = moment_transfer(spec)
    skew_x, kurt_x = _transfer_to_input(np.asarray(skew, float), np.asarray(kurt, float), s3, s4)
    return np.vectorize(johnson.family_of, otypes=[object])(skew_x, kurt_x)


def lognormal_line(spec: SurfaceSpec, skew):
    """Surface kurtosis on the SL line (Fig 1) at surface skewness ``skew``."""
    s3, s4 = moment_transfer(spec)
    skew_x = np.asarray(skew, float) / s3
    return 3.0 + s4 * (johnson.lognormal_kurt(skew_x) - 3.0)


def fit_input(spec: SurfaceSpec) -> johnson.JohnsonCurve:
    """The Johnson law of the white noise, with the moments :func:`input_moments` gives."""
    skew_x, kurt_x = input_moments(spec)
    return johnson.fit(skew_x, kurt_x)


# --------------------------------------------------------------------------- calibration

#: Seed of the calibration's white noise: one fixed stream, so a spec's
#: calibration (and so its surfaces) is the same on every run.
CALIBRATION_SEED = 20061124
#: Standard error of the estimated expected sample moments at which the
#: calibration stops adding surfaces: relative to Ku, and to max(1, |Sk|).
CALIBRATION_RSE = 1e-3
#: Most surface points (surfaces x nx x ny) one calibration evaluation reads.
CALIBRATION_MAX_POINTS = 1e8
#: Fewest calibration surfaces.
CALIBRATION_MIN_SAMPLES = 2000
#: Relative distance of the estimated expected moments from the targets at
#: which the calibration's solve stops ...
CALIBRATION_SOLVE_TOL = 1e-5
#: ... or this fraction of the estimate's standard error, if larger (the
#: solve's error is then negligible against the calibration's own).
CALIBRATION_SOLVE_SE = 0.05
#: Noise points (surfaces x noise field) drawn and filtered at once by the calibration.
CALIBRATION_BATCH_POINTS = 2**19
_CALIBRATION_MAX_EVALUATIONS = 12
#: Halvings of a Broyden step toward the last point whose sample moments were finite.
_CALIBRATION_MAX_HALVINGS = 6


@dataclass(frozen=True)
class FilterCalibration:
    """The process moments that give a window the target sample moments (:func:`calibrate_filter`).

    Attributes
    ----------
    skew, kurt : float
        Moments of the infinite process fed to Eq 12-13 (``SurfaceSpec.skew``,
        ``.kurt`` of the paper's method) so that the expected sample moments
        of one window equal the spec's targets.
    expected_skew, expected_kurt : float
        Estimated expected sample skewness and kurtosis of a window at the
        solution (control-variate mean over ``samples`` fixed-seed surfaces).
    skew_se, kurt_se : float
        Their standard errors: the calibration's own error.
    paper_skew, paper_kurt : float
        The same estimate for the paper's method (process moments = targets):
        its bias is ``paper_kurt - spec.kurt``.
    samples : int
        Calibration surfaces (fixed seed :data:`CALIBRATION_SEED`).
    evaluations : int
        Estimates made (each over the same ``samples`` surfaces).
    converged : bool
        The estimate met the targets to :data:`CALIBRATION_SOLVE_TOL`.
    seconds : float
        Wall time.
    """

    skew: float
    kurt: float
    expected_skew: float
    expected_kurt: float
    skew_se: float
    kurt_se: float
    paper_skew: float
    paper_kurt: float
    samples: int
    evaluations: int
    converged: bool
    seconds: float

    def as_attrs(self) -> dict:
        """Plain-type dictionary with ``calibration_`` keys (for HDF5 attributes)."""
        return {f"calibration_{k}": (v if isinstance(v, bool | int) else float(v))
                for k, v in self.__dict__.items()}


def _control_variate_mean(values: np.ndarray, controls: np.ndarray) -> tuple[float, float]:
    """Mean of ``values`` corrected by zero-mean ``controls`` (columns), and its SE."""
    centred = controls - controls.mean(axis=0)
    beta = np.linalg.lstsq(centred, values - values.mean(), rcond=None)[0]
    corrected = values - controls @ beta
    return float(corrected.mean()), float(corrected.std(ddof=1) / math.sqrt(len(values)))


class _SampleMoments:
    """Sample moments of fixed-seed filter surfaces for any process moments.

    The same white noise (common random numbers: batch ``k`` is seeded
    ``(CALIBRATION_SEED, k)``) is used for every (Sk, Ku), so the estimate is
    a smooth, deterministic function of them that a root finder can solve.
    """

    def __init__(self, spec: SurfaceSpec, seed: int):
        self.spec = replace(spec, sigma=1.0)
        self.seed = int(seed)
        self.kernel = filter_kernel(self.spec)
        self.noise_shape = noise_shape(self.spec, self.kernel.weights)
        self.batch = max(1, CALIBRATION_BATCH_POINTS // math.prod(self.noise_shape))
        # padded noise: the circular form of the filter (equal to rounding, 3-5x faster)
        self.filter = functools.partial(apply_filter, self.spec, self.kernel) \
            if self.spec.periodic else CircularValidFilter(self.kernel, self.noise_shape)
        self.s3, self.s4 = moment_transfer(self.spec)
        self._cache = None

    def draws(self, skew: float, kurt: float, count: int) -> np.ndarray:
        """Per-surface (Sk, Ku, z^3, z^4, z^2) of the first ``count`` surfaces, shape (count, 5).

        The last three are the raw moments minus their exact expectations
        (controls of zero mean). Batches already drawn for the same (Sk, Ku)
        are reused.
        """
        key = (float(skew), float(kurt))
        done = self._cache[1] if self._cache and self._cache[0] == key else np.empty((0, 5))
        batches = math.ceil(count / self.batch)
        have = len(done) // self.batch
        if batches > have:
            curve = fit_input(replace(self.spec, skew=skew, kurt=kurt))
            mean_x, std_x, skew_x, kurt_x = curve.moments()
            # the fitted law's own moments, so the controls have exactly zero mean
            means = np.array([self.s3 * skew_x, 3.0 + self.s4 * (kurt_x - 3.0), 1.0])
            rows = [done]
            for k in range(have, batches):
                eta = np.random.default_rng([self.seed, k]).standard_normal(
                    (self.batch, *self.noise_shape))
                z = self.filter((curve.transform(eta) - mean_x) / std_x)
                axes = (-2, -1)
                z2 = z * z
                raw = np.stack([(z2 * z).mean(axis=axes), (z2 * z2).mean(axis=axes),
                                z2.mean(axis=axes)], axis=1) - means
                stats = height_stats(z)
                rows.append(np.column_stack([stats["skew"], stats["kurt"], raw]))
            done = np.concatenate(rows)
            self._cache = (key, done)
        return done[:count]

    def estimate(self, skew: float, kurt: float, count: int):
        """Expected sample (Sk, Ku) and their standard errors over ``count`` surfaces."""
        d = self.draws(skew, kurt, count)
        sk, sk_se = _control_variate_mean(d[:, 0], d[:, 2:])
        ku, ku_se = _control_variate_mean(d[:, 1], d[:, 2:])
        return np.array([sk, ku]), np.array([sk_se, ku_se])


def expected_sample_moments(spec: SurfaceSpec, count: int = 2000, *,
                            seed: int = CALIBRATION_SEED) -> tuple[np.ndarray, np.ndarray]:
    """Expected sample (Sk, Ku) of one window of the paper's filter generator.

    The process moments are ``spec.skew``, ``spec.kurt`` (Eq 12-13, as the
    paper uses them). Estimated over ``count`` fixed-seed surfaces with
    control variates (the raw third and fourth moments and the variance,
    whose expectations are known exactly from Eq 12-13): 2-5 times smaller
    standard errors than the plain mean. Returns ``(means, standard_errors)``,
    each ``[Sk, Ku]``.
    """
    return _SampleMoments(spec, seed).estimate(spec.skew, spec.kurt, int(count))


def _on_bound(spec: SurfaceSpec, skew: float) -> float:
    """The filter's smallest reachable kurtosis at process skewness ``skew`` (Eq 15),
    nudged inside so the white noise's Johnson law can still be fitted."""
    return float(kurt_min(spec, skew)) * (1.0 + 1e-9) + 1e-12


def sample_bound(spec: SurfaceSpec, skew, count: int = 1000, *,
                 seed: int = CALIBRATION_SEED) -> tuple[np.ndarray, np.ndarray]:
    """The reachable region's edge for a window's expected sample moments (Fig 2, same rule).

    For each process skewness in ``skew``, the process on the filter's bound
    (Eq 15: ``Ku = kurt_min(spec, skew)``, a two-point white noise) is
    sampled on ``spec``'s grid and its expected sample (Sk, Ku) estimated over
    ``count`` fixed-seed surfaces (:func:`expected_sample_moments`). The
    calibrated filter (``method="filter"``) reaches every target above the
    returned curve; the paper's method, every target above
    :func:`kurt_min`. Returns ``(sample_skew, sample_kurt)``, arrays like
    ``skew``.
    """
    skew = np.atleast_1d(np.asarray(skew, dtype=float))
    sampler = _SampleMoments(spec, seed)
    out = np.array([sampler.estimate(s, _on_bound(spec, s), int(count))[0] for s in skew])
    return out[:, 0], out[:, 1]


def _moment_scale(target: np.ndarray) -> np.ndarray:
    return np.array([max(1.0, abs(target[0])), abs(target[1])])


def calibrate_filter(spec: SurfaceSpec, *, rse: float = CALIBRATION_RSE,
                     max_points: float = CALIBRATION_MAX_POINTS,
                     seed: int = CALIBRATION_SEED) -> FilterCalibration:
    """Process moments whose windows have the target *sample* moments in expectation.

    Eq 12-13 give the skewness and kurtosis of the infinite filtered process.
    The sample moments of one finite window are biased: the window's mean is
    removed, and a ratio of sample moments is not the ratio of their
    expectations; the fewer correlation lengths the window holds, the larger
    the bias (kurtosis -1.4 % at (0, 4.5) on 60 x 60 over 9 mm with
    b = 1 mm, -3.1 % on 30 x 30 over 4.5 mm, +0.6 % at (2, 10)). This finds
    the process moments (Sk_p, Ku_p) for which the expected sample (Sk, Ku) of
    a window of ``spec`` equal ``(spec.skew, spec.kurt)``:

    1. The expectation is estimated over fixed-seed surfaces of the paper's
       generator with control variates (:func:`expected_sample_moments`);
       surfaces are added in batches until both standard errors are below
       ``rse`` (relative to Ku, and to max(1, |Sk|)), with at least
       :data:`CALIBRATION_MIN_SAMPLES` and at most ``max_points`` surface
       points.
    2. Broyden's method on the 2 x 2 system, starting from the targets, with
       the same surfaces for every estimate (a smooth, deterministic
       function), until the estimate is within :data:`CALIBRATION_SOLVE_TOL`
       (relative) or 5 % of its standard error of the targets; steps that would leave the filter's
       reachable region (Eq 15) stop on its edge.

    The result depends only on the spec's moments, grid, size, correlation
    length, ACF and periodicity (not on sigma), and is cached per process.
    Costs 0.1 ms per 60 x 60 surface and estimate: about 1-4 s per cell.

    Raises
    ------
    InfeasibleMoments
        When the target is below the absolute bound Ku >= Sk^2 + 1, or the
        expected sample moments cannot reach it without a process beyond the
        filter's bound (Eq 15): the message gives the nearest reachable
        kurtosis.
    """
    return _calibrate(replace(spec, sigma=1.0), float(rse), float(max_points), int(seed))


@functools.lru_cache(maxsize=256)
def _calibrate(spec: SurfaceSpec, rse: float, max_points: float, seed: int) -> FilterCalibration:
    start = time.perf_counter()
    # a target below the absolute limit (Eq 14) is solved from the filter's bound like
    # one below the bound: the refusal gives the kurtosis this generator reaches
    target = np.array([spec.skew, spec.kurt])
    scale = _moment_scale(target)
    sampler = _SampleMoments(spec, seed)
    # Sk = 0: the law and the filter are symmetric, so the expected sample
    # skewness is 0 exactly; only the kurtosis is estimated and solved
    symmetric = spec.skew == 0.0

    def estimate(theta, count):
        g, se = sampler.estimate(*theta, count)
        if symmetric:
            g[0], se[0] = 0.0, 0.0
        return g, se

    theta = np.array([spec.skew, max(spec.kurt, _on_bound(spec, spec.skew))])
    # 1. grow the sample at the targets until the standard errors are small enough
    most = max(sampler.batch, int(max_points // math.prod(spec.shape)) // sampler.batch
               * sampler.batch)
    count, g, se = _grow_sample(estimate, theta, sampler.batch, most, rse * scale)
    if theta[1] == spec.kurt:
        paper = g
    else:  # the paper's method cannot make this target at all
        paper = np.array([math.nan, math.nan])
    # 2. Broyden on g(theta) = target with the same surfaces
    theta, g, se, evaluations, converged = _solve(spec, estimate, count, theta, g, se, scale)
    result = FilterCalibration(
        skew=float(theta[0]), kurt=float(theta[1]),
        expected_skew=float(g[0]), expected_kurt=float(g[1]),
        skew_se=float(se[0]), kurt_se=float(se[1]),
        paper_skew=float(paper[0]), paper_kurt=float(paper[1]),
        samples=int(count), evaluations=evaluations, converged=converged,
        seconds=time.perf_counter() - start,
    )
    if not converged:
        log.warning(
            "calibrate_filter: the expected sample moments (%.5f, %.5f) did not reach the "
            "targets (%g, %g) to %.0e in %d estimates; using the closest", g[0], g[1],
            spec.skew, spec.kurt, CALIBRATION_SOLVE_TOL, evaluations)
    log.info(
        "calibrate_filter: targets (%g, %g) -> process (%.5f, %.5f); paper's method gives "
        "(%.4f, %.4f); %d surfaces x %d estimates, SE (%.1e, %.1e), %.2f s",
        spec.skew, spec.kurt, theta[0], theta[1], paper[0], paper[1], count,
        evaluations, se[0], se[1], result.seconds)
    return result


def _grow_sample(estimate, theta, batch: int, most: int, se_limit: np.ndarray):
    """Calibration surfaces (whole batches, at least :data:`CALIBRATION_MIN_SAMPLES`, at most
    ``most``) until both standard errors at ``theta`` are below ``se_limit``.

    Returns the count and the estimate ``(g, se)`` over that many surfaces.
    """
    count = min(most, math.ceil(CALIBRATION_MIN_SAMPLES / batch) * batch)
    while True:
        g, se = estimate(theta, count)
        if np.all(se <= se_limit) or count >= most:
            return count, g, se
        needed = 1.1 * float(np.max((se / se_limit) ** 2)) * count
        count = min(most, max(count + batch, math.ceil(needed / batch) * batch))


def _solve(spec: SurfaceSpec, estimate, count: int, theta, g, se, scale):
    """Broyden's method on ``estimate(theta) = (spec.skew, spec.kurt)``, from ``theta``.

    A step below the filter's bound (Eq 15) stops on it, and the skewness is
    then solved along the bound. Returns ``(theta, g, se, evaluations,
    converged)``; raises :class:`InfeasibleMoments` when the target lies below
    the bound's expected sample kurtosis.
    """
    target = np.array([spec.skew, spec.kurt])
    jac = np.eye(2)
    evaluations, converged, on_edge, slope = 1, False, False, 1.0
    tol = np.maximum(CALIBRATION_SOLVE_TOL * scale, CALIBRATION_SOLVE_SE * se)
    while True:
        residual = target - g
        if np.all(np.abs(residual) <= tol):
            converged = True
            break
        if on_edge and abs(residual[0]) <= tol[0]:
            if residual[1] < 0:  # the skewness is right, the kurtosis cannot go lower
                absolute = spec.skew**2 + 1.0
                below = (f"below the absolute limit Ku >= Sk^2 + 1 = {absolute:g} (Eq 14) "
                         "and so " if spec.kurt < absolute else "")
                raise InfeasibleMoments(
                    f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is {below}not reachable in "
                    f"expectation by the filter generator for the {spec.acf} ACF with "
                    f"corr_length = {mm_text(spec.corr_length)} mm on a {spec.grid[0]} x "
                    f"{spec.grid[1]} grid over {mm_text(spec.size)} mm: on the filter's bound "
                    f"(Eq 15) a window's expected sample kurtosis at this skewness is "
                    f"{g[1]:.4f}. Raise kurt to at least {reachable(g[1])}, or use "
                    "method='exact', "
                    "which is limited only by Ku >= Sk^2 + 1."
                )
            on_edge = False  # the target lies above the bound: leave it
        if evaluations >= _CALIBRATION_MAX_EVALUATIONS:
            break
        if on_edge:
            skew = theta[0] + residual[0] / slope
            proposal = np.array([skew, _on_bound(spec, skew)])
        else:
            proposal = theta + np.linalg.solve(jac, residual)
            if proposal[1] < _on_bound(spec, proposal[0]):
                proposal[1] = _on_bound(spec, proposal[0])
                on_edge = True
        new_g, se = estimate(proposal, count)
        for _ in range(_CALIBRATION_MAX_HALVINGS):  # a law the sampler cannot draw: nan
            if np.all(np.isfinite(new_g)):
                break
            proposal = 0.5 * (theta + proposal)
            proposal[1] = max(proposal[1], _on_bound(spec, proposal[0]))
            new_g, se = estimate(proposal, count)
        if not np.all(np.isfinite(new_g)):
            raise InfeasibleMoments(
                f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} could not be calibrated "
                f"for the filter on a {spec.grid[0]} x {spec.grid[1]} grid over "
                f"{mm_text(spec.size)} mm: the process near the filter's bound (Eq 15) "
                f"gives no finite sample moments here. Raise kurt, use a larger surface "
                "relative to corr_length, or use method='exact'.")
        evaluations += 1
        d_theta, d_g = proposal - theta, new_g - g
        if np.dot(d_theta, d_theta) > 0:
            jac = jac + np.outer(d_g - jac @ d_theta, d_theta) / np.dot(d_theta, d_theta)
        if d_theta[0] != 0 and d_g[0] != 0:
            slope = d_g[0] / d_theta[0]
        theta, g = proposal, new_g
    return theta, g, se, evaluations, converged
