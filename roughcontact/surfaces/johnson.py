"""Johnson translator: fit a Johnson curve to four moments and evaluate it.

Kumar, Sadeghi & Krousgrill (2006) turn Gaussian white noise ``eta`` into a
non-Gaussian white noise ``x`` with prescribed skewness and kurtosis by one of
Johnson's translations (Eq 6-8):

- SU: ``x = xi + lam * sinh((eta - gamma) / delta)``
- SL: ``x = xi + lam * exp((eta - gamma) / delta)``, ``lam = +-1``
- SB: ``x = xi + lam / (1 + exp(-(eta - gamma) / delta))``
- SN: ``x = xi + lam * (eta - gamma) / delta``
- ST: the two-point limit of SB on the boundary ``Ku = Sk^2 + 1`` (Eq 14-15).

The parameters are found from the moments with the algorithm of Hill, Hill &
Holder (1976), "Fitting Johnson curves by moments", Applied Statistics 25,
180-189 (algorithm AS 99), run with double-precision settings. Where AS 99
faults or misses the target, a bracketing solver on accurate moments takes
over: closed forms for SU, adaptive Gauss-Kronrod quadrature over ``eta`` for
SB. Every fit is checked against its target before it is returned.

Conventions: skewness keeps its sign; kurtosis is Pearson's (normal = 3).
Everything here is dimensionless apart from ``mean``, ``std``, ``xi`` and
``lam``, which carry the unit of ``x``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special, stats

from roughcontact.errors import InfeasibleMoments

__all__ = ["FAMILIES", "JohnsonCurve", "family_of", "fit", "lognormal_kurt"]

FAMILIES = ("SN", "SL", "SU", "SB", "ST")

#: Relative tolerance for "on the ST limit", "on the SL line" and "normal".
BOUNDARY_RTOL = 1e-12
#: A fitted law must reproduce the standardised target moments this closely.
FIT_ATOL = 1e-8
#: AS 99 results further than this from the target go to the robust solver.
FIRST_TRY_ATOL = 1e-10
#: Near-normal region (see :func:`_near_normal_excess`): for |Sk| <= NEAR_NORMAL_SKEW and
#: -NEAR_NORMAL_EXCESS < Ku - 3 < K*(Sk) the fit targets Ku = 3 + K*(Sk), because the exact
#: curves there cannot be stored in double precision.
NEAR_NORMAL_SKEW = 1e-6
NEAR_NORMAL_EXCESS = 1e-10

# AS 99 double-precision settings (Hill, Hill & Holder 1976; see module doc).
_AS99_TOL_SU = 1e-12  # SU iteration: |beta1 - z| stopping tolerance
_AS99_TT = 1e-6  # SB Newton: stopping tolerance on the steps of gamma, delta
_AS99_SB_LIMIT = 50  # SB Newton: maximum iterations
_AS99_ZZ = 1e-5  # MOM: agreement of successive trapezoid halvings
_AS99_MOM_TERMS = 20000  # MOM: maximum trapezoid terms on each side
_AS99_EXPA = 700.0  # MOM: largest gamma/delta accepted

_ETA_MAX = 38.5  # |eta| beyond which the normal density underflows
_EXP_ARG_MAX = 700.0  # larger sinh/exp arguments mean wrong parameters
_MOMENT_RTOL = 1e-13  # relative accuracy of the SB quadrature
_SOLVER_FTOL = 1e-12  # the robust solvers stop once skew/kurt match this closely
_OMEGA_MAX = 100.0  # largest (gamma - 38.5)/delta the SB solver explores
_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)

# Gauss-Kronrod 7-15 rule on [-1, 1] (QUADPACK qk15); the Gauss nodes are the
# odd-indexed Kronrod nodes.
_XK = (
    0.991455371120812639206854697526329,
    0.949107912342758524526189684047851,
    0.864864423359769072789712788640926,
    0.741531185599394439863864773280788,
    0.586087235467691130294144845693013,
    0.405845151377397166906606412076961,
    0.207784955007898467600689403773245,
)
_WK = (
    0.022935322010529224963732008058970,
    0.063092092629978553290700663189204,
    0.104790010322250183839876322541518,
    0.140653259715525918745189590510238,
    0.169004726639267902826583426598550,
    0.190350578064785409913256402421014,
    0.204432940075298892414161999234649,
)
_WK0 = 0.209482141084727828012999174891714
_WG = (
    0.129484966168869693270611432679082,
    0.279705391489276667901467771423780,
    0.381830050505118944950369775488975,
)
_WG0 = 0.417959183673469387755102040816327
_GK_NODES = np.array([-x for x in _XK] + [0.0] + list(reversed(_XK)))
_GK_WEIGHTS = np.array(list(_WK) + [_WK0] + list(reversed(_WK)))
_G_WEIGHTS = np.array(list(_WG) + [_WG0] + list(reversed(_WG)))


# ---------------------------------------------------------------------------
# Boundaries of the (Sk, Ku) plane
# ---------------------------------------------------------------------------


def _lognormal_wm1(skew):
    """``w - 1`` of the lognormal law with skewness ``skew`` (Cardano, stable form).

    Solves ``beta1 = (w - 1)(w + 2)^2`` with ``beta1 = skew^2`` by
    ``u - 1 = expm1(log1p(beta1/2 + y)/3)``, ``y = |Sk| sqrt(1 + beta1/4)``,
    ``w - 1 = (u - 1)^2 / u``, which keeps full relative accuracy as
    ``skew -> 0``.
    """
    beta1 = np.square(skew)
    y = np.abs(skew) * np.sqrt(1.0 + 0.25 * beta1)
    um1 = np.expm1(np.log1p(0.5 * beta1 + y) / 3.0)
    return um1 * um1 / (1.0 + um1)


def _lognormal_kurt_from_wm1(wm1):
    """Kurtosis ``w^4 + 2 w^3 + 3 w^2 - 3`` of a lognormal law, written in ``w - 1``."""
    return 3.0 + wm1 * (16.0 + wm1 * (15.0 + wm1 * (6.0 + wm1)))


def lognormal_kurt(skew):
    """Kurtosis of the lognormal (SL) line at the given skewness.

    Parameters
    ----------
    skew : float or array_like
        Skewness ``Sk`` (dimensionless, either sign).

    Returns
    -------
    float or numpy.ndarray
        Pearson kurtosis ``beta2_L = w^4 + 2 w^3 + 3 w^2 - 3`` with ``w`` the
        real root of ``Sk^2 = (w - 1)(w + 2)^2`` (Johnson's lognormal line,
        the SU/SB boundary in Fig 1 of Kumar et al. 2006). Accurate to full
        relative precision in ``beta2_L - 3`` near the normal point.
    """
    result = _lognormal_kurt_from_wm1(_lognormal_wm1(np.asarray(skew, dtype=float)))
    return float(result) if np.ndim(result) == 0 else result


def _near_normal_excess(skew, kurt):
    """Excess kurtosis ``Ku - 3`` that :func:`fit` targets (exact for Ku near 3). Vectorised.

    Near the normal point every Johnson curve but the nearly symmetric SU one
    stores a law of standard deviation ``std`` as ``x = xi + lam f(u)`` with
    ``|xi|, |lam| ~ std / |Sk|`` (SB at any Ku, SL, SU with ``|Omega| ~ 1``;
    ``delta ~ 1/|Sk|``): in double precision its mean is then known only to
    about ``eps / |Sk|`` times std (3e-8 at ``Sk = 1e-8``, 3e-6 at 1e-10;
    the SL fit missed ``FIT_ATOL`` there). A nearly symmetric SU curve with the
    same skewness and excess kurtosis ``K`` has ``|xi| ~ 4 |Sk| std / (3 K)``
    instead. For ``|Sk| <= NEAR_NORMAL_SKEW`` and
    ``-NEAR_NORMAL_EXCESS < Ku - 3 < K*`` the target excess is therefore
    raised to ``K* = sqrt(4 eps |Sk| / 3)``, where the rounding of the curve
    (``~ K*``) and the change of the kurtosis balance: at most
    ``1e-10 + 1.7e-11`` (``K*(1e-6)``), the skewness kept. ``K*/Sk^2 >= 17``
    there, so the curve is SU far from the lognormal line (``16/9``), or SN
    for ``|Sk| <= BOUNDARY_RTOL``. Outside this region the exact curve is
    kept: its mean rounds to at most about 6e-9 std (SL just above
    ``|Sk| = 1e-6``), within ``FIT_ATOL``.
    """
    sk = np.asarray(skew, dtype=float)
    excess = np.asarray(kurt, dtype=float) - 3.0
    floor = np.sqrt(4.0 / 3.0 * np.finfo(float).eps * np.abs(sk))
    near = (np.abs(sk) <= NEAR_NORMAL_SKEW) & (excess > -NEAR_NORMAL_EXCESS) & (excess < floor)
    result = np.where(near, floor, excess)
    return float(result) if np.ndim(result) == 0 else result


def family_of(skew, kurt):
    """Johnson family that :func:`fit` chooses for a target (Sk, Ku).

    Parameters
    ----------
    skew, kurt : float or array_like
        Skewness and Pearson kurtosis (normal = 3); broadcast together.

    Returns
    -------
    str or numpy.ndarray of str
        ``"ST"`` within a relative ``BOUNDARY_RTOL`` of ``Ku = Sk^2 + 1``
        (Eq 14), ``"infeasible"`` below it, ``"SN"`` within that tolerance of
        (0, 3), ``"SL"`` within it of the lognormal line, ``"SU"`` above the
        line and ``"SB"`` between the line and the ST limit. Near the normal
        point the class is that of the kurtosis :func:`fit` targets there
        (:func:`_near_normal_excess`): SU or SN, never SL for
        ``|Sk| <= NEAR_NORMAL_SKEW``.

    Raises
    ------
    ValueError
        If any input is not finite.
    """
    sk = np.asarray(skew, dtype=float)
    ku = np.asarray(kurt, dtype=float)
    if not np.all(np.isfinite(sk)):
        raise ValueError("skew must be finite")
    if not np.all(np.isfinite(ku)):
        raise ValueError("kurt must be finite")
    sk, ku = np.broadcast_arrays(sk, ku)
    st_limit = sk * sk + 1.0
    wm1 = _lognormal_wm1(sk)
    sl_line = _lognormal_kurt_from_wm1(wm1)
    # Compared as excess kurtosis (exact near 3, where Ku itself rounds the line away).
    excess = _near_normal_excess(sk, ku)
    sl_excess = wm1 * (16.0 + wm1 * (15.0 + wm1 * (6.0 + wm1)))
    family = np.where(excess > sl_excess, "SU", "SB").astype("<U10")
    on_line = (np.abs(excess - sl_excess) <= BOUNDARY_RTOL * sl_line) & (
        np.abs(sk) > NEAR_NORMAL_SKEW
    )
    family[on_line] = "SL"
    normal = (np.abs(sk) <= BOUNDARY_RTOL) & (np.abs(excess) <= 3.0 * BOUNDARY_RTOL)
    family[normal] = "SN"
    on_limit = np.abs(ku - st_limit) <= BOUNDARY_RTOL * st_limit
    family[on_limit] = "ST"
    family[(ku < st_limit) & ~on_limit] = "infeasible"
    return str(family) if family.ndim == 0 else family


# ---------------------------------------------------------------------------
# The fitted law
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class JohnsonCurve:
    """A Johnson curve ``x = xi + lam * f((eta - gamma) / delta)`` (Eq 6-8).

    Attributes
    ----------
    family : str
        ``"SN"``, ``"SL"``, ``"SU"``, ``"SB"`` or ``"ST"``.
    gamma, delta : float
        Shape parameters (dimensionless), ``delta > 0``. For ``"ST"`` gamma is
        unused and delta is the probability of the value ``lam``.
    xi, lam : float
        Location and scale (unit of x). For ``"SL"`` lam is +1 or -1 and the
        scale is carried by gamma. For ``"ST"`` xi and lam are the two
        support points.

    Notes
    -----
    Fits return ``lam > 0`` for SU and SN (the scipy ``johnsonsu``/``norm``
    conventions) and a lam carrying the sign of the skewness for SL (as in the
    paper) and SB (with ``gamma >= 0``; this avoids the cancellation
    ``xi ~ -lam`` near the lognormal line). For ``lam < 0`` the law is the
    paper's one, and :meth:`transform` applies the formula to ``-eta`` so that
    it stays the (increasing) quantile function; ``-eta`` has the same law as
    ``eta``. For SL this is the AS 100 form ``lam * exp((lam*eta - gamma)/delta)``.
    """

    family: str
    gamma: float
    delta: float
    xi: float
    lam: float

    def __post_init__(self):
        if self.family not in FAMILIES:
            raise ValueError(f"family must be one of {FAMILIES}, got {self.family!r}")
        for name in ("gamma", "delta", "xi", "lam"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)  # plain floats, also from numpy scalars
        if self.family == "ST":
            if not 0.0 < self.delta < 1.0:
                raise ValueError(f"ST probability delta must lie in (0, 1), got {self.delta!r}")
        elif self.delta <= 0.0:
            raise ValueError(f"delta must be positive, got {self.delta!r}")

    def transform(self, eta):
        """Map standard-normal noise to the law (Eq 6-8 of Kumar et al. 2006).

        Parameters
        ----------
        eta : float or array_like
            Standard-normal values (dimensionless).

        Returns
        -------
        float or numpy.ndarray
            ``x``, non-decreasing in ``eta``: this is the quantile function
            ``x = F^-1(Phi(eta))`` of the law. SB is evaluated with
            ``scipy.special.expit`` (no overflow); ST returns ``lam`` where
            ``eta > Phi^-1(1 - delta)`` and ``xi`` elsewhere.

        Raises
        ------
        OverflowError
            If a sinh/exp argument exceeds 700: the parameters are wrong (for
            example ST parameters used as SU), so the values are not clipped.
        """
        eta = np.asarray(eta, dtype=float)
        if self.family == "ST":
            threshold = stats.norm.isf(self.delta)
            return np.where(eta > threshold, self.lam, self.xi)[()]
        noise = eta if self.lam >= 0.0 else -eta
        u = (noise - self.gamma) / self.delta
        if self.family == "SU":
            _check_exp_argument(np.abs(u), "sinh")
            return (self.xi + self.lam * np.sinh(u))[()]
        if self.family == "SL":
            _check_exp_argument(u, "exp")
            return (self.xi + self.lam * np.exp(u))[()]
        if self.family == "SB":
            return (self.xi + self.lam * special.expit(u))[()]
        return (self.xi + self.lam * u)[()]

    def moments(self):
        """Mean, standard deviation, skewness and kurtosis of the law.

        Returns
        -------
        tuple of float
            ``(mean, std, skew, kurt)``; mean and std in the unit of x, kurt
            Pearson's (normal = 3). Closed forms for SN, SL, SU (scaled for
            large ``|gamma/delta|``) and ST; for SB adaptive Gauss-Kronrod
            quadrature over ``eta`` of the central moments, relative accuracy
            about 1e-13. No sampling.
        """
        if self.family == "ST":
            return _two_point_moments(self.xi, self.lam, self.delta)
        sign = 1.0 if self.lam >= 0.0 else -1.0
        scale = abs(self.lam)
        if self.family == "SN":
            mean = self.xi - self.lam * self.gamma / self.delta
            return (mean, scale / self.delta, 0.0, 3.0)
        if self.family == "SL":
            wm1 = math.expm1(1.0 / self.delta**2)
            w = 1.0 + wm1
            level = math.exp(-self.gamma / self.delta)
            mean = self.xi + self.lam * level * math.sqrt(w)
            std = scale * level * math.sqrt(w * wm1)
            skew = sign * (w + 2.0) * math.sqrt(wm1)
            return (mean, std, skew, _lognormal_kurt_from_wm1(wm1))
        if self.family == "SU":
            wm1 = math.expm1(1.0 / self.delta**2)
            omega = self.gamma / self.delta
            mean_u, std_u, skew_u, kurt_u = _su_shape_moments(wm1, omega)
            return (self.xi + self.lam * mean_u, scale * std_u, sign * skew_u, kurt_u)
        mean_u, var_u, skew_u, kurt_u = _sb_shape_moments(abs(self.gamma), self.delta)
        if self.gamma < 0.0:  # U(-g) has the law of 1 - U(g)
            mean_u, skew_u = 1.0 - mean_u, -skew_u
        return (self.xi + self.lam * mean_u, scale * math.sqrt(var_u), sign * skew_u, kurt_u)

    def cdf(self, x):
        """Cumulative distribution function ``P(X <= x)``.

        Parameters
        ----------
        x : float or array_like
            Values in the unit of x.

        Returns
        -------
        float or numpy.ndarray
            ``Phi(+-eta(x))`` with ``eta(x)`` the inverse of Eq 6-8 (sign of
            lam); a step function for ST.
        """
        x = np.asarray(x, dtype=float)
        if self.family == "ST":
            return ((1.0 - self.delta) * (x >= self.xi) + self.delta * (x >= self.lam))[()]
        eta, _ = self._inverse(x)
        return special.ndtr(eta if self.lam >= 0.0 else -eta)[()]

    def pdf(self, x):
        """Probability density of the law.

        Parameters
        ----------
        x : float or array_like
            Values in the unit of x.

        Returns
        -------
        float or numpy.ndarray
            Density in 1/(unit of x), zero outside the support.

        Raises
        ------
        ValueError
            For ST, a two-point law without a density.
        """
        if self.family == "ST":
            raise ValueError("the ST (two-point) law has no density; use cdf() or moments()")
        eta, log_slope = self._inverse(np.asarray(x, dtype=float))
        with np.errstate(over="ignore", invalid="ignore"):
            log_pdf = -0.5 * eta * eta + log_slope
            density = _INV_SQRT_2PI * np.exp(log_pdf)
        return np.where(np.isfinite(eta), density, 0.0)[()]

    def _inverse(self, x):
        """``eta(x)`` of the paper's formula and ``log |d eta / d x|``."""
        z = (x - self.xi) / self.lam
        log_scale = math.log(self.delta / abs(self.lam))
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.family == "SU":
                unit = np.arcsinh(z)
                log_slope = log_scale - 0.5 * np.log1p(z * z)
            elif self.family == "SL":
                inside = z > 0.0
                zi = np.where(inside, z, 1.0)
                unit = np.where(inside, np.log(zi), -np.inf)
                log_slope = log_scale - np.log(zi)
            elif self.family == "SB":
                inside = (z > 0.0) & (z < 1.0)
                zi = np.where(inside, z, 0.5)
                unit = np.where(inside, special.logit(zi), np.where(z <= 0.0, -np.inf, np.inf))
                log_slope = log_scale - np.log(zi) - np.log1p(-zi)
            else:
                unit = z
                log_slope = np.full_like(z, log_scale)
        return self.gamma + self.delta * unit, log_slope


