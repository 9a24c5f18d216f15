"""Frictionless normal contact of a rigid flat with a rough elastic body.

Solves the displacement-controlled contact problem of Section 3 of Kumar,
Sadeghi & Krousgrill (2006): given the influence coefficients ``C`` (Eq 16),
the initial separation ``f = z_max - z`` (Eq 21) and the rigid-body approach
``d``, find the contact pressure ``p`` that minimizes the complementary energy
(Eq 17, 18, 27)

    V(p) = 1/2 p . C p - p . (d - f)    subject to    p >= 0,

whose optimality (KKT) conditions are Eq 19-22: with the gap
``g = u + f - d`` and ``u = C p``,

    g = 0 where p > 0 (contact),   g >= 0 where p = 0 (separation).

All quantities are SI: ``p`` in Pa, ``u``, ``f``, ``d``, ``g`` in m, ``C`` in
m/Pa, loads in N.

Hardness cap (elastic-perfectly-plastic elements)
-------------------------------------------------
With ``hardness = H`` [Pa] every public solver caps the pressure: it
minimizes the same ``V(p)`` over the box ``0 <= p <= H``, whose KKT
conditions are

    g = 0 where 0 < p < H (elastic contact),   g >= 0 where p = 0,
    g <= 0 where p = H (saturated, the plastic area).

The saturated elements carry ``H`` whatever the approach, so at fixed
free and saturated sets only the free set ``F`` moves with ``d``
(``C_FF p_F = d 1 - f_F - C_FU H``) and the tangent stiffness is
``dF/dd = dA 1^T (C_FF)^-1 1``. ``hardness=None`` (the default) is the
uncapped problem, computed exactly as without the keyword. With a cap the
pressure no longer scales with ``sigma E`` alone: the elastic
``phat = p L / (E sigma)`` of :mod:`roughcontact.contact.nondim` depends
only on the surface shape and ``d / sigma``, but the cap becomes
``phat <= H L / (E sigma)``, so a capped solution depends on that group
too, and one dimensionless solve no longer serves every (sigma, E): it
serves every (sigma, E, H) with the same ``H L / (E sigma)``.
``plastic_area_fraction`` in the results is the fraction of elements at
``p = H`` (included in ``real_area_fraction``).

Methods
-------
``"steepest"``
    Projected steepest descent, the paper's method (Fig 6): the gradient
    ``g`` on the free set (``p > 0`` or ``g < 0``), exact line search, then
    projection onto ``p >= 0``; kept as a slow baseline. With a cap the
    elements at ``H`` with ``g < 0`` are held and the projection is onto
    ``[0, H]``.
``"cg"``
    Constrained conjugate gradients of Polonsky & Keer (1999), in the
    displacement-controlled form (no load constraint, so no mean-gap shift).
    With a cap the free set is ``0 < p < H``, iterates are projected onto
    ``[0, H]``, and elements at ``H`` with a positive gap are released like
    elements out of contact with a negative gap join (conjugacy restarts).
``"exact"``
    Block principal pivoting (Kim & Park 2011, after Judice & Pires 1994) for
    the linear complementarity problem, with a Cholesky factorization of
    ``C`` on the contact set at every pivot; finite, for up to a few thousand
    unknowns; the reference. One surface at a time. With a cap, its
    box-constrained extension: free, zero and saturated sets,
    ``C_FF p_F = d - f_F - C_FU H`` on the free set, and ``p > H`` or
    ``g > 0`` at the cap counted as infeasible.
``"pivot"``
    The same pivoting, for dense matrices, with every surface in flight at
    once (:func:`sweep`): each round factors each surface's ``C_AA`` on its
    current contact guess, and one product ``P C`` gives the gaps of all of
    them, whatever approach step each is at; a surface whose step is solved
    starts its next step at once from the predicted contact set, and takes
    its tangent ``(C_AA)^-1 1`` from the same factor. It needs about two
    rounds per step at the study's loads (1-15 % contact). Why it is the
    default for dense matrices: the products ``C p`` are the cost of an
    iterative method, and the paper's and the graded meshes have near-null
    checkerboard modes (one trilinear face per contact element: the
    consistent nodal loads of a checkerboard pressure nearly cancel;
    condition number 7e8 at 60 x 60 against about 1e2 for ``refined``), so
    CG needs hundreds of products per step on them. A Cholesky factorization
    is backward stable whatever the condition number: the KKT residual stays
    at rounding (1e-15) and a paper-mesh cell costs what a refined-mesh cell
    costs. ``benchmarks/bench_contact.py`` measures both.
``"auto"``
    ``"pivot"`` for a dense matrix, ``"cg"`` for a matrix-free operator
    (:func:`resolve_method`).

Convergence
-----------
Every method stops on the same dimensionless KKT residual,

    r = max_i | min(C_ii p_i, g_i) | / max_i |d - f_i|,

the max-norm of the projected-gradient (natural) residual of Eq 27 with the
diagonal scaling ``C_ii``, measured in units of the largest rigid
interference. It is zero exactly when ``p >= 0``, ``g >= 0`` and
``p_i g_i = 0``; a negative pressure, a penetration (negative gap) and a gap
left open under positive pressure all raise it. ``converged`` is ``r <= tol``.
With a cap ``H`` it is the natural residual of the box-constrained problem,

    r = max_i | C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H) | / max_i |d - f_i|,

i.e. ``C_ii (p_i - clip(p_i - g_i / C_ii, 0, H))``, the distance moved by a
diagonally scaled projected gradient step. It is zero exactly at the KKT
point above (a pressure above ``H`` and a positive gap at the cap raise it
too), and it is the uncapped residual for ``H = inf``.

Operators
---------
``operator`` is either a dense symmetric influence matrix (ndarray, n x n,
m/Pa; then ``element_area`` [m^2] must be given) or an object with
``shape == (n, n)``, ``element_area`` [m^2], ``diagonal()`` (the
self-compliances ``C_ii`` [m/Pa]) and ``matvec(p)`` accepting (n,) and
(n, m) arrays, such as :class:`roughcontact.elasticity.halfspace.PeriodicHalfSpace`.
An optional ``grid = (nx, ny)`` attribute fixes the surface shape (ny, nx).

Performance
-----------
The products ``C p`` dominate. :func:`solve_many` and :func:`sweep` apply
``C`` to all unfinished surfaces at once (BLAS 3), and ``precision="mixed"``
takes the search-direction products in single precision (about half the
time; the result still meets ``tol`` in double precision). :func:`sweep`
starts each step from a first-order extrapolation of the previous solution
(``extrapolate``), exact on an unchanged contact set. On a 2-core machine
shared with other jobs one BLAS thread (``OPENBLAS_NUM_THREADS=1``) was
faster than two. On the paper's FE block matrix (condition number about
7e8) the constrained CG still needs several hundred iterations per sweep
step; see ``benchmarks/bench_contact.py`` and its results.

References
----------
I. A. Polonsky, L. M. Keer, "A numerical method for solving rough contact
problems based on the multi-level multi-summation and conjugate gradient
techniques", Wear 231 (1999) 206-219.
J. Kim, H. Park, "Fast nonnegative matrix factorization: an active-set-like
method and comparisons", SIAM J. Sci. Comput. 33 (2011) 3261-3281.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from roughcontact.contact import validity

__all__ = [
    "METHODS",
    "resolve_method",
    "PRECISIONS",
    "ContactResult",
    "SweepResult",
    "kkt_residual",
    "solve",
    "solve_many",
    "sweep",
    "tangent_stiffness",
]

logger = logging.getLogger("roughcontact.contact")

METHODS = ("steepest", "cg", "exact", "pivot", "auto")
PRECISIONS = ("double", "mixed")

#: Relative asymmetry max|C - C^T| / max|C| accepted for a dense matrix.
SYMMETRY_RTOL = 1e-8
#: Largest n for which ``method="exact"`` forms a dense matrix from an operator.
EXACT_MAX_UNKNOWNS = 6000
#: Iterations between exact recomputations of u = C p (rounding-drift control).
_REFRESH_EVERY = 100
#: Residual at which single-precision products hand over to an exact check.
_MIXED_FLOOR = 1e-5
#: Largest share of changed elements for which a correction gathers rows of C.
_SPARSE_ROWS = 1.0 / 32.0


# ---------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class ContactResult:
    """Solution of one displacement-controlled contact problem (Eq 27).

    Attributes
    ----------
    pressure : ndarray
        Contact pressure ``p`` [Pa], same shape as the ``gap0`` passed in.
    displacement : ndarray
        Elastic surface displacement ``u = C p`` [m] (Eq 16).
    gap : ndarray
        ``u + f - d`` [m]; zero in contact, positive outside (Eq 19-22).
    approach : float
        Rigid-body approach ``d`` [m].
    load : float
        Total force ``F = sum p dA`` [N].
    nominal_pressure : float
        ``P = F / A_n`` [Pa], ``A_n = n dA`` the nominal area.
    real_area_fraction : float
        Fraction of elements with ``p > 0`` [-] (saturated ones included).
    max_pressure : float
        Largest element pressure [Pa].
    mean_plane_deflection : float
        Mean of ``u`` [m], the bulk deflection ``d_b`` of Eq 35.
    iterations : int
        Iterations (pivots for ``"exact"``) performed.
    matvecs : int
        Applications of ``C`` to a pressure field, counting partial
        (column-subset) products by their share of a full product, rounded up.
    residual : float
        Dimensionless KKT residual (module docstring) of the returned ``p``.
    converged : bool
        ``residual <= tol``.
    method : str
        Method used.
    tol : float
        Requested tolerance on ``residual``.
    plastic_area_fraction : float
        Fraction of elements at the cap, ``p = H`` [-]; 0 without a cap.
    hardness : float or None
        Pressure cap ``H`` [Pa] of the solve; None without a cap.
    """

    pressure: np.ndarray
    displacement: np.ndarray
    gap: np.ndarray
    approach: float
    load: float
    nominal_pressure: float
    real_area_fraction: float
    max_pressure: float
    mean_plane_deflection: float
    iterations: int
    matvecs: int
    residual: float
    converged: bool
    method: str
    tol: float
    plastic_area_fraction: float = 0.0
    hardness: float | None = None


@dataclass(frozen=True)
class SweepResult:
    """Force-deflection sweep of m surfaces over k approaches.

    Every array has shape (m, k): surface by approach step, except
    ``pressure`` (m, k, *surface shape), present only when fields were asked
    for.

    Attributes
    ----------
    approach : ndarray
        Rigid-body approach ``d`` [m].
    load : ndarray
        Total force ``F`` [N].
    nominal_pressure : ndarray
        ``P = F / A_n`` [Pa].
    mean_plane_deflection : ndarray
        Mean of ``u`` [m] (Eq 35).
    real_area_fraction : ndarray
        Fraction of elements in contact, ``p > 0`` [-] (saturated ones included).
    max_pressure : ndarray
        Largest element pressure [Pa].
    tangent_stiffness : ndarray
        ``dF/dd`` [N/m] at fixed contact set (and, with a cap, fixed
        saturated set), see :func:`tangent_stiffness`; NaN where it was not
        computed. The normalized stiffness of Eq 33 is
        ``k_P = (L / A_n) dF/dd``.
    iterations, matvecs : ndarray of int
        Work of the contact solve at each step.
    residual : ndarray
        KKT residual of each solution.
    converged : ndarray of bool
        Contact solve converged.
    stiffness_converged : ndarray of bool
        The active-set solve for ``tangent_stiffness`` converged.
    pressure : ndarray or None
        Pressure fields [Pa] when ``return_fields=True``.
    method : str
        Contact method.
    tol : float
        Contact tolerance.
    plastic_area_fraction : ndarray
        Fraction of elements at the cap, ``p = H`` [-]; zeros without a cap
        (also when not given to the constructor).
    hardness : float or None
        Pressure cap ``H`` [Pa] of the sweep; None without a cap.
    profile_ranks : ndarray of int or None
        Ranks of the profiles, (R,), when ``profile=True``.
    pressure_profile : ndarray or None
        (m, k, R): the ``r``-th largest element pressure [Pa] of each solution
        at the ranks ``r`` of ``profile_ranks``.
    load_profile : ndarray or None
        (m, k, R): share of the load on the ``r`` most loaded elements [-].
    """

    approach: np.ndarray
    load: np.ndarray
    nominal_pressure: np.ndarray
    mean_plane_deflection: np.ndarray
    real_area_fraction: np.ndarray
    max_pressure: np.ndarray
    tangent_stiffness: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    pressure: np.ndarray | None
    method: str
    tol: float
    plastic_area_fraction: np.ndarray | None = None
    hardness: float | None = None
    profile_ranks: np.ndarray | None = None
    pressure_profile: np.ndarray | None = None
    load_profile: np.ndarray | None = None

    def __post_init__(self):
        zero_plastic_area(self)


def zero_plastic_area(result) -> None:
    """Give a frozen result built without ``plastic_area_fraction`` zeros (no cap) of
    its ``approach``'s shape (the ``__post_init__`` of the sweep results)."""
    if result.plastic_area_fraction is None:
        object.__setattr__(result, "plastic_area_fraction", np.zeros(np.shape(result.approach)))


