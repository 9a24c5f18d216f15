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

This module holds the public side: the regions of the (Sk, Ku) plane
(:func:`family_of`, :func:`lognormal_kurt`), the fitted law
(:class:`JohnsonCurve`, one small class per family behind it) and
:func:`fit`. The moments of each family's shape variable are in
:mod:`roughcontact.surfaces.johnson_moments`, the AS 99 and bracketing solvers
for the SU and SB shapes in :mod:`roughcontact.surfaces.johnson_solvers`.

Conventions: skewness keeps its sign; kurtosis is Pearson's (normal = 3).
Everything here is dimensionless apart from ``mean``, ``std``, ``xi`` and
``lam``, which carry the unit of ``x``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from roughcontact.errors import InfeasibleMoments
from roughcontact.surfaces.johnson_moments import (
    INV_SQRT_2PI,
    lognormal_kurt_from_wm1,
    lognormal_wm1,
    sb_shape_moments,
    su_excess,
    su_shape,
    su_shape_moments,
)
from roughcontact.surfaces.johnson_solvers import as99_sb, as99_su, sb_robust, su_robust

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

_EXP_ARG_MAX = 700.0  # larger sinh/exp arguments mean wrong parameters


# ---------------------------------------------------------------------------
# Boundaries of the (Sk, Ku) plane
# ---------------------------------------------------------------------------


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
        the SU/SB boundary in Fig 1 of Kumar et al. 2006). Correctly rounded
        near the normal point: the excess ``beta2_L - 3`` is computed to full
        relative precision, but the returned kurtosis, a double near 3, holds
        it only to one spacing of 3 (4.4e-16).
    """
    result = lognormal_kurt_from_wm1(lognormal_wm1(np.asarray(skew, dtype=float)))
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
    wm1 = lognormal_wm1(sk)
    sl_line = lognormal_kurt_from_wm1(wm1)
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

    The formulas of each family live in one small class (``_Unbounded`` for
    SU, ``_Lognormal``, ``_Bounded``, ``_Normal``, ``_TwoPoint``), chosen once
    by ``family``.
    """

    family: str
    gamma: float
    delta: float
    xi: float
    lam: float

    def __post_init__(self):
        if self.family not in _LAWS:
            raise ValueError(f"family must be one of {FAMILIES}, got {self.family!r}")
        for name in ("gamma", "delta", "xi", "lam"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)  # plain floats, also from numpy scalars
        _LAWS[self.family].check_delta(self.delta)

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
        return _LAWS[self.family].transform(self, np.asarray(eta, dtype=float))

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
        return _LAWS[self.family].moments(self)

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
        return _LAWS[self.family].cdf(self, np.asarray(x, dtype=float))

    def pdf(self, x):
        """Probability density of the law at ``x`` (float or array_like, in the unit of
        x).

        Returns
        -------
        float or numpy.ndarray
            Density in 1/(unit of x), zero outside the support.

        Raises
        ------
        ValueError
            For ST, a two-point law without a density.
        """
        return _LAWS[self.family].pdf(self, x)


class _Law:
    """A continuous family: ``x = xi + lam f(u)``, ``u = (+-eta - gamma) / delta``.

    Subclasses give ``f`` (:meth:`unit`), its inverse with the log of its slope
    (:meth:`unit_inverse`) and the moments of the law.
    """

    @staticmethod
    def check_delta(delta):
        if delta <= 0.0:
            raise ValueError(f"delta must be positive, got {delta!r}")

    def transform(self, curve, eta):
        noise = eta if curve.lam >= 0.0 else -eta
        u = (noise - curve.gamma) / curve.delta
        return (curve.xi + curve.lam * self.unit(u))[()]

    def cdf(self, curve, x):
        eta, _ = self.inverse(curve, x)
        return special.ndtr(eta if curve.lam >= 0.0 else -eta)[()]

    def pdf(self, curve, x):
        eta, log_slope = self.inverse(curve, np.asarray(x, dtype=float))
        with np.errstate(over="ignore", invalid="ignore"):
            log_pdf = -0.5 * eta * eta + log_slope
            density = INV_SQRT_2PI * np.exp(log_pdf)
        return np.where(np.isfinite(eta), density, 0.0)[()]

    def inverse(self, curve, x):
        """``eta(x)`` of the paper's formula and ``log |d eta / d x|``."""
        z = (x - curve.xi) / curve.lam
        log_scale = math.log(curve.delta / abs(curve.lam))
        with np.errstate(divide="ignore", invalid="ignore"):
            unit, log_slope = self.unit_inverse(z, log_scale)
        return curve.gamma + curve.delta * unit, log_slope


