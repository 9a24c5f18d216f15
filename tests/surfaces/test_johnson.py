"""Tests of the Johnson translator (AS 99 fit, Eq 6-8 of Kumar et al. 2006).

Fitted moments are compared with independent references: scipy.stats closed
forms for SU, SL and SN, and quadrature over eta of the transform itself
(scipy.integrate.quad_vec) for SB, whose scipy moments are unreliable near
the lognormal line.
"""

import math

import numpy as np
import pytest
from scipy import integrate, stats

from roughcontact import InfeasibleMoments
from roughcontact.surfaces import johnson as jn

ATOL = 1e-8  # required agreement of the fitted moments with the target


def _sl(skew, offset=0.0):
    """A point at ``offset`` from the lognormal line at this skewness."""
    return (skew, jn.lognormal_kurt(skew) + offset)


def _quadrature_moments(curve, span=12.0):
    """Mean, std, skew, kurt of ``curve.transform(eta)`` by adaptive quadrature over eta.

    Independent of the library's SB quadrature: raw moments of the transform
    (the target mean is 0, so they are well conditioned), scipy's quad_vec,
    breakpoints on a unit grid and around the logistic transition.
    """
    centre = curve.gamma if curve.lam >= 0 else -curve.gamma
    steps = curve.delta * np.array([-30.0, -10.0, -3.0, -1.0, 0.0, 1.0, 3.0, 10.0, 30.0])
    points = np.unique(np.clip(np.r_[np.arange(-span, span + 1.0), centre + steps], -span, span))
    powers = np.arange(1, 5)

    def integrand(eta):
        return curve.transform(eta) ** powers * math.exp(-0.5 * eta * eta) / math.sqrt(2 * math.pi)

    raw, _ = integrate.quad_vec(integrand, -span, span, points=points[1:-1], epsabs=1e-300,
                                epsrel=1e-13)
    m1, m2, m3, m4 = raw
    var = m2 - m1 * m1
    skew = (m3 - 3 * m1 * m2 + 2 * m1**3) / var**1.5
    kurt = (m4 - 4 * m1 * m3 + 6 * m1 * m1 * m2 - 3 * m1**4) / var**2
    return np.array([m1, math.sqrt(var), skew, kurt])


def _assert_target(moments, skew, kurt, mean=0.0, std=1.0, atol=ATOL):
    got = np.asarray(moments, dtype=float)
    scaled = np.array([(got[0] - mean) / std, got[1] / std - 1.0, got[2] - skew, got[3] - kurt])
    assert np.all(np.abs(scaled) <= atol), (skew, kurt, got)


# ---------------------------------------------------------------------------
# Grids of targets
# ---------------------------------------------------------------------------

SU_TARGETS = [
    (0.0, 3.0 + 1e-6), (1e-4, 3.0 + 1e-4), (-1e-4, 3.0 + 1e-4), (0.0, 5.0), (0.5, 4.0),
    (-0.5, 4.0), (1.0, 6.0), (-1.0, 6.0), (2.0, 15.0), (-3.0, 30.0), (4.0, 100.0),
    (-4.0, 100.0), (0.0, 100.0), (1.0, 120.0), (-6.0, 120.0), (4.0, 45.0), (-4.0, 60.0),
    _sl(1.0, 1e-6), _sl(-1.0, 1e-6), _sl(2.0, 1e-3), _sl(-2.0, 1e-3), _sl(0.5, 1e-6),
    _sl(-3.0, 1e-6), _sl(4.0, 1e-3),
]

SKEWS_NEAR_ST = [0.0, 0.5, -0.5, 1.0, -1.0, 2.0, -2.0, 3.0, -3.0]

SB_TARGETS = (
    [(s, s * s + 1.0 + 1e-3) for s in SKEWS_NEAR_ST]
    + [(0.0, 2.0), (0.0, 3.0 - 1e-6), (1e-4, 3.0 - 1e-4), (-1e-4, 3.0 - 1e-4), (0.5, 3.0),
       (-0.5, 2.0), (1.0, 4.0), (-1.0, 3.0), (2.0, 8.0), (-2.0, 6.0), (3.0, 15.0),
       (-3.0, 20.0), (4.0, 17.5), (-4.0, 30.0), (9.0, 100.0), (-9.0, 100.0)]
    + [_sl(s, -off) for s in (0.5, -1.0, 2.0, -3.0) for off in (1e-6, 1e-3)]
)

SL_SKEWS = [0.1, -0.1, 0.5, -1.0, 1.0, 2.0, -3.0, 4.0]