# ---------------------------------------------------------------------------
# Operators and input checks


@dataclass(frozen=True)
class _Operator:
    """Uniform view of a dense matrix or a matrix-free influence operator.

    ``apply`` maps pressures stored one surface per row, shape (m, n), to
    displacements of the same shape (``u_i = C p_i``).
    """

    n: int
    apply: Callable[[np.ndarray], np.ndarray]
    diagonal: np.ndarray
    element_area: float
    surface_shape: tuple[int, int] | None
    matrix: np.ndarray | None
    zero_mean: bool = False


def _check_element_area(element_area) -> float:
    try:
        area = float(element_area)
    except (TypeError, ValueError):
        raise ValueError(
            f"element_area must be a positive area in m^2, got {element_area!r}"
        ) from None
    if not np.isfinite(area) or area <= 0.0:
        raise ValueError(f"element_area must be a finite positive area in m^2, got {area!r}")
    return area


def _check_dense(matrix: np.ndarray) -> np.ndarray:
    """Validate a dense influence matrix: square, finite, symmetric, C_ii > 0."""
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ValueError(f"operator must be a square (n, n) matrix, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        raise ValueError("operator must contain only finite influence coefficients (NaN/inf found)")
    diagonal = np.diag(matrix).copy()
    if (diagonal <= 0.0).any():
        i = int(np.argmin(diagonal))
        raise ValueError(
            f"operator must have a positive diagonal (self-compliance C_ii > 0 m/Pa), "
            f"got C[{i}, {i}] = {diagonal[i]!r}"
        )
    scale = np.abs(matrix).max()
    n = matrix.shape[0]
    block = max(1, 2_000_000 // n)
    asymmetry = 0.0
    for start in range(0, n, block):
        stop = min(n, start + block)
        part = np.abs(matrix[start:stop] - matrix[:, start:stop].T).max()
        asymmetry = max(asymmetry, float(part))
    if asymmetry > SYMMETRY_RTOL * scale:
        raise ValueError(
            f"operator must be symmetric (Eq 39): max|C - C^T| / max|C| = "
            f"{asymmetry / scale:.3g} > {SYMMETRY_RTOL:g}; symmetrize with (C + C.T) / 2"
        )
    return diagonal


def _as_operator(operator, element_area) -> _Operator:
    """Wrap ``operator`` (ndarray or matvec object) after validating it."""
    if isinstance(operator, np.ndarray) or not hasattr(operator, "matvec"):
        if element_area is None:
            raise ValueError("element_area must be given (m^2) when operator is a dense matrix")
        area = _check_element_area(element_area)
        try:
            matrix = np.ascontiguousarray(operator, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                "operator must be a dense (n, n) matrix or an object with matvec"
            ) from None
        diagonal = _check_dense(matrix)
        # C is symmetric, so the rows of P @ C are the products C p_i.
        return _Operator(matrix.shape[0], matrix.__rmatmul__, diagonal, area, None, matrix)
    missing = [name for name in ("shape", "diagonal") if not hasattr(operator, name)]
    if missing:
        raise ValueError(
            f"operator must provide matvec, shape, diagonal() and element_area; missing {missing}"
        )
    shape = tuple(operator.shape)
    if len(shape) != 2 or shape[0] != shape[1] or shape[0] < 1:
        raise ValueError(f"operator.shape must be (n, n), got {shape}")
    n = int(shape[0])
    if element_area is None:
        if not hasattr(operator, "element_area"):
            raise ValueError("element_area must be given (m^2): operator has no element_area")
        element_area = operator.element_area
    area = _check_element_area(element_area)
    diagonal = np.asarray(operator.diagonal(), dtype=float).reshape(-1)
    if diagonal.shape != (n,) or not np.isfinite(diagonal).all() or (diagonal <= 0.0).any():
        raise ValueError(
            "operator must have a finite positive diagonal (C_ii > 0 m/Pa) of length n"
        )
    surface_shape = None
    grid = getattr(operator, "grid", None)
    if grid is not None:
        nx, ny = (int(g) for g in grid)
        if nx * ny == n:
            surface_shape = (ny, nx)
    matvec = operator.matvec

    def apply(pressure: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(np.asarray(matvec(pressure.T), dtype=float).T)

    # Operators whose rows sum to zero (PeriodicHalfSpace, mean_compliance=0)
    # leave Eq 27 unbounded for d >= mean(f); see _check_bounded.
    zero_mean = getattr(operator, "mean_compliance", None) == 0.0
    return _Operator(n, apply, diagonal, area, surface_shape, None, zero_mean)


def _check_bounded(op: _Operator, gaps: np.ndarray, d: np.ndarray, name: str) -> None:
    """Reject approaches with no solution for an operator with zero row sums.

    If ``C 1 = 0`` (mean displacement fixed to zero), ``V(p + c 1) = V(p) -
    c sum(d - f)``, so Eq 27 has no minimizer (the load is unbounded) unless
    ``d < mean(f)``.
    """
    if not op.zero_mean:
        return
    mean_gap = gaps.mean(axis=1)
    if (d >= mean_gap).any():
        j = int(np.argmax(d - mean_gap))
        raise ValueError(
            f"{name} must be below the mean initial separation ({mean_gap[j]:.6g} m) for an "
            f"operator with zero mean displacement (mean_compliance = 0): beyond it the load "
            f"is unbounded; got {d[j]:.6g} m"
        )


def _check_surfaces(gaps0, op: _Operator, name: str, batched: bool):
    """Return the gaps as an (m, n) array and the shape of one surface as given.

    A single surface may be (ny, nx) or flat (n,); a batch (m, ny, nx) or (m, n).
    """
    gaps = np.asarray(gaps0, dtype=float)
    n = op.n
    expected = "(m, ny, nx) or (m, n)" if batched else "(ny, nx) or (n,)"
    if batched and (gaps.ndim not in (2, 3) or gaps.shape[0] < 1):
        raise ValueError(f"{name} must have shape {expected} with n = {n}, got {gaps.shape}")
    surface_shape = gaps.shape[1:] if batched else gaps.shape
    ok = math.prod(surface_shape) == n and len(surface_shape) in (1, 2)
    if ok and len(surface_shape) == 2 and op.surface_shape is not None:
        ok = tuple(surface_shape) == op.surface_shape
        expected = f"{expected} with (ny, nx) = {op.surface_shape}"
    if not ok:
        raise ValueError(f"{name} must have shape {expected} with n = {n}, got {gaps.shape}")
    if not np.isfinite(gaps).all():
        raise ValueError(f"{name} must be finite (NaN or inf heights found)")
    return np.ascontiguousarray(gaps.reshape(-1, n)), tuple(surface_shape)


def _check_approach(approach, m: int, name: str = "approach") -> np.ndarray:
    d = np.asarray(approach, dtype=float)
    if d.ndim == 0:
        d = np.full(m, float(d))
    if d.shape != (m,):
        raise ValueError(f"{name} must be a scalar or an array of length m = {m}, got {d.shape}")
    if not np.isfinite(d).all():
        raise ValueError(f"{name} must be finite (m)")
    if (d < 0.0).any():
        raise ValueError(f"{name} must be non-negative (rigid approach d >= 0 m), got {d.min()!r}")
    return d


def resolve_method(method: str, operator) -> str:
    """The method ``"auto"`` stands for: ``"pivot"`` for a dense matrix, else ``"cg"``.

    Other methods are returned unchanged. Block principal pivoting needs the
    dense ``C`` (its blocks ``C_AA`` are factored); a matrix-free operator
    (hybrid, half-space) is solved by CG.
    """
    if method != "auto":
        return method
    dense = isinstance(operator, np.ndarray) or getattr(operator, "matrix", None) is not None
    return "pivot" if dense else "cg"


def _check_options(method, tol, max_iter, precision="double"):
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise ValueError(f"tol must be a finite positive number, got {tol!r}") from None
    if not np.isfinite(tol) or tol <= 0.0:
        raise ValueError(f"tol must be a finite positive number, got {tol!r}")
    if max_iter is not None:
        try:
            valid = not isinstance(max_iter, bool) and int(max_iter) == max_iter >= 0
        except (TypeError, ValueError):
            valid = False
        if not valid:
            raise ValueError(f"max_iter must be a non-negative integer or None, got {max_iter!r}")
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
    return tol


def _approach_steps(approaches, m: int, unit: str) -> np.ndarray:
    """Approaches as an (m, k) array, shared (k,) ones broadcast; checked finite and >= 0."""
    steps = np.asarray(approaches, dtype=float)
    if steps.ndim == 1:
        steps = np.broadcast_to(steps, (m, steps.size))
    if steps.ndim != 2 or steps.shape[0] != m or steps.shape[1] < 1:
        raise ValueError(
            f"approaches must have shape (k,) or (m, k) with m = {m}, got {np.shape(approaches)}"
        )
    if not np.isfinite(steps).all() or (steps < 0.0).any():
        raise ValueError(f"approaches must be finite and non-negative ({unit})")
    return steps


def _default_max_iter(method: str, n: int) -> int:
    if method == "cg":
        return max(1000, 2 * n)
    if method == "steepest":
        return max(20000, 20 * n)
    return 10 * n + 100


def _check_initial_pressure(p0, m: int, n: int, name: str = "p0",
                            hardness: float | None = None) -> np.ndarray:
    """Starting pressures as (m, n) [Pa]; clipped to ``hardness`` when there is a cap."""
    if p0 is None:
        return np.zeros((m, n))
    p = np.asarray(p0, dtype=float)
    if p.size != n * m:
        raise ValueError(
            f"{name} must have the shape of the gaps ({m * n} values), got {p.shape}"
        )
    if not np.isfinite(p).all() or (p < 0.0).any():
        raise ValueError(f"{name} must be finite and non-negative (Pa)")
    p = p.reshape(m, n).copy()
    if hardness is not None:
        np.minimum(p, hardness, out=p)
    return p


def _check_hardness(hardness) -> float | None:
    """The pressure cap ``H`` [Pa] as a float, or None for no cap (None or +inf).

    Raises
    ------
    ValueError
        Naming ``hardness`` unless it is None or a positive real number (not
        NaN, not a bool, string or array).
    """
    if hardness is None:
        return None
    value = float("nan")
    if not isinstance(hardness, (bool, np.bool_, str, bytes)) and np.ndim(hardness) == 0:
        try:
            value = float(hardness)
        except (TypeError, ValueError):
            pass
    if not value > 0.0:  # also NaN
        raise ValueError(
            f"hardness must be None or a positive pressure cap in Pa, got {hardness!r}"
        )
    return None if math.isinf(value) else value


def _free(pressure: np.ndarray, hardness: float | None) -> np.ndarray:
    """Elements free to move with ``d``: ``p > 0``, and ``p < H`` with a cap."""
    if hardness is None:
        return pressure > 0.0
    return (pressure > 0.0) & (pressure < hardness)


def _plastic_fraction(pressure: np.ndarray, hardness: float | None) -> np.ndarray:
    """Fraction of elements at the cap ``p = H`` [-] per row (0 without a cap)."""
    if hardness is None:
        return np.zeros(pressure.shape[:-1])
    return np.count_nonzero(pressure >= hardness, axis=-1) / pressure.shape[-1]


def _record_step(table, rows, step, pressure, displacement, residual, op, hardness,
                 ranks=None) -> None:
    """A sweep step's summary columns of ``table`` for ``rows`` (a surface or a slice),
    from the solved pressure [Pa] and displacement [m] (last axis: elements); with
    ``ranks``, also its pressure and load profiles (:mod:`roughcontact.contact.validity`)."""
    n = pressure.shape[-1]
    load = pressure.sum(axis=-1) * op.element_area
    table["load"][rows, step] = load
    table["nominal_pressure"][rows, step] = load / (n * op.element_area)
    table["mean_plane_deflection"][rows, step] = displacement.mean(axis=-1)
    table["real_area_fraction"][rows, step] = np.count_nonzero(pressure > 0.0, axis=-1) / n
    table["max_pressure"][rows, step] = pressure.max(axis=-1)
    table["plastic_area_fraction"][rows, step] = _plastic_fraction(pressure, hardness)
    table["residual"][rows, step] = residual
    if ranks is not None:
        values, shares = validity.pressure_profile(pressure, ranks)
        table["pressure_profile"][rows, step] = values
        table["load_profile"][rows, step] = shares


# ---------------------------------------------------------------------------
# Residual


def _gap_scale(rigid: np.ndarray) -> np.ndarray:
    """Largest rigid interference ``max_i |d - f_i|`` per surface [m] (1 if zero)."""
    scale = np.abs(rigid).max(axis=1)
    return np.where(scale > 0.0, scale, 1.0)


def _residual(pressure, gap, diagonal, scale, hardness=None) -> np.ndarray:
    """Per-surface KKT residual, rows = surfaces (module docstring).

    ``max_i |min(C_ii p_i, g_i)| / scale`` without a cap; with ``hardness``
    ``H``, ``max_i |C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H)| / scale``,
    which is the same expression when ``H`` is infinite.
    """
    natural = pressure * diagonal
    if hardness is None:
        np.minimum(natural, gap, out=natural)
    else:
        natural -= np.clip(natural - gap, 0.0, hardness * diagonal)
    return np.maximum(natural.max(axis=1), -natural.min(axis=1)) / scale + 0.0


def kkt_residual(operator, gap0, approach, pressure, *, element_area=None,
                 hardness=None) -> float:
    """Dimensionless KKT residual of a pressure field for Eq 27.

    ``r = max_i |min(C_ii p_i, g_i)| / max_i |d - f_i|`` with
    ``g = C p + f - d``; zero exactly at the solution. With a cap
    ``0 <= p <= H`` the residual of the bounded problem,
    ``r = max_i |C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H)| / max_i |d - f_i|``
    (module docstring), zero exactly at its KKT point.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients [m/Pa].
    gap0 : ndarray, (ny, nx) or (n,)
        Initial separation ``f`` [m] (Eq 21).
    approach : float
        Rigid-body approach ``d`` [m].
    pressure : ndarray
        Pressure [Pa], same shape as ``gap0``.
    element_area : float, optional
        Element area [m^2]; not used by the residual, accepted for symmetry
        with :func:`solve`.
    hardness : float, optional
        Pressure cap ``H`` [Pa] of the problem the pressure is scored
        against; default None (no cap).

    Returns
    -------
    float
        The residual [-].
    """
    hardness = _check_hardness(hardness)
    op = _as_operator(operator, 1.0 if element_area is None else element_area)
    gaps, _ = _check_surfaces(gap0, op, "gap0", batched=False)
    d = _check_approach(approach, 1)
    p = np.asarray(pressure, dtype=float)
    if p.size != op.n or not np.isfinite(p).all():
        raise ValueError(f"pressure must be finite with n = {op.n} values, got {p.shape}")
    p = p.reshape(1, op.n)
    rigid = gaps - d[:, None]
    gap = op.apply(p) + rigid
    return float(_residual(p, gap, op.diagonal, _gap_scale(rigid), hardness)[0])


# ---------------------------------------------------------------------------
# Iterative methods (batched over surfaces)


@dataclass
class _Batch:
    """Per-surface outputs of a batched solve (mutable work record), rows = surfaces."""

    pressure: np.ndarray
    displacement: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray


def _new_batch(m: int, n: int) -> _Batch:
    return _Batch(
        pressure=np.zeros((m, n)),
        displacement=np.zeros((m, n)),
        iterations=np.zeros(m, dtype=int),
        matvecs=np.zeros(m),
        residual=np.zeros(m),
        converged=np.zeros(m, dtype=bool),
    )


def _sparse_product(op: _Operator, rows, cols, values, m: int, cost: np.ndarray, fast=None):
    """``delta C`` for the sparse change ``delta[rows, cols] = values``, shape (m, n).

    ``rows`` must be sorted (as from ``np.nonzero``). With a dense
    (symmetric) matrix a surface with few changed elements uses only those
    rows of ``C`` and is charged that share of a full product; the other
    touched surfaces get one batched full product (single precision when
    ``fast`` is given).
    """
    product = np.zeros((m, op.n))
    if not rows.size:
        return product
    touched, starts, counts = np.unique(rows, return_index=True, return_counts=True)
    sparse = counts <= _SPARSE_ROWS * op.n if op.matrix is not None else counts < 0
    for surface, start, count in zip(touched[sparse], starts[sparse], counts[sparse],
                                     strict=True):
        elements = cols[start : start + count]
        product[surface] = values[start : start + count] @ op.matrix[elements]
        cost[surface] += count / op.n
    dense = touched[~sparse]
    if dense.size:
        delta = np.zeros((dense.size, op.n))
        selected = np.isin(rows, dense)
        delta[np.searchsorted(dense, rows[selected]), cols[selected]] = values[selected]
        product[dense] = op.apply(delta) if fast is None else _fast_product(fast, delta)
        cost[dense] += 1.0
    return product


def _fast_product(fast, direction: np.ndarray) -> np.ndarray:
    """``direction @ C`` with the single-precision copy of ``C``, in double."""
    return (direction.astype(np.float32) @ fast).astype(float)


def _check_curvature(op: _Operator, direction, curvature, surfaces, method, iteration,
                     fast=None) -> None:
    """Refuse a non-convex problem: a search direction with ``s . C s <= 0``.

    Eq 27 is a convex problem only for a positive definite ``C``; a non-zero
    direction ``s`` with non-positive curvature proves that ``C`` is not,
    and the line search along it has no minimum (``"exact"`` refuses such a
    ``C`` when its Cholesky factorization fails). Called only when some
    curvature is ``<= 0``, so the normal iteration pays nothing: zero
    directions (nothing left to move) pass, and with ``fast`` the
    single-precision curvature is confirmed with a double-precision product
    before refusing.

    Raises
    ------
    ValueError
        Naming the surface (row of the batch), the iteration and the curvature.
    """
    rows = np.flatnonzero((curvature <= 0.0) & direction.any(axis=1))
    if not rows.size:
        return
    if fast is not None:
        exact = np.einsum("ij,ij->i", op.apply(direction[rows]), direction[rows])
        bent = exact <= 0.0
        rows, values = rows[bent], exact[bent]
        if not rows.size:
            return
    else:
        values = curvature[rows]
    norm = float(np.einsum("i,i->", direction[rows[0]], direction[rows[0]]))
    raise ValueError(
        f"operator must be positive definite: the {method} search direction s of surface "
        f"{int(surfaces[rows[0]])} at iteration {iteration} has non-positive curvature "
        f"s.C s / s.s = {values[0] / norm:.6g} m/Pa <= 0, so C has a negative or zero "
        f"eigenvalue and Eq 27 has no unique minimum; check the influence matrix "
        f"(symmetric positive definite, Eq 39)"
    )


def _iterate(op: _Operator, gaps, d, pressure, tol, max_iter, method, fast,
             hardness=None) -> _Batch:
    """Projected steepest descent or constrained CG on the rows of ``gaps``.

    Each surface (row) is an independent problem (Eq 27) with its own active
    set, search direction and convergence; finished surfaces leave the batch
    so the products ``P C`` shrink as the solve proceeds. The gap
    ``g = C p + f - d`` is updated from the product with the search direction
    and a sparse correction for the elements changed by the projection; it is
    recomputed exactly every ``_REFRESH_EVERY`` iterations and before a
    surface is accepted as converged. With ``fast`` (a single-precision copy
    of ``C``) the search-direction products are single precision; the
    rounding this leaves in ``g`` is removed by the exact recomputations
    (the first when the residual estimate reaches ``_MIXED_FLOOR``), so the
    returned solution meets ``tol`` in double precision all the same.

    With a cap ``hardness = H`` the iterates are projected onto
    ``0 <= p <= H``: for CG the free set is ``0 < p < H``, and the elements
    at the cap whose gap is positive (they would unload) leave it with
    ``p = H - step * g``, mirroring the elements out of contact that
    penetrate; elements at the cap with a negative gap stay saturated.
    """
    m, n = gaps.shape
    out = _new_batch(m, n)
    diagonal = op.diagonal
    rigid = gaps - d[:, None]
    scale = _gap_scale(rigid)
    surfaces = np.arange(m)
    p = pressure.copy()
    cost = np.zeros(m)
    gap = rigid.copy()
    loaded = np.flatnonzero(p.any(axis=1))
    if loaded.size:
        gap[loaded] += op.apply(p[loaded])
        cost[loaded] += 1.0
    stale = np.zeros(m, dtype=bool)
    verify_at = np.full(m, max(tol, _MIXED_FLOOR) if fast is not None else tol)
    direction = np.zeros((m, n))
    previous_norm = np.zeros(m)
    conjugate = np.zeros(m, dtype=bool)
    # with a cap: elements that joined or left a bound at the last projection
    moved = np.zeros((m, n), dtype=bool) if hardness is not None else None
    iteration = 0
    while surfaces.size:
        res = _residual(p, gap, diagonal, scale, hardness)
        last = iteration >= max_iter
        check = stale & ((res <= verify_at) | last)
        if check.any():
            # Accept only on an exactly recomputed gap.
            idx = np.flatnonzero(check)
            gap[idx] = op.apply(p[idx]) + rigid[idx]
            cost[idx] += 1.0
            res[idx] = _residual(p[idx], gap[idx], diagonal, scale[idx], hardness)
            stale[idx] = False
            verify_at[idx] = tol
        finished = ~stale & ((res <= tol) | last)
        if finished.any():
            idx = np.flatnonzero(finished)
            target = surfaces[idx]
            out.pressure[target] = p[idx]
            out.displacement[target] = gap[idx] - rigid[idx]
            out.iterations[target] = iteration
            out.matvecs[target] = cost[idx]
            out.residual[target] = res[idx]
            out.converged[target] = res[idx] <= tol
            keep = ~finished
            surfaces = surfaces[keep]
            if not surfaces.size:
                break
            p, gap, rigid, direction = (a[keep] for a in (p, gap, rigid, direction))
            if moved is not None:
                moved = moved[keep]
            scale, previous_norm, conjugate, cost, stale, verify_at = (
                a[keep] for a in (scale, previous_norm, conjugate, cost, stale, verify_at)
            )
        if method == "cg":
            active = _free(p, hardness)
            if moved is not None:
                # Polonsky & Keer: a joining element is in the contact set. One
                # that joined at the cap (or left it for 0) would otherwise stay
                # out of the search direction; when all join at once (no step
                # yet) their Jacobi values can all exceed H and then all be
                # released again, without end.
                active |= moved
        else:
            active = (p > 0.0) | (gap < 0.0)
            if hardness is not None:
                active &= ~((p >= hardness) & (gap < 0.0))
        gap_active = gap * active
        if method == "cg":
            norm = np.einsum("ij,ij->i", gap_active, gap_active)
            ratio = np.divide(norm, previous_norm, out=np.zeros_like(norm),
                              where=conjugate & (previous_norm > 0.0))
            direction *= ratio[:, None]
            direction += gap_active
            direction *= active
            previous_norm = norm
        else:
            direction = gap_active
        product = op.apply(direction) if fast is None else _fast_product(fast, direction)
        cost += 1.0
        numerator = np.einsum("ij,ij->i", gap_active, direction)
        denominator = np.einsum("ij,ij->i", product, direction)
        if (denominator <= 0.0).any():
            _check_curvature(op, direction, denominator, surfaces, method, iteration, fast)
        step = np.divide(numerator, denominator, out=np.zeros_like(numerator),
                         where=denominator > 0.0)
        step[~(np.isfinite(step) & (step > 0.0))] = 0.0
        p -= step[:, None] * direction
        # Projection onto p >= 0 and, for CG, the elements of Polonsky & Keer
        # that are out of contact but penetrate: they join the contact set
        # with p = -step * g (a Jacobi step -g / C_ii if there is no step), and
        # the conjugacy restarts. With a cap, the same onto p <= H: elements
        # at the cap with a positive gap leave it with p = H - step * g.
        changed = p < 0.0
        if hardness is not None:
            changed |= p > hardness
        if method == "cg":
            overlap = (p <= 0.0) & (gap < 0.0)
            changed |= overlap
            if hardness is not None:
                release = (p >= hardness) & (gap > 0.0)
                changed |= release
                overlap |= release
            conjugate = ~overlap.any(axis=1)
        rows, cols = np.nonzero(changed)
        trial = p[rows, cols]
        new = np.zeros_like(trial) if hardness is None else np.clip(trial, 0.0, hardness)
        if method == "cg":
            joins = overlap[rows, cols]
            g_join = gap[rows[joins], cols[joins]]
            s_join = step[rows[joins]]
            new[joins] = np.where(s_join > 0.0, -s_join * g_join,
                                  -g_join / diagonal[cols[joins]])
            if hardness is not None:
                # released elements start from H, joining ones from 0
                new[joins] += np.where(g_join > 0.0, hardness, 0.0)
                new[joins] = np.clip(new[joins], 0.0, hardness)
                moved[:] = False
                moved[rows[joins], cols[joins]] = True
        p[rows, cols] = new
        gap -= step[:, None] * product
        iteration += 1
        if iteration % _REFRESH_EVERY == 0:
            gap = op.apply(p) + rigid
            cost += 1.0
            stale[:] = False
        else:
            gap += _sparse_product(op, rows, cols, new - trial, p.shape[0], cost, fast)
            stale[:] = True
    out.matvecs = np.ceil(out.matvecs - 1e-9).astype(int)
    return out


# ---------------------------------------------------------------------------
# Exact method: block principal pivoting on the LCP


def _dense_matrix(op: _Operator) -> np.ndarray:
    if op.matrix is not None:
        return op.matrix
    if op.n > EXACT_MAX_UNKNOWNS:
        raise ValueError(
            f"method='exact' forms the dense matrix and is meant for up to "
            f"{EXACT_MAX_UNKNOWNS} unknowns; operator has n = {op.n}: use method='cg'"
        )
    matrix = op.apply(np.eye(op.n))
    return 0.5 * (matrix + matrix.T)


def _swap(passive: np.ndarray, upper: np.ndarray | None, flip: np.ndarray,
          over: np.ndarray | None) -> None:
    """Exchange the elements ``flip`` between the free set and their bound, in place.

    A free element leaves for the cap ``U`` if it is ``over`` it, else for
    ``p = 0``; an element at either bound becomes free.
    """
    passive ^= flip
    if upper is not None:
        upper[flip] = over[flip]


def _infeasible(passive, upper, x, w, diagonal, slack, hardness):
    """Infeasible variables of a pivoting guess, and the free ones above the cap.

    ``x < 0`` or ``x > H`` on the free set, ``w < 0`` at ``p = 0``, ``w > 0``
    at ``p = H`` (beyond the rounding ``slack`` [m]). Returns
    ``(infeasible, over)``; ``over`` is None without a cap.
    """
    if hardness is None:
        return (passive & (x * diagonal < -slack)) | (~passive & (w < -slack)), None
    over = passive & ((x - hardness) * diagonal > slack)
    infeasible = ((passive & (x * diagonal < -slack)) | over
                  | (~passive & ~upper & (w < -slack)) | (upper & (w > slack)))
    return infeasible, over


def _capped_rhs(matrix, rhs, idx, top, hardness):
    """``b_F - C_FU H``: the right-hand side on the free set ``idx`` with ``top`` at the cap."""
    if hardness is None or not top.size or not idx.size:
        return rhs
    return rhs - hardness * matrix[np.ix_(idx, top)].sum(axis=1)


def _pivoting(matrix, rhs, start, tol, max_iter, diagonal, scale, hardness=None, upper=None):
    """Block principal pivoting for ``w = C x - b, x >= 0, w >= 0, x.w = 0``.

    Returns ``(x, w, iterations)``. Infeasible variables (negative ``x`` on
    the contact set, negative ``w`` off it) are exchanged in blocks; when
    blocks stop reducing their number, single exchanges of the largest index
    (Murty's rule) guarantee finite termination for a P-matrix such as an SPD
    ``C`` (Kim & Park 2011, Algorithm 2).

    With a cap ``hardness = H`` it solves the box-constrained problem
    ``0 <= x <= H`` with three sets: free ``F``
    (``C_FF x_F = b_F - C_FU H``), ``x = 0`` and ``x = H`` (``upper``, the
    starting guess of the last); ``x > H`` on ``F`` and ``w > 0`` on the
    upper set are infeasible too, and an exchange moves a free variable to
    the bound it violates. The same block/single exchange safeguard is
    used; ``max_iter`` bounds the work in any case and an unfinished solve
    is reported by its residual.
    """
    n = rhs.size
    passive = start.copy()
    if hardness is not None:
        upper = np.zeros(n, dtype=bool) if upper is None else upper & ~passive
    best = n + 1
    budget = 3
    slack = 1e-3 * tol * scale  # infeasible only beyond rounding
    for iteration in range(max_iter + 1):
        x = np.zeros(n)
        idx = np.flatnonzero(passive)
        top = None
        if hardness is not None:
            top = np.flatnonzero(upper)
            x[top] = hardness
        if idx.size:
            try:
                factor = scipy.linalg.cho_factor(matrix[np.ix_(idx, idx)], lower=True,
                                                 check_finite=False)
            except np.linalg.LinAlgError:
                raise ValueError(
                    "operator must be positive definite: Cholesky factorization of C on "
                    "the contact set failed"
                ) from None
            x[idx] = scipy.linalg.cho_solve(
                factor, _capped_rhs(matrix, rhs[idx], idx, top, hardness), check_finite=False)
        w = matrix @ x - rhs
        infeasible, over = _infeasible(passive, upper, x, w, diagonal, slack, hardness)
        count = int(infeasible.sum())
        if count == 0 or iteration == max_iter:
            break
        if count < best:
            best, budget = count, 3
        elif budget > 0:
            budget -= 1
        else:
            single = np.zeros(n, dtype=bool)
            single[np.flatnonzero(infeasible)[-1]] = True
            infeasible = single
        _swap(passive, upper, infeasible, over)
    x = np.maximum(x, 0.0) if hardness is None else np.clip(x, 0.0, hardness)
    return x, iteration


def _exact(op: _Operator, gaps, d, pressure, tol, max_iter, hardness=None) -> _Batch:
    m, n = gaps.shape
    matrix = _dense_matrix(op)
    out = _new_batch(m, n)
    rigid = gaps - d[:, None]
    scale = _gap_scale(rigid)
    for j in range(m):
        loaded = pressure[j].any()
        start = _free(pressure[j], hardness) if loaded else rigid[j] < 0.0
        upper = pressure[j] >= hardness if loaded and hardness is not None else None
        x, iterations = _pivoting(matrix, -rigid[j], start, tol, max_iter, op.diagonal,
                                  scale[j], hardness, upper)
        u = matrix @ x
        out.pressure[j] = x
        out.displacement[j] = u
        out.iterations[j] = iterations
        out.matvecs[j] = iterations + 2
        out.residual[j] = _residual(x[None], (u + rigid[j])[None], op.diagonal,
                                    scale[j : j + 1], hardness)[0]
        out.converged[j] = out.residual[j] <= tol
    out.matvecs = out.matvecs.astype(int)
    return out


def _fast_matrix(op: _Operator, precision: str, method: str):
    """Single-precision copy of a dense ``C`` for ``precision="mixed"``, else None."""
    if precision == "mixed" and op.matrix is not None and method not in ("exact", "pivot"):
        return op.matrix.astype(np.float32)
    return None


def _run(op, gaps, d, pressure, method, tol, max_iter, fast=None, hardness=None) -> _Batch:
    if max_iter is None:
        max_iter = _default_max_iter(method, op.n)
    if method in ("exact", "pivot"):
        batch = _exact(op, gaps, d, pressure, tol, int(max_iter), hardness)
    else:
        batch = _iterate(op, gaps, d, pressure, tol, int(max_iter), method, fast, hardness)
    failed = np.flatnonzero(~batch.converged)
    if failed.size:
        logger.warning(
            "contact solve (%s) did not converge in %d iterations for %d of %d surfaces; "
            "largest KKT residual %.3g > tol %.3g",
            method, int(max_iter), failed.size, gaps.shape[0],
            float(batch.residual[failed].max()), tol,
        )
    return batch


def _result(batch: _Batch, j: int, rigid_j, op: _Operator, shape, method, tol,
            approach, hardness=None) -> ContactResult:
    p = batch.pressure[j]
    u = batch.displacement[j]
    load = float(p.sum() * op.element_area)
    return ContactResult(
        pressure=p.reshape(shape).copy(),
        displacement=u.reshape(shape).copy(),
        gap=(u + rigid_j).reshape(shape),
        approach=float(approach),
        load=load,
        nominal_pressure=load / (op.n * op.element_area),
        real_area_fraction=float(np.count_nonzero(p > 0.0)) / op.n,
        max_pressure=float(p.max()),
        mean_plane_deflection=float(u.mean()),
        iterations=int(batch.iterations[j]),
        matvecs=int(batch.matvecs[j]),
        residual=float(batch.residual[j]),
        converged=bool(batch.converged[j]),
        method=method,
        tol=tol,
        plastic_area_fraction=float(_plastic_fraction(p, hardness)),
        hardness=hardness,
    )


# ---------------------------------------------------------------------------
# Public solvers


def solve(operator, gap0, approach, *, method="cg", tol=1e-10, max_iter=None, p0=None,
          element_area=None, precision="double", hardness=None) -> ContactResult:
    """Contact pressure under a rigid flat at prescribed approach (Eq 27).

    Minimizes ``V = 1/2 p.C p - p.(d - f)`` over ``p >= 0`` (Eq 17, 18, 27 of
    Kumar et al. 2006): at the solution the gap ``u + f - d`` vanishes where
    ``p > 0`` and is non-negative elsewhere (Eq 19-22), ``u = C p`` (Eq 16).

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa]: a dense symmetric matrix (then
        ``element_area`` is required) or an object with ``matvec``, ``shape``,
        ``diagonal()`` and ``element_area`` (e.g. ``PeriodicHalfSpace``).
    gap0 : ndarray, (ny, nx) or (n,)
        Initial separation ``f = z_max - z`` [m] (Eq 21), element order
        ``k = iy * nx + ix``. Results come back in the same shape.
    approach : float
        Rigid-body approach ``d >= 0`` [m] (displacement control).
    method : {"cg", "steepest", "exact", "pivot", "auto"}
        See the module docstring; ``"pivot"`` is ``"exact"`` for a single
        solve, ``"auto"`` is ``"pivot"`` for a dense matrix and ``"cg"``
        for a matrix-free operator (:func:`resolve_method`).
    tol : float
        Tolerance on the dimensionless KKT residual (module docstring).
    max_iter : int, optional
        Iteration limit; default ``max(1000, 2n)`` for ``"cg"``,
        ``max(20000, 20n)`` for ``"steepest"``, ``10n + 100`` pivots for
        ``"exact"``.
    p0 : ndarray, optional
        Non-negative starting pressure [Pa] (warm start), shape of ``gap0``;
        default zero. ``"exact"`` takes its support as the first contact set.
    element_area : float, optional
        Element area ``dA`` [m^2]; default ``operator.element_area``.
    precision : {"double", "mixed"}
        ``"mixed"`` takes the search-direction products of ``"cg"`` and
        ``"steepest"`` with a single-precision copy of a dense ``C`` (about
        twice as fast); convergence is still decided on double-precision
        residuals, so the result meets ``tol`` either way. Ignored for
        matrix-free operators and ``"exact"``.
    hardness : float, optional
        Pressure cap ``H`` [Pa] (elastic-perfectly-plastic elements): solves
        Eq 27 over ``0 <= p <= H`` instead of ``p >= 0``; default None (no
        cap; ``+inf`` is the same). See the module docstring. ``p0`` is
        clipped to ``H``.

    Returns
    -------
    ContactResult
        Solution and diagnostics. If the limit is reached first, the last
        iterate is returned with ``converged=False`` and a warning is logged
        on the ``roughcontact.contact`` logger.

    Raises
    ------
    ValueError
        On invalid input; the message names the argument.
    """
    tol = _check_options(method, tol, max_iter, precision)
    hardness = _check_hardness(hardness)
    op = _as_operator(operator, element_area)
    method = resolve_method(method, op)
    gaps, shape = _check_surfaces(gap0, op, "gap0", batched=False)
    d = _check_approach(approach, 1)
    _check_bounded(op, gaps, d, "approach")
    pressure = _check_initial_pressure(p0, 1, op.n, hardness=hardness)
    fast = _fast_matrix(op, precision, method)
    batch = _run(op, gaps, d, pressure, method, tol, max_iter, fast, hardness)
    return _result(batch, 0, gaps[0] - d[0], op, shape, method, tol, d[0], hardness)


def solve_many(operator, gaps0, approach, *, method="cg", tol=1e-10, max_iter=None, p0=None,
               element_area=None, precision="double",
               hardness=None) -> tuple[ContactResult, ...]:
    """Solve m contact problems with one operator in one batched call (Eq 27).

    Same problem as :func:`solve` for each surface; the iterative methods
    work on all unfinished surfaces at once with matrix-matrix products
    ``[p_1 ... p_m]^T C`` (BLAS 3 for a dense matrix), each surface keeping
    its own contact set, search direction and convergence flag; finished
    surfaces drop out of the products.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`solve`.
    gaps0 : ndarray, (m, ny, nx) or (m, n)
        Initial separations ``f`` [m] (Eq 21), one per surface.
    approach : float or ndarray (m,)
        Rigid-body approach ``d >= 0`` [m], shared or per surface.
    method, tol, max_iter, element_area, precision, hardness
        As in :func:`solve`.
    p0 : ndarray, optional
        Starting pressures [Pa], shape of ``gaps0``.

    Returns
    -------
    tuple of ContactResult
        One result per surface, fields shaped like one surface of ``gaps0``.
    """
    tol = _check_options(method, tol, max_iter, precision)
    hardness = _check_hardness(hardness)
    op = _as_operator(operator, element_area)
    method = resolve_method(method, op)
    gaps, shape = _check_surfaces(gaps0, op, "gaps0", batched=True)
    m = gaps.shape[0]
    d = _check_approach(approach, m)
    _check_bounded(op, gaps, d, "approach")
    pressure = _check_initial_pressure(p0, m, op.n, hardness=hardness)
    fast = _fast_matrix(op, precision, method)
    batch = _run(op, gaps, d, pressure, method, tol, max_iter, fast, hardness)
    return tuple(
        _result(batch, j, gaps[j] - d[j], op, shape, method, tol, d[j], hardness)
        for j in range(m)
    )


# ---------------------------------------------------------------------------
# Tangent stiffness


def _active_set_cg(op: _Operator, active, start, tol, max_iter, fast=None):
    """Solve ``C_AA x = 1`` on each surface's contact set ``A`` by CG.

    ``active`` (m, n) bool; ``start`` (m, n) initial guess (used on ``A``).
    Stops when ``||1 - C_AA x|| <= tol ||1_A||`` (Euclidean), checked on a
    double-precision residual; with ``fast`` the CG products are single
    precision and the solve restarts from the exact residual (iterative
    refinement) until it is met. Returns ``(x, converged, products)``.
    """
    m, n = active.shape
    mask = active.astype(float)
    x = start * mask
    products = np.zeros(m, dtype=int)
    target = np.sqrt(mask.sum(axis=1))
    converged = target == 0.0
    surfaces = np.flatnonzero(~converged)
    xs, ms = x[surfaces], mask[surfaces]
    limit = (tol * target[surfaces]) ** 2
    iteration = 0
    while surfaces.size and iteration < max_iter:
        # Exact residual, then CG until its recursive estimate meets tol.
        residual = ms - ms * op.apply(xs)
        products[surfaces] += 1
        rr = np.einsum("ij,ij->i", residual, residual)
        done = rr <= limit
        if done.any():
            x[surfaces[done]] = xs[done]
            converged[surfaces[done]] = True
            keep = ~done
            surfaces, xs, ms, residual, rr, limit = (
                a[keep] for a in (surfaces, xs, ms, residual, rr, limit)
            )
            if not surfaces.size:
                break
        direction = residual.copy()
        inner = np.ones(surfaces.size, dtype=bool)
        while inner.any() and iteration < max_iter:
            iteration += 1
            if fast is None:
                q = op.apply(direction)
            else:
                q = _fast_product(fast, direction)
            q *= ms
            products[surfaces] += inner
            curvature = np.einsum("ij,ij->i", direction, q)
            alpha = np.divide(rr, curvature, out=np.zeros_like(rr),
                              where=inner & (curvature > 0.0))
            xs += alpha[:, None] * direction
            residual -= alpha[:, None] * q
            rr_new = np.einsum("ij,ij->i", residual, residual)
            inner &= (rr_new > limit) & (alpha > 0.0)
            beta = np.divide(rr_new, rr, out=np.zeros_like(rr), where=rr > 0.0)
            direction *= beta[:, None]
            direction += residual
            direction[~inner] = 0.0
            rr = rr_new
    x[surfaces] = xs
    return x, converged, products


def tangent_stiffness(operator, pressure, *, element_area=None, tol=1e-10, max_iter=None,
                      x0=None, hardness=None) -> float:
    """Tangent contact stiffness ``dF/dd`` [N/m] at a solved contact state.

    On a fixed contact set ``A`` (elements with ``p > 0``) the solution of
    Eq 27 satisfies ``C_AA p_A = d 1 - f_A``, so ``dp_A/dd = x`` with
    ``C_AA x = 1`` and

        dF/dd = dA * 1^T x = dA * 1^T (C_AA)^-1 1.

    With a cap ``H`` the saturated elements (``p = H``) do not move with
    ``d``: ``A`` is then the free set ``0 < p < H`` only
    (``C_AA p_A = d 1 - f_A - C_AU H``, whose right-hand side changes with
    ``d`` only through ``d 1``), and the saturated load ``H dA |U|`` adds
    nothing to ``dF/dd``.

    This is the derivative of the load-approach curve between changes of the
    contact set (its one-sided derivative where the set changes), without the
    noise of a finite difference. ``x`` is found by conjugate gradients on
    ``A``. It feeds the normalized stiffness ``k_P = (L / A_n) dF/dd`` of
    Eq 33.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`solve`.
    pressure : ndarray
        Solved contact pressure [Pa]; only its support ``p > 0`` is used.
    element_area : float, optional
        Element area ``dA`` [m^2]; default ``operator.element_area``.
    tol : float
        Relative Euclidean residual of ``C_AA x = 1`` at which CG stops.
    max_iter : int, optional
        CG iteration limit, default ``max(1000, 2n)``.
    x0 : ndarray, optional
        Starting guess for ``x = (C_AA)^-1 1`` [Pa/m] (warm start).
    hardness : float, optional
        Pressure cap ``H`` [Pa] of the solve that gave ``pressure``;
        elements with ``p >= H`` are left out of ``A``. Default None.

    Returns
    -------
    float
        ``dF/dd`` [N/m]; 0 without contact. A warning is logged if CG does
        not reach ``tol``.
    """
    hardness = _check_hardness(hardness)
    op = _as_operator(operator, element_area)
    p = np.asarray(pressure, dtype=float)
    if p.size != op.n or not np.isfinite(p).all():
        raise ValueError(f"pressure must be finite with n = {op.n} values, got {p.shape}")
    tol = _check_options("cg", tol, max_iter)
    start = np.zeros((1, op.n))
    if x0 is not None:
        start = np.asarray(x0, dtype=float).reshape(1, op.n)
    limit = _default_max_iter("cg", op.n) if max_iter is None else int(max_iter)
    x, converged, _ = _active_set_cg(op, _free(p.reshape(1, op.n), hardness), start, tol,
                                     limit)
    if not converged[0]:
        logger.warning("tangent stiffness: CG on the contact set did not reach tol %.3g", tol)
    return float(op.element_area * x.sum())


# ---------------------------------------------------------------------------
# Sweep


def _warn_unconverged(flags, table, method, tol) -> None:
    failed = ~flags["converged"]
    if failed.any():
        logger.warning(
            "contact sweep (%s): %d of %d steps did not converge; largest KKT residual "
            "%.3g > tol %.3g", method, int(failed.sum()), failed.size,
            float(table["residual"][failed].max()), tol)


def _predict(pressure, approach, last_approach, rate, hardness=None) -> np.ndarray:
    """First-order predictor ``max(p + (d - d_last) dp/dd, 0)`` [Pa] for the next step.

    On a fixed contact set the solution of Eq 27 is linear in ``d``
    (``C_AA p_A = d 1 - f_A``), so with the exact ``dp/dd`` the prediction is
    the solution whenever no element enters or leaves contact; rows of
    ``rate`` that are not finite (no rate yet) keep ``p``. With a cap the
    prediction is clipped to ``[0, H]``.
    """
    delta = (approach - last_approach)[:, None]
    predicted = pressure + delta * np.nan_to_num(rate, nan=0.0, posinf=0.0, neginf=0.0)
    if hardness is not None:
        return np.clip(predicted, 0.0, hardness, out=predicted)
    return np.maximum(predicted, 0.0, out=predicted)


class _PivotState:
    """Block principal pivoting of one surface through its approach steps (:func:`_pivot_sweep`)."""

    __slots__ = ("step", "passive", "upper", "best", "budget", "rounds", "factor", "index",
                 "members")

    def __init__(self, passive: np.ndarray, upper: np.ndarray | None = None):
        self.step = 0
        # the free set, and with a cap the saturated set (p = H; None without)
        self.passive, self.upper = passive, upper
        self.best, self.budget, self.rounds = passive.size + 1, 3, 0
        # lower Cholesky factor of C on the elements ``index`` (in that order),
        # and the same set as a mask
        self.factor, self.index, self.members = None, None, None

    def refactor(self, matrix: np.ndarray) -> str:
        """Bring the factor to the current contact guess: keep it if the set is
        unchanged, extend it if elements were only added, else factor anew.
        Returns which of ``"kept"``, ``"extended"``, ``"new"`` it did."""
        if self.members is not None and np.array_equal(self.passive, self.members):
            return "kept"
        idx = np.flatnonzero(self.passive)
        grown = (self.members is not None and self.index.size
                 and not (self.members & ~self.passive).any())
        try:
            if grown:
                added = np.flatnonzero(self.passive & ~self.members)
                coupling = scipy.linalg.solve_triangular(
                    self.factor, matrix[np.ix_(self.index, added)], lower=True,
                    check_finite=False)
                corner = scipy.linalg.cholesky(
                    matrix[np.ix_(added, added)] - coupling.T @ coupling, lower=True,
                    check_finite=False)
                size = self.index.size
                factor = np.zeros((size + added.size, size + added.size))
                factor[:size, :size] = self.factor
                factor[size:, :size] = coupling.T
                factor[size:, size:] = corner
                self.factor, self.index = factor, np.concatenate([self.index, added])
                kind = "extended"
            elif idx.size:
                self.factor = scipy.linalg.cholesky(matrix[np.ix_(idx, idx)], lower=True,
                                                    check_finite=False)
                self.index, kind = idx, "new"
            else:
                self.factor, self.index, kind = None, idx, "new"
        except np.linalg.LinAlgError:
            raise ValueError(
                "operator must be positive definite: Cholesky factorization of C on "
                "the contact set failed"
            ) from None
        self.members = self.passive.copy()
        return kind

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``(C_AA)^-1 rhs_A`` in the factor's element order."""
        return scipy.linalg.cho_solve((self.factor, True), rhs, check_finite=False)

    def exchange(self, infeasible: np.ndarray, over: np.ndarray | None = None) -> None:
        """Kim & Park (2011), Algorithm 2: block exchanges while they reduce the
        number of infeasible variables (3 tries otherwise), then Murty's single
        exchange of the largest index, which terminates for a P-matrix. With
        a cap, free elements ``over`` it move to the saturated set."""
        count = int(infeasible.sum())
        if count < self.best:
            self.best, self.budget = count, 3
        elif self.budget > 0:
            self.budget -= 1
        else:
            single = np.zeros_like(infeasible)
            single[np.flatnonzero(infeasible)[-1]] = True
            infeasible = single
        _swap(self.passive, self.upper, infeasible, over)

    def restart(self, passive: np.ndarray, upper: np.ndarray | None = None) -> None:
        self.passive, self.upper = passive, upper
        self.best, self.budget, self.rounds = passive.size + 1, 3, 0


def _pivot_sweep(op: _Operator, gaps, steps, tol, max_iter, stiffness, table, counts, flags,
                 fields, hardness=None, ranks=None) -> None:
    """Every surface's sweep by block principal pivoting, all in flight at once.

    Each surface advances through its own steps; every round factors each
    in-flight surface's ``C_AA`` on its current contact guess ``A``
    (Cholesky), solves ``C_AA p_A = d - f_A``, and then computes the gaps of
    *all* in-flight surfaces, whatever step each is at, with one product
    ``P C`` (the only pass over ``C``). A surface whose guess is consistent
    (``p_A >= 0``, ``g >= 0`` off ``A``, to rounding) has solved its step:
    its tangent ``(C_AA)^-1 1`` comes from the same factor, and its next step
    starts at once from the predicted set ``{p + (d' - d) dp/dd > 0}``.
    With a cap ``hardness = H`` each surface also keeps a saturated set
    ``U`` (``p = H``): the free set solves ``C_FF p_F = d - f_F - C_FU H``,
    ``p > H`` on it and ``g > 0`` on ``U`` are infeasible too, the tangent
    is ``(C_FF)^-1 1`` (saturated elements fixed) and the predicted ``U``
    is ``{p + (d' - d) dp/dd >= H}``.
    Fills the (m, k) arrays of ``table``, ``counts``, ``flags`` in place.
    """
    m, n = gaps.shape
    k = steps.shape[1]
    matrix, diagonal = _dense_matrix(op), op.diagonal
    empty = None if hardness is None else np.zeros(n, dtype=bool)
    states = [_PivotState(gaps[j] - steps[j, 0] < 0.0, None if empty is None else empty.copy())
              for j in range(m)]
    ones = np.ones(n)
    while True:
        flight = [j for j in range(m) if states[j].step < k]
        if not flight:
            return
        rows = len(flight)
        x = np.zeros((rows, n))
        for r, j in enumerate(flight):
            state = states[j]
            state.refactor(matrix)
            top = None
            if hardness is not None:
                top = np.flatnonzero(state.upper)
                x[r, top] = hardness
            if state.index.size:
                idx = state.index
                x[r, idx] = state.solve(_capped_rhs(
                    matrix, steps[j, state.step] - gaps[j, idx], idx, top, hardness))
        gap = x @ matrix  # C is symmetric: the rows are C p
        for r, j in enumerate(flight):
            state = states[j]
            step = state.step
            d = steps[j, step]
            gap[r] += gaps[j] - d
            state.rounds += 1
            scale = _gap_scale((gaps[j] - d)[None])[0]
            slack = 1e-3 * tol * scale
            infeasible, over = _infeasible(state.passive, state.upper, x[r], gap[r], diagonal,
                                           slack, hardness)
            if infeasible.any() and state.rounds <= max_iter:
                state.exchange(infeasible, over)
                continue
            if hardness is None:
                p = np.maximum(x[r], 0.0)
            else:
                p = np.clip(x[r], 0.0, hardness)
            residual = _residual(p[None], gap[r][None], diagonal, np.array([scale]),
                                 hardness)[0]
            _record_step(table, j, step, p, gap[r] - gaps[j] + d, residual, op, hardness,
                         ranks)
            counts["iterations"][j, step] = state.rounds
            counts["matvecs"][j, step] = state.rounds
            flags["converged"][j, step] = residual <= tol
            rate = np.zeros(n)
            if state.index.size and (stiffness or step + 1 < k):
                rate[state.index] = state.solve(ones[: state.index.size])
            if stiffness:
                table["tangent_stiffness"][j, step] = op.element_area * rate.sum()
                flags["stiffness_converged"][j, step] = True
            if fields is not None:
                fields[j, step] = p.reshape(fields.shape[2:])
            state.step += 1
            if state.step < k:
                predicted = p + (steps[j, state.step] - d) * rate
                start, upper = predicted > 0.0, None
                if hardness is not None:
                    upper = predicted >= hardness
                    start &= ~upper
                    if not upper.any() and not start.any():
                        upper = empty.copy()
                        start = gaps[j] - steps[j, state.step] < 0.0
                elif not start.any():
                    start = gaps[j] - steps[j, state.step] < 0.0
                state.restart(start, upper)


def sweep(operator, gaps0, approaches, *, method="cg", tol=1e-10, max_iter=None,
          element_area=None, return_fields=False, stiffness=True, stiffness_tol=1e-6,
          precision="double", extrapolate=True, hardness=None, profile=False) -> SweepResult:
    """Force-deflection curves of m surfaces over k approaches (Eq 27, 33, 35).

    Solves Eq 27 for every surface at every approach, all surfaces at once
    (see :func:`solve_many`), each step warm-started from the previous
    solution or, with ``extrapolate``, from its first-order extrapolation
    ``max(p_k + (d_k+1 - d_k) dp/dd, 0)``: ``dp/dd`` is the tangent
    ``(C_AA)^-1 1`` of the stiffness solve when ``stiffness`` is on, else the
    secant of the last two steps. On an unchanged contact set the solution is
    linear in ``d`` (Eq 27), so the prediction is then exact up to the
    stiffness tolerance and the contact solve only corrects the elements
    that enter or leave contact. With ``stiffness`` the tangent stiffness
    ``dF/dd = dA 1^T (C_AA)^-1 1`` (see :func:`tangent_stiffness`) is found
    at every step by CG on the contact set, warm-started from the previous
    step's ``(C_AA)^-1 1``.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`solve`.
    gaps0 : ndarray, (m, ny, nx) or (m, n)
        Initial separations ``f`` [m] (Eq 21).
    approaches : ndarray, (k,) or (m, k)
        Rigid-body approaches ``d >= 0`` [m] at each step, shared or per
        surface; warm starts help most when they increase.
    method, tol, max_iter, element_area, precision, hardness
        As in :func:`solve`; ``precision`` also applies to the stiffness CG.
        With ``hardness`` the tangent and the extrapolation hold the
        saturated elements (``p = H``) fixed.
    return_fields : bool
        Keep the pressure fields (m, k, *surface shape) [Pa].
    stiffness : bool
        Compute ``tangent_stiffness`` (otherwise NaN).
    stiffness_tol : float
        Relative residual of the active-set CG for the stiffness; the
        relative error of ``dF/dd`` is of the same order or smaller.
    extrapolate : bool
        Start each step from the extrapolated pressure (above) instead of the
        previous solution. Only the starting point changes: every solution
        still meets ``tol``.
    profile : bool
        Keep every solution's pressure and load profiles
        (:func:`roughcontact.contact.validity.pressure_profile` at the ranks
        of :func:`~roughcontact.contact.validity.rank_grid`): enough to tell,
        for any hardness chosen later, how much of the contact area and load
        lies above it (:func:`~roughcontact.contact.validity.fractions_above`).

    Returns
    -------
    SweepResult
    """
    tol = _check_options(method, tol, max_iter, precision)
    try:
        stiffness_tol = _check_options("cg", stiffness_tol, None)
    except ValueError:
        raise ValueError(
            f"stiffness_tol must be a finite positive number, got {stiffness_tol!r}"
        ) from None
    hardness = _check_hardness(hardness)
    op = _as_operator(operator, element_area)
    method = resolve_method(method, op)
    gaps, shape = _check_surfaces(gaps0, op, "gaps0", batched=True)
    m, n = gaps.shape
    steps = _approach_steps(approaches, m, "m")
    _check_bounded(op, gaps, steps.max(axis=1), "approaches")
    k = steps.shape[1]
    names = ("load", "nominal_pressure", "mean_plane_deflection", "real_area_fraction",
             "max_pressure", "residual", "plastic_area_fraction")
    table = {name: np.zeros((m, k)) for name in names}
    table["tangent_stiffness"] = np.full((m, k), np.nan)
    counts = {name: np.zeros((m, k), dtype=int) for name in ("iterations", "matvecs")}
    flags = {name: np.zeros((m, k), dtype=bool) for name in ("converged", "stiffness_converged")}
    fields = np.zeros((m, k, *shape)) if return_fields else None
    ranks = validity.rank_grid(n) if profile else None
    if profile:
        table["pressure_profile"] = np.zeros((m, k, ranks.size))
        table["load_profile"] = np.zeros((m, k, ranks.size))
    if method == "pivot":
        limit = _default_max_iter("exact", n) if max_iter is None else int(max_iter)
        _pivot_sweep(op, gaps, steps, tol, limit, stiffness, table, counts, flags, fields,
                     hardness, ranks)
        _warn_unconverged(flags, table, method, tol)
        return SweepResult(approach=np.array(steps), pressure=fields, method=method, tol=tol,
                           hardness=hardness, profile_ranks=ranks, **table, **counts, **flags)
    pressure = np.zeros((m, n))
    tangent = np.zeros((m, n))
    cg_limit = _default_max_iter("cg", n)
    fast = _fast_matrix(op, precision, method)
    rate = np.full((m, n), np.nan)
    for step in range(k):
        start = pressure
        if extrapolate and step > 0:
            start = _predict(pressure, steps[:, step], steps[:, step - 1], rate, hardness)
        batch = _run(op, gaps, steps[:, step].copy(), start, method, tol, max_iter, fast,
                     hardness)
        if extrapolate and not stiffness:
            # Secant dp/dd of this step, for the next prediction.
            delta = steps[:, step] - (steps[:, step - 1] if step > 0 else np.nan)
            with np.errstate(invalid="ignore", divide="ignore"):
                rate = (batch.pressure - pressure) / delta[:, None]
        pressure = batch.pressure
        _record_step(table, slice(None), step, pressure, batch.displacement, batch.residual, op,
                     hardness, ranks)
        counts["iterations"][:, step] = batch.iterations
        counts["matvecs"][:, step] = batch.matvecs
        flags["converged"][:, step] = batch.converged
        if stiffness:
            tangent, ok, _ = _active_set_cg(op, _free(pressure, hardness), tangent,
                                            stiffness_tol, cg_limit, fast)
            table["tangent_stiffness"][:, step] = op.element_area * tangent.sum(axis=1)
            rate = tangent
            flags["stiffness_converged"][:, step] = ok
            if not ok.all():
                logger.warning(
                    "tangent stiffness: active-set CG did not reach tol %.3g for %d surfaces "
                    "at step %d", stiffness_tol, int((~ok).sum()), step,
                )
        if return_fields:
            fields[:, step] = pressure.reshape(m, *shape)
    return SweepResult(
        approach=np.array(steps),
        pressure=fields,
        method=method,
        tol=tol,
        hardness=hardness,
        profile_ranks=ranks,
        **table,
        **counts,
        **flags,
    )
