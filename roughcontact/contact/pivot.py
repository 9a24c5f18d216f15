"""Block principal pivoting for the linear complementarity problem of Eq 27.

Eq 27 is the LCP ``w = C x - b, x >= 0, w >= 0, x.w = 0`` with ``b = d - f``
(``x`` the pressure, ``w`` the gap). Block principal pivoting (Kim & Park
2011, Algorithm 2, after Judice & Pires 1994) guesses the free set ``F``
(the contact set), solves ``C_FF x_F = b_F`` by a Cholesky factorization,
and exchanges the infeasible variables (``x < 0`` on ``F``, ``w < 0`` off
it) in blocks; when blocks stop reducing their number, single exchanges of
the largest index (Murty's rule) guarantee finite termination for a
P-matrix such as an SPD ``C``. With a cap ``H`` it solves the
box-constrained problem ``0 <= x <= H`` with three sets: free ``F``
(``C_FF x_F = b_F - C_FU H``), ``x = 0`` and ``x = H`` (``U``, the
saturated set); ``x > H`` on ``F`` and ``w > 0`` on ``U`` are infeasible
too, and an exchange moves a free variable to the bound it violates.

Every surface in flight is one :class:`PivotState`. A *round* factors each
surface's ``C_FF`` on its current guess and computes the gaps of all of
them with one product ``X C`` (the only pass over ``C``), whatever approach
step each is at. :func:`solve` runs the rounds for one approach
(``"exact"`` and ``"pivot"`` of :func:`roughcontact.contact.solve`);
:func:`sweep` runs them through every surface's approach steps: a surface
whose step is solved takes its tangent ``(C_FF)^-1 1`` from the same factor
and starts its next step at once from the predicted sets. It needs about
two rounds per step at the study's loads (1-15 % contact).

Why it is the default for dense matrices: the products ``C p`` are the cost
of an iterative method, and the paper's and the graded meshes have
near-null checkerboard modes (one trilinear face per contact element: the
consistent nodal loads of a checkerboard pressure nearly cancel; condition
number 7e8 at 60 x 60 against about 1e2 for ``refined``), so CG needs
hundreds of products per step on them. A Cholesky factorization is backward
stable whatever the condition number: the KKT residual stays at rounding
(1e-15) and a paper-mesh cell costs what a refined-mesh cell costs.
``benchmarks/bench_contact.py`` measures both.

References
----------
J. Kim, H. Park, "Fast nonnegative matrix factorization: an active-set-like
method and comparisons", SIAM J. Sci. Comput. 33 (2011) 3261-3281.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.linalg

from roughcontact.contact.kkt import free_set, gap_scale, kkt_residuals
from roughcontact.contact.products import Products, rows_product
from roughcontact.contact.result import Batch, SweepTable
from roughcontact.elasticity.protocol import DenseInfluence, InfluenceOperator

__all__ = ["EXACT_MAX_UNKNOWNS", "PivotState", "default_max_iter", "dense_influence", "solve",
           "sweep"]

logger = logging.getLogger("roughcontact.contact")

#: Largest n for which pivoting forms a dense matrix from a matrix-free operator.
EXACT_MAX_UNKNOWNS = 6000
#: Block exchanges tried without reducing the number of infeasible variables.
BLOCK_TRIES = 3


def default_max_iter(n: int) -> int:
    """Pivot limit for ``n`` unknowns: ``10n + 100``."""
    return 10 * n + 100


def dense_influence(operator: InfluenceOperator) -> InfluenceOperator:
    """The operator with its dense matrix: itself if it holds one, else formed (small n)."""
    if operator.matrix is not None:
        return operator
    n = operator.shape[0]
    if n > EXACT_MAX_UNKNOWNS:
        raise ValueError(
            f"method='exact' forms the dense matrix and is meant for up to "
            f"{EXACT_MAX_UNKNOWNS} unknowns; operator has n = {n}: use method='cg'"
        )
    matrix = rows_product(operator, np.eye(n))
    return DenseInfluence(0.5 * (matrix + matrix.T), operator.element_area, operator.grid,
                          operator.mean_compliance)


def _not_positive_definite() -> ValueError:
    return ValueError(
        "operator must be positive definite: Cholesky factorization of C on "
        "the contact set failed"
    )


def infeasible_set(free, upper, x, w, diagonal, slack, hardness):
    """Infeasible variables of a pivoting guess, and the free ones above the cap.

    ``x < 0`` or ``x > H`` on the free set, ``w < 0`` at ``p = 0``, ``w > 0``
    at ``p = H`` (beyond the rounding ``slack`` [m]). Returns
    ``(infeasible, over)``; ``over`` is None without a cap.
    """
    if hardness is None:
        return (free & (x * diagonal < -slack)) | (~free & (w < -slack)), None
    over = free & ((x - hardness) * diagonal > slack)
    infeasible = ((free & (x * diagonal < -slack)) | over
                  | (~free & ~upper & (w < -slack)) | (upper & (w > slack)))
    return infeasible, over


class PivotState:
    """Block principal pivoting of one surface: its sets, its factor, its progress.

    ``free`` is the free set (the contact guess), ``upper`` with a cap the
    saturated set (``p = H``; None without a cap); ``step`` the approach step
    the surface is at (:func:`sweep`), ``rounds`` the rounds of that step;
    ``priority`` (n,) the expected pressure of each element at this step, by
    which the factor orders its elements (None: element order).

    The factor keeps its elements in order of decreasing expected pressure:
    the elements that leave a contact set are mostly those at the edges of
    its spots, where the pressure is lowest, so they sit at the end of the
    factor, and a set that lost them keeps the factor up to the first one
    that left and appends the rest (:meth:`refactor`) instead of factoring
    ``C_FF`` anew. The order changes the factor's rounding only.
    """

    __slots__ = ("step", "free", "upper", "best", "best_sets", "budget", "rounds", "factor",
                 "index", "members", "priority", "saturated", "saturated_load", "cold",
                 "spent")

    def __init__(self, free: np.ndarray, upper: np.ndarray | None = None,
                 priority: np.ndarray | None = None):
        self.step = 0
        # the step started from the cold guess (:func:`_cold_sets`); the rounds of its
        # earlier attempts (a warm start that did not settle)
        self.cold, self.spent = True, 0
        self.restart(free, upper, priority)
        # lower Cholesky factor of C on the elements ``index`` (in that order),
        # and the same set as a mask
        self.factor, self.index, self.members = None, None, None
        # with a cap: C 1_U [unit of C] for the saturated set ``saturated``
        self.saturated, self.saturated_load = None, None

    def restart(self, free: np.ndarray, upper: np.ndarray | None = None,
                priority: np.ndarray | None = None) -> None:
        """Start a new problem (the next step) from the sets ``free`` and ``upper``, with
        the elements' expected pressures ``priority`` (their order in a new factor)."""
        self.free, self.upper, self.priority = free, upper, priority
        self.best, self.budget, self.rounds = free.size + 1, BLOCK_TRIES, 0
        self.best_sets = None

    def refactor(self, operator: InfluenceOperator) -> str:
        """Bring the factor to the current free set: keep it if the set is unchanged;
        else keep its leading part up to the first element that left the set (all of
        it if none left) and append the elements of the set that are not in it
        (:meth:`_extend`), or factor ``C_FF`` anew if the first element left.
        Returns which of ``"kept"``, ``"extended"`` (the leading part kept),
        ``"new"`` it did."""
        if self.members is not None and np.array_equal(self.free, self.members):
            return "kept"
        if operator.mean_compliance == 0.0 and self.free.all():
            self._leave_null_space()
        kept = 0
        if self.members is not None and self.index.size:
            left = np.flatnonzero(~self.free[self.index])
            kept = left[0] if left.size else self.index.size
        try:
            if kept:
                self._truncate(kept)
                kind = self._extend(operator)
            else:
                kind = self._factor(operator)
        except np.linalg.LinAlgError:
            raise _not_positive_definite() from None
        self.members = self.free.copy()
        return kind

    def _leave_null_space(self) -> None:
        """An operator with ``C 1 = 0`` is singular on the set of every element (and
        definite on any smaller one), and every element free is no solution unless
        ``d = mean f`` exactly: the element of the largest expected pressure goes to
        the cap (to zero pressure without one), and the exchanges go on from there."""
        j = int(np.argmax(self.priority)) if self.priority is not None else 0
        self.free[j] = False
        if self.upper is not None:
            self.upper[j] = True

    def _ordered(self, elements: np.ndarray) -> np.ndarray:
        """``elements`` in order of decreasing :attr:`priority` (ties: element order)."""
        if self.priority is None or elements.size < 2:
            return elements
        return elements[np.argsort(-self.priority[elements], kind="stable")]

    def _truncate(self, size: int) -> None:
        """Keep the factor's leading ``size`` elements: the factor of their ``C`` block."""
        if size < self.index.size:
            self.factor = np.asfortranarray(self.factor[:size, :size])
            self.index = self.index[:size]
            self.members = np.zeros_like(self.free)
            self.members[self.index] = True

    def _factor(self, operator: InfluenceOperator) -> str:
        idx = self._ordered(np.flatnonzero(self.free))
        self.factor = None
        if idx.size:
            self.factor = scipy.linalg.cholesky(operator.restrict(idx).matrix, lower=True,
                                                check_finite=False)
        self.index = idx
        return "new"

    def _extend(self, operator: InfluenceOperator) -> str:
        """Append the rows of the elements added to the free set to the factor."""
        added = self._ordered(np.flatnonzero(self.free & ~self.members))
        if not added.size:
            return "extended"
        coupling = scipy.linalg.solve_triangular(
            self.factor, operator.matrix[np.ix_(self.index, added)], lower=True,
            check_finite=False)
        corner = scipy.linalg.cholesky(
            operator.restrict(added).matrix - coupling.T @ coupling, lower=True,
            check_finite=False)
        size = self.index.size
        # Fortran order, as LAPACK's: cho_solve would copy a C-ordered factor at every call
        factor = np.zeros((size + added.size, size + added.size), order="F")
        factor[:size, :size] = self.factor
        factor[size:, :size] = coupling.T
        factor[size:, size:] = corner
        self.factor, self.index = factor, np.concatenate([self.index, added])
        return "extended"

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``(C_FF)^-1 rhs_F`` in the factor's element order."""
        return scipy.linalg.cho_solve((self.factor, True), rhs, check_finite=False)

    def pressure(self, matrix: np.ndarray, rhs: np.ndarray, hardness, out: np.ndarray) -> None:
        """The pressure of the current sets into ``out`` (zeros): ``H`` on the saturated
        set, ``(C_FF)^-1 (b_F - C_FU H)`` on the free set, for ``b = rhs`` (n,)."""
        idx = self.index
        if hardness is not None and self.upper.any():
            out[self.upper] = hardness
            if idx.size:
                out[idx] = self.solve(rhs[idx] - hardness * self._saturated_load(matrix)[idx])
        elif idx.size:
            out[idx] = self.solve(rhs[idx])

    def _saturated_load(self, matrix: np.ndarray) -> np.ndarray:
        """``C 1_U`` (n,) for the saturated set ``U``: the rows of ``C`` (symmetric) that
        entered ``U`` added to, those that left it taken from, the last one, or summed
        anew when more than half of ``U`` changed. Rows are contiguous, where the
        columns ``C_FU`` a free set takes would be gathered one by one."""
        upper = self.upper
        if self.saturated is not None:
            entered = np.flatnonzero(upper & ~self.saturated)
            left = np.flatnonzero(self.saturated & ~upper)
            if entered.size + left.size <= upper.sum() // 2:
                if entered.size:
                    self.saturated_load += matrix[entered].sum(axis=0)
                if left.size:
                    self.saturated_load -= matrix[left].sum(axis=0)
                self.saturated = upper.copy()
                return self.saturated_load
        self.saturated_load = matrix[upper].sum(axis=0)
        self.saturated = upper.copy()
        return self.saturated_load

    def settled(self, x, gap, diagonal, slack: float, hardness, max_iter: int) -> bool:
        """Count a round; exchange the infeasible variables of ``x`` and its ``gap`` and
        return False, or True when the guess is feasible (or ``max_iter`` exchanges
        were made)."""
        self.rounds += 1
        infeasible, over = infeasible_set(self.free, self.upper, x, gap, diagonal, slack,
                                          hardness)
        if infeasible.any() and self.rounds <= max_iter:
            self.exchange(infeasible, over)
            return False
        return True

    def exchange(self, infeasible: np.ndarray, over: np.ndarray | None = None) -> None:
        """Kim & Park (2011), Algorithm 2: block exchanges while they reduce the
        number of infeasible variables (``BLOCK_TRIES`` tries otherwise), then
        Murty's single exchange of the largest index, which terminates for a
        P-matrix. With a cap, free elements ``over`` it move to the saturated set.

        The single exchanges start from the sets with the fewest infeasible variables
        so far, not from where the block exchanges stalled: measured on a capped,
        ill-conditioned block (the paper's mesh, 10 x 10 under a 10 mm block, 0.06 E*
        against H = 0.1 E*), Murty's rule from a stalled guess with 58 infeasible
        variables had not settled after 1100 exchanges; from the best guess (7) it
        settled in 85 rounds."""
        count = int(infeasible.sum())
        if count < self.best:
            self.best, self.budget = count, BLOCK_TRIES
            self.best_sets = (self.free.copy(), None if self.upper is None
                              else self.upper.copy(), infeasible.copy(),
                              None if over is None else over.copy())
        elif self.budget > 0:
            self.budget -= 1
        else:
            if self.budget == 0 and self.best_sets is not None:  # back to the best guess
                free, upper, infeasible, over = self.best_sets
                self.free = free.copy()
                self.upper = None if upper is None else upper.copy()
                self.budget = -1
            single = np.zeros_like(infeasible)
            single[np.flatnonzero(infeasible)[-1]] = True
            infeasible = single
        self.free ^= infeasible
        if self.upper is not None:
            self.upper[infeasible] = over[infeasible]