# ---------------------------------------------------------------------------
# SU, SL, SN: closed forms of scipy.stats
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(("skew", "kurt"), SU_TARGETS)
def test_su_fit_matches_scipy_and_target(skew, kurt):
    curve = jn.fit(skew, kurt)
    assert curve.family == "SU"
    mean, var, sk, excess = stats.johnsonsu(
        a=curve.gamma, b=curve.delta, loc=curve.xi, scale=curve.lam
    ).stats("mvsk")
    scipy_moments = [float(mean), math.sqrt(var), float(sk), float(excess) + 3.0]
    _assert_target(scipy_moments, skew, kurt)
    np.testing.assert_allclose(curve.moments(), scipy_moments, rtol=0, atol=1e-10)


@pytest.mark.parametrize("skew", SL_SKEWS)
def test_sl_fit_matches_scipy_lognormal(skew):
    kurt = jn.lognormal_kurt(skew)
    curve = jn.fit(skew, kurt, mean=1.5, std=0.4)
    assert curve.family == "SL"
    assert curve.lam == math.copysign(1.0, skew)
    # x = xi + lam * exp(-gamma/delta) * exp(eta/delta): lam times a lognormal
    law = stats.lognorm(s=1.0 / curve.delta, scale=math.exp(-curve.gamma / curve.delta))
    mean, var, sk, excess = law.stats("mvsk")
    scipy_moments = [curve.xi + curve.lam * float(mean), math.sqrt(var),
                     curve.lam * float(sk), float(excess) + 3.0]
    _assert_target(scipy_moments, skew, kurt, mean=1.5, std=0.4)
    _assert_target(curve.moments(), skew, kurt, mean=1.5, std=0.4)


def test_sn_fit_matches_scipy_normal():
    curve = jn.fit(0.0, 3.0, mean=-2.0, std=3.5)
    assert curve.family == "SN"
    mean, var = stats.norm(loc=-2.0, scale=3.5).stats("mv")
    np.testing.assert_allclose(curve.moments(), [mean, math.sqrt(var), 0.0, 3.0], atol=1e-12)
    eta = np.linspace(-4, 4, 9)
    np.testing.assert_allclose(curve.transform(eta), -2.0 + 3.5 * eta, atol=1e-12)


def test_lognormal_kurt_matches_scipy_lognormal():
    sigmas = np.array([1e-3, 0.1, 0.5, 0.9, 1.2])
    skew, excess = stats.lognorm(s=sigmas).stats("sk")
    np.testing.assert_allclose(jn.lognormal_kurt(skew), excess + 3.0, rtol=1e-12)
    np.testing.assert_allclose(jn.lognormal_kurt(-skew), excess + 3.0, rtol=1e-12)
    # stable near the normal point: beta2 - 3 ~ 16 beta1 / 9. beta2 is a double
    # next to 3, so beta2 - 3 = 1.8e-12 can be right only to a spacing of 3
    # (4.4e-16, 2.5e-4 of it; measured 0.2 spacing, beta2 correctly rounded), not
    # to rel=1e-5; approx's default abs=1e-12 passed anything from 0.8e-12 to 2.8e-12.
    # Cardano's w - 1 = u + 1/u - 2 without the stable form is 3.2 spacings off.
    assert jn.lognormal_kurt(1e-6) - 3.0 == pytest.approx(16.0 / 9.0 * 1e-12, rel=1e-5,
                                                          abs=np.spacing(3.0))


# ---------------------------------------------------------------------------
# SB: independent quadrature
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(("skew", "kurt"), SB_TARGETS)
def test_sb_fit_matches_quadrature_and_target(skew, kurt):
    curve = jn.fit(skew, kurt)
    assert curve.family == "SB"
    reference = _quadrature_moments(curve)
    _assert_target(reference, skew, kurt)
    _assert_target(curve.moments(), skew, kurt)
    np.testing.assert_allclose(curve.moments(), reference, rtol=0, atol=1e-9)


def test_sb_general_location_and_scale():
    curve = jn.fit(-1.2, 3.5, mean=4.0, std=0.25)
    assert curve.family == "SB"
    _assert_target(curve.moments(), -1.2, 3.5, mean=4.0, std=0.25)
    scaled = _quadrature_moments(curve)
    _assert_target(scaled, -1.2, 3.5, mean=4.0, std=0.25, atol=1e-7)