def _check_exp_argument(arg, name):
    """Raise OverflowError if an exponential argument exceeds ``_EXP_ARG_MAX``."""
    largest = np.max(arg, initial=-np.inf)
    if largest > _EXP_ARG_MAX:
        raise OverflowError(
            f"{name} argument {largest:.4g} exceeds {_EXP_ARG_MAX:g}: the Johnson parameters "
            "do not belong to this family (for example ST or SB parameters used as SU)"
        )


def _two_point_moments(low, high, prob):
    """Moments of the law taking ``high`` with probability ``prob`` and ``low`` otherwise."""
    spread = high - low
    pq = prob * (1.0 - prob)
    mean = low + prob * spread
    skew = math.copysign(1.0, spread) * (1.0 - 2.0 * prob) / math.sqrt(pq)
    return (mean, abs(spread) * math.sqrt(pq), skew, 1.0 / pq - 3.0)


# ---------------------------------------------------------------------------
# SU: closed-form moments
# ---------------------------------------------------------------------------


def _su_shape(wm1, abs_omega):
    """Scaled SU shape quantities for ``U = sinh(Z/delta - Omega)``.

    With ``w = exp(1/delta^2)``, ``a = |Omega|`` and ``t = exp(-2a)`` the
    moments of Johnson (1949) factor as ``Var U = e^{2a} V``,
    ``mu3 = e^{3a} M3``, ``mu4 = e^{4a} M4``, so skewness and kurtosis never
    overflow (the naive ``cosh 4 Omega`` does for ``|Omega| > 177``).

    Returns
    -------
    tuple of float
        ``(V, |skew U|, kurt U)``; the sign of skew U is ``-sign(Omega)``.
    """
    w = 1.0 + wm1
    t = math.exp(-2.0 * abs_omega)
    one_m_t = -math.expm1(-2.0 * abs_omega)
    one_m_t3 = -math.expm1(-6.0 * abs_omega)
    base = w * (1.0 + t * t) + 2.0 * t
    var_scaled = 0.25 * wm1 * base
    skew = math.sqrt(w * wm1) * (w * (w + 2.0) * one_m_t3 + 3.0 * t * one_m_t) / base**1.5
    kurt_l = _lognormal_kurt_from_wm1(wm1)
    numerator = (
        w * w * kurt_l * (1.0 + t**4)
        + 4.0 * w * w * (w + 2.0) * t * (1.0 + t * t)
        + 6.0 * (2.0 * w + 1.0) * t * t
    )
    return var_scaled, skew, numerator / (base * base)


