"""The contact methods by name, and the solves at one approach (:func:`solve`, :func:`solve_many`).

A solve takes a :class:`~roughcontact.contact.problem.Problem` (the operator, the
gaps, the cap) and a :class:`~roughcontact.contact.problem.SolverOptions` (the
method by name, ``tol``, ``max_iter``, ``precision``, ``load_tol``, ``retries``);
they meet in a :class:`Solver`, the method looked up once in :data:`REGISTRY`.

Frictionless normal contact of a rigid flat with a rough elastic body
(Section 3 of Kumar, Sadeghi & Krousgrill 2006): given the influence
coefficients ``C`` (Eq 16), the initial separation ``f = z_max - z`` (Eq
21) and the rigid-body approach ``d``, find the contact pressure ``p`` that
minimizes the complementary energy (Eq 17, 18, 27)

    V(p) = 1/2 p . C p - p . (d - f)    subject to    p >= 0,

whose optimality (KKT) conditions are Eq 19-22: with the gap
``g = u + f - d`` and ``u = C p``, ``g = 0`` where ``p > 0`` (contact) and
``g >= 0`` where ``p = 0`` (separation). Every method stops on the same KKT
residual (:mod:`roughcontact.contact.kkt`). All quantities are SI: ``p``
in Pa, ``u``, ``f``, ``d``, ``g`` in m, ``C`` in m/Pa, loads in N.

Hardness cap: with ``hardness = H`` [Pa] every method minimizes the same
``V(p)`` over ``0 <= p <= H`` (elastic-perfectly-plastic elements); the
elements at ``H`` are the plastic area (``plastic_area_fraction`` of the
results, included in ``real_area_fraction``). ``hardness=None`` (the
default) is the uncapped problem, computed exactly as without a cap.
A capped solution depends on ``H L / (E sigma)`` besides the surface shape
and ``d / sigma``, so one dimensionless solve
(:mod:`roughcontact.contact.nondim`) serves every (sigma, E, H) with the
same ``H L / (E sigma)``.

Methods (:data:`REGISTRY`; :data:`METHODS` also holds ``"auto"``):

``"steepest"``
    Projected steepest descent, the paper's method (Fig 6;
    :mod:`roughcontact.contact.steepest`); a slow baseline.
``"cg"``
    Constrained conjugate gradients of Polonsky & Keer (1999)
    (:mod:`roughcontact.contact.cg`).
``"pcg"``
    Preconditioned constrained CG for grid FFT operators (half-space,
    periodic, spectral, hybrid block: a
    :class:`~roughcontact.elasticity.protocol.PreconditionedOperator`):
    the |q| stencil preconditioner on the free set, Polak-Ribiere
    conjugacy kept across changes of the contact set, float32 direction
    products with ``precision="mixed"``, load control inside the iteration,
    cold solves above 128 x 128 started from coarser grids
    (:mod:`roughcontact.contact.pcg`, :mod:`roughcontact.contact.nested`).
    Any other operator is solved unpreconditioned. No hardness cap.
``"pivot"``
    Block principal pivoting (:mod:`roughcontact.contact.pivot`), finite,
    for dense matrices (or up to a few thousand unknowns): the reference.
    Its sweep keeps every surface in flight at once.
``"exact"``
    The same pivoting, whose sweep solves one approach at a time with the
    shared approach loop (:mod:`roughcontact.contact.sweeps`); for a single
    solve it is ``"pivot"``.
``"auto"``
    ``"pivot"`` for a dense matrix, ``"pcg"`` for a grid FFT operator
    without a hardness cap, ``"cg"`` for any other matrix-free operator or a
    capped problem on one (:func:`resolve_method`); the default.

Iteration limits (the options' ``max_iter``, default ``Method.default_max_iter``):
``max(1000, 2n)`` for ``"cg"``, ``20 max(1000, 4 sqrt(n))`` for ``"pcg"``
(which also stops a solve whose residual has not halved in
``max(1000, 4 sqrt(n))`` iterations), ``max(20000, 20n)`` for
``"steepest"``, ``10n + 100`` pivots.

Tolerances and retries: every result is ``converged`` only if its KKT
residual met ``tol`` and, under load control, its load met ``load_tol``
(:mod:`roughcontact.contact.loads`). A solve that stops short is solved
again cold, then by block principal pivoting where the matrix is dense or
can be formed, and only then returned flagged, the attempts logged
(:mod:`roughcontact.contact.retries`; options with ``retries=False`` return a
method's own result).

Operators: ``operator`` is a dense symmetric influence matrix (ndarray, n x
n, m/Pa; then ``element_area`` [m^2] must be given), an
:class:`roughcontact.elasticity.protocol.InfluenceOperator` (such as
:class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace`), or any
object with ``shape == (n, n)``, ``diagonal()`` and ``matvec(p)`` accepting
(n,) and (n, m) arrays; it is checked and wrapped once
(:func:`roughcontact.contact.checks.as_operator`) and certified symmetric
positive definite (:func:`roughcontact.contact.checks.check_definite`):
Eq 27 has one minimizer only then, and a method meeting its tolerance on
an indefinite ``C`` would prove nothing. The certificate is kept on the
operator object, so pass a
:class:`~roughcontact.elasticity.protocol.DenseInfluence` rather than a
plain ndarray to solve many times with one dense matrix (the Cholesky
factorization of a 60 x 60 grid's matrix costs about one second).

Precision: ``precision="mixed"`` takes the search-direction products of
``"cg"`` and ``"steepest"`` with a single-precision copy of a dense ``C``
(about twice as fast), and as float32 FFTs of a grid FFT operator (also the
direction products of ``"pcg"``); convergence is still decided on
double-precision residuals, so the result meets ``tol`` either way. Ignored
by pivoting and by other matrix-free operators.

Performance: the products ``C p`` dominate the iterative methods.
:func:`solve_many` and :func:`roughcontact.contact.sweep` apply ``C`` to all
unfinished surfaces at once (BLAS 3), and ``precision="mixed"`` takes the
search-direction products in single precision (about half the time; the
result still meets ``tol`` in double precision): from a float32 copy of a
dense matrix, or float32 FFTs of a grid operator (``"pcg"``). On a 2-core machine
shared with other jobs one BLAS thread (``OPENBLAS_NUM_THREADS=1``) was
faster than two.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughcontact.contact import cg, checks, pcg, pivot, steepest
from roughcontact.contact.controls import Approaches, Loads
from roughcontact.contact.problem import DEFAULT_OPTIONS, Problem, SolverOptions
from roughcontact.contact.products import PRECISIONS, Products
from roughcontact.contact.result import Batch, ContactResult
from roughcontact.contact.retries import settle

__all__ = ["METHODS", "PRECISIONS", "REGISTRY", "Method", "Solver", "check_method",
           "fallbacks", "method_for", "resolve_method", "solve", "solve_many", "solve_problem"]

@dataclass(frozen=True)
class Method:
    """A contact method: how it solves a batch at one approach, and its approach sweep.

    Attributes
    ----------
    name : str
        Its name in :data:`REGISTRY`, recorded in the results.
    solve : callable
        ``solve(products, gaps, d, pressure, tol, max_iter, hardness) -> Batch``.
    default_max_iter : callable
        Iteration limit for ``n`` unknowns when none is given.
    single_precision : bool
        Takes single-precision search products (``precision="mixed"``).
    sweep : callable or None
        ``sweep(solver, steps, table)`` (a :class:`Solver`), its own
        approach loop; None: the shared loop of :mod:`roughcontact.contact.sweeps`.
    load : callable or None
        ``load(products, gaps, P, pressure, tol, max_iter, hardness) -> (Batch,
        approaches)``, load control at mean pressures ``P`` [Pa] inside the
        method; None: an outer solve on the approach
        (:mod:`roughcontact.contact.loads`).
    """

    name: str
    solve: Callable[..., Batch]
    default_max_iter: Callable[[int], int]
    single_precision: bool
    sweep: Callable[..., None] | None = None
    load: Callable[..., tuple] | None = None

    def max_iter(self, max_iter, n: int) -> int:
        """``max_iter`` as an int, or the method's default for ``n`` unknowns."""
        return self.default_max_iter(n) if max_iter is None else int(max_iter)

    def products(self, operator, precision: str) -> Products:
        """The products of a solve with ``operator`` at ``precision``."""
        return Products.of(operator, precision, self.single_precision)