class _Normal(_Law):
    """SN: ``f(u) = u``."""

    @staticmethod
    def unit(u):
        return u

    @staticmethod
    def unit_inverse(z, log_scale):
        return z, np.full_like(z, log_scale)

    @staticmethod
    def moments(curve):
        mean = curve.xi - curve.lam * curve.gamma / curve.delta
        return (mean, abs(curve.lam) / curve.delta, 0.0, 3.0)


class _Lognormal(_Law):
    """SL: ``f(u) = exp(u)``, lam = +-1."""

    @staticmethod
    def unit(u):
        _check_exp_argument(u, "exp")
        return np.exp(u)

    @staticmethod
    def unit_inverse(z, log_scale):
        inside = z > 0.0
        zi = np.where(inside, z, 1.0)
        return np.where(inside, np.log(zi), -np.inf), log_scale - np.log(zi)

    @staticmethod
    def moments(curve):
        sign = 1.0 if curve.lam >= 0.0 else -1.0
        wm1 = math.expm1(1.0 / curve.delta**2)
        w = 1.0 + wm1
        level = math.exp(-curve.gamma / curve.delta)
        mean = curve.xi + curve.lam * level * math.sqrt(w)
        std = abs(curve.lam) * level * math.sqrt(w * wm1)
        skew = sign * (w + 2.0) * math.sqrt(wm1)
        return (mean, std, skew, lognormal_kurt_from_wm1(wm1))


class _Unbounded(_Law):
    """SU: ``f(u) = sinh(u)``."""

    @staticmethod
    def unit(u):
        _check_exp_argument(np.abs(u), "sinh")
        return np.sinh(u)

    @staticmethod
    def unit_inverse(z, log_scale):
        return np.arcsinh(z), log_scale - 0.5 * np.log1p(z * z)

    @staticmethod
    def moments(curve):
        sign = 1.0 if curve.lam >= 0.0 else -1.0
        wm1 = math.expm1(1.0 / curve.delta**2)
        omega = curve.gamma / curve.delta
        mean_u, std_u, skew_u, kurt_u = su_shape_moments(wm1, omega)
        return (curve.xi + curve.lam * mean_u, abs(curve.lam) * std_u, sign * skew_u, kurt_u)


class _Bounded(_Law):
    """SB: ``f(u) = 1 / (1 + exp(-u))``, evaluated with ``scipy.special.expit``."""

    @staticmethod
    def unit(u):
        return special.expit(u)

    @staticmethod
    def unit_inverse(z, log_scale):
        inside = (z > 0.0) & (z < 1.0)
        zi = np.where(inside, z, 0.5)
        unit = np.where(inside, special.logit(zi), np.where(z <= 0.0, -np.inf, np.inf))
        return unit, log_scale - np.log(zi) - np.log1p(-zi)

    @staticmethod
    def moments(curve):
        sign = 1.0 if curve.lam >= 0.0 else -1.0
        mean_u, var_u, skew_u, kurt_u = sb_shape_moments(abs(curve.gamma), curve.delta)
        if curve.gamma < 0.0:  # U(-g) has the law of 1 - U(g)
            mean_u, skew_u = 1.0 - mean_u, -skew_u
        return (curve.xi + curve.lam * mean_u, abs(curve.lam) * math.sqrt(var_u),
                sign * skew_u, kurt_u)


class _TwoPoint:
    """ST: ``xi`` with probability ``1 - delta``, ``lam`` with probability ``delta``."""

    @staticmethod
    def check_delta(delta):
        if not 0.0 < delta < 1.0:
            raise ValueError(f"ST probability delta must lie in (0, 1), got {delta!r}")

    @staticmethod
    def transform(curve, eta):
        threshold = -special.ndtri(curve.delta)  # scipy.stats.norm.isf, without scipy.stats
        return np.where(eta > threshold, curve.lam, curve.xi)[()]

    @staticmethod
    def moments(curve):
        return _two_point_moments(curve.xi, curve.lam, curve.delta)

    @staticmethod
    def cdf(curve, x):
        return ((1.0 - curve.delta) * (x >= curve.xi) + curve.delta * (x >= curve.lam))[()]

    @staticmethod
    def pdf(curve, x):
        raise ValueError("the ST (two-point) law has no density; use cdf() or moments()")