def _su_excess(wm1, abs_omega):
    """Excess kurtosis ``kurt U - 3`` of :func:`_su_shape`, free of cancellation near normal.

    ``numerator - 3 base^2`` of :func:`_su_shape` simplifies (``e = w - 1``,
    ``L = beta2_L - 3`` of the lognormal line) to
    ``w^2 L (1 + t^4) + 4 w e (4 + e) t (1 + t^2) - 6 e^2 t^2``, every term
    ``O(e)``, so the excess keeps its relative accuracy as ``w -> 1``.
    """
    w = 1.0 + wm1
    t = math.exp(-2.0 * abs_omega)
    base = w * (1.0 + t * t) + 2.0 * t
    excess_l = wm1 * (16.0 + wm1 * (15.0 + wm1 * (6.0 + wm1)))
    numerator = (
        w * w * excess_l * (1.0 + t**4)
        + 4.0 * w * wm1 * (4.0 + wm1) * t * (1.0 + t * t)
        - 6.0 * wm1 * wm1 * t * t
    )
    return numerator / (base * base)


def _su_shape_moments(wm1, omega):
    """Mean, std, skewness and kurtosis of ``U = sinh((Z - gamma)/delta)``.

    ``E U = -sqrt(w) sinh(Omega)`` and the scaled forms of :func:`_su_shape`;
    ``wm1 = w - 1 = expm1(1/delta^2)`` and ``Omega = gamma/delta``.
    """
    a = abs(omega)
    var_scaled, skew, kurt = _su_shape(wm1, a)
    mean = -math.sqrt(1.0 + wm1) * math.sinh(omega)
    std = math.exp(a) * math.sqrt(var_scaled)
    signed_skew = -math.copysign(skew, omega) if omega != 0.0 else 0.0
    return mean, std, signed_skew, kurt


