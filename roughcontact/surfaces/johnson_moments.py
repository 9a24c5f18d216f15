"""Moments of the shape variables of Johnson's curves.

The fit of :mod:`roughcontact.surfaces.johnson` needs the standardised moments
of the variable ``U`` of each family for given shape parameters:

- the lognormal (SL) line ``beta1 = (w - 1)(w + 2)^2``, ``beta2_L(w)``, in
  forms accurate near the normal point;
- SU: Johnson's (1949) closed forms, scaled so that nothing overflows for
  large ``|gamma / delta|``;
- SB: adaptive Gauss-Kronrod (7-15) quadrature over ``eta`` of the mean and
  the central moments (never raw moments, which cancel near the normal point).

All quantities are dimensionless.
"""

from __future__ import annotations

import math

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

ETA_MAX = 38.5
"""``|eta|`` beyond which the standard normal density underflows."""
INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)
_MOMENT_RTOL = 1e-13  # relative accuracy of the SB quadrature

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
# The lognormal line
# ---------------------------------------------------------------------------


def lognormal_wm1(skew):
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


def lognormal_kurt_from_wm1(wm1):
    """Kurtosis ``w^4 + 2 w^3 + 3 w^2 - 3`` of a lognormal law, written in ``w - 1``."""
    return 3.0 + wm1 * (16.0 + wm1 * (15.0 + wm1 * (6.0 + wm1)))



# ---------------------------------------------------------------------------
# SU: closed-form moments
# ---------------------------------------------------------------------------


def su_shape(wm1, abs_omega):
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
    kurt_l = lognormal_kurt_from_wm1(wm1)
    numerator = (
        w * w * kurt_l * (1.0 + t**4)
        + 4.0 * w * w * (w + 2.0) * t * (1.0 + t * t)
        + 6.0 * (2.0 * w + 1.0) * t * t
    )
    return var_scaled, skew, numerator / (base * base)


def su_excess(wm1, abs_omega):
    """Excess kurtosis ``kurt U - 3`` of :func:`su_shape`, free of cancellation near normal.

    ``numerator - 3 base^2`` of :func:`su_shape` simplifies (``e = w - 1``,
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


def su_shape_moments(wm1, omega):
    """Mean, std, skewness and kurtosis of ``U = sinh((Z - gamma)/delta)``.

    ``E U = -sqrt(w) sinh(Omega)`` and the scaled forms of :func:`su_shape`;
    ``wm1 = w - 1 = expm1(1/delta^2)`` and ``Omega = gamma/delta``.
    """
    a = abs(omega)
    var_scaled, skew, kurt = su_shape(wm1, a)
    mean = -math.sqrt(1.0 + wm1) * math.sinh(omega)
    std = math.exp(a) * math.sqrt(var_scaled)
    signed_skew = -math.copysign(skew, omega) if omega != 0.0 else 0.0
    return mean, std, signed_skew, kurt


def su_symmetric_wm1(kurt):
    """``w - 1`` of the symmetric SU law with kurtosis ``kurt`` (exact, AS 99).

    ``w^2 = sqrt(2 beta2 - 2) - 1``, written as
    ``w^2 - 1 = 2 (beta2 - 3) / (sqrt(2 beta2 - 2) + 2)`` for accuracy near 3.
    """
    w2m1 = 2.0 * (kurt - 3.0) / (math.sqrt(2.0 * kurt - 2.0) + 2.0)
    return w2m1 / (1.0 + math.sqrt(1.0 + w2m1))


def lognormal_wm1_from_kurt(kurt):
    """``w - 1`` of the lognormal law with kurtosis ``kurt > 3``."""
    excess = kurt - 3.0
    upper = max(1.0, excess ** 0.25)
    return scipy.optimize.brentq(
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

    Notes
    -----
    ``scipy.integrate.quad_vec`` computes the same integrals as accurately
    (both within 4e-14 of a 50-digit reference from bulk SB to near the
    normal point, the ST limit and the lognormal line), but it calls the
    integrand at one ``x`` at a time, where this rule evaluates every node of
    every panel in one array operation: one :func:`sb_shape_moments` takes
    20-150 ms with it instead of 0.5-1 ms, and ``johnson.fit`` over the
    (Sk, Ku) grids of Figs 1 and 2 takes 32-101 s instead of 0.4-1.5 s
    (``benchmarks/bench_sb_quadrature.py``).
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
    fixed = np.concatenate([[-ETA_MAX, -30.0, -22.0, -16.0, -12.0, -9.0], np.arange(-7.0, 8.0),
                            [9.0, 12.0, 16.0, 22.0, 30.0, ETA_MAX]])
    step = d * np.array([-30.0, -10.0, -5.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 5.0, 10.0, 30.0])
    edges = np.unique(np.clip(np.concatenate([fixed, g + step]), -ETA_MAX, ETA_MAX))
    return edges[np.concatenate([[True], np.diff(edges) > 1e-14 * (1.0 + np.abs(edges[1:]))])]


def sb_shape_moments(g, d, rtol=_MOMENT_RTOL):
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
    level = scipy.special.expit(-g * inv_d) if narrow else 0.0
    denominator = 2.0 * math.cosh(0.5 * g * inv_d) if narrow else 1.0

    def deviation_from_level(eta):
        u = (eta - g) * inv_d
        if narrow:
            return np.sinh(0.5 * eta * inv_d) / (denominator * np.cosh(0.5 * u))
        return scipy.special.expit(u)

    def first(eta):
        return (deviation_from_level(eta) * INV_SQRT_2PI * np.exp(-0.5 * eta * eta))[None]

    edges = _sb_edges(g, d)
    (offset,) = _gauss_kronrod(first, edges, rtol)

    def central(eta):
        dev = deviation_from_level(eta) - offset
        dev2 = dev * dev * INV_SQRT_2PI * np.exp(-0.5 * eta * eta)
        return np.stack([dev2, dev2 * dev, dev2 * dev * dev])

    mu2, mu3, mu4 = _gauss_kronrod(central, edges, rtol)
    return float(level + offset), float(mu2), float(mu3 / mu2**1.5), float(mu4 / mu2**2)