def _round(operator: InfluenceOperator, states, rhs: np.ndarray, hardness):
    """One round: each state's pressure on its sets for ``b = rhs`` (rows), and the
    products ``C x`` of all of them with one product (C is symmetric)."""
    matrix = operator.matrix
    x = np.zeros(rhs.shape)
    for r, state in enumerate(states):
        state.refactor(operator)
        state.pressure(matrix, rhs[r], hardness, x[r])
    return x, x @ matrix


def _cold_sets(rigid: np.ndarray, hardness):
    """First guess without a pressure: the interfering elements ``d > f`` free, none at the
    cap; the deepest interference first in the factor (priority ``-rigid``)."""
    return (rigid < 0.0, None if hardness is None else np.zeros(rigid.size, dtype=bool),
            -rigid)


def _clip(x: np.ndarray, hardness) -> np.ndarray:
    return np.maximum(x, 0.0) if hardness is None else np.clip(x, 0.0, hardness)


def solve(products: Products, gaps, d, pressure, tol: float, max_iter: int,
          hardness=None) -> Batch:
    """Block principal pivoting on the rows of ``gaps`` at approaches ``d`` [m].

    Each surface starts from the support of its ``pressure`` [Pa] (free
    ``0 < p < H``, saturated ``p >= H``), or, without one, from the elements
    in interference. Finished surfaces get their gap recomputed from the
    returned (clipped) pressure. ``iterations`` counts the pivots (rounds
    after the first), ``matvecs`` the products.
    """
    operator = dense_influence(products.operator)
    diagonal = products.operator.diagonal()
    m, n = gaps.shape
    out = Batch.empty(m, n)
    rigid = gaps - d[:, None]
    slack = 1e-3 * tol * gap_scale(rigid)  # infeasible only beyond rounding
    states = []
    for j in range(m):
        loaded = pressure[j].any()
        upper = None if hardness is None or not loaded else pressure[j] >= hardness
        priority = pressure[j] if hardness is None else np.minimum(pressure[j],
                                                                   hardness - pressure[j])
        states.append(PivotState(free_set(pressure[j], hardness), upper, priority)
                      if loaded else PivotState(*_cold_sets(rigid[j], hardness)))
    pending = np.arange(m)
    while pending.size:
        x, gap = _round(operator, [states[j] for j in pending], -rigid[pending], hardness)
        gap += rigid[pending]
        done = np.array([states[j].settled(x[r], gap[r], diagonal, slack[j], hardness,
                                           max_iter) for r, j in enumerate(pending)])
        finished = pending[done]
        if finished.size:
            p = _clip(x[done], hardness)
            u = rows_product(operator, p)
            rounds = np.array([states[j].rounds for j in finished])
            residual = kkt_residuals(p, u + rigid[finished], diagonal,
                                     gap_scale(rigid[finished]), hardness)
            out.store(finished, p, u, rounds - 1, rounds + 1, residual, tol)
        pending = pending[~done]
    out.count_whole_products()
    return out