def _su_symmetric_wm1(kurt):
    """``w - 1`` of the symmetric SU law with kurtosis ``kurt`` (exact, AS 99).

    ``w^2 = sqrt(2 beta2 - 2) - 1``, written as
    ``w^2 - 1 = 2 (beta2 - 3) / (sqrt(2 beta2 - 2) + 2)`` for accuracy near 3.
    """
    w2m1 = 2.0 * (kurt - 3.0) / (math.sqrt(2.0 * kurt - 2.0) + 2.0)
    return w2m1 / (1.0 + math.sqrt(1.0 + w2m1))


def _lognormal_wm1_from_kurt(kurt):
    """``w - 1`` of the lognormal law with kurtosis ``kurt > 3``."""
    excess = kurt - 3.0
    upper = max(1.0, excess ** 0.25)
    return optimize.brentq(
        lambda e: e * (16.0 + e * (15.0 + e * (6.0 + e))) - excess,
        0.0,
        upper,
        xtol=1e-300,
        rtol=4.0 * np.finfo(float).eps,
    )


# ---------------------------------------------------------------------------
# SB: moments by adaptive Gauss-Kronrod quadrature over eta
# ---------------------------------------------------------------------------


def _gauss_kronrod(integrand, edges, rtol, max_rounds=60, max_panels=4000):
    """Adaptive vectorised Gauss-Kronrod (7-15) quadrature of several integrands.

    Parameters
    ----------
    integrand : callable
        ``integrand(x) -> array (m, *x.shape)``, vectorised over ``x``.
    edges : numpy.ndarray
        Increasing panel boundaries (breakpoints) covering the interval.
    rtol : float
        Target error relative to ``int |f|`` for each integrand; the error
        estimate is ``|K15 - G7|`` per panel and the panels with more than
        their share of the remaining error budget are bisected.

    Returns
    -------
    numpy.ndarray
        The ``m`` integrals (Kronrod estimates).
    """
    lo, hi = edges[:-1], edges[1:]
    done = 0.0
    done_abs = 0.0
    used = 0.0
    for _ in range(max_rounds):
        half = 0.5 * (hi - lo)
        nodes = (0.5 * (hi + lo))[:, None] + half[:, None] * _GK_NODES
        values = integrand(nodes)
        kronrod = (values @ _GK_WEIGHTS) * half
        gauss = (values[..., 1::2] @ _G_WEIGHTS) * half
        absolute = (np.abs(values) @ _GK_WEIGHTS) * half
        estimate = done + kronrod.sum(axis=-1)
        tol = rtol * (done_abs + absolute.sum(axis=-1))
        tol = np.where(tol > 0.0, tol, np.finfo(float).tiny)
        share = np.max(np.abs(kronrod - gauss) / tol[:, None], axis=0)
        budget = 1.0 - used
        if share.sum() <= budget:
            return estimate
        split = share > budget / (2.0 * share.size)
        keep = ~split
        done = done + kronrod[:, keep].sum(axis=-1)
        done_abs = done_abs + absolute[:, keep].sum(axis=-1)
        used += share[keep].sum()
        mid = 0.5 * (lo[split] + hi[split])
        lo, hi = np.concatenate([lo[split], mid]), np.concatenate([mid, hi[split]])
        if lo.size > max_panels:
            break
    raise RuntimeError(
        f"SB moment quadrature did not reach rtol={rtol:g} ({max_rounds} rounds, "
        f"{max_panels} active panels at most)"
    )


