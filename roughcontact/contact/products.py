"""The products ``C p`` of the contact solvers, in double or mixed precision.

The solvers store pressures one surface per row, shape (m, n), and apply
``C`` to all unfinished surfaces at once (for a dense matrix one BLAS 3
product ``P C``, since ``C`` is symmetric). The products are the cost of
the iterative methods; ``precision="mixed"`` takes the search-direction
products with a single-precision copy of a dense ``C`` or the float32
FFTs of a grid operator (about half the time), while the residuals that
decide convergence stay double precision.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.elasticity.protocol import InfluenceOperator, PreconditionedOperator

__all__ = ["PRECISIONS", "SINGLE_PRECISION", "SPARSE_ROWS", "Products", "rows_product"]

#: Whether each precision takes the search-direction products in single precision.
SINGLE_PRECISION = {"double": False, "mixed": True}
PRECISIONS = tuple(SINGLE_PRECISION)
#: Largest share of changed elements for which a correction gathers rows of C.
SPARSE_ROWS = 1.0 / 32.0


def rows_product(operator: InfluenceOperator, rows: np.ndarray) -> np.ndarray:
    """``C p_i`` for pressures stored one per row: (m, n) -> (m, n), C-contiguous."""
    return np.ascontiguousarray(np.asarray(operator.matvec(rows.T), dtype=float).T)


@dataclass(frozen=True)
class Products:
    """The products of one solve: exact ones, search-direction ones, sparse corrections.

    Attributes
    ----------
    operator : InfluenceOperator
        ``C`` [m/Pa].
    single : ndarray (n, n) of float32, PreconditionedOperator or None
        Single-precision copy of a dense ``C`` for the search-direction
        products (``precision="mixed"``), or the grid FFT operator whose
        float32 products serve them; None: every product is exact.
    precision : str
        The precision asked for (:data:`PRECISIONS`); a method that takes
        its own single-precision products from a grid operator
        (:mod:`roughcontact.contact.pcg`) reads it here.
    """

    operator: InfluenceOperator
    single: np.ndarray | None = None
    precision: str = "double"

    @classmethod
    def of(cls, operator: InfluenceOperator, precision: str = "double",
           single_ok: bool = True) -> Products:
        """The products for ``precision``: single-precision search products for a dense
        matrix (a float32 copy) or a grid FFT operator (its float32 transforms), and a
        method that takes them (``single_ok``)."""
        single = None
        base = getattr(operator, "base", operator)
        if SINGLE_PRECISION[precision] and single_ok:
            if operator.matrix is not None:
                single = operator.matrix.astype(np.float32)
            elif isinstance(base, PreconditionedOperator):
                single = base
        return cls(operator, single, precision if single_ok else "double")

    @property
    def mixed(self) -> bool:
        """The search-direction products are single precision."""
        return self.single is not None

    def exact(self, rows: np.ndarray) -> np.ndarray:
        """``C p_i`` in double precision, rows = surfaces."""
        return rows_product(self.operator, rows)

    def search(self, rows: np.ndarray) -> np.ndarray:
        """``C s_i`` for search directions: single precision when :attr:`mixed`."""
        if self.single is None:
            return self.exact(rows)
        if isinstance(self.single, np.ndarray):
            return (rows.astype(np.float32) @ self.single).astype(float)
        nx, ny = self.single.grid
        fields = self.single.apply(rows.astype(np.float32).reshape(-1, ny, nx))
        return np.asarray(fields, dtype=float).reshape(rows.shape)

    def correction(self, rows, cols, values, m: int, cost: np.ndarray) -> np.ndarray:
        """``delta C`` for the sparse change ``delta[rows, cols] = values``, shape (m, n).

        ``rows`` must be sorted (as from ``np.nonzero``). With a dense
        (symmetric) matrix a surface with few changed elements uses only those
        rows of ``C`` and is charged that share of a full product in ``cost``;
        the other touched surfaces get one batched full product (single
        precision when :attr:`mixed`).
        """
        n = self.operator.shape[0]
        matrix = self.operator.matrix
        product = np.zeros((m, n))
        if not rows.size:
            return product
        touched, starts, counts = np.unique(rows, return_index=True, return_counts=True)
        sparse = counts <= SPARSE_ROWS * n if matrix is not None else counts < 0
        for surface, start, count in zip(touched[sparse], starts[sparse], counts[sparse],
                                         strict=True):
            elements = cols[start : start + count]
            product[surface] = values[start : start + count] @ matrix[elements]
            cost[surface] += count / n
        dense = touched[~sparse]
        if dense.size:
            delta = np.zeros((dense.size, n))
            selected = np.isin(rows, dense)
            delta[np.searchsorted(dense, rows[selected]), cols[selected]] = values[selected]
            product[dense] = self.search(delta)
            cost[dense] += 1.0
        return product