# ---------------------------------------------------------------------------
# ST and the infeasible region
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("skew", [0.0, 0.5, -1.0, 2.0, -3.0])
def test_st_on_the_limit_is_a_two_point_law(skew):
    kurt = skew * skew + 1.0
    curve = jn.fit(skew, kurt, mean=0.5, std=2.0)
    assert curve.family == "ST"
    low, high, prob = curve.xi, curve.lam, curve.delta
    assert low < high
    values = np.array([low, high])
    weights = np.array([1.0 - prob, prob])
    mean = weights @ values
    std = math.sqrt(weights @ (values - mean) ** 2)
    sk = weights @ (values - mean) ** 3 / std**3
    ku = weights @ (values - mean) ** 4 / std**4
    _assert_target([mean, std, sk, ku], skew, kurt, mean=0.5, std=2.0, atol=1e-12)
    _assert_target(curve.moments(), skew, kurt, mean=0.5, std=2.0, atol=1e-12)
    eta = stats.norm.ppf((np.arange(100000) + 0.5) / 100000)
    x = curve.transform(eta)
    assert set(np.unique(x)) == {low, high}
    assert np.all(np.diff(x) >= 0)
    assert np.mean(x == high) == pytest.approx(prob, abs=2e-5)
    assert curve.cdf(low - 1.0) == 0.0 and curve.cdf(high) == 1.0
    assert curve.cdf(0.5 * (low + high)) == pytest.approx(1.0 - prob)
    with pytest.raises(ValueError, match="no density"):
        curve.pdf(0.0)


def test_below_the_limit_is_infeasible_with_the_limit_in_the_message():
    with pytest.raises(InfeasibleMoments, match=r"Sk\^2 \+ 1 = 2 .*at least 2 or reduce "
                                                 r"\|skew\| to at most 0\.7071\."):
        jn.fit(1.0, 1.5)  # sqrt(0.5) = 0.70711 rounded down: inside the limit
    with pytest.raises(ValueError, match="at least 5 "):  # InfeasibleMoments is a ValueError
        jn.fit(-2.0, 4.99)
    assert jn.family_of(1.0, 1.9) == "infeasible"


# ---------------------------------------------------------------------------
# Transform, cdf, pdf
# ---------------------------------------------------------------------------

CURVE_TARGETS = [(1.0, 6.0), (-1.0, 6.0), (0.0, 2.0), (1.0, 4.0), (-1.0, 4.0),
                 _sl(1.0), _sl(-1.0), (0.0, 3.0), (-2.0, 12.0)]


@pytest.mark.parametrize(("skew", "kurt"), CURVE_TARGETS)
def test_transform_is_the_quantile_function(skew, kurt):
    curve = jn.fit(skew, kurt, mean=0.3, std=2.0)
    u = np.linspace(1e-6, 1.0 - 1e-6, 4001)
    eta = stats.norm.ppf(u)
    x = curve.transform(eta)
    assert np.all(np.diff(x) > 0)
    np.testing.assert_allclose(curve.cdf(x), u, rtol=0, atol=1e-10)


@pytest.mark.parametrize(("skew", "kurt"), CURVE_TARGETS)
def test_pdf_is_the_derivative_of_the_cdf(skew, kurt):
    curve = jn.fit(skew, kurt)
    x = curve.transform(np.linspace(-3.0, 3.0, 25))
    step = 1e-5 * (1.0 + np.abs(x))
    numeric = (curve.cdf(x + step) - curve.cdf(x - step)) / (2 * step)
    np.testing.assert_allclose(curve.pdf(x), numeric, rtol=1e-6)
    total, _ = integrate.quad(curve.pdf, curve.transform(-8.0), curve.transform(8.0), limit=200)
    assert total == pytest.approx(1.0, abs=1e-9)