def _next_sets(p, rate, delta: float, rigid_next, hardness):
    """The predicted sets of the next step: ``p + delta dp/dd`` positive (free) and,
    with a cap, at or above ``H`` (saturated), and the prediction itself (the factor's
    order); the cold guess if nothing is predicted."""
    predicted = p + delta * rate
    start, upper = predicted > 0.0, None
    if hardness is not None:
        upper = predicted >= hardness
        start &= ~upper
        if not upper.any() and not start.any():
            return _cold_sets(rigid_next, hardness)
        # the elements that leave a capped free set are those nearest either bound
        return start, upper, np.minimum(predicted, hardness - predicted)
    if not start.any():
        return _cold_sets(rigid_next, hardness)
    return start, upper, predicted


def _step_solved(state: PivotState, j: int, x, gap, steps, operator, diagonal, solver,
                 table: SweepTable) -> None:
    """Record surface ``j``'s solved step (pressure ``x``, ``gap``), its tangent from
    the factor, and restart it at its next step from the predicted sets.

    ``solver`` is the sweep's :class:`roughcontact.contact.methods.Solver` (its
    problem's gaps ``f`` and cap, its options' ``tol`` and ``stiffness``). A step that
    did not settle within ``max_iter`` pivots is pivoted again from the cold guess if
    it started from a prediction; if it started cold it is recorded unconverged,
    logged, and the next step starts cold, not from it."""
    step, hardness = state.step, solver.problem.hardness
    gaps, options = solver.problem.gaps, solver.options
    d = steps[j, step]
    k = steps.shape[1]
    scale = gap_scale((gaps[j] - d)[None])[0]
    p = _clip(x, hardness)
    residual = kkt_residuals(p[None], gap[None], diagonal, np.array([scale]), hardness)[0]
    converged = residual <= options.tol
    if not converged and not state.cold:
        state.spent += state.rounds
        state.restart(*_cold_sets(gaps[j] - d, hardness))
        state.cold = True
        return
    table.record(j, step, p, gap - gaps[j] + d, residual, operator.element_area, hardness, gap)
    rounds = state.spent + state.rounds
    table.record_work(j, step, rounds, rounds, converged)
    rate = np.zeros(p.size)
    if converged and state.index.size and (options.stiffness or step + 1 < k):
        rate[state.index] = state.solve(np.ones(state.index.size))
    if options.stiffness:
        table.record_stiffness(j, step, operator.element_area * rate.sum(), converged)
    if not converged:
        logger.warning("contact sweep (%s): surface %d, step %d (approach %.6g m) did not "
                       "settle in %d pivots, from the predicted sets and from the cold "
                       "guess (KKT residual %.3g > tol %.3g); flagged, its next step "
                       "starts cold", solver.method.name, j, step, d, rounds, residual,
                       options.tol)
    state.step += 1
    state.spent = 0
    if state.step < k:
        rigid_next = gaps[j] - steps[j, state.step]
        if converged:
            state.restart(*_next_sets(p, rate, steps[j, state.step] - d, rigid_next, hardness))
        else:
            state.restart(*_cold_sets(rigid_next, hardness))
        state.cold = not converged


