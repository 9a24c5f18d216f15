"""Surface generation (Section 2 of Kumar et al. 2006): filter, moments, seeds."""

import logging

import numpy as np
import pytest
from scipy import stats

from roughcontact import InfeasibleMoments
from roughcontact.surfaces import calibration, exact, johnson, spectra, statistics, synthetic
from roughcontact.surfaces.spec import SurfaceSpec

MM = 1e-3


def paper_spec(**kw):
    base = dict(grid=60, size=9 * MM, corr_length=1 * MM, sigma=1.0)
    base.update(kw)
    return SurfaceSpec(**base)


# ------------------------------------------------------------------ the filter


@pytest.mark.parametrize("b", [0.5, 1.0, 3.0])
@pytest.mark.parametrize("periodic", [True, False])
def test_kernel_parseval_and_zero_phase(b, periodic):
    kern = spectra.filter_kernel(paper_spec(corr_length=b * MM, periodic=periodic))
    h = kern.weights
    assert np.sum(h**2) == pytest.approx(1.0, rel=1e-12)
    # zero phase: H real and non-negative, h even about lag 0
    assert np.all(kern.transfer >= 0)
    assert np.allclose(h, np.roll(h[::-1, ::-1], 1, axis=(0, 1)), atol=1e-14)
    assert np.allclose(np.fft.fft2(h).real, kern.transfer, atol=1e-10)


def test_kernel_reproduces_target_acf():
    """The filter's autocorrelation sum_k h_k h_(k+l) equals R(l)/sigma^2 (Eq 1, 11)."""
    spec = paper_spec(corr_length=1 * MM)
    h = spectra.filter_kernel(spec).weights
    acf = np.fft.ifft2(np.abs(np.fft.fft2(h)) ** 2).real
    dx = spec.spacing[0]
    for lag in (1, 3, 6, 12):
        assert acf[0, lag] == pytest.approx(np.exp(-2.3 * lag * dx / 1e-3), abs=2e-3)


# Values measured with an independent reference implementation (research notes,
# section 6.4): periodic 60 x 60 grid over 9 mm.
@pytest.mark.parametrize(
    ("b", "s3", "s4", "kmin"),
    [(1.0, 0.4401, 0.2781, (2.444, 3.880, 8.19)), (2.0, 0.2557, 0.1122, (2.776, 4.492, 9.64))],
)
def test_moment_transfer_matches_independent_reference(b, s3, s4, kmin):
    spec = paper_spec(corr_length=b * MM)
    got3, got4 = calibration.moment_transfer(spec)
    assert got3 == pytest.approx(s3, abs=6e-4)
    assert got4 == pytest.approx(s4, abs=6e-4)
    assert calibration.kurt_min(spec, np.array([0.0, 1.0, 2.0])) == pytest.approx(kmin, abs=0.01)


def test_moment_transfer_formula_on_kernel():
    """Eq 12-13 computed directly from the kernel used."""
    spec = paper_spec(corr_length=2 * MM)
    h = spectra.filter_kernel(spec).weights
    s3, s4 = calibration.moment_transfer(spec)
    assert s3 == pytest.approx(np.sum(h**3), rel=1e-12)
    assert s4 == pytest.approx(np.sum(h**4), rel=1e-12)
    # Cauchy-Schwarz: the reachable region lies inside Eq 14
    assert s3**2 <= s4


def test_input_moments_inverts_transfer():
    spec = paper_spec(skew=-0.8, kurt=4.0)
    s3, s4 = calibration.moment_transfer(spec)
    skew_x, kurt_x = calibration.input_moments(spec)
    assert s3 * skew_x == pytest.approx(-0.8)
    assert 3 + s4 * (kurt_x - 3) == pytest.approx(4.0)


def test_infeasible_target_names_the_bound():
    spec = paper_spec(corr_length=3 * MM, skew=0.0, kurt=2.8)
    kmin = float(calibration.kurt_min(spec, 0.0))
    assert kmin > 2.8
    with pytest.raises(InfeasibleMoments) as err:
        synthetic.generate(spec, 1, method="paper")
    assert f"{kmin:.4f}" in str(err.value)
    assert "method='exact'" in str(err.value)
    assert isinstance(err.value, ValueError)