#: The law of each family, by its name (the keys are :data:`FAMILIES`).
_LAWS = {"SN": _Normal(), "SL": _Lognormal(), "SU": _Unbounded(), "SB": _Bounded(),
         "ST": _TwoPoint()}


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
    """Why (skew, kurt) has no distribution (Eq 14), with values that have one: the limit
    rounded up (kurt) and down (|skew|) at 4 decimals, so the advice followed lies inside."""
    limit = skew * skew + 1.0
    message = (
        f"kurtosis {kurt:g} is below the limit Sk^2 + 1 = {limit:g} for skewness {skew:g} "
        f"(Eq 14); no distribution exists; raise kurt to at least "
        f"{math.ceil(limit * 1e4 - 1e-9) / 1e4:g}"
    )
    if kurt >= 1.0:
        message += (" or reduce |skew| to at most "
                    f"{math.floor(math.sqrt(kurt - 1.0) * 1e4) / 1e4:g}")
    return message + "."


def _fit_st(skew, kurt, mean, std):
    """Two-point law on ``Ku = Sk^2 + 1`` (AS 99 type 5): support points xi < lam."""
    beta1 = skew * skew
    root = math.sqrt(beta1 / (beta1 + 4.0))
    small = 2.0 / ((beta1 + 4.0) * (1.0 + root))  # 1/2 - root/2 without cancellation
    prob_high = small if skew > 0.0 else 0.5 + 0.5 * root
    spread = std / math.sqrt(small * (1.0 - small))
    low = mean - prob_high * spread
    return JohnsonCurve("ST", 0.0, prob_high, low, low + spread)


def _fit_sn(skew, kurt, mean, std):
    """Normal curve: ``x = mean + std * eta``."""
    return JohnsonCurve("SN", 0.0, 1.0, mean, std)


def _fit_sl(skew, kurt, mean, std):
    """Lognormal curve in closed form; lam = sign(Sk), the scale in gamma."""
    wm1 = float(lognormal_wm1(skew))
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
    skew = su_shape(wm1, abs_omega)[1]
    excess = kurt - 3.0
    return max(abs(skew - abs_skew) / min(1.0, abs_skew) if abs_skew > 0.0 else skew,
               abs(su_excess(wm1, abs_omega) - excess) / min(1.0, excess))


def _fit_su(skew, kurt, mean, std):
    """SU curve: AS 99 iteration, then nested bracketing if it misses."""
    abs_skew = abs(skew)
    shape = as99_su(abs_skew, kurt)
    if shape is None or _su_misfit(*shape, abs_skew, kurt) > FIRST_TRY_ATOL:
        shape = su_robust(abs_skew, kurt)
    wm1, abs_omega = shape
    var_scaled = su_shape(wm1, abs_omega)[0]
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
    shape = as99_sb(abs_skew, kurt)
    moments = None
    if shape is not None:
        moments = sb_shape_moments(*shape)
        if max(abs(moments[2] - abs_skew), abs(moments[3] - kurt)) > FIRST_TRY_ATOL:
            shape = None
    if shape is None:
        *shape, moments = sb_robust(abs_skew, kurt)
    g, d = shape
    mean_u, var_u = moments[0], moments[1]
    lam = (1.0 if skew >= 0.0 else -1.0) * std / math.sqrt(var_u)
    return JohnsonCurve("SB", g, d, mean - lam * mean_u, lam)


#: The fit of each family, by its name: ``(skew, kurt, mean, std) -> JohnsonCurve``; ST, SN
#: and SL are fixed by the skewness alone.
_FITS = {"ST": _fit_st, "SN": _fit_sn, "SL": _fit_sl, "SU": _fit_su, "SB": _fit_sb}


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
    fit_family = _FITS.get(family_of(skew, kurt))
    if fit_family is None:  # below the ST limit
        raise InfeasibleMoments(_infeasible_message(skew, kurt))
    # Near the normal point the fit aims at a kurtosis within 1.2e-10 of the
    # target that double precision can represent (see _near_normal_excess).
    excess = _near_normal_excess(skew, kurt)
    fitted_kurt = kurt if excess == kurt - 3.0 else 3.0 + excess
    curve = fit_family(skew, fitted_kurt, mean, std)
    _check_fit(curve, (mean, std, skew, kurt))
    return curve