#: The methods by name.
REGISTRY = {
    "steepest": Method("steepest", steepest.solve, steepest.default_max_iter, True),
    "cg": Method("cg", cg.solve, cg.default_max_iter, True),
    "exact": Method("exact", pivot.solve, pivot.default_max_iter, False),
    "pivot": Method("pivot", pivot.solve, pivot.default_max_iter, False, pivot.sweep),
    "pcg": Method("pcg", pcg.solve, pcg.default_max_iter, True, load=pcg.solve_load),
}


def _auto(operator, hardness) -> str:
    """Block principal pivoting needs the dense ``C`` (it factors its blocks
    ``C_AA``); a grid FFT operator (half-space, periodic, spectral, hybrid)
    is solved by preconditioned CG unless capped, any other matrix-free
    operator or a capped problem by CG."""
    if checks.given_matrix(operator) is not None:
        return "pivot"
    uncapped = hardness is None or np.isinf(float(hardness))
    return "pcg" if uncapped and checks.preconditioned_operator(operator) is not None else "cg"


#: Names that stand for a method chosen from the operator.
_CHOSEN = {"auto": _auto}
METHODS = (*REGISTRY, *_CHOSEN)


def check_method(method) -> None:
    """``method`` is one of :data:`METHODS`."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")


def resolve_method(method: str, operator, hardness=None) -> str:
    """The method ``"auto"`` stands for: ``"pivot"`` for a dense matrix, ``"pcg"`` for
    a grid FFT operator without a cap (``hardness`` [Pa] None), else ``"cg"``.

    Other methods are returned unchanged. Block principal pivoting needs the
    dense ``C`` (its blocks ``C_AA`` are factored); the preconditioned CG
    needs a :class:`~roughcontact.elasticity.protocol.PreconditionedOperator`
    and solves only the uncapped problem; CG takes any operator and a cap.
    """
    choose = _CHOSEN.get(method)
    return method if choose is None else choose(operator, hardness)


def method_for(method: str, operator, hardness=None) -> Method:
    """The :class:`Method` ``method`` names for ``operator`` (``"auto"`` resolved)."""
    return REGISTRY[resolve_method(method, operator, hardness)]


def fallbacks(method: Method, operator) -> tuple:
    """The methods tried, in turn, on a surface ``method`` left unconverged
    (:mod:`roughcontact.contact.retries`), each with its products: block principal
    pivoting where ``operator`` holds its dense matrix or can form it
    (:data:`roughcontact.contact.pivot.EXACT_MAX_UNKNOWNS`), unless ``method`` pivots
    already; none otherwise."""
    if method.name in ("pivot", "exact"):
        return ()
    if operator.matrix is None and operator.shape[0] > pivot.EXACT_MAX_UNKNOWNS:
        return ()
    exact = REGISTRY["exact"]
    return ((exact, exact.products(operator, "double")),)


@dataclass(frozen=True)
class Solver:
    """A :class:`~roughcontact.contact.problem.Problem` and its
    :class:`~roughcontact.contact.problem.SolverOptions` bound to the method chosen
    for them (:meth:`of`): what every solve and sweep of the problem runs.

    Attributes
    ----------
    problem : Problem
        What is solved (checked).
    options : SolverOptions
        How (checked).
    method : Method
        The method ``options.method`` names for the problem (``"auto"`` resolved,
        :func:`method_for`).
    max_iter : int
        Its iteration limit (``options.max_iter``, or the method's default for ``n``
        unknowns).
    products : Products
        The products ``C p`` of its solves at ``options.precision``.
    fallbacks : tuple
        The methods tried in turn on an unconverged surface (:func:`fallbacks`);
        empty without ``options.retries``.
    """

    problem: Problem
    options: SolverOptions
    method: Method
    max_iter: int
    products: Products
    fallbacks: tuple

    @classmethod
    def of(cls, problem: Problem, options: SolverOptions) -> Solver:
        """The solver of ``problem`` with ``options`` (the method's name checked)."""
        check_method(options.method)
        op = problem.operator
        chosen = method_for(options.method, op, problem.hardness)
        return cls(problem, options, chosen, chosen.max_iter(options.max_iter, op.shape[0]),
                   chosen.products(op, options.precision),
                   fallbacks(chosen, op) if options.retries else ())

    def settle(self, control, start) -> tuple[Batch, np.ndarray]:
        """Every surface of the problem under ``control``
        (:class:`~roughcontact.contact.controls.Approaches` or ``Loads``) from ``start``
        [Pa], retried where unconverged (:func:`roughcontact.contact.retries.settle`);
        the batch and the approaches [m]."""
        return settle(self.method, self.products, self.problem.gaps, control, start,
                      self.options.tol, self.max_iter, self.problem.hardness, self.fallbacks,
                      retry=self.options.retries)


def solve_problem(problem: Problem, approach=None, *, mean_pressure=None, p0=None,
                  options: SolverOptions = DEFAULT_OPTIONS) -> tuple[ContactResult, ...]:
    """Solve every surface of ``problem`` at ``approach`` [m] or ``mean_pressure`` [Pa]
    from ``p0`` [Pa] (None: zero) with ``options``, retried where unconverged
    (:mod:`roughcontact.contact.retries`); one :class:`ContactResult` each, fields in
    ``problem.shape``. The arguments as in :func:`solve_many`."""
    solver = Solver.of(problem, options)
    gaps, hardness = problem.gaps, problem.hardness
    m, n = gaps.shape
    checks.check_control(approach, mean_pressure)
    if mean_pressure is None:
        d = checks.check_approach(approach, m)
        checks.check_bounded(problem.operator, gaps, d, "approach", hardness)
        control = Approaches(d)
    else:
        control = Loads(checks.check_mean_pressure(mean_pressure, m), options.load_tol)
    pressure = checks.check_initial_pressure(p0, m, n, hardness=hardness)
    batch, d = solver.settle(control, pressure)
    return tuple(batch.contact_result(j, gaps[j] - d[j], problem.operator.element_area,
                                      problem.shape, str(batch.solved_by[j]), options.tol, d[j],
                                      hardness)
                 for j in range(m))


def solve(operator, gap0, approach=None, *, mean_pressure=None, p0=None, hardness=None,
          element_area=None, options: SolverOptions = DEFAULT_OPTIONS) -> ContactResult:
    """Contact pressure under a rigid flat at prescribed approach or mean pressure (Eq 27).

    Minimizes ``V = 1/2 p.C p - p.(d - f)`` over ``p >= 0`` (Eq 17, 18, 27 of
    Kumar et al. 2006): at the solution the gap ``u + f - d`` vanishes where
    ``p > 0`` and is non-negative elsewhere (Eq 19-22), ``u = C p`` (Eq 16).
    The short form of ``solve_problem(Problem.of(operator, gap0, ...), ...)[0]``
    (:class:`~roughcontact.contact.problem.Problem`, :func:`solve_problem`).

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa]: a dense symmetric matrix (then
        ``element_area`` is required) or an operator object (module
        docstring), e.g. ``PeriodicHalfSpace``.
    gap0 : ndarray, (ny, nx) or (n,)
        Initial separation ``f = z_max - z`` [m] (Eq 21), element order
        ``k = iy * nx + ix``. Results come back in the same shape.
    approach : float, optional
        Rigid-body approach ``d >= 0`` [m] (displacement control).
    mean_pressure : float, optional
        Nominal pressure ``P = sum p / n >= 0`` [Pa] instead (load control,
        :mod:`roughcontact.contact.loads`); the approach is found with the solution.
    p0 : ndarray, optional
        Non-negative starting pressure [Pa] (warm start), shape of ``gap0``;
        default zero. Pivoting takes its support as the first contact set.
    hardness : float, optional
        Pressure cap ``H`` [Pa]: Eq 27 over ``0 <= p <= H`` (module docstring);
        default None (no cap; ``+inf`` is the same). ``p0`` is clipped to ``H``.
    element_area : float, optional
        Element area ``dA`` [m^2]; default ``operator.element_area``.
    options : SolverOptions
        The method (module docstring; ``"auto"``, the default: :func:`resolve_method`),
        the KKT tolerance ``tol`` (default 1e-10), ``max_iter``, ``precision``, the
        load's ``load_tol`` and ``retries``
        (:class:`~roughcontact.contact.problem.SolverOptions`).

    Returns
    -------
    ContactResult
        Solution and diagnostics; ``converged=False`` (and a warning naming the
        attempts) only if every attempt failed. Invalid input raises ValueError
        naming the argument.
    """
    problem = Problem.of(operator, gap0, hardness=hardness, element_area=element_area,
                         batched=False)
    return solve_problem(problem, approach, mean_pressure=mean_pressure, p0=p0,
                         options=options)[0]


def solve_many(operator, gaps0, approach=None, *, mean_pressure=None, p0=None, hardness=None,
               element_area=None,
               options: SolverOptions = DEFAULT_OPTIONS) -> tuple[ContactResult, ...]:
    """Solve m contact problems with one operator in one batched call (Eq 27).

    Same problem as :func:`solve` for each surface; all unfinished surfaces
    are worked on at once with matrix-matrix products ``[p_1 ... p_m]^T C``
    (BLAS 3 for a dense matrix), each surface keeping its own contact set,
    search direction and convergence flag; finished surfaces drop out of the
    products. The short form of ``solve_problem(Problem.of(operator, gaps0, ...), ...)``.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`solve`.
    gaps0 : ndarray, (m, ny, nx) or (m, n)
        Initial separations ``f`` [m] (Eq 21), one per surface.
    approach : float or ndarray (m,), optional
        Rigid-body approach ``d >= 0`` [m], shared or per surface.
    mean_pressure : float or ndarray (m,), optional
        Mean pressure ``P >= 0`` [Pa] instead (load control, see :func:`solve`).
    p0 : ndarray, optional
        Starting pressures [Pa], shape of ``gaps0``.
    hardness, element_area, options
        As in :func:`solve`.

    Returns
    -------
    tuple of ContactResult
        One result per surface, fields shaped like one surface of ``gaps0``.
    """
    problem = Problem.of(operator, gaps0, hardness=hardness, element_area=element_area)
    return solve_problem(problem, approach, mean_pressure=mean_pressure, p0=p0,
                         options=options)