def test_pdf_matches_scipy_with_its_sign_conventions():
    x = np.linspace(-3.0, 4.0, 29)
    su = jn.fit(1.0, 6.0)
    law = stats.johnsonsu(a=su.gamma, b=su.delta, loc=su.xi, scale=su.lam)
    np.testing.assert_allclose(su.pdf(x), law.pdf(x), rtol=1e-12, atol=1e-300)
    for skew in (1.0, -1.0):
        sb = jn.fit(skew, 4.0)
        if sb.lam > 0:
            law = stats.johnsonsb(a=sb.gamma, b=sb.delta, loc=sb.xi, scale=sb.lam)
        else:  # xi + lam U with lam < 0 is the mirror image
            law = stats.johnsonsb(a=-sb.gamma, b=sb.delta, loc=sb.xi + sb.lam, scale=-sb.lam)
        np.testing.assert_allclose(sb.pdf(x), law.pdf(x), rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(sb.cdf(x), law.cdf(x), rtol=0, atol=1e-12)
    sl = jn.fit(-1.0, jn.lognormal_kurt(-1.0))
    law = stats.lognorm(s=1.0 / sl.delta, scale=math.exp(-sl.gamma / sl.delta))
    np.testing.assert_allclose(sl.pdf(x), law.pdf(sl.lam * (x - sl.xi)), rtol=1e-12)
    sn = jn.fit(0.0, 3.0, mean=1.0, std=2.0)
    np.testing.assert_allclose(sn.pdf(x), stats.norm(1.0, 2.0).pdf(x), rtol=1e-13)


def test_transform_refuses_overflowing_parameters():
    wrong = jn.JohnsonCurve("SU", gamma=0.0, delta=1e-3, xi=0.0, lam=1.0)
    with pytest.raises(OverflowError, match="sinh"):
        wrong.transform(np.array([0.0, 1.0]))
    sb = jn.JohnsonCurve("SB", gamma=2.0, delta=1e-4, xi=0.0, lam=1.0)
    assert np.all(np.isfinite(sb.transform(np.linspace(-8, 8, 101))))  # expit: no overflow


# ---------------------------------------------------------------------------
# Signs, families, validation
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("skew", "kurt", "family"),
    [(-1.0, 6.0, "SU"), (-1.0, 3.0, "SB"), (-1.0, None, "SL"), (-1.0, 2.0, "ST"),
     (-3.0, 10.01, "SB"), (-0.5, 1e2, "SU")],
)
def test_negative_target_skew_gives_negative_realised_skew(skew, kurt, family):
    kurt = jn.lognormal_kurt(skew) if kurt is None else kurt
    curve = jn.fit(skew, kurt)
    assert curve.family == family
    if family == "ST":  # two-point law: the rare value is the low one
        p, spread = curve.delta, curve.lam - curve.xi
        realised = spread**3 * p * (1 - p) * (1 - 2 * p) / (spread**2 * p * (1 - p)) ** 1.5
        assert p > 0.5
    else:
        realised = _quadrature_moments(curve)[2]
    assert realised == pytest.approx(skew, abs=1e-7)
    mirror = jn.fit(-skew, kurt)
    assert mirror.family == family
    assert mirror.moments()[2] == pytest.approx(-skew, abs=ATOL)


def test_family_of_agrees_with_fit_on_a_grid():
    skews = np.array([-4.0, -2.0, -1.0, -0.3, 0.0, 0.3, 1.0, 2.0, 4.0])
    kurts = np.array([1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0, 20.0, 50.0])
    sk, ku = np.meshgrid(skews, kurts)
    families = jn.family_of(sk, ku)
    assert families.shape == sk.shape
    seen = set()
    for s, k, family in zip(sk.ravel(), ku.ravel(), families.ravel(), strict=True):
        assert family == jn.family_of(float(s), float(k))
        if family == "infeasible":
            with pytest.raises(InfeasibleMoments):
                jn.fit(s, k)
        else:
            assert jn.fit(s, k).family == family
        seen.add(str(family))
    assert seen == {"infeasible", "ST", "SN", "SU", "SB"}
    assert jn.family_of(2.0, jn.lognormal_kurt(2.0)) == "SL"
    assert jn.family_of(2.0, jn.lognormal_kurt(2.0) * (1 + 1e-9)) == "SU"
    assert jn.family_of(2.0, jn.lognormal_kurt(2.0) * (1 - 1e-9)) == "SB"


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [({"skew": math.nan, "kurt": 3.0}, "skew"), ({"skew": 0.0, "kurt": math.inf}, "kurt"),
     ({"skew": 0.0, "kurt": 3.0, "mean": math.nan}, "mean"),
     ({"skew": 0.0, "kurt": 3.0, "std": 0.0}, "std"),
     ({"skew": 0.0, "kurt": 3.0, "std": -1.0}, "std")],
)
def test_invalid_arguments_are_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        jn.fit(**kwargs)


def test_fitted_moments_scale_with_mean_and_std():
    for skew, kurt in [(0.7, 5.0), (0.7, 2.5), (-2.0, 5.0), _sl(0.7)]:
        unit = jn.fit(skew, kurt)
        scaled = jn.fit(skew, kurt, mean=-3.0, std=7.0)
        assert scaled.family == unit.family
        _assert_target(scaled.moments(), skew, kurt, mean=-3.0, std=7.0)
        eta = np.linspace(-3, 3, 13)
        np.testing.assert_allclose(scaled.transform(eta), -3.0 + 7.0 * unit.transform(eta),
                                   rtol=0, atol=1e-8)