def sweep(solver, steps, table: SweepTable) -> None:
    """Every surface's sweep by block principal pivoting, all in flight at once.

    ``solver`` is the checked :class:`roughcontact.contact.methods.Solver` (its
    method names the sweep in the log, its products give ``C``, its problem's gaps
    ``f`` (m, n) [m] and cap ``H`` [Pa], its options ``tol`` and ``stiffness``, its
    ``max_iter`` the pivots of a step). Each surface advances through its own approaches
    ``steps`` (m, k) [m]; every round factors each in-flight surface's ``C_FF``
    on its current guess, solves ``C_FF p_F = d - f_F`` (``- C_FU H`` with a
    cap), and computes the gaps of *all* in-flight surfaces, whatever step each
    is at, with one product ``P C``. A surface whose guess is consistent
    (``p_F >= 0``, ``g >= 0`` off ``F``, to rounding) has solved its step:
    its tangent ``(C_FF)^-1 1`` comes from the same factor (saturated
    elements fixed), and its next step starts at once from the predicted
    sets ``{p + (d' - d) dp/dd > 0}`` (and ``>= H`` for the saturated set).
    A step that does not settle is retried and flagged as in
    :func:`_step_solved`. Fills ``table`` in place.
    """
    products, gaps, hardness = solver.products, solver.problem.gaps, solver.problem.hardness
    dense = dense_influence(products.operator)
    diagonal = products.operator.diagonal()
    m = gaps.shape[0]
    k = steps.shape[1]
    states = [PivotState(*_cold_sets(gaps[j] - steps[j, 0], hardness)) for j in range(m)]
    while True:
        flight = [j for j in range(m) if states[j].step < k]
        if not flight:
            break
        rhs = np.array([steps[j, states[j].step] - gaps[j] for j in flight])
        x, gap = _round(dense, [states[j] for j in flight], rhs, hardness)
        for r, j in enumerate(flight):
            state = states[j]
            gap[r] += gaps[j] - steps[j, state.step]
            scale = gap_scale((gaps[j] - steps[j, state.step])[None])[0]
            if state.settled(x[r], gap[r], diagonal, 1e-3 * solver.options.tol * scale,
                             hardness, solver.max_iter):
                _step_solved(state, j, x[r], gap[r], steps, dense, diagonal, solver, table)