def _sb_edges(g, d):
    """Quadrature breakpoints over eta: a fixed grid plus ``g + d*{0, +-1, ..., +-30}``."""
    fixed = np.concatenate([[-_ETA_MAX, -30.0, -22.0, -16.0, -12.0, -9.0], np.arange(-7.0, 8.0),
                            [9.0, 12.0, 16.0, 22.0, 30.0, _ETA_MAX]])
    step = d * np.array([-30.0, -10.0, -5.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 5.0, 10.0, 30.0])
    edges = np.unique(np.clip(np.concatenate([fixed, g + step]), -_ETA_MAX, _ETA_MAX))
    return edges[np.concatenate([[True], np.diff(edges) > 1e-14 * (1.0 + np.abs(edges[1:]))])]


def _sb_shape_moments(g, d, rtol=_MOMENT_RTOL):
    """Mean, variance, skewness and kurtosis of ``U = 1/(1 + exp(-(Z - g)/d))``.

    The mean comes from one adaptive quadrature over ``eta`` and the central
    moments ``E (U - mean)^k``, k = 2, 3, 4, from a second one (never from raw
    moments, which cancel near the normal point). For ``d >= 1/2`` the values
    of U are measured from their median ``U(0) = expit(-g/d)`` in the exact form
    ``U - U(0) = sinh(eta/(2d)) / (2 cosh(u/2) cosh(g/(2d)))``, so that the
    deviations keep full relative accuracy even when U barely varies (large d).

    Parameters
    ----------
    g : float
        ``gamma >= 0`` (dimensionless).
    d : float
        ``delta > 0``.

    Returns
    -------
    tuple of float
        ``(mean, variance, skewness, kurtosis)`` of U.
    """
    inv_d = 1.0 / d
    narrow = d >= 0.5
    level = special.expit(-g * inv_d) if narrow else 0.0
    denominator = 2.0 * math.cosh(0.5 * g * inv_d) if narrow else 1.0

    def deviation_from_level(eta):
        u = (eta - g) * inv_d
        if narrow:
            return np.sinh(0.5 * eta * inv_d) / (denominator * np.cosh(0.5 * u))
        return special.expit(u)

    def first(eta):
        return (deviation_from_level(eta) * _INV_SQRT_2PI * np.exp(-0.5 * eta * eta))[None]

    edges = _sb_edges(g, d)
    (offset,) = _gauss_kronrod(first, edges, rtol)

    def central(eta):
        dev = deviation_from_level(eta) - offset
        dev2 = dev * dev * _INV_SQRT_2PI * np.exp(-0.5 * eta * eta)
        return np.stack([dev2, dev2 * dev, dev2 * dev * dev])

    mu2, mu3, mu4 = _gauss_kronrod(central, edges, rtol)
    return float(level + offset), float(mu2), float(mu3 / mu2**1.5), float(mu4 / mu2**2)


# ---------------------------------------------------------------------------
# AS 99 (Hill, Hill & Holder 1976), double-precision settings
# ---------------------------------------------------------------------------


def _as99_su(abs_skew, kurt):
    """SU shape by Johnson's iteration (AS 99, SUFIT) with ``TOL = 1e-12``.

    Returns
    -------
    tuple of float or None
        ``(w - 1, |Omega|)``, or None where the iteration faults.
    """
    beta1 = abs_skew * abs_skew
    beta3 = kurt - 3.0
    try:
        w = math.sqrt(math.sqrt(2.0 * kurt - 2.8 * beta1 - 2.0) - 1.0)
        if abs_skew <= _AS99_TOL_SU:
            return _su_symmetric_wm1(kurt), 0.0
        for _ in range(200):
            w1, wm1 = w + 1.0, w - 1.0
            z = w1 * beta3
            v = w * (6.0 + w * (3.0 + w))
            a = 8.0 * (wm1 * (3.0 + w * (7.0 + v)) - z)
            b = 16.0 * (wm1 * (6.0 + v) - beta3)
            m = (math.sqrt(a * a - 2.0 * b * (wm1 * (3.0 + w * (9.0 + w * (10.0 + v)))
                                              - 2.0 * w1 * z)) - a) / b
            z = m * wm1 * (4.0 * (w + 2.0) * m + 3.0 * w1 * w1) ** 2 / (2.0 * (2.0 * m + w1) ** 3)
            w = math.sqrt(math.sqrt(1.0 - 2.0 * (1.5 - kurt + beta1 * (
                kurt - 1.5 - w * w * (1.0 + 0.5 * w * w)) / z)) - 1.0)
            if abs(beta1 - z) <= _AS99_TOL_SU:
                break
        else:
            return None
        omega = math.asinh(math.sqrt(m / w))
    except (ValueError, ZeroDivisionError, OverflowError):
        return None
    if not (math.isfinite(omega) and w > 1.0):
        return None
    return w - 1.0, omega


def _as99_mom(g, d):
    """Raw moments ``E U^r``, r = 1..6, of SB by Goodwin's trapezoid rule (AS 99, MOM).

    ``E U^r = pi^{-1/2} int exp(-v^2) (1 + exp(g/d - sqrt(2) v / d))^{-r} dv``,
    summed over the whole range where ``exp(-v^2)`` is representable (in log
    form, so nothing overflows) and halving the step from ``h = d/4``
    (``0.75`` if ``d >= 3``) until successive estimates agree to ``ZZ``.

    Returns
    -------
    numpy.ndarray or None
        The six moments, or None on a fault (``g/d > EXPA``, too many terms,
        a zero sum, no convergence).
    """
    ratio = g / d
    if ratio > _AS99_EXPA:
        return None
    h = 0.75 if d >= 3.0 else 0.25 * d
    powers = np.arange(1.0, 7.0)[:, None]
    previous = None
    for _ in range(12):
        n = math.ceil(_ETA_MAX / math.sqrt(2.0) / h)
        if n > _AS99_MOM_TERMS:
            return None
        v = h * np.arange(-n, n + 1)
        softplus = np.logaddexp(0.0, ratio - math.sqrt(2.0) * v / d)
        moments = h / math.sqrt(math.pi) * np.exp(-v * v - powers * softplus).sum(axis=1)
        if np.any(moments <= 0.0):
            return None
        if previous is not None and np.all(np.abs(moments - previous) <= _AS99_ZZ * moments):
            return moments
        previous = moments
        h *= 0.5
    return None


