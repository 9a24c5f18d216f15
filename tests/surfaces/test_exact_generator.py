"""The ``exact`` generator (IAAFT): exact sample moments, matched spectrum, stagnation stop.

Moments, spectra and ACF lags are computed here with numpy and scipy.stats,
not with the library's ``height_stats`` or ``correlation_length``.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy import stats

from roughcontact.surfaces import exact, spectra, synthetic
from roughcontact.surfaces.spec import SurfaceSpec

MM = 1e-3
#: The benchmark's targets: normal, skewed both ways, heavy-tailed, next to Ku = Sk^2 + 1.
TARGETS = [(0.0, 3.0), (2.0, 10.0), (-1.5, 7.0), (0.0, 20.0), (1.0, 2.05)]
SEEDS = (1, 2, 3)


def paper_spec(**kw):
    base = dict(grid=60, size=9 * MM, corr_length=1 * MM, sigma=1.0)
    base.update(kw)
    return SurfaceSpec(**base)


@pytest.fixture(autouse=True)
def _quiet(caplog):
    caplog.set_level(logging.ERROR)


def _decay_lag(profile, step, level=0.1):
    k = int(np.nonzero(profile <= level)[0][0])
    return step * (k - 1 + (profile[k - 1] - level) / (profile[k - 1] - profile[k]))


def _lags(z, spacing):
    """10 % lags (x, y) [m] of the circular sample ACF, from numpy FFTs."""
    dev = z - z.mean()
    f = np.fft.fft2(dev)
    acf = np.fft.ifft2(f * np.conj(f)).real
    acf /= acf[0, 0]
    ny, nx = z.shape
    return (_decay_lag(acf[0, : nx // 2 + 1], spacing[0]),
            _decay_lag(acf[: ny // 2 + 1, 0], spacing[1]))


def _zero_mean_target_lag(spec):
    """10 % lag along x [m] of Eq 1's ACF on the periodic grid minus its mean.

    A zero-mean periodic surface has no DC power: its expected sample ACF is
    the target ACF minus the target's mean over the lag grid.
    """
    ny, nx = spec.shape
    dx, dy = spec.spacing
    lx = np.minimum(np.arange(nx), nx - np.arange(nx)) * dx
    ly = np.minimum(np.arange(ny), ny - np.arange(ny)) * dy
    r = np.hypot(lx[None, :] / spec.corr_length[0], ly[:, None] / spec.corr_length[1])
    acf = np.exp(-spectra.ACF_DECAY * r)
    acf = acf - acf.mean()
    return _decay_lag(acf[0, : nx // 2 + 1] / acf[0, 0], dx)


@pytest.mark.parametrize(("skew", "kurt"), TARGETS)
@pytest.mark.parametrize("sigma", [1.0, 2.5e-6])
def test_every_realisation_has_the_target_moments_to_1e_6(skew, kurt, sigma):
    spec = paper_spec(skew=skew, kurt=kurt, sigma=sigma)
    for seed in SEEDS:
        z, _ = exact.generate_exact(spec, seed)
        flat = z.ravel()
        assert abs(flat.mean()) < 1e-12 * sigma
        assert abs(flat.std() / sigma - 1.0) < 1e-6  # population std, as height_stats
        assert abs(stats.skew(flat) - skew) < 1e-6
        assert abs(stats.kurtosis(flat, fisher=False) - kurt) < 1e-6


@pytest.mark.parametrize(("skew", "kurt"), TARGETS)
def test_height_set_moments_and_it_is_the_surfaces_sorted(skew, kurt):
    spec = paper_spec(skew=skew, kurt=kurt, grid=(48, 40))
    heights = exact.target_heights(spec)
    assert np.all(np.diff(heights) >= 0)
    assert abs(stats.skew(heights) - skew) < 1e-9
    assert abs(stats.kurtosis(heights, fisher=False) - kurt) < 1e-9
    z, _ = exact.generate_exact(spec, 5)
    assert np.array_equal(np.sort(z, axis=None), heights)


@pytest.mark.parametrize(("skew", "kurt"), TARGETS[:4])
def test_acf_lag_is_the_zero_mean_target_lag(skew, kurt):
    """Mean 10 % lag over 5 seeds, x and y: within 1 % of b of the lag of the
    zero-mean target ACF (0.953 b on this grid), so within 6 % of b."""
    spec = paper_spec(skew=skew, kurt=kurt)
    lags = [_lags(exact.generate_exact(spec, seed)[0], spec.spacing) for seed in range(5)]
    expected = _zero_mean_target_lag(spec)
    assert expected == pytest.approx(0.953 * MM, abs=0.002 * MM)
    assert np.mean(lags) == pytest.approx(expected, abs=0.01 * MM)
    assert np.mean(lags) == pytest.approx(1 * MM, rel=0.06)


def test_acf_lag_next_to_the_absolute_limit():
    """At (1, 2.05) the heights are nearly two-valued: the rank constraint
    shortens the lag further (0.89 b measured); bound 0.85-0.96 b."""
    spec = paper_spec(skew=1.0, kurt=2.05)
    lags = [_lags(exact.generate_exact(spec, seed)[0], spec.spacing) for seed in range(5)]
    assert 0.85 * MM < np.mean(lags) < 0.96 * MM


def _spectral_error(z, spec):
    """Relative L2 error of |FFT2(z / sigma)| against the zero-mean unit-variance target."""
    ny, nx = spec.shape
    dx, dy = spec.spacing
    lag_x = np.fft.fftfreq(nx, 1.0 / nx) * dx
    lag_y = np.fft.fftfreq(ny, 1.0 / ny) * dy
    r = np.hypot(lag_x[None, :] / spec.corr_length[0], lag_y[:, None] / spec.corr_length[1])
    power = np.clip(np.fft.fft2(np.exp(-spectra.ACF_DECAY * r)).real, 0.0, None)
    power[0, 0] = 0.0
    target = np.sqrt(power * (z.size**2 / power.sum()))
    amp = np.abs(np.fft.fft2(z / spec.sigma))
    return np.linalg.norm(amp - target) / np.linalg.norm(target)


@pytest.mark.parametrize(("skew", "kurt", "bound"),
                         [(0.0, 3.0, 2e-3), (2.0, 10.0, 2e-3), (-1.5, 7.0, 2e-3),
                          (0.0, 20.0, 3e-3), (1.0, 2.05, 0.3)])
def test_spectral_error_reported_and_small(skew, kurt, bound):
    spec = paper_spec(skew=skew, kurt=kurt)
    z, info = exact.generate_exact(spec, 4)
    assert info.spectral_error == pytest.approx(_spectral_error(z, spec), rel=1e-9)
    assert info.spectral_error < bound


@pytest.mark.parametrize(("skew", "kurt"), TARGETS)
def test_stagnation_stops_the_iterations(skew, kurt):
    """Default rtol 1e-2: 20-57 rounds measured over 10 seeds; bound 70 (cap 100)."""
    spec = paper_spec(skew=skew, kurt=kurt)
    for seed in SEEDS:
        _, info = exact.generate_exact(spec, seed)
        assert info.converged
        assert 1 <= info.iterations <= 70


def test_tolerance_and_cap():
    spec = paper_spec(skew=2.0, kurt=10.0)
    _, loose = exact.generate_exact(spec, 3, rtol=0.1)
    _, default = exact.generate_exact(spec, 3)
    _, capped = exact.generate_exact(spec, 3, max_iter=3, rtol=0.0)
    assert loose.iterations < default.iterations
    assert loose.spectral_error > default.spectral_error
    assert capped.iterations == 3 and not capped.converged
    assert capped.spectral_error > default.spectral_error


def test_same_seed_same_bits():
    spec = paper_spec(skew=-1.5, kurt=7.0)
    a, info_a = exact.generate_exact(spec, 17)
    b, info_b = exact.generate_exact(spec, 17)
    assert np.array_equal(a, b) and info_a == info_b
    assert np.array_equal(synthetic.generate(spec, 17, method="exact"), a)
    assert np.array_equal(synthetic.generate_many(spec, [3, 17], method="exact")[1], a)
    assert not np.array_equal(exact.generate_exact(spec, 18)[0], a)


@pytest.mark.parametrize("grid", [(61, 47), (45, 64)])
def test_odd_and_oblong_grids(grid):
    """The half-spectrum bookkeeping (odd nx, no Nyquist column) and nx != ny."""
    spec = paper_spec(grid=grid, size=(9 * MM, 7 * MM), corr_length=(1 * MM, 0.7 * MM),
                      skew=-1.0, kurt=6.0, sigma=3e-6)
    z, info = exact.generate_exact(spec, 2)
    assert z.shape == (grid[1], grid[0])
    assert info.spectral_error == pytest.approx(_spectral_error(z, spec), rel=1e-9)
    assert info.converged and info.spectral_error < 2e-3
    assert abs(z.std() / 3e-6 - 1.0) < 1e-6
    assert abs(stats.kurtosis(z.ravel(), fisher=False) - 6.0) < 1e-6
