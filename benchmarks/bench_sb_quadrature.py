"""SB moments: the library's vectorised Gauss-Kronrod rule against scipy.integrate.quad_vec.

The Johnson SB fit (:mod:`roughcontact.surfaces.johnson`) needs the mean and
central moments of ``U = 1 / (1 + exp(-(eta - gamma) / delta))`` for
``eta ~ N(0, 1)``; :func:`roughcontact.surfaces.johnson_moments.sb_shape_moments`
integrates them over eta with a hand-written adaptive Gauss-Kronrod (7-15)
rule that evaluates all nodes of all panels in one array operation.
``scipy.integrate.quad_vec`` does the same job with a scalar integrand. This
compares the two on the same integrands, breakpoints and tolerance (error
relative to ``int |f|`` for each moment: ``quad_vec`` integrates ``[f, |f|]``
with the max norm, one moment at a time):

1. accuracy of (mean, variance, skewness, kurtosis) against a 50-digit
   ``mpmath`` reference (skipped if mpmath is not installed), from bulk SB to
   near the normal point, the ST limit and the lognormal line;
2. wall time of one moment evaluation;
3. wall time of ``johnson.fit`` over the (Sk, Ku) grids of the figures (the
   white noise's moments on Fig 2's bound for b = 1, 2, 3 mm on 64 x 64 over
   10 mm; the study's cells; a grid over Fig 1's plane from the ST limit to
   the SU region), with the largest relative change of the fitted parameters.

Usage::

    .venv/bin/python benchmarks/bench_sb_quadrature.py          # about 3 min

Prints a Markdown report.
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy import integrate, special  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.surfaces import johnson, johnson_moments, johnson_solvers  # noqa: E402
from roughcontact.surfaces.calibration import input_moments, kurt_min, moment_transfer  # noqa: E402
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402

#: (regime, gamma, delta) of the accuracy and speed table.
CASES = [("bulk", 0.5, 1.0), ("bulk", 2.0, 0.8), ("bulk, symmetric", 0.0, 2.0), ("bulk", 1.0, 0.3),
         ("near normal", 0.0, 20.0), ("near normal", 1.0, 141.0), ("near normal", 5.0, 300.0),
         ("near ST", 0.0, 0.045), ("near ST", 1.05, 0.0081), ("near ST", 0.3, 4e-3),
         ("near SL", 30.0, 0.5), ("near SL", 300.0, 3.0)]


def quad_vec_moments(g: float, d: float, rtol: float = 1e-13) -> tuple[float, ...]:
    """:func:`sb_shape_moments`'s integrands and breakpoints, integrated by quad_vec."""
    inv_d = 1.0 / d
    narrow = d >= 0.5
    level = special.expit(-g * inv_d) if narrow else 0.0
    denominator = 2.0 * math.cosh(0.5 * g * inv_d) if narrow else 1.0

    def deviation(eta):
        if narrow:
            return np.sinh(0.5 * eta * inv_d) / (denominator * np.cosh(0.5 * (eta - g) * inv_d))
        return special.expit((eta - g) * inv_d)

    edges = johnson_moments._sb_edges(g, d)

    def integral(f):
        def pair(eta):
            value = f(eta) * johnson_moments.INV_SQRT_2PI * math.exp(-0.5 * eta * eta)
            return np.array([value, abs(value)])

        result, _ = integrate.quad_vec(pair, edges[0], edges[-1], epsabs=0.0, epsrel=rtol,
                                       norm="max", points=edges[1:-1], quadrature="gk15",
                                       limit=100000)
        return float(result[0])

    offset = integral(deviation)
    mu2, mu3, mu4 = (integral(lambda eta, k=k: (deviation(eta) - offset) ** k) for k in (2, 3, 4))
    return level + offset, mu2, mu3 / mu2**1.5, mu4 / mu2**2


def reference_moments(g: float, d: float) -> tuple[float, ...] | None:
    """The same four moments to 50 digits by mpmath (breakpoints every 0.25 in eta)."""
    try:
        import mpmath as mp
    except ImportError:
        return None
    mp.mp.dps = 50
    g, d = mp.mpf(g), mp.mpf(d)

    def pdf(eta):
        return mp.exp(-eta * eta / 2) / mp.sqrt(2 * mp.pi)

    def u(eta):
        return 1 / (1 + mp.exp(-(eta - g) / d))

    points = [mp.mpf(k) / 4 for k in range(-160, 161)]
    mean = mp.quad(lambda eta: u(eta) * pdf(eta), points)
    mu2, mu3, mu4 = (mp.quad(lambda eta, k=k: (u(eta) - mean) ** k * pdf(eta), points)
                     for k in (2, 3, 4))
    return float(mean), float(mu2), float(mu3 / mu2**1.5), float(mu4 / mu2**2)