def _as99_sb_start(abs_skew, kurt):
    """Initial (gamma, delta) of the SB Newton iteration (AS 99, SBFIT)."""
    beta1 = abs_skew * abs_skew
    wm1 = float(_lognormal_wm1(abs_skew))
    kurt_l = _lognormal_kurt_from_wm1(wm1)
    e = (kurt - beta1 - 1.0) / (kurt_l - beta1 - 1.0)
    if abs_skew <= 1e-9:
        f = 2.0
    else:
        d_l = 1.0 / math.sqrt(math.log1p(wm1))
        f = 1.25 * d_l if d_l < 0.64 else 2.0 - 8.5245 / (d_l * (d_l * (d_l - 2.163) + 11.346))
    f = e * f + 1.0
    d = 0.8 * (f - 1.0) if f < 1.8 else (0.626 * f - 0.408) * (3.0 - f) ** -0.479
    if beta1 < _AS99_TT:
        g = 0.0
    elif d <= 1.0:
        g = (0.7466 * d**1.7973 + 0.5955) * beta1**0.485
    else:
        u, y = (0.0623, 0.4043) if d <= 2.5 else (0.0124, 0.5291)
        g = beta1 ** (u * d + y) * (0.9281 + d * (1.0614 * d - 0.7077))
    return g, d


def _as99_sb(abs_skew, kurt):
    """SB shape by the Newton iteration of AS 99 (SBFIT) with ``TT = 1e-6``.

    Returns
    -------
    tuple of float or None
        ``(gamma, delta)`` with ``gamma >= 0``, or None on a fault.
    """
    beta1 = abs_skew * abs_skew
    g, d = _as99_sb_start(abs_skew, kurt)
    for _ in range(_AS99_SB_LIMIT):
        if not (d > 0.0 and math.isfinite(g) and math.isfinite(d)):
            return None
        mu = _as99_mom(g, d)
        if mu is None:
            return None
        mu = [None, *mu]  # 1-based, as in the algorithm
        s = mu[1] * mu[1]
        h2 = mu[2] - s
        if h2 <= 0.0:
            return None
        h2a = h2 * math.sqrt(h2)
        h2b = h2 * h2
        h3 = mu[3] - mu[1] * (3.0 * mu[2] - 2.0 * s)
        h4 = mu[4] - mu[1] * (4.0 * mu[3] - mu[1] * (6.0 * mu[2] - 3.0 * s))
        rbet, bet2 = h3 / h2a, h4 / h2b
        deriv = [0.0] * 4
        for j in range(2):
            dd = [0.0] * 5
            for k in range(1, 5):
                if j == 0:
                    step = mu[k + 1] - mu[k]
                else:
                    step = ((g * d - k) * (mu[k] - mu[k + 1])
                            + (k + 1) * (mu[k + 1] - mu[k + 2])) / (d * d)
                dd[k] = k * step / d
            t = 2.0 * mu[1] * dd[1]
            s1 = mu[1] * dd[2]
            y = dd[2] - t
            deriv[j] = (dd[3] - 3.0 * (s1 + mu[2] * dd[1] - t * mu[1]) - 1.5 * h3 * y / h2) / h2a
            deriv[j + 2] = (
                dd[4] - 4.0 * (dd[3] * mu[1] + dd[1] * mu[3])
                + 6.0 * (mu[2] * t + mu[1] * (s1 - t * mu[1])) - 2.0 * h4 * y / h2
            ) / h2b
        det = deriv[0] * deriv[3] - deriv[1] * deriv[2]
        if det == 0.0 or not math.isfinite(det):
            return None
        dg = (deriv[3] * (rbet - abs_skew) - deriv[1] * (bet2 - kurt)) / det
        ddelta = (deriv[0] * (bet2 - kurt) - deriv[2] * (rbet - abs_skew)) / det
        g -= dg
        if beta1 == 0.0 or g < 0.0:
            g = 0.0
        d -= ddelta
        if abs(dg) <= _AS99_TT and abs(ddelta) <= _AS99_TT:
            return (g, d) if d > 0.0 else None
    return None


# ---------------------------------------------------------------------------
# Robust solvers: nested bracketing on accurate moments
# ---------------------------------------------------------------------------

_EPS = float(np.finfo(float).eps)


class _RootFound(Exception):
    """Raised inside a bracketing search once ``|f(x)| <= ftol``."""

    def __init__(self, x):
        super().__init__(x)
        self.x = x


def _brent(func, lo, hi, f_lo=None, f_hi=None, xtol=1e-15, ftol=0.0):
    """``scipy.optimize.brentq`` on ``[lo, hi]``, stopping early once ``|f| <= ftol``.

    ``f_lo`` and ``f_hi`` are known values at the ends of the bracket (limits
    that cannot be evaluated there, such as the ST or lognormal boundary).
    """

    def wrapped(x):
        if x == lo and f_lo is not None:
            return f_lo
        if x == hi and f_hi is not None:
            return f_hi
        value = func(x)
        if abs(value) <= ftol:
            raise _RootFound(x)
        return value

    try:
        return optimize.brentq(wrapped, lo, hi, xtol=xtol, rtol=4.0 * _EPS, maxiter=200)
    except _RootFound as found:
        return found.x


def _su_robust(abs_skew, kurt):
    """SU shape ``(w - 1, |Omega|)`` by nested bracketing on the closed forms.

    Outer loop on ``|Omega|`` in ``[0, 40]`` matching the skewness (zero at
    ``Omega = 0``, the lognormal one as ``|Omega| -> inf``; ``t = exp(-80)``
    is that limit to double precision); inner loop on ``log(w - 1)`` between
    the lognormal ``w`` of this kurtosis and the symmetric one, matching the
    excess kurtosis (:func:`_su_excess`). Both match to relative accuracy, so
    a tiny skewness near the normal point is reproduced, not rounded to zero.
    """
    excess = kurt - 3.0
    wm1_sym = _su_symmetric_wm1(kurt)
    if abs_skew == 0.0:
        return wm1_sym, 0.0
    log_lo = math.log(_lognormal_wm1_from_kurt(kurt))
    log_hi = math.log(wm1_sym)
    omega_cap = 40.0

    def wm1_for(abs_omega):
        def excess_gap(log_wm1):
            return _su_excess(math.exp(log_wm1), abs_omega) - excess

        f_lo, f_hi = excess_gap(log_lo), excess_gap(log_hi)
        if f_lo >= 0.0:
            return math.exp(log_lo)
        if f_hi <= 0.0:
            return math.exp(log_hi)
        return math.exp(_brent(excess_gap, log_lo, log_hi, f_lo=f_lo, f_hi=f_hi,
                               xtol=1e-15 * (1.0 + abs(log_lo))))

    def skew_gap(abs_omega):
        return _su_shape(wm1_for(abs_omega), abs_omega)[1] - abs_skew

    f_cap = skew_gap(omega_cap)
    if f_cap <= 0.0:
        return wm1_for(omega_cap), omega_cap
    abs_omega = _brent(skew_gap, 0.0, omega_cap, f_lo=-abs_skew, f_hi=f_cap, xtol=1e-300,
                       ftol=_SOLVER_FTOL * min(1.0, abs_skew))
    return wm1_for(abs_omega), abs_omega