def test_larger_correlation_length_shrinks_region():
    """Fig 2: the larger b, the higher Ku_min (fixed grid and size)."""
    skew = np.linspace(-2, 2, 9)
    curves = [calibration.kurt_min(paper_spec(corr_length=b * MM), skew) for b in (1, 2, 3)]
    assert np.all(curves[0] < curves[1]) and np.all(curves[1] < curves[2])
    assert np.all(curves[0] > skew**2 + 1)


# ------------------------------------------------------------------ generation


def test_same_seed_same_bits_and_batch_equals_single():
    spec = paper_spec(skew=0.5, kurt=4.0)
    a = synthetic.generate(spec, 123)
    b = synthetic.generate(spec, 123)
    many = synthetic.generate_many(spec, [7, 123])
    assert a.shape == (60, 60)
    assert np.array_equal(a, b)
    assert np.array_equal(many[1], a)
    assert not np.array_equal(many[0], a)


def test_shape_is_ny_nx_and_zero_mean_in_metres():
    spec = SurfaceSpec(grid=(40, 24), size=(6 * MM, 3.6 * MM), corr_length=0.5 * MM,
                       sigma=30e-6)
    z = synthetic.generate(spec, 5)
    assert z.shape == (24, 40)
    assert abs(z.mean()) < 1e-18
    assert 10e-6 < z.std() < 60e-6


@pytest.fixture(scope="module")
def skewed_ensemble():
    spec = paper_spec(skew=-0.8, kurt=4.0)
    seeds = synthetic.derive_seeds(1, "ensemble-test", 300)
    return spec, synthetic.generate_many(spec, seeds)


def test_ensemble_moments_within_three_standard_errors(skewed_ensemble):
    """Issue acceptance: (Sk -0.8, Ku 4.0, b 1 mm, 60 x 60 over 9 mm)."""
    spec, z = skewed_ensemble
    st = statistics.height_stats(z)
    n = len(z)
    for name, target in (("skew", -0.8), ("kurt", 4.0)):
        values = st[name]
        se = values.std(ddof=1) / np.sqrt(n)
        assert abs(values.mean() - target) < 3 * se, (name, values.mean(), se)
    assert st["sigma"].mean() == pytest.approx(1.0, rel=0.05)


def test_ensemble_correlation_length_within_20_percent(skewed_ensemble):
    spec, z = skewed_ensemble
    lags = np.array([statistics.correlation_length(s, spec.spacing) for s in z[:100]])
    assert np.nanmean(lags[:, 0]) == pytest.approx(1 * MM, rel=0.2)
    assert np.nanmean(lags[:, 1]) == pytest.approx(1 * MM, rel=0.2)


def test_anisotropic_and_gaussian_acf_lags():
    spec = SurfaceSpec(grid=(96, 96), size=(14.4 * MM, 14.4 * MM),
                       corr_length=(2 * MM, 0.5 * MM), acf="gaussian")
    z = synthetic.generate_many(spec, range(30))
    mean_acf = np.mean([statistics.autocorrelation_map(s) for s in z], axis=0)
    dx = spec.spacing[0]
    bx = statistics._decay_lag(mean_acf[0, :48], dx, 0.1)
    by = statistics._decay_lag(mean_acf[:48, 0], dx, 0.1)
    assert bx == pytest.approx(2 * MM, rel=0.2)
    assert by == pytest.approx(0.5 * MM, rel=0.2)


def test_non_periodic_has_no_wraparound():
    """Opposite edges correlate like neighbours on a periodic surface, not otherwise."""
    kw = dict(corr_length=1 * MM)
    per = synthetic.generate_many(paper_spec(**kw), range(200))
    pad = synthetic.generate_many(paper_spec(periodic=False, **kw), range(200))

    def edge_corr(z):
        return np.mean(z[:, :, 0] * z[:, :, -1]) / np.mean(z**2)

    expected_neighbour = np.exp(-2.3 * 0.15)
    assert edge_corr(per) == pytest.approx(expected_neighbour, abs=0.06)
    assert abs(edge_corr(pad)) < 0.06