def relative_error(moments, reference) -> float:
    """Largest error: mean relative to the std, variance, skewness (to max(1, |Sk|)), kurtosis."""
    mean, var, skew, kurt = moments
    r_mean, r_var, r_skew, r_kurt = reference
    return max(abs(mean - r_mean) / math.sqrt(r_var), abs(var - r_var) / r_var,
               abs(skew - r_skew) / max(1.0, abs(r_skew)), abs(kurt - r_kurt) / r_kurt)


def timed(function, *args) -> tuple[float, object]:
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def fit_grids() -> dict[str, list[tuple[float, float]]]:
    """(Sk, Ku) of the white noise fitted for Figs 1 and 2 and the study's cells."""
    bound = []
    for b in (1.0, 2.0, 3.0):
        spec = SurfaceSpec(grid=64, size=10e-3, corr_length=b * 1e-3)
        s3, s4 = moment_transfer(spec)
        for skew in np.linspace(-3, 3, 13):  # on the bound, nudged inside as sample_bound does
            kurt = float(kurt_min(spec, skew)) * (1.0 + 1e-9) + 1e-12
            bound.append((skew / s3, 3.0 + (kurt - 3.0) / s4))
    cells = [input_moments(SurfaceSpec(grid=60, size=9e-3, corr_length=b * 1e-3, skew=skew,
                                       kurt=kurt))
             for b, (skew, kurt) in [(1.0, m) for m in [(0, 3), (-0.8, 4), (0.8, 4), (0, 4.5),
                                                        (1, 4.5)]] + [(0.5, (0, 3)), (2.0, (0, 3))]]
    plane = [(s, s * s + 1 + k) for s in np.linspace(-3, 3, 13)
             for k in (1e-6, 1e-3, 1e-2, 0.1, 0.5, 1, 2, 4, 8)]
    return {"Fig 2's bound, b = 1, 2, 3 mm": bound, "the study's cells": cells,
            "Fig 1's plane, ST limit to SU": plane}


def main() -> None:
    print("## One evaluation of the SB moments\n")
    print("| regime | gamma | delta | error, library | error, quad_vec | ms, library | "
          "ms, quad_vec |")
    print("|---|---|---|---|---|---|---|")
    for regime, g, d in CASES:
        t_library, library = timed(johnson_moments.sb_shape_moments, g, d)
        t_scipy, scipy_result = timed(quad_vec_moments, g, d)
        reference = reference_moments(g, d)
        errors = ("n/a", "n/a") if reference is None else (
            f"{relative_error(library, reference):.1e}",
            f"{relative_error(scipy_result, reference):.1e}")
        print(f"| {regime} | {g:g} | {d:g} | {errors[0]} | {errors[1]} | {1e3 * t_library:.2f} | "
              f"{1e3 * t_scipy:.1f} |")
    print("\n## johnson.fit over the figures' grids\n")
    print("| grid | fits | SB fits | s, library | s, quad_vec | largest relative change "
          "of (gamma, delta, xi, lam) |")
    print("|---|---|---|---|---|---|")
    library_moments = johnson_moments.sb_shape_moments
    for name, points in fit_grids().items():
        t_library, curves = timed(lambda p=points: [johnson.fit(*x) for x in p])
        for module in (johnson, johnson_solvers):  # the modules that call the SB moments
            module.sb_shape_moments = quad_vec_moments
        try:
            t_scipy, others = timed(lambda p=points: [johnson.fit(*x) for x in p])
        finally:
            for module in (johnson, johnson_solvers):
                module.sb_shape_moments = library_moments
        change = max(abs(getattr(a, f) - getattr(b, f)) / max(abs(getattr(a, f)), 1e-300)
                     for a, b in zip(curves, others, strict=True)
                     for f in ("gamma", "delta", "xi", "lam"))
        sb = sum(c.family == "SB" for c in curves)
        print(f"| {name} | {len(points)} | {sb} | {t_library:.2f} | {t_scipy:.1f} | "
              f"{change:.1e} |")


if __name__ == "__main__":
    main()
