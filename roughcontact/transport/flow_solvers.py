"""The linear solvers of the flow's five-point system (:mod:`roughcontact.transport.flow`):
each a value with ``solve(matrix, rhs) -> (x, iterations)`` and ``solve_by(matrix, rhs)
-> (x, iterations, name)`` (the name of the solver that answered: a fallback's own), and
the iterative refinement a solve off balance is given (:func:`refined`).

The system is symmetric positive definite in exact arithmetic: :class:`DirectSolver`
(SuperLU, the default), :class:`BandedCholesky` (LAPACK's band Cholesky, faster on
small grids with sealed sides, falling back to SuperLU) and :class:`JacobiCG`
(memory of a few vectors).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.linalg as linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from roughcontact.errors import FlowNotConverged

__all__ = ["DIRECT", "BandedCholesky", "DirectSolver", "JacobiCG", "refined"]

logger = logging.getLogger("roughcontact.transport")


@dataclass(frozen=True)
class DirectSolver:
    """Sparse LU of the flow system (SuperLU through :func:`scipy.sparse.linalg.splu`).

    Parameters
    ----------
    ordering : str
        SuperLU's column ordering; ``"MMD_AT_PLUS_A"`` (minimum degree of
        ``A^T + A``, the ordering of a symmetric matrix) fills in least on the
        five-point systems measured, about half of ``COLAMD``'s and
        ``MMD_ATA``'s at 256^2 and 512^2 (``benchmarks/bench_flow.py --parts
        ordering``).
    batch_unknowns : int
        Most elements of the fields solved in one block-diagonal system (at least one
        field). SuperLU's ordering and factorisation grow faster than the unknowns: 60
        fields of 60 x 60 along x and y took 2.35 s in one system, 1.09 s eight at a
        time and 0.99 s one at a time (minimum of 3), so the default is one field of up
        to 64 x 64 elements.
    """

    ordering: str = "MMD_AT_PLUS_A"
    batch_unknowns: int = 1 << 12

    def solve(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int]:
        """``matrix^-1 rhs`` and the number of iterations (0: a direct solve)."""
        factor = spla.splu(matrix.tocsc(), permc_spec=self.ordering,
                           options={"SymmetricMode": True})
        return factor.solve(rhs), 0

    def solve_by(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int, str]:
        """:meth:`solve`, and the name of the solver that gave the answer (its own)."""
        return (*self.solve(matrix, rhs), type(self).__name__)


@dataclass(frozen=True)
class JacobiCG:
    """Conjugate gradients with the diagonal as preconditioner
    (:func:`scipy.sparse.linalg.cg`).

    Converged when the residual's 2-norm is at most ``rtol`` times the
    right-hand side's; raises :class:`~roughcontact.errors.FlowNotConverged`
    after ``max_iter`` iterations otherwise. Slower than :class:`DirectSolver`
    at every size measured, but its memory is that of a few vectors.
    """

    rtol: float = 1e-10
    max_iter: int = 100_000
    batch_unknowns: int = 1 << 18

    def solve(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int]:
        """``matrix^-1 rhs`` to ``rtol`` and the number of CG iterations."""
        inverse_diagonal = 1.0 / matrix.diagonal()
        preconditioner = spla.LinearOperator(matrix.shape, matvec=lambda r: inverse_diagonal * r)
        count = [0]

        def step(_):
            count[0] += 1

        x, info = spla.cg(matrix, rhs, rtol=self.rtol, maxiter=self.max_iter,
                          M=preconditioner, callback=step)
        if info != 0:
            raise FlowNotConverged(f"JacobiCG: no convergence to rtol={self.rtol:g} in "
                                   f"{self.max_iter} iterations; use DirectSolver()")
        return x, count[0]

    def solve_by(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int, str]:
        """:meth:`solve`, and the name of the solver that gave the answer (its own)."""
        return (*self.solve(matrix, rhs), type(self).__name__)


#: The default solver.
DIRECT = DirectSolver()


@dataclass(frozen=True)
class BandedCholesky:
    """Cholesky factorisation of the flow system in band storage (LAPACK's ``pbsv``
    through :func:`scipy.linalg.solveh_banded`), the unknowns in the elements' order.

    The five-point system of a field numbered row by row across the flow has a
    bandwidth ``w`` of at most the ``nx`` elements along the flow when the sides are
    sealed; the factorisation costs about ``n w^2`` for ``n`` unknowns, with no
    ordering: a 60 x 60 field in 2.8 ms against :class:`DirectSolver`'s 14 ms (the
    conductance the same to 5e-13; ``benchmarks/bench_flow_cost.py``). Periodic sides
    couple the first row and the last (``w`` about ``n``), and a large grid's ``w``
    is too wide: a system of bandwidth over ``max_bandwidth`` is solved by
    ``fallback``, and so a system that rounding leaves without a positive pivot (it
    is symmetric positive definite in exact arithmetic).
    """

    max_bandwidth: int = 256
    fallback: DirectSolver = DIRECT
    batch_unknowns: int = 1 << 12

    def solve(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int]:
        """``matrix^-1 rhs`` and the number of iterations (0: a direct solve)."""
        return self.solve_by(matrix, rhs)[:2]

    def solve_by(self, matrix: sp.csr_matrix, rhs: np.ndarray) -> tuple[np.ndarray, int, str]:
        """:meth:`solve`, and the name of the solver that gave the answer: its own, or
        its ``fallback``'s (said on the ``roughcontact.transport`` logger: at debug
        level beyond the bandwidth, the usual path of periodic sides; at info level
        without a positive pivot)."""
        upper = sp.triu(matrix, format="coo")
        width = int((upper.col - upper.row).max(initial=0))
        if width > self.max_bandwidth:
            logger.debug("flow: bandwidth %d over BandedCholesky's %d; solved by %s",
                         width, self.max_bandwidth, type(self.fallback).__name__)
            return self.fallback.solve_by(matrix, rhs)
        band = np.zeros((width + 1, matrix.shape[0]))
        band[width + upper.row - upper.col, upper.col] = upper.data
        try:
            return (linalg.solveh_banded(band, rhs, lower=False, check_finite=False), 0,
                    type(self).__name__)
        except np.linalg.LinAlgError:  # not positive definite to rounding: pivot instead
            logger.info("flow: BandedCholesky found no positive pivot (%d unknowns); "
                        "solved by %s", matrix.shape[0], type(self.fallback).__name__)
            return self.fallback.solve_by(matrix, rhs)


def refined(matrix, rhs, solution, solver, rounds: int = 3) -> np.ndarray:
    """``solution`` of ``matrix x = rhs`` after ``rounds`` of iterative refinement, the
    residual and the sum in extended precision (``np.longdouble``: 64-bit mantissa on
    x86-64), each correction solved in double (Wilkinson 1963; Higham, Accuracy and
    Stability of Numerical Algorithms, 2nd ed. 2002, Ch 12, the residual in extended
    precision: Sec 12.1)."""
    wide = matrix.astype(np.longdouble)
    x = np.asarray(solution, dtype=np.longdouble)
    target = np.asarray(rhs, dtype=np.longdouble)
    for _ in range(rounds):
        residual = target - wide @ x
        if not residual.any():
            break
        correction, _ = solver.solve(matrix, residual.astype(float))
        x = x + correction
    return x.astype(float)