def test_non_periodic_moments(skewed_ensemble):
    spec = paper_spec(skew=-0.8, kurt=4.0, periodic=False)
    z = synthetic.generate_many(spec, range(200))
    st = statistics.height_stats(z)
    se = st["skew"].std(ddof=1) / np.sqrt(len(z))
    assert abs(st["skew"].mean() + 0.8) < 3 * se


def test_warnings_for_long_correlation_and_coarse_grid(caplog):
    with caplog.at_level(logging.WARNING, logger="roughcontact.surface"):
        synthetic.generate(paper_spec(corr_length=5 * MM), 1)
    assert "exceeds half the domain" in caplog.text and "0.005" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="roughcontact.surface"):
        synthetic.generate(paper_spec(corr_length=0.05 * MM), 1)
    assert "shorter than the grid spacing" in caplog.text


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        (dict(grid=(1, 60)), "grid"),
        (dict(grid=3), "grid"),
        (dict(sigma=0.0), "sigma"),
        (dict(sigma=-1e-6), "sigma"),
        (dict(size=(9 * MM, np.inf)), "size"),
        (dict(corr_length=0.0), "corr_length"),
        (dict(acf="fractal"), "acf"),
        (dict(kurt=np.nan), "kurt"),
    ],
)
def test_spec_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        paper_spec(**kwargs)


# ------------------------------------------------------------------ exact method


def test_exact_method_height_distribution_is_exact():
    spec = paper_spec(corr_length=3 * MM, skew=0.0, kurt=2.6, sigma=2.0)
    assert calibration.kurt_min(spec, 0.0) > 2.6  # the filter cannot reach it
    z, info = exact.generate_exact(spec, 11)
    assert np.allclose(np.sort(z, axis=None), exact.target_heights(spec), rtol=0, atol=1e-12)
    st = statistics.height_stats(z)
    assert st["sigma"] == pytest.approx(2.0, rel=1e-12)
    # the corrected quantile set has exactly the target moments
    assert st["kurt"] == pytest.approx(2.6, abs=1e-9)
    assert st["skew"] == pytest.approx(0.0, abs=1e-9)
    assert info.spectral_error < 0.35
    assert info.iterations >= 1


def test_exact_method_spectrum_close_to_filter():
    spec = paper_spec(skew=-0.8, kurt=4.0)
    z, info = exact.generate_exact(spec, 3)
    st = statistics.height_stats(z)
    assert st["skew"] == pytest.approx(-0.8, abs=1e-9)
    assert st["kurt"] == pytest.approx(4.0, abs=1e-9)
    assert info.spectral_error < 0.01
    bx, by = statistics.correlation_length(z, spec.spacing)
    assert 0.6 * MM < bx < 1.4 * MM


# ------------------------------------------------------------------ statistics and seeds


def test_height_stats_match_scipy():
    rng = np.random.default_rng(0)
    z = rng.gamma(2.0, size=(3, 20, 30))
    st = statistics.height_stats(z)
    flat = z.reshape(3, -1)
    assert np.allclose(st["mean"], flat.mean(axis=1))
    assert np.allclose(st["sigma"], flat.std(axis=1))
    assert np.allclose(st["skew"], stats.skew(flat, axis=1))
    assert np.allclose(st["kurt"], stats.kurtosis(flat, axis=1, fisher=True) + 3)


def test_derived_seeds_are_prefix_stable_and_cell_specific():
    a = synthetic.derive_seeds(2006, "cell-a", 60)
    assert np.array_equal(synthetic.derive_seeds(2006, "cell-a", 5), a[:5])
    assert len(set(a.tolist())) == 60
    assert not np.any(np.isin(synthetic.derive_seeds(2006, "cell-b", 60), a))
    assert not np.array_equal(synthetic.derive_seeds(2007, "cell-a", 5), a[:5])


def test_realised_input_noise_has_fitted_moments():
    """The translated white noise (before filtering) has the Johnson curve's moments."""
    spec = paper_spec(skew=0.8, kurt=4.0)
    skew_x, kurt_x = calibration.input_moments(spec)
    curve = johnson.fit(skew_x, kurt_x)
    x = curve.transform(np.random.default_rng(1).standard_normal(400_000))
    assert stats.skew(x) == pytest.approx(skew_x, abs=0.05 * max(1, abs(skew_x)))
    assert curve.moments()[2] == pytest.approx(skew_x, abs=1e-8)
