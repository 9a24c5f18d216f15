"""The calibrated filter generator: a window's expected sample moments are the targets.

Checked on surfaces whose seeds are independent of the calibration's, with
moments computed by scipy.stats; the paper's uncorrected method is the
control: its bias must show at the same sample size.
"""

import numpy as np
import pytest
from scipy import stats

from roughcontact.surfaces import calibration, synthetic
from roughcontact.surfaces.calibration import calibrate_filter
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import generate_many

MM = 1e-3


def sample_moments(spec, method, count, key):
    seeds = synthetic.derive_seeds(99, key, count)
    z = generate_many(spec, seeds, method=method).reshape(count, -1)
    return stats.skew(z, axis=1), stats.kurtosis(z, axis=1, fisher=False)


def mean_and_se(values):
    return values.mean(), values.std(ddof=1) / np.sqrt(len(values))


def test_small_window_kurtosis_bias_is_removed():
    """30 x 30 over 4.5 mm, b = 1 mm, Gaussian target: the paper's method gives a
    mean sample kurtosis 2.4 % low (issue 16: 2.930 +- 0.005)."""
    spec = SurfaceSpec(grid=30, size=4.5 * MM, corr_length=MM, skew=0.0, kurt=3.0)
    _, paper = sample_moments(spec, "paper", 4000, "small")
    _, fixed = sample_moments(spec, "filter", 4000, "small")
    mean, se = mean_and_se(paper)
    assert mean < 3.0 - 5 * se and mean < 2.96
    mean, se = mean_and_se(fixed)
    assert abs(mean - 3.0) < 3 * se
    assert se < 0.005  # the test can see a 0.5 % error


def test_skewed_window_skewness_and_kurtosis_both_on_target():
    """(2, 10) on 60 x 60 over 9 mm: the paper's method overshoots the skewness
    (+0.7 %); the calibrated one hits both moments."""
    spec = SurfaceSpec(grid=60, size=9 * MM, corr_length=MM, skew=2.0, kurt=10.0)
    paper_sk, _ = sample_moments(spec, "paper", 3000, "skewed")
    sk, ku = sample_moments(spec, "filter", 3000, "skewed")
    mean, se = mean_and_se(paper_sk)
    assert mean > 2.0 + 3 * se
    for values, target in ((sk, 2.0), (ku, 10.0)):
        mean, se = mean_and_se(values)
        assert abs(mean - target) < 3 * se


def test_control_variates_agree_with_the_plain_mean_and_shrink_the_error():
    spec = SurfaceSpec(grid=60, size=9 * MM, corr_length=MM, skew=0.8, kurt=4.0)
    (sk, ku), (sk_se, ku_se) = calibration.expected_sample_moments(spec, 3000)
    plain_sk, plain_ku = sample_moments(spec, "paper", 3000, "plain")
    for est, est_se, values in ((sk, sk_se, plain_sk), (ku, ku_se, plain_ku)):
        mean, se = mean_and_se(values)
        assert abs(est - mean) < 3 * np.hypot(se, est_se)
        assert est_se < 0.8 * se


def test_calibration_is_reproducible_and_independent_of_sigma():
    spec = SurfaceSpec(grid=30, size=4.5 * MM, corr_length=MM, skew=-0.5, kurt=4.0)
    first = calibration._calibrate.__wrapped__(spec, calibration.CALIBRATION_RSE,
                                             calibration.CALIBRATION_MAX_POINTS,
                                             calibration.CALIBRATION_SEED)
    again = calibrate_filter(SurfaceSpec(grid=30, size=4.5 * MM, corr_length=MM, sigma=3e-5,
                                         skew=-0.5, kurt=4.0))
    assert (first.skew, first.kurt, first.samples) == (again.skew, again.kurt, again.samples)
    assert first.converged
    assert first.expected_skew == pytest.approx(-0.5, abs=0.05 * first.skew_se + 1e-5)
    assert first.expected_kurt == pytest.approx(4.0, abs=0.05 * first.kurt_se + 4e-5)
    assert first.kurt_se <= calibration.CALIBRATION_RSE * 4.0


def test_stored_surfaces_are_the_paper_generator_at_the_calibrated_moments():
    from dataclasses import replace
    spec = SurfaceSpec(grid=30, size=4.5 * MM, corr_length=MM, skew=0.5, kurt=4.0)
    cal = calibrate_filter(spec)
    direct = generate_many(replace(spec, skew=cal.skew, kurt=cal.kurt), [3, 4], method="paper")
    assert np.array_equal(generate_many(spec, [3, 4]), direct)
