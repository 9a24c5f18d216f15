"""Hard cases of the surface generator: the edges of what a grid can represent."""

import logging

import numpy as np
import pytest

from roughcontact import InfeasibleMoments
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, kurt_min
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.statistics import correlation_length, height_stats
from roughcontact.surfaces.synthetic import generate, generate_many

MM = 1e-3


def spec(**kw):
    base = dict(grid=(60, 60), size=(9 * MM, 9 * MM), corr_length=(1 * MM, 1 * MM),
                sigma=1.0, skew=0.0, kurt=3.0)
    return SurfaceSpec(**{**base, **kw})


def test_just_above_the_reachable_kurtosis():
    probe = spec(skew=-1.0)
    bound = float(kurt_min(probe, -1.0))
    ok = spec(skew=-1.0, kurt=bound + 1e-3)
    skew_x, kurt_x = input_moments(ok)
    assert kurt_x >= skew_x**2 + 1  # the white noise is a valid (near two-point) law
    z = generate_many(ok, range(40), method="paper")
    assert np.all(np.isfinite(z))
    stats = height_stats(z)
    # ensemble means within 3 standard errors of the targets
    for name, target in (("skew", -1.0), ("kurt", bound + 1e-3)):
        se = stats[name].std(ddof=1) / np.sqrt(len(z))
        assert abs(stats[name].mean() - target) < 3 * se + 1e-9, name
    with pytest.raises(InfeasibleMoments, match="minimum kurtosis"):
        generate(spec(skew=-1.0, kurt=bound - 1e-3), 0, method="paper")


def test_the_calibrated_bound_lies_below_the_process_bound():
    """A window's sample kurtosis is biased low on the filter's bound (Eq 15), so the
    calibrated filter reaches targets a little below it, and refuses, naming the
    reachable kurtosis, further down."""
    bound = float(kurt_min(spec(skew=-1.0), -1.0))
    near = spec(skew=-1.0, kurt=bound - 1e-3)
    cal = calibrate_filter(near)
    assert cal.converged
    assert cal.kurt >= float(kurt_min(near, cal.skew))  # a valid process
    assert cal.expected_kurt == pytest.approx(bound - 1e-3, abs=0.05 * cal.kurt_se + 1e-4)
    with pytest.raises(InfeasibleMoments, match="not reachable in expectation") as err:
        generate(spec(skew=-1.0, kurt=bound - 0.3), 0)
    reachable = float(str(err.value).split("Raise kurt to at least ")[1].split(",")[0])
    assert bound - 0.3 < reachable < bound


def test_correlation_length_shorter_than_the_spacing_warns_and_stays_finite(caplog):
    s = spec(corr_length=(0.05 * MM, 0.05 * MM))  # dx = 0.15 mm
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        z = generate(s, 1)
    assert "shorter than the grid spacing" in caplog.text
    assert np.all(np.isfinite(z))
    # nearly white noise: neighbours almost uncorrelated
    r = np.corrcoef(z[:, :-1].ravel(), z[:, 1:].ravel())[0, 1]
    assert abs(r) < 0.2


def test_correlation_length_beyond_half_the_domain_warns_with_numbers(caplog):
    s = spec(corr_length=(6 * MM, 6 * MM))
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        z = generate(s, 1)
    assert "exceeds half the domain" in caplog.text
    assert "0.006 m" in caplog.text and "0.0045 m" in caplog.text
    assert np.all(np.isfinite(z)) and z.std() > 0


def test_anisotropic_lengths_ten_to_one():
    s = spec(grid=(128, 64), size=(12 * MM, 6 * MM), corr_length=(2 * MM, 0.2 * MM))
    lags = np.array([correlation_length(z, s.spacing) for z in generate_many(s, range(20))])
    bx, by = lags.mean(axis=0)
    assert bx / by == pytest.approx(10.0, rel=0.3)
    assert by == pytest.approx(0.2 * MM, rel=0.3)


@pytest.mark.parametrize("grid", [(1, 60), (60, 1), (3, 60)])
def test_degenerate_grid_is_refused_with_a_clear_message(grid):
    with pytest.raises(ValueError, match=r"SurfaceSpec.grid must be integers >= 4"):
        spec(grid=grid)
