"""Preconditioned constrained conjugate gradients for Eq 27 on FFT grid operators.

Solves the frictionless contact of a rigid flat with a rough elastic body on
a grid: find ``p`` [Pa] minimising the complementary energy (Eq 17, 18, 27
of Kumar et al. 2006)

    V(p) = 1/2 p . C p - p . (d - f)        subject to  p >= 0,

whose KKT conditions (Eq 19-22) are ``g = 0`` where ``p > 0`` and ``g >= 0``
where ``p = 0``, with the gap ``g = C p + f - d`` [m]. Two controls:
*displacement control* (the approach ``d`` [m] given) and *load control*
(the mean pressure ``P`` [Pa] given, ``sum p = n P``; ``d`` is then the
Lagrange multiplier of that constraint and is returned as the approach).

Method (Polonsky & Keer 1999, with the preconditioner and the conjugacy of
ASPHER and the changes measured for issue 28), on the free set
``F = {p > 0}`` kept as sorted flat indices:

1. Mean mode. Load control: ``alpha = mean_F(u + f)`` (Polonsky & Keer's
   mean-gap shift). Displacement control: ``p`` and ``u`` are scaled by
   ``s = (d - mean_F f) / mean_F u``, which puts the mean gap on ``F`` at
   exactly ``d`` (exact for the scaling mode, no product), and ``alpha = d``.
2. Residual ``r = (u + f - alpha)_F``; elements out of ``F`` with
   ``u + f < alpha`` penetrate.
3. Stop on the KKT residual of :mod:`roughcontact.contact.kkt` (``d =
   alpha``), decided on an exactly recomputed (double-precision) ``u``.
4. Preconditioner: the 13-tap stencil of ``E* |q| / 2`` (the inverse of the
   half-space symbol ``2 / (E* |q|)``, the operator's
   :meth:`~roughcontact.elasticity.protocol.PreconditionedOperator.preconditioner`;
   for the hybrid block that of its Love part) applied on ``F`` only and
   centred on ``F`` before and after.
5. Direction ``t = z + beta t_old``, Polak-Ribiere+ ``beta >= 0``, *kept*
   across changes of ``F`` (new elements start at 0; Polonsky & Keer
   restart, which costs 3.5x the iterations at 17 % contact), centred on
   ``F``; restarted if not a descent direction.
6. Step ``tau = r.t / t.(w - mean_F w)``, ``w = C t``; ``p <- p - tau t``;
   elements that fall to ``p <= 0`` leave, penetrating ones join with
   ``p = -tau_J (u + f - alpha)``, ``tau_J = (r.t)^2 / (t.(w - mean w) |r|^2)``.
   ``u`` is carried: ``u <- u - tau w`` plus ``C e`` for the clipped and
   joined amounts ``e``, by kernel columns when few elements changed
   (``column_budget`` of the operator), else by one product. Load control
   rescales ``p`` and ``u`` to the load.

One product per iteration (two when many elements changed), one stencil
application. Precision ``"mixed"``: every product of a direction or a
correction is float32, ``p``, ``u`` and every reduction float64; ``u`` is
recomputed exactly (one float64 product) when the residual first falls
below :data:`EXACT_AT`, before every acceptance and every
:data:`REFRESH_EVERY` iterations; an exact residual :data:`DRIFT_FACTOR`
times the carried one switches the remaining products to float64. Measured:
the same iterations as all-double products down to tol 1e-11, 2-3 double
products per solve. ``"double"`` takes every product in float64.

Starts: a warm start (a sweep's previous or predicted pressure) as given;
a cold start on a grid of more than :data:`NESTED_MIN_ELEMENTS` elements
from the coarser grids' solutions (:mod:`roughcontact.contact.nested`,
coarse levels to 1e-3); otherwise the lower half of the gap range uniformly
loaded. Operators that are not grid FFT operators (a dense matrix) are
solved by the same iteration without preconditioner, coarse levels or
float32 FFTs (their float32 products come from a float32 copy of the
matrix).

Batches: the surfaces of a batch are solved together. Each surface's solve
is a generator (:func:`solve_steps`) that yields every product it needs;
:func:`run_solves` advances all the solves in flight one product at a time
and takes the products waiting on the same operator in the same precision
as one batched product (for the hybrid block one batched FFT for Love's
part and one GEMM for the finite-body correction, whose product with one
surface at a time is memory-bound). Free sets, step lengths, iteration
counts, the drift safeguard and the float64 KKT test stay per surface:
each surface gets the iterates it gets alone, up to the rounding of the
batched product. At most :data:`IN_FLIGHT_ELEMENTS` elements are in flight.

References
----------
I. A. Polonsky, L. M. Keer, Wear 231 (1999) 206-219.
V. A. Yastrebov, ASPHER 0.1.3 (2025), src/contact_solver.cpp.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from roughcontact.contact.checks import preconditioned_operator
from roughcontact.contact.free_stencil import FreeSetStencil
from roughcontact.contact.kkt import gap_scale, kkt_residuals
from roughcontact.contact.nested import level_operators, nested_solve
from roughcontact.contact.products import SINGLE_PRECISION, Products
from roughcontact.contact.result import Batch
from roughcontact.elasticity.transforms import Stencil

__all__ = ["DRIFT_FACTOR", "EXACT_AT", "IN_FLIGHT_ELEMENTS", "NESTED_MIN_ELEMENTS",
           "REFRESH_EVERY", "STALL_WINDOWS", "ProductRequest", "Solution", "constrained_pcg",
           "default_max_iter", "grid_operator", "run_solves", "solve", "solve_load",
           "solve_steps", "stall_window"]

#: Residual at which the carried displacement is first recomputed in double.
EXACT_AT = 1e-5
#: Iterations between exact recomputations of u when no check happened.
REFRESH_EVERY = 200
#: An exact residual this many times the carried one switches products to double.
DRIFT_FACTOR = 10.0
#: Cold solves on grids of more elements start from coarser grids (nested continuation).
NESTED_MIN_ELEMENTS = 128 * 128
#: Elements of the surfaces solved together (64 surfaces at 256^2, 4 at 1024^2): bounds
#: the memory of the batched products and of the solves in flight.
IN_FLIGHT_ELEMENTS = 2**22


#: A solve's iteration limit is this many stall windows (:func:`stall_window`).
STALL_WINDOWS = 20


def stall_window(n: int) -> int:
    """Iterations without progress after which a solve of ``n`` unknowns stops:
    ``max(1000, 4 sqrt(n))``.

    Progress is the KKT residual falling below half its best value so far. A
    preconditioned solve on a grid FFT operator converges in O(sqrt(n))
    iterations (measured for issue 28: 100-600 at 64^2-1024^2); an
    unpreconditioned one on an ill-conditioned dense block (the paper's mesh,
    condition number 1e8) may need several thousand and still halve its residual
    every few hundred iterations, while a solve whose free set cycles (measured: a
    32 x 32 paper-mesh block under load control, the residual between 0.43 and 0.66
    for 20000 iterations) makes none. So the budget follows the problem: a solve
    goes on while it converges, up to :func:`default_max_iter`, and one that stalls
    stops after this window, to be retried (:mod:`roughcontact.contact.retries`).
    """
    return max(1000, int(4 * np.sqrt(n)))


def default_max_iter(n: int) -> int:
    """Iteration limit for ``n`` unknowns: :data:`STALL_WINDOWS` stall windows,
    ``20 max(1000, 4 sqrt(n))``; a solve that stalls stops earlier (:func:`stall_window`)."""
    return STALL_WINDOWS * stall_window(n)


@dataclass(frozen=True)
class Solution:
    """One solve of :func:`constrained_pcg` (arrays of the surface's ``(ny, nx)`` shape).

    ``pressure`` [Pa]; ``displacement`` ``u = C p`` [m], exact (float64);
    ``approach`` [m] (given, or found under load control); ``iterations``;
    ``products`` (float32 and float64 products plus kernel columns by their
    share of a product); ``residual`` the KKT residual on the exact ``u``.
    """

    pressure: np.ndarray
    displacement: np.ndarray
    approach: float
    iterations: int
    products: float
    residual: float


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """``a . b`` without BLAS (a threaded BLAS spin-waits between these small products)."""
    return float(np.einsum("i,i->", a, b))


@dataclass(frozen=True)
class ProductRequest:
    """A product the solve of one surface waits for: ``C e`` [m] on ``operator``'s grid,
    ``e[rows, cols] = values`` [Pa], taken in ``dtype`` (float32 or float64)."""

    operator: object
    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray
    dtype: type


class _Products:
    """Products of the operator in the working precision, counted; sparse ones by columns.

    :meth:`product` and :meth:`exact` are generators: they yield a
    :class:`ProductRequest` and receive its product from :func:`run_solves`, which
    takes the products of all the surfaces in flight together.
    """

    def __init__(self, operator, single: bool):
        self.operator = operator
        self.n = operator.grid[0] * operator.grid[1]
        self.single = single
        # the kernel columns are float32: used only for single-precision corrections
        self.budget = operator.column_budget if single else -1
        self.count = 0.0

    def use_double(self) -> None:
        """Continue with double-precision products (drift safeguard)."""
        self.single, self.budget = False, -1

    def product(self, rows, cols, values):
        """``C e`` for ``e[rows, cols] = values``, in the working precision (a generator)."""
        self.count += 1.0
        dtype = np.float32 if self.single else np.float64
        return (yield ProductRequest(self.operator, rows, cols, values, dtype))

    def exact(self, rows, cols, values):
        """``C e`` in double precision, as a C-contiguous float64 array (a generator)."""
        self.count += 1.0
        product = yield ProductRequest(self.operator, rows, cols, values, np.float64)
        return np.array(product, dtype=np.float64, order="C")

    def add(self, target, rows, cols, values):
        """``target += C e``: kernel columns for a few elements, else one product
        (a generator)."""
        if rows.size <= self.budget:
            self.count += rows.size / self.n
            self.operator.add_columns(target, rows, cols, values)
        else:
            target += yield from self.product(rows, cols, values)


class _Iteration:
    """The state of one solve: free set, its pressures, the carried displacement."""

    def __init__(self, operator, gap0, approach, mean_pressure, pressure0, single: bool):
        self.f = np.ascontiguousarray(gap0, dtype=np.float64)
        ny, nx = self.f.shape
        self.nx, self.n = nx, nx * ny
        self.f_flat = self.f.reshape(-1)
        self.f_min, self.f_max = float(self.f.min()), float(self.f.max())
        self.diagonal = np.asarray(operator.diagonal(), dtype=np.float64).reshape(-1)
        self.approach = approach
        self.total_load = None if mean_pressure is None else float(mean_pressure) * self.n
        self.work = _Products(operator, single)
        self.stencil = FreeSetStencil(operator.preconditioner(), (ny, nx))
        if pressure0 is not None and np.any(pressure0 > 0.0):
            flat = np.flatnonzero(np.asarray(pressure0).reshape(-1) > 0.0)
            p_free = np.asarray(pressure0, dtype=np.float64).reshape(-1)[flat]
        else:  # the lower half of the gap range, uniformly loaded (rescaled at once)
            flat = np.flatnonzero(self.f_flat <= self.f_min + 0.5 * (self.f_max - self.f_min))
            p_free = np.ones(flat.size)
        self._set_free(flat, p_free)
        if self.total_load is not None:
            self.p_free *= self.total_load / self.p_free.sum()
        self.u = None  # C p, from :meth:`start`
        self.in_free = np.zeros(self.n, dtype=bool)
        self.in_free[flat] = True
        self.t_free = np.zeros(flat.size)
        self.r_prev = np.zeros(flat.size)
        self.zr_old = 1.0
        self.conjugate = False

    def _set_free(self, flat, p_free) -> None:
        self.flat, self.p_free = flat, p_free
        self.rows, self.cols = np.divmod(flat, self.nx)
        self.f_free = self.f_flat[flat]
        self.c_free = self.diagonal[flat]

    def start(self):
        """``u = C p`` of the starting pressure, in the working precision (a generator)."""
        u = yield from self.work.product(self.rows, self.cols, self.p_free)
        self.u = np.array(u, dtype=np.float64, order="C")

    def residual(self) -> float:
        """Mean mode, residual on ``F``, penetrations; the KKT residual (module docstring)."""
        rows, cols = self.rows, self.cols
        if self.total_load is None and rows.size:
            u_mean = float(self.u[rows, cols].mean())
            if u_mean > 0.0:
                s = max((self.approach - float(self.f_free.mean())) / u_mean, 0.0)
                self.p_free *= s
                self.u *= s
        v_free = self.u[rows, cols] + self.f_free
        self.alpha = float(v_free.mean()) if self.total_load is not None else self.approach
        self.r_free = v_free - self.alpha
        combined = (self.u + self.f).reshape(-1)
        out = np.flatnonzero(combined < self.alpha)
        self.out_flat = out[~self.in_free[out]]
        self.g_out = combined[self.out_flat] - self.alpha
        natural = np.minimum(self.c_free * self.p_free, self.r_free)
        worst = max(float(natural.max(initial=0.0)), -float(natural.min(initial=0.0)),
                    -float(self.g_out.min(initial=0.0)))
        return worst / (max(self.alpha - self.f_min, self.f_max - self.alpha) or 1.0)

    def recompute(self):
        """``u = C p`` exactly (double precision; a generator)."""
        self.u = yield from self.work.exact(self.rows, self.cols, self.p_free)

    def step(self):
        """One preconditioned CG step on ``F`` and the update of ``F`` (module docstring;
        a generator)."""
        descent = (yield from self._descend()) if self.rows.size >= 2 else None
        if descent is None:  # nothing to descend on F: Jacobi activation of the penetrating
            trial, tau_join = self.p_free, None  # elements (one element, or r = 0 on F)
        else:
            trial, tau_join = descent
        leaving = trial <= 0.0
        if leaving.any() or self.out_flat.size:
            yield from self._change_set(trial, leaving, tau_join)
        else:
            self.p_free = trial
            self.conjugate = True
        if self.total_load is not None:
            s = self.total_load / self.p_free.sum()
            self.p_free *= s
            self.u *= s

    def _descend(self):
        """Direction, step length and the carried ``u``; the trial pressures on ``F``
        (a generator).

        None when the direction vanishes: then only the free set can change.
        """
        r_free = self.r_free
        z = self.stencil(self.rows, self.cols, r_free, centred=True)
        if not z.any():  # r is constant on F (its mean is set by the rescaling)
            return None
        zr = _dot(z, r_free)
        conjugate = self.conjugate and self.zr_old > 0.0
        beta = max(0.0, _dot(z, r_free - self.r_prev) / self.zr_old) if conjugate else 0.0
        t_free = z + beta * self.t_free if beta else z
        if beta:
            t_free -= t_free.mean()  # a carried direction must keep the mean mode
            if not _dot(r_free, t_free) > 0.0:
                t_free = z  # not a descent direction: restart
        self.t_free, self.r_prev, self.zr_old = t_free, r_free, zr
        ct = yield from self.work.product(self.rows, self.cols, t_free)
        ct_free = ct[self.rows, self.cols].astype(np.float64)
        ct_free -= ct_free.mean()
        num, den = _dot(r_free, t_free), _dot(ct_free, t_free)
        if not den > 0.0:
            raise ValueError(
                f"operator must be positive definite: the pcg direction has non-positive "
                f"curvature t.C t = {den:g} on the contact set")
        tau = num / den
        rr = _dot(r_free, r_free)
        self.u -= tau * ct
        return self.p_free - tau * t_free, (num * num / (den * rr) if rr > 0.0 else tau)

    def _change_set(self, trial, leaving, tau_join):
        """Clip the leaving elements, add the penetrating ones, correct ``u`` for both
        (a generator)."""
        out_flat = self.out_flat
        if tau_join is None:
            p_join = -self.g_out / self.diagonal[out_flat]
        else:
            p_join = -tau_join * self.g_out
        out_rows, out_cols = np.divmod(out_flat, self.nx)
        yield from self.work.add(self.u, np.concatenate([self.rows[leaving], out_rows]),
                                 np.concatenate([self.cols[leaving], out_cols]),
                                 np.concatenate([-trial[leaving], p_join]))
        self.in_free[self.flat[leaving]] = False
        self.in_free[out_flat] = True
        kept = ~leaving
        flat = self.flat[kept]
        where = np.searchsorted(flat, out_flat)  # merge two sorted index sets
        self._set_free(np.insert(flat, where, out_flat), np.insert(trial[kept], where, p_join))
        self.t_free = np.insert(self.t_free[kept], where, 0.0)
        self.r_prev = np.insert(self.r_prev[kept], where, 0.0)
        self.conjugate = True

    def pressure(self) -> np.ndarray:
        """The pressure field [Pa], shape of the gap."""
        p = np.zeros(self.n)
        p[self.flat] = self.p_free
        return p.reshape(self.f.shape)


def constrained_pcg(operator, gap0, *, approach=None, mean_pressure=None, tol=1e-8,
                    pressure0=None, max_iter=None, single=True) -> Solution:
    """Solve Eq 27 on a grid operator by preconditioned constrained CG (module docstring).

    Parameters
    ----------
    operator : roughcontact.elasticity.protocol.PreconditionedOperator
        ``C`` [m/Pa] on the grid of ``gap0``.
    gap0 : ndarray (ny, nx)
        Initial separation ``f`` [m] (Eq 21).
    approach : float, optional
        Rigid approach ``d`` [m] (displacement control).
    mean_pressure : float, optional
        Mean pressure ``P >= 0`` [Pa] (load control); exactly one of the two.
    tol : float
        Tolerance on the KKT residual (:mod:`roughcontact.contact.kkt`).
    pressure0 : ndarray (ny, nx), optional
        Starting pressure [Pa] (a warm start or a coarser grid's solution);
        default the lower half of the gap range, uniformly loaded.
    max_iter : int, optional
        Iteration limit, default :func:`default_max_iter`; a solve whose residual
        has not halved in :func:`stall_window` iterations stops before it.
    single : bool
        Direction and correction products in float32 (``precision="mixed"``).

    Returns
    -------
    Solution
        Its ``residual`` is computed on the exact ``u``; it exceeds ``tol``
        only when ``max_iter`` was reached or the solve stalled.
    """
    return run_solves([solve_steps(operator, gap0, approach=approach,
                                   mean_pressure=mean_pressure, tol=tol, pressure0=pressure0,
                                   max_iter=max_iter, single=single)])[0]


def solve_steps(operator, gap0, *, approach=None, mean_pressure=None, tol=1e-8, pressure0=None,
                max_iter=None, single=True):
    """:func:`constrained_pcg` as a generator of its products, for :func:`run_solves`.

    It yields every product it needs (a :class:`ProductRequest`), is sent the
    product, and returns the :class:`Solution`. The arguments are those of
    :func:`constrained_pcg`, checked here (before the first product).
    """
    if (approach is None) == (mean_pressure is None):
        raise ValueError("give exactly one of approach (m) and mean_pressure (Pa)")
    f = np.asarray(gap0, dtype=np.float64)
    max_iter = default_max_iter(f.size) if max_iter is None else int(max_iter)
    return _iterate(operator, f, None if approach is None else float(approach), mean_pressure,
                    tol, pressure0, max_iter, single)


def _iterate(operator, f, approach, mean_pressure, tol, pressure0, max_iter, single):
    """The iteration of :func:`constrained_pcg` on checked arguments (a generator)."""
    if mean_pressure is not None and not mean_pressure > 0.0:
        return _unloaded(f, tol)
    state = _Iteration(operator, f, approach, mean_pressure, pressure0, single)
    yield from state.start()
    exact, exact_next, carried = False, EXACT_AT, np.inf
    iteration = since_exact = 0
    window = stall_window(f.size)
    best, progress_at = np.inf, 0  # the best residual's last halving, and when
    while True:
        res = state.residual()
        if res <= 0.5 * best:
            best, progress_at = res, iteration
        if exact and since_exact == 0 and state.work.single \
                and res > max(DRIFT_FACTOR * carried, tol):
            state.work.use_double()  # the float32 recurrence drifted: continue in double
        stop = iteration >= max_iter or iteration - progress_at >= window
        if res <= max(tol, exact_next) or stop or since_exact >= REFRESH_EVERY:
            if not exact:
                yield from state.recompute()
                exact, since_exact, exact_next, carried = True, 0, tol, res
                continue  # the residual again, on the exact u
            if res <= tol or stop:
                break
        yield from state.step()
        exact = False
        since_exact += 1
        iteration += 1
    pressure = state.pressure()
    rigid = (f - state.alpha).reshape(1, -1)
    residual = kkt_residuals(pressure.reshape(1, -1), state.u.reshape(1, -1) + rigid,
                             state.diagonal, gap_scale(rigid))
    return Solution(pressure, state.u, state.alpha, iteration, state.work.count,
                    float(residual[0]))


def _unloaded(f: np.ndarray, tol: float) -> Solution:
    """Zero load: no pressure, the flat just touching the highest point (``d = min f``)."""
    zero = np.zeros_like(f)
    return Solution(zero, zero.copy(), float(f.min()), 0, 0.0, 0.0)


def run_solves(solves, in_flight: int = 1) -> list:
    """Run generator solves (:func:`solve_steps`) together; their results, in order.

    At most ``in_flight`` solves advance at a time; the next one starts
    when one ends. Each round every solve in flight waits for one product:
    the requests on the same operator in the same dtype are scattered into
    one ``(k, ny, nx)`` batch and taken as one product (for the hybrid block
    its Love part one batched FFT, its finite-body correction one GEMM), and
    each solve is sent its own row. Each solve keeps its own free set, step
    lengths, iteration count and convergence test: the result of every solve
    is the one it gives alone, up to the rounding of the batched product.
    """
    solves = list(solves)
    results = [None] * len(solves)
    pending = {}  # index -> (generator, its request)

    def advance(i, generator, product):
        try:
            pending[i] = (generator, generator.send(product))
        except StopIteration as stop:
            pending.pop(i, None)
            results[i] = stop.value

    queue = iter(enumerate(solves))

    def refill():
        for i, generator in queue:
            advance(i, generator, None)
            if len(pending) >= limit:
                return

    limit = max(1, int(in_flight))
    refill()
    while pending:
        for members, product in _batched_products(pending):
            for j, i in enumerate(members):
                advance(i, pending[i][0], product[j])
        if len(pending) < limit:
            refill()
    return results


def _batched_products(pending: dict):
    """The products of the pending requests, one per (operator, dtype): ``(members,
    products)`` pairs, ``products[j]`` that of solve ``members[j]``."""
    groups = {}
    for i, (_, request) in pending.items():
        groups.setdefault((id(request.operator), request.dtype), []).append(i)
    out = []
    for members in groups.values():
        requests = [pending[i][1] for i in members]
        operator = requests[0].operator
        nx, ny = operator.grid
        fields = np.zeros((len(members), ny, nx), dtype=requests[0].dtype)
        for field, request in zip(fields, requests, strict=True):
            field[request.rows, request.cols] = request.values
        out.append((members, operator.apply(fields)))
    return out


class _Unpreconditioned:
    """Any other operator seen as one row of ``n`` elements, without a preconditioner.

    Products by ``matvec`` (float32 ones from the single-precision copy of a
    dense matrix when there is one), the identity as stencil, kernel columns
    from the rows of a dense matrix; no coarser copy.
    """

    def __init__(self, products: Products):
        self.products = products
        n = products.operator.shape[0]
        self.grid = (n, 1)
        matrix = products.operator.matrix
        self.column_budget = max(1, n // 32) if matrix is not None else 0

    def apply(self, pressure):
        """``C p`` of fields ``(k, 1, n)`` [Pa], float32 ones from the float32 matrix."""
        flat = pressure.reshape(-1, self.grid[0])
        if pressure.dtype == np.float32 and isinstance(self.products.single, np.ndarray):
            return (flat @ self.products.single).reshape(pressure.shape)
        return self.products.exact(flat.astype(np.float64)).reshape(pressure.shape)

    def diagonal(self):
        return self.products.operator.diagonal()

    def preconditioner(self):
        return Stencil(np.zeros((1, 2), dtype=int), np.ones(1), False)

    def add_columns(self, target, rows, cols, values) -> None:
        target += np.asarray(values) @ self.products.operator.matrix[cols]


def grid_operator(products: Products):
    """The grid operator behind ``products``, or the unpreconditioned view of any other
    (one row of ``n`` elements, the identity as stencil) that :func:`run_solves` takes
    the products of alike."""
    operator = preconditioned_operator(products.operator)
    return _Unpreconditioned(products) if operator is None else operator


def _check_uncapped(hardness) -> None:
    if hardness is not None:
        raise ValueError("method 'pcg' does not solve the capped problem (hardness); "
                         "use method='cg' (method='auto' does)")


def _solve_rows(products: Products, gaps, key: str, controls, pressure, tol: float,
                max_iter: int, hardness):
    """Every row of ``gaps`` by :func:`constrained_pcg` at its control, the rows solved
    together (:func:`run_solves`); the batch and the approaches [m]."""
    _check_uncapped(hardness)
    operator = grid_operator(products)
    nx, ny = operator.grid
    single = SINGLE_PRECISION[products.precision]
    m, n = gaps.shape
    cold = ~pressure.any(axis=1)
    nested = nx * ny > NESTED_MIN_ELEMENTS and cold.any()
    levels = level_operators(operator) if nested else None

    def solve_level(level, gap, level_tol, start, j):
        return solve_steps(level, gap, tol=level_tol, pressure0=start, max_iter=max_iter,
                           single=single, **{key: float(controls[j])})

    def solve_row(j):
        gap = gaps[j].reshape(ny, nx)
        if not cold[j]:  # a warm start (a sweep's previous step)
            solution = yield from solve_level(operator, gap, tol, pressure[j].reshape(ny, nx), j)
            return solution, 0.0
        if nested:
            return (yield from nested_solve(partial(solve_level, j=j), levels, gap, tol=tol))
        return (yield from solve_level(operator, gap, tol, None, j)), 0.0

    out = Batch.empty(m, n)
    approaches = np.zeros(m)
    solutions = run_solves((solve_row(j) for j in range(m)), max(1, IN_FLIGHT_ELEMENTS // n))
    for j, (solution, coarse_work) in enumerate(solutions):
        out.store(j, solution.pressure.reshape(-1), solution.displacement.reshape(-1),
                  solution.iterations, solution.products + coarse_work, solution.residual, tol)
        approaches[j] = solution.approach
    out.count_whole_products()
    return out, approaches


def solve(products: Products, gaps, d, pressure, tol: float, max_iter: int,
          hardness=None) -> Batch:
    """Preconditioned CG on the rows of ``gaps`` at approaches ``d`` [m] (displacement
    control), each started from its row of ``pressure`` [Pa] when not zero; a cold
    start on a grid of more than :data:`NESTED_MIN_ELEMENTS` elements starts from the
    coarser grids' solutions (:func:`roughcontact.contact.nested.nested_solve`;
    ``iterations`` are the fine grid's, ``matvecs`` count the coarse levels' products
    by their share of a fine one). The rows are solved together (:func:`run_solves`)."""
    return _solve_rows(products, gaps, "approach", d, pressure, tol, max_iter, hardness)[0]


def solve_load(products: Products, gaps, mean_pressures, pressure, tol: float, max_iter: int,
               hardness=None):
    """Preconditioned CG at mean pressures [Pa] (load control, inside the iteration).

    Returns
    -------
    (Batch, ndarray)
        The solutions and the approaches [m] found (the multipliers of the load).
    """
    return _solve_rows(products, gaps, "mean_pressure", mean_pressures, pressure, tol, max_iter,
                       hardness)
