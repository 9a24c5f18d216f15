"""Shape parameters of SU and SB curves from a target skewness and kurtosis.

Two solvers, used in this order by :func:`roughcontact.surfaces.johnson.fit`:

1. AS 99 (Hill, Hill & Holder 1976, "Fitting Johnson curves by moments",
   Applied Statistics 25, 180-189) with double-precision settings: Johnson's
   iteration for SU (SUFIT) and the Newton iteration for SB (SBFIT) on raw
   moments by Goodwin's trapezoid rule (MOM).
2. Where AS 99 faults or misses the target (near the ST limit, the lognormal
   line or the normal point): nested bracketing (``scipy.optimize.brentq``)
   on the accurate moments of :mod:`roughcontact.surfaces.johnson_moments`.

Inputs are ``|Sk|`` and the Pearson kurtosis ``Ku`` (normal = 3); outputs
are dimensionless shape parameters.
"""

from __future__ import annotations

import math

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

from roughcontact.surfaces.johnson_moments import (
    ETA_MAX,
    lognormal_kurt_from_wm1,
    lognormal_wm1,
    lognormal_wm1_from_kurt,
    sb_shape_moments,
    su_excess,
    su_shape,
    su_symmetric_wm1,
)

# AS 99 double-precision settings (Hill, Hill & Holder 1976; see module doc).
_AS99_TOL_SU = 1e-12  # SU iteration: |beta1 - z| stopping tolerance
_AS99_TT = 1e-6  # SB Newton: stopping tolerance on the steps of gamma, delta
_AS99_SB_LIMIT = 50  # SB Newton: maximum iterations
_AS99_ZZ = 1e-5  # MOM: agreement of successive trapezoid halvings
_AS99_MOM_TERMS = 20000  # MOM: maximum trapezoid terms on each side
_AS99_EXPA = 700.0  # MOM: largest gamma/delta accepted
_SOLVER_FTOL = 1e-12  # the robust solvers stop once skew/kurt match this closely
_OMEGA_MAX = 100.0  # largest (gamma - 38.5)/delta the SB solver explores


# ---------------------------------------------------------------------------
# AS 99 (Hill, Hill & Holder 1976), double-precision settings
# ---------------------------------------------------------------------------


def as99_su(abs_skew, kurt):
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
            return su_symmetric_wm1(kurt), 0.0
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
        n = math.ceil(ETA_MAX / math.sqrt(2.0) / h)
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
    wm1 = float(lognormal_wm1(abs_skew))
    kurt_l = lognormal_kurt_from_wm1(wm1)
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


def as99_sb(abs_skew, kurt):
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
        return scipy.optimize.brentq(wrapped, lo, hi, xtol=xtol, rtol=4.0 * _EPS, maxiter=200)
    except _RootFound as found:
        return found.x


def su_robust(abs_skew, kurt):
    """SU shape ``(w - 1, |Omega|)`` by nested bracketing on the closed forms.

    Outer loop on ``|Omega|`` in ``[0, 40]`` matching the skewness (zero at
    ``Omega = 0``, the lognormal one as ``|Omega| -> inf``; ``t = exp(-80)``
    is that limit to double precision); inner loop on ``log(w - 1)`` between
    the lognormal ``w`` of this kurtosis and the symmetric one, matching the
    excess kurtosis (:func:`su_excess`). Both match to relative accuracy, so
    a tiny skewness near the normal point is reproduced, not rounded to zero.
    """
    excess = kurt - 3.0
    wm1_sym = su_symmetric_wm1(kurt)
    if abs_skew == 0.0:
        return wm1_sym, 0.0
    log_lo = math.log(lognormal_wm1_from_kurt(kurt))
    log_hi = math.log(wm1_sym)
    omega_cap = 40.0

    def wm1_for(abs_omega):
        def excess_gap(log_wm1):
            return su_excess(math.exp(log_wm1), abs_omega) - excess

        f_lo, f_hi = excess_gap(log_lo), excess_gap(log_hi)
        if f_lo >= 0.0:
            return math.exp(log_lo)
        if f_hi <= 0.0:
            return math.exp(log_hi)
        return math.exp(_brent(excess_gap, log_lo, log_hi, f_lo=f_lo, f_hi=f_hi,
                               xtol=1e-15 * (1.0 + abs(log_lo))))

    def skew_gap(abs_omega):
        return su_shape(wm1_for(abs_omega), abs_omega)[1] - abs_skew

    f_cap = skew_gap(omega_cap)
    if f_cap <= 0.0:
        return wm1_for(omega_cap), omega_cap
    abs_omega = _brent(skew_gap, 0.0, omega_cap, f_lo=-abs_skew, f_hi=f_cap, xtol=1e-300,
                       ftol=_SOLVER_FTOL * min(1.0, abs_skew))
    return wm1_for(abs_omega), abs_omega


def sb_robust(abs_skew, kurt):
    """SB shape ``(gamma, delta, moments of U)``, ``gamma >= 0``, by nested bracketing.

    Outer loop on ``q = 1/(1 + delta)^2`` between the lognormal line
    (``delta = delta_L(Sk)``; ``q = 0`` for ``Sk = 0``, the normal point) and
    the ST limit (``q = 1``), matching the kurtosis; the kurtosis is close to
    linear in q at both ends. Inner loop on ``gamma`` matching the skewness,
    started from the previous solution. Moments from :func:`sb_shape_moments`.
    """
    st_limit = abs_skew * abs_skew + 1.0
    wm1_l = float(lognormal_wm1(abs_skew))
    kurt_l = lognormal_kurt_from_wm1(wm1_l)
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
            return 0.0, sb_shape_moments(0.0, d)
        evaluated = {}

        def skew_gap(g):
            evaluated[g] = sb_shape_moments(g, d)
            return evaluated[g][2] - abs_skew

        cap = ETA_MAX + _OMEGA_MAX * d
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
        return g, evaluated[g] if g in evaluated else sb_shape_moments(g, d)

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


