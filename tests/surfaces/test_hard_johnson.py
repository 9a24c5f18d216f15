"""Hard cases of the Johnson translator: the edges of the (Sk, Ku) plane."""

import numpy as np
import pytest
import scipy.stats

from roughcontact import InfeasibleMoments
from roughcontact.surfaces import johnson


def check(curve, skew, kurt, tol=1e-8):
    mean, std, sk, ku = curve.moments()
    assert mean == pytest.approx(0.0, abs=tol)
    assert std == pytest.approx(1.0, abs=tol)
    assert sk == pytest.approx(skew, abs=tol)
    assert ku == pytest.approx(kurt, abs=tol)


@pytest.mark.parametrize("skew", [-2.0, 0.5, 1.5])
def test_just_above_the_two_point_limit(skew):
    kurt = skew**2 + 1 + 1e-3
    curve = johnson.fit(skew, kurt)
    assert curve.family == "SB"  # bounded: the only family near the ST limit
    check(curve, skew, kurt)
    # sampling the transform reproduces the target (independent of moments())
    eta = np.random.default_rng(0).standard_normal(400_000)
    x = curve.transform(eta)
    assert np.all(np.isfinite(x))
    assert scipy.stats.skew(x) == pytest.approx(skew, abs=0.03)


def test_on_the_two_point_limit_and_below():
    curve = johnson.fit(1.0, 2.0)
    assert curve.family == "ST"
    check(curve, 1.0, 2.0, tol=1e-12)
    with pytest.raises(InfeasibleMoments, match=r"below the limit Sk\^2 \+ 1"):
        johnson.fit(1.0, 2.0 - 1e-6)


@pytest.mark.parametrize("offset", [0.0, 1e-6, -1e-6])
@pytest.mark.parametrize("skew", [-1.0, 0.8])
def test_on_and_beside_the_lognormal_line(skew, offset):
    kurt = johnson.lognormal_kurt(skew) + offset
    curve = johnson.fit(skew, kurt)
    expected = {0.0: "SL", 1e-6: "SU", -1e-6: "SB"}[offset]
    assert curve.family == expected or (offset == 0.0 and curve.family in ("SL",))
    check(curve, skew, kurt)
    if curve.family == "SL":  # against scipy's lognormal
        s = curve.delta ** -1
        law = scipy.stats.lognorm(s)
        assert abs(law.stats(moments="s")) == pytest.approx(abs(skew), rel=1e-10)


def test_near_the_normal_point():
    curve = johnson.fit(1e-4, 3 + 1e-4)
    check(curve, 1e-4, 3 + 1e-4, tol=1e-9)
    # nearly the identity transform on the bulk of the normal law
    eta = np.linspace(-3, 3, 13)
    assert np.abs(curve.transform(eta) - eta).max() < 1e-3


@pytest.mark.parametrize(("skew", "kurt"), [(0.0, 100.0), (4.0, 30.0), (-4.0, 30.0),
                                           (4.0, 17.5), (-4.0, 100.0)])
def test_heavy_tails_and_strong_skew(skew, kurt):
    curve = johnson.fit(skew, kurt)
    check(curve, skew, kurt)
    x = curve.transform(np.linspace(-8, 8, 401))
    assert np.all(np.isfinite(x)) and np.all(np.diff(x) >= 0)  # monotone, no overflow
    if kurt - skew**2 - 1 > 2:  # far from the two-point limit: strictly increasing
        assert np.all(np.diff(curve.transform(np.linspace(-2, 2, 41))) > 0)
    else:  # near it the law is nearly two-point: mass piles up at the two bounds
        assert curve.family == "SB"
        assert x.min() == pytest.approx(curve.xi, abs=1e-6)
        assert x.max() == pytest.approx(curve.xi + curve.lam, abs=1e-6)
    if curve.family == "SU":
        law = scipy.stats.johnsonsu(curve.gamma, curve.delta, loc=curve.xi, scale=curve.lam)
        mean, var, sk, ex = law.stats(moments="mvsk")
        assert float(sk) == pytest.approx(skew, abs=1e-6)
        assert float(ex) + 3 == pytest.approx(kurt, abs=1e-5 * kurt)