def _sb_robust(abs_skew, kurt):
    """SB shape ``(gamma, delta, moments of U)``, ``gamma >= 0``, by nested bracketing.

    Outer loop on ``q = 1/(1 + delta)^2`` between the lognormal line
    (``delta = delta_L(Sk)``; ``q = 0`` for ``Sk = 0``, the normal point) and
    the ST limit (``q = 1``), matching the kurtosis; the kurtosis is close to
    linear in q at both ends. Inner loop on ``gamma`` matching the skewness,
    started from the previous solution. Moments from :func:`_sb_shape_moments`.
    """
    st_limit = abs_skew * abs_skew + 1.0
    wm1_l = float(_lognormal_wm1(abs_skew))
    kurt_l = _lognormal_kurt_from_wm1(wm1_l)
    if abs_skew == 0.0:
        q_min = 0.0
    else:
        d_l = 1.0 / math.sqrt(math.log1p(wm1_l))
        q_min = 1.0 / (1.0 + d_l) ** 2
    warm = {"g": 1.0, "d": 1.0}  # last inner solution, the start of the next search
    solved = {}  # q -> (gamma, moments of U)

    def gamma_for(d):
        """(gamma, moments) with skew U = |Sk| at this delta, or None if out of reach."""
        if abs_skew == 0.0:
            return 0.0, _sb_shape_moments(0.0, d)
        evaluated = {}

        def skew_gap(g):
            evaluated[g] = _sb_shape_moments(g, d)
            return evaluated[g][2] - abs_skew

        cap = _ETA_MAX + _OMEGA_MAX * d
        start = warm["g"] * d / warm["d"] if min(d, warm["d"]) >= 1.0 else warm["g"]
        start = min(max(start, 1e-9), cap)
        f_start = skew_gap(start)
        if abs(f_start) <= _SOLVER_FTOL:
            g = start
        else:
            g = _bracket_increasing(skew_gap, start, f_start, 0.0, -abs_skew, cap)
            if g is None:
                return None
        warm["g"], warm["d"] = g, d
        return g, evaluated[g] if g in evaluated else _sb_shape_moments(g, d)

    def delta_of(q):
        return 1.0 / math.sqrt(q) - 1.0

    def kurt_gap(q):
        solution = gamma_for(delta_of(q))
        if solution is None:  # indistinguishable from the lognormal line
            return kurt_l - kurt
        solved[q] = solution
        return solution[1][3] - kurt

    f_lognormal = (kurt_l if abs_skew > 0.0 else 3.0) - kurt
    q = _brent(kurt_gap, q_min, 1.0, f_lo=f_lognormal, f_hi=st_limit - kurt, ftol=_SOLVER_FTOL)
    d = delta_of(q)
    solution = solved.get(q) or gamma_for(d)
    if solution is None:
        raise RuntimeError(f"SB fit failed: no gamma for delta={d!r} (Sk={abs_skew}, Ku={kurt})")
    return solution[0], d, solution[1]


def _bracket_increasing(func, start, f_start, lower, f_lower, upper):
    """Root of an increasing ``func`` on ``[lower, upper]``, searched outward from ``start``.

    Steps of 5 % of ``start``, growing fourfold, find a bracket; Brent's
    method (stopping at ``|f| <= _SOLVER_FTOL``) finishes. ``f_lower`` is the
    known value at ``lower``. Returns None if ``func(upper) < 0``.
    """
    step = 0.05 * start
    if f_start < 0.0:
        lo, f_lo = start, f_start
        while True:
            hi = min(lo + step, upper)
            f_hi = func(hi)
            if f_hi >= 0.0:
                break
            if hi >= upper:
                return None
            lo, f_lo, step = hi, f_hi, 4.0 * step
    else:
        hi, f_hi = start, f_start
        while True:
            lo = max(hi - step, lower)
            f_lo = f_lower if lo == lower else func(lo)
            if f_lo <= 0.0:
                break
            hi, f_hi, step = lo, f_lo, 4.0 * step
    if f_lo == 0.0 or f_hi == 0.0:
        return lo if f_lo == 0.0 else hi
    return _brent(func, lo, hi, f_lo=f_lo, f_hi=f_hi, xtol=1e-15 * (1.0 + hi),
                  ftol=_SOLVER_FTOL)


# ---------------------------------------------------------------------------
# Fitting
# ---------------------------------------------------------------------------


def _finite_float(value, name):
    """``float(value)``, raising ValueError naming the argument if it is not finite."""
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a finite real number, got {value!r}") from exc
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {number!r}")
    return number


def _infeasible_message(skew, kurt):
    limit = skew * skew + 1.0
    message = (
        f"kurtosis {kurt!r} is below the limit Sk^2 + 1 = {limit!r} for skewness {skew!r} "
        f"(Eq 14); no distribution exists; raise kurt to at least {limit!r}"
    )
    if kurt >= 1.0:
        message += f" or reduce |skew| to at most {math.sqrt(kurt - 1.0)!r}"
    return message + "."


def _fit_st(skew, mean, std):
    """Two-point law on ``Ku = Sk^2 + 1`` (AS 99 type 5): support points xi < lam."""
    beta1 = skew * skew
    root = math.sqrt(beta1 / (beta1 + 4.0))
    small = 2.0 / ((beta1 + 4.0) * (1.0 + root))  # 1/2 - root/2 without cancellation
    prob_high = small if skew > 0.0 else 0.5 + 0.5 * root
    spread = std / math.sqrt(small * (1.0 - small))
    low = mean - prob_high * spread
    return JohnsonCurve("ST", 0.0, prob_high, low, low + spread)


def _fit_sl(skew, mean, std):
    """Lognormal curve in closed form; lam = sign(Sk), the scale in gamma."""
    wm1 = float(_lognormal_wm1(skew))
    log_w = math.log1p(wm1)
    delta = 1.0 / math.sqrt(log_w)
    gamma = 0.5 * delta * (log_w + math.log(wm1) - 2.0 * math.log(std))
    lam = 1.0 if skew >= 0.0 else -1.0
    return JohnsonCurve("SL", gamma, delta, mean - lam * std / math.sqrt(wm1), lam)


def _su_misfit(wm1, abs_omega, abs_skew, kurt):
    """Misfit of an SU shape, relative to ``min(1, |Sk|)`` and ``min(1, Ku - 3)``.

    Relative near the normal point, where AS 99's tolerance on ``beta1`` does
    not resolve the skewness.
    """
    skew = _su_shape(wm1, abs_omega)[1]
    excess = kurt - 3.0
    return max(abs(skew - abs_skew) / min(1.0, abs_skew) if abs_skew > 0.0 else skew,
               abs(_su_excess(wm1, abs_omega) - excess) / min(1.0, excess))


def _fit_su(skew, kurt, mean, std):
    """SU curve: AS 99 iteration, then nested bracketing if it misses."""
    abs_skew = abs(skew)
    shape = _as99_su(abs_skew, kurt)
    if shape is None or _su_misfit(*shape, abs_skew, kurt) > FIRST_TRY_ATOL:
        shape = _su_robust(abs_skew, kurt)
    wm1, abs_omega = shape
    var_scaled = _su_shape(wm1, abs_omega)[0]
    sign = 1.0 if skew > 0.0 else -1.0  # Omega = -sign(Sk) |Omega| for lam > 0
    delta = 1.0 / math.sqrt(math.log1p(wm1))
    gamma = -sign * abs_omega * delta
    root_v = math.sqrt(var_scaled)
    lam = std * math.exp(-abs_omega) / root_v
    # xi = mean + lam sqrt(w) sinh(Omega), with e^{-a} sinh(a) = (1 - e^{-2a})/2
    xi = mean - sign * std * math.sqrt(1.0 + wm1) * 0.5 * -math.expm1(-2.0 * abs_omega) / root_v
    return JohnsonCurve("SU", gamma, delta, xi, lam)


def _fit_sb(skew, kurt, mean, std):
    """SB curve: AS 99 Newton, then nested bracketing if it faults or misses."""
    abs_skew = abs(skew)
    shape = _as99_sb(abs_skew, kurt)
    moments = None
    if shape is not None:
        moments = _sb_shape_moments(*shape)
        if max(abs(moments[2] - abs_skew), abs(moments[3] - kurt)) > FIRST_TRY_ATOL:
            shape = None
    if shape is None:
        *shape, moments = _sb_robust(abs_skew, kurt)
    g, d = shape
    mean_u, var_u = moments[0], moments[1]
    lam = (1.0 if skew >= 0.0 else -1.0) * std / math.sqrt(var_u)
    return JohnsonCurve("SB", g, d, mean - lam * mean_u, lam)


def _check_fit(curve, target):
    """Raise RuntimeError if the curve's moments miss the target by more than FIT_ATOL."""
    mean, std, skew, kurt = target
    got = curve.moments()
    errors = (abs(got[0] - mean) / std, abs(got[1] - std) / std,
              abs(got[2] - skew), abs(got[3] - kurt))
    if not max(errors) <= FIT_ATOL:
        raise RuntimeError(
            f"Johnson {curve.family} fit missed its target: moments {got} for target "
            f"(mean, std, skew, kurt) = {target}; errors (mean/std, std/std, skew, kurt) "
            f"= {errors} exceed {FIT_ATOL:g}; parameters {curve}"
        )


def fit(skew, kurt, mean=0.0, std=1.0):
    """Fit a Johnson curve to four moments (AS 99 of Hill, Hill & Holder 1976).

    Parameters
    ----------
    skew : float
        Target skewness ``Sk = sqrt(beta1)`` with its sign.
    kurt : float
        Target Pearson kurtosis ``Ku = beta2`` (normal = 3), ``Ku >= Sk^2 + 1``.
    mean : float, optional
        Target mean, unit of x.
    std : float, optional
        Target standard deviation, unit of x, positive.

    Returns
    -------
    JohnsonCurve
        The curve of the family given by :func:`family_of`: ST on
        ``Ku = Sk^2 + 1`` (Eq 14-15), SN at (0, 3), SL on the lognormal line,
        SU above it and SB between. Its moments (:meth:`JohnsonCurve.moments`)
        equal the target within ``FIT_ATOL = 1e-8`` (mean and std relative to
        std); this is verified before returning. The fit is continuous through
        the normal point: for ``|Sk| <= 1e-6`` and ``-1e-10 < Ku - 3 < K*``,
        ``K* = sqrt(4 eps |Sk| / 3) <= 1.7e-11``, it is the SU curve (SN for
        ``|Sk| <= 1e-12``) of kurtosis ``3 + K*``, whose parameters round to
        about ``K*`` std in double precision (those of the exact SB, SL or SU
        curve there round to ``eps / |Sk|`` std); see
        :func:`_near_normal_excess`.

    Raises
    ------
    ValueError
        If an argument is not finite or ``std <= 0``.
    InfeasibleMoments
        If ``Ku < Sk^2 + 1``: no distribution has these moments.
    RuntimeError
        If the fitted curve misses the target (never expected).

    Notes
    -----
    SU: AS 99's iteration (SUFIT) with tolerance 1e-12, checked with the
    closed-form moments; SB: AS 99's Newton iteration (SBFIT, MOM) with
    ``TT = 1e-6``, ``ZZ = 1e-5``, 20000 terms and ``EXPA = 700``, with the
    moments recomputed by adaptive quadrature at the final (gamma, delta).
    Results further than 1e-10 from the target, and faults (near the ST limit,
    the lognormal line or the normal point), are solved again by nested
    bracketing (``scipy.optimize.brentq``) on accurate moments.
    """
    skew = _finite_float(skew, "skew")
    kurt = _finite_float(kurt, "kurt")
    mean = _finite_float(mean, "mean")
    std = _finite_float(std, "std")
    if std <= 0.0:
        raise ValueError(f"std must be positive, got {std!r}")
    family = family_of(skew, kurt)
    if family == "infeasible":
        raise InfeasibleMoments(_infeasible_message(skew, kurt))
    # Near the normal point the fit aims at a kurtosis within 1.2e-10 of the
    # target that double precision can represent (see _near_normal_excess).
    excess = _near_normal_excess(skew, kurt)
    fitted_kurt = kurt if excess == kurt - 3.0 else 3.0 + excess
    if family == "ST":
        curve = _fit_st(skew, mean, std)
    elif family == "SN":
        curve = JohnsonCurve("SN", 0.0, 1.0, mean, std)
    elif family == "SL":
        curve = _fit_sl(skew, mean, std)
    elif family == "SU":
        curve = _fit_su(skew, fitted_kurt, mean, std)
    else:
        curve = _fit_sb(skew, fitted_kurt, mean, std)
    _check_fit(curve, (mean, std, skew, kurt))
    return curve

