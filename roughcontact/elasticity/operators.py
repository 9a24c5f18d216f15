"""Matrix-free influence operators of the finite block, for large contact grids.

A dense influence matrix of n = nx * ny contact elements needs 8 n^2 bytes:
104 MB at 60 x 60, 1.7 GB at 120 x 120, 34 GB at 256 x 256. Its finite-element
construction grows faster still (a 3-D factorization plus n solves). The
paper stopped at 60 x 60 for that reason.

:class:`BlockOperator` applies the unit-modulus compliance ``E C`` [m] of the
block without forming it, by the decomposition of
:func:`roughcontact.elasticity.hybrid.hybrid_unit_modulus_influence`:

    E C = E C_love + A_f W K W^T,

- ``E C_love``: Love's (1929) uniformly loaded rectangles on a half-space at
  the fine grid (:func:`roughcontact.elasticity.halfspace.halfspace_influence` with
  E = 1). It is block Toeplitz, so its product is a zero-padded FFT
  convolution: O(n log n) time and O(n) memory.
- ``K = (E C_fe - E C_love) / A_c`` [1/m]: the finite-body correction per
  unit loaded area, from a finite-element model of the same block on a
  *coarse* contact grid (at most ``COARSE_MAX`` elements per side). The
  correction varies on the scale of the block (thickness, distance to the
  free sides and the rigid base), not of an element, so a coarse grid
  resolves it; ``W`` is the separable linear interpolation from coarse to
  fine element centres and ``A_f``, ``A_c`` the fine and coarse element
  areas. Its product costs two small interpolations and one dense
  ``nc x nc`` product.

With no correction (``correction=None``) the operator is the half-space
itself (no finite body).

Accuracy (measured at 60 x 60 on the paper's block, nu = 0, against the
"converged" finite-element matrix, see ``hybrid_unit_modulus_influence``):
the interior entries within 0.3 % ("converged" coarse model) or 0.9 %
("refined"), and k_P, real area and peak pressure within 1.2 %. Next to
the free lateral faces the correction is not smooth, so the outermost ring of
elements has diagonal errors of up to 14-18 %. The paper's 5-layer mesh and
the graded preset are too stiff in the near field (diagonal -82 % and -51 %)
to serve as the coarse model: their error would be interpolated into the
fine grid, so they are refused.

The product is the same operator as the dense hybrid matrix (to rounding,
tests/elasticity/test_operators.py), so these accuracy figures carry over.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse

from roughcontact.elasticity.coarse_correction import CoarseCorrection
from roughcontact.elasticity.halfspace import _check_grid, _element_kernel
from roughcontact.elasticity.hybrid import centre_interpolation, finite_body_correction
from roughcontact.elasticity.influence import estimate_cost, unit_modulus_influence
from roughcontact.elasticity.protocol import GridOperator
from roughcontact.elasticity.transforms import DTYPES, ColumnTable, PaddedConvolution, q_stencil

__all__ = [
    "COARSE_MAX",
    "COLUMN_BUDGET",
    "DENSE_MAX_ELEMENTS",
    "HYBRID_MESHES",
    "OPERATORS",
    "BlockOperator",
    "block_operator",
    "choose_operator",
    "coarse_geometry",
    "coarsened_side",
    "default_coarse_grid",
    "halfspace_operator",
    "hybrid_operator",
]

logger = logging.getLogger("roughcontact.operators")

#: Influence models of a geometry: the dense finite-element matrix, the
#: matrix-free hybrid (Love + coarse finite-element correction), the
#: matrix-free half-space (Love only), or chosen by :func:`choose_operator`.
OPERATORS = ("dense", "hybrid", "halfspace", "auto")
#: Mesh presets accurate enough in the near field to serve as the coarse model.
HYBRID_MESHES = ("refined", "converged")
#: Largest coarse contact grid per side of the finite-element correction.
COARSE_MAX = 64
#: Largest grid (elements) for which ``operator: auto`` keeps the dense matrix:
#: up to 64 x 64 its product (BLAS) is as fast as the FFT operator and its
#: entries are the finite-element model's own (benchmarks/bench_operators.py).
DENSE_MAX_ELEMENTS = 64 * 64
#: Changed elements whose displacement is summed by kernel columns rather than taken
#: by one product (a column costs about 1/25 of a single-precision product at 512^2
#: and 1024^2; the hybrid adds its correction, about a quarter of a product, once).
COLUMN_BUDGET = 24


def default_coarse_grid(grid, coarse_max: int | None = None) -> tuple[int, int]:
    """Coarse grid of the correction: ``g / k`` per side, the smallest k giving ``<= coarse_max``.

    ``k`` divides ``g`` when possible (then coarse and fine elements nest);
    otherwise ``ceil(g / k)``.
    """
    coarse_max = COARSE_MAX if coarse_max is None else int(coarse_max)
    out = []
    for g in (int(v) for v in grid):
        k0 = max(1, math.ceil(g / coarse_max))
        k = next((k for k in range(k0, 2 * k0 + 1) if g % k == 0), None)
        out.append(g // k if k is not None else math.ceil(g / k0))
    return (out[0], out[1])


def coarsened_side(grid: int, coarsening: int = 2) -> int:
    """Coarse grid (per side) of a hybrid operator on ``grid`` x ``grid`` coarsened
    ``coarsening`` times: ``grid // coarsening``, at most :data:`COARSE_MAX`
    (then :func:`default_coarse_grid`). The speed report's grid study uses it."""
    coarse = grid // coarsening
    if coarse > COARSE_MAX:
        coarse = default_coarse_grid((grid, grid))[0]
    return coarse


@dataclass(frozen=True)
class BlockOperator(GridOperator):
    """Matrix-free unit-modulus compliance ``E C`` [m] of the finite block.

    ``u = matvec(p)`` is the displacement [m] times Young's modulus [Pa] for
    element pressures ``p`` [Pa] (or, equally, the displacement for E = 1 Pa);
    elements are row-major over y then x, as in the dense matrices. Divide by
    E (or use :func:`roughcontact.contact.nondim.dimensionless_operator`) for C.

    Parameters
    ----------
    grid : (int, int)
        Contact elements ``(nx, ny)``.
    size : (float, float)
        Nominal contact area ``(Lx, Ly)`` [m].
    nu : float
        Poisson's ratio [-].
    correction : ndarray (nc, nc), CoarseCorrection or None
        Finite-body correction ``K`` per unit loaded area [1/m] on the coarse
        grid (symmetric; or prepared as a
        :class:`~roughcontact.elasticity.coarse_correction.CoarseCorrection`),
        or None for the half-space alone. The attribute holds ``K``
        symmetrized (float64).
    coarse_grid : (int, int) or None
        Coarse contact elements ``(ncx, ncy)`` of ``correction``.
    workers : int
        Threads of the FFTs (``scipy.fft``), default 1.

    Notes
    -----
    Products: the Love part by the pruned zero-padded FFT of
    :class:`roughcontact.elasticity.transforms.PaddedConvolution`, the
    correction by the interpolations and the dense ``nc x nc`` product
    (by the block's mirror classes when ``K`` has its symmetry,
    :mod:`roughcontact.elasticity.coarse_correction`), both in the dtype of
    the pressure (:meth:`apply`: float32 or float64), for a batch of fields
    at once. Both kinds also sum kernel columns (:meth:`add_columns`,
    ``column_budget`` :data:`COLUMN_BUDGET`), offer the stencil of Love's
    part as preconditioner (:meth:`preconditioner`) and a copy on the grid
    coarser by 2 (:meth:`coarsened`, the same prepared correction), so they
    are :class:`roughcontact.elasticity.protocol.PreconditionedOperator`.

    It is an :class:`roughcontact.elasticity.protocol.InfluenceOperator`
    (matrix-free: ``matrix`` is None; it fixes no common row sum, so
    ``mean_compliance`` is None).
    """

    grid: tuple[int, int]
    size: tuple[float, float]
    nu: float
    correction: np.ndarray | None = field(default=None, repr=False, compare=False)
    coarse_grid: tuple[int, int] | None = None
    workers: int = 1
    _love: PaddedConvolution = field(init=False, repr=False, compare=False)
    _columns: ColumnTable | None = field(init=False, repr=False, compare=False)
    _px: np.ndarray | None = field(init=False, repr=False, compare=False)
    _py: np.ndarray | None = field(init=False, repr=False, compare=False)
    _interpolations: dict | None = field(init=False, repr=False, compare=False)
    _correction: CoarseCorrection | None = field(init=False, repr=False, compare=False)
    _diagonal: np.ndarray = field(init=False, repr=False, compare=False)
    mean_compliance = None

    def __post_init__(self):
        nx, ny, lx, ly = _check_grid(self.grid, self.size)
        nu = float(self.nu)
        if not 0.0 <= nu < 0.5:
            raise ValueError(f"nu must satisfy 0 <= nu < 0.5, got {self.nu!r}")
        set_ = object.__setattr__
        set_(self, "grid", (nx, ny))
        set_(self, "size", (lx, ly))
        set_(self, "nu", nu)
        dx, dy = lx / nx, ly / ny
        kernel = _element_kernel(nx, ny, dx, dy, 1.0, nu)
        set_(self, "_love", PaddedConvolution(kernel, int(self.workers)))
        diagonal = np.full(nx * ny, kernel[0, 0])
        set_(self, "_columns", ColumnTable.even(kernel))
        if self.correction is None:
            if self.coarse_grid is not None:
                raise ValueError("coarse_grid is given but correction is None")
            for name in ("_px", "_py", "_interpolations", "_correction"):
                set_(self, name, None)
        else:
            if self.coarse_grid is None:
                raise ValueError("correction needs its coarse_grid (ncx, ncy)")
            ncx, ncy, _, _ = _check_grid(self.coarse_grid, self.size)
            set_(self, "coarse_grid", (ncx, ncy))
            prepared = self.correction
            if not isinstance(prepared, CoarseCorrection) or prepared.coarse_grid != (ncx, ncy):
                prepared = CoarseCorrection.of(self.correction, (ncx, ncy))
            set_(self, "_correction", prepared)
            set_(self, "correction", prepared.matrix)
            px = centre_interpolation(nx, ncx)
            py = centre_interpolation(ny, ncy)
            set_(self, "_px", px)
            set_(self, "_py", py)
            # the interpolations in both dtypes: to the coarse grid dense (x: a GEMM,
            # y: a batched product on fields already narrowed to ncx <= COARSE_MAX),
            # back to the fine grid sparse (two taps per row; the x one times the
            # fine element area)
            set_(self, "_interpolations", {t: (
                px.astype(t), np.ascontiguousarray(py.T, dtype=t),
                scipy.sparse.csr_array(py.astype(t)),
                scipy.sparse.csr_array((px * dx * dy).astype(t))) for t in DTYPES})
            diagonal = diagonal + dx * dy * _interpolated_diagonal(prepared.matrix, px, py)
        if not np.all(diagonal > 0):
            raise ValueError("operator has a non-positive self-compliance: the correction "
                             "is inconsistent with the grid")
        diagonal.setflags(write=False)
        set_(self, "_diagonal", diagonal)

    @property
    def kind(self) -> str:
        """"hybrid" (with a finite-body correction) or "halfspace"."""
        return "halfspace" if self.correction is None else "hybrid"

    def diagonal(self) -> np.ndarray:
        """Self-compliances ``E C_ii`` [m], shape (n,)."""
        return self._diagonal

    #: Changed elements summed by kernel columns rather than a product.
    column_budget = COLUMN_BUDGET

    def _apply(self, fields: np.ndarray) -> np.ndarray:
        """``E C p`` [m * Pa / Pa = m] of pressure fields of shape (m, ny, nx), in their
        dtype (float32 or float64)."""
        u = self._love(fields)
        if self.correction is not None:
            u += self._prolong(self._correction.apply(self._restrict(fields)))
        return u

    def _restrict(self, fields: np.ndarray) -> np.ndarray:
        """``W^T p``: fields (m, ny, nx) [Pa] on the coarse grid (m, ncy, ncx), in their
        dtype: along x by one GEMM with a dense ``W_x`` (4x faster than the sparse
        product at 256^2 with 64 coarse columns, which transposes the fields), then
        ``W_y^T`` on the narrowed fields."""
        m, ny, nx = fields.shape
        ncx, _ = self.coarse_grid
        px, py_t, _, _ = self._interpolations[fields.dtype]
        rows = (fields.reshape(m * ny, nx) @ px).reshape(m, ny, ncx)  # p W_x
        return np.matmul(py_t, rows)  # W_y^T p W_x

    def _prolong(self, coarse: np.ndarray) -> np.ndarray:
        """``A_f W c``: coarse fields (m, ncy, ncx) [m/m^2] back on the fine grid times the
        fine element area (m, ny, nx) [m], in their dtype."""
        nx, ny = self.grid
        ncx, ncy = self.coarse_grid
        m = coarse.shape[0]
        _, _, py, px_area = self._interpolations[coarse.dtype]
        back = py @ coarse.transpose(1, 0, 2).reshape(ncy, m * ncx)
        back = back.reshape(ny, m, ncx).transpose(1, 0, 2).reshape(m * ny, ncx)
        return (back @ px_area.T).reshape(m, ny, nx)

    def add_columns(self, target: np.ndarray, rows, cols, values) -> None:
        """``target += E C e`` [m], ``e[rows, cols] = values`` [Pa]: Love's part by kernel
        columns (float32), the correction by the coarse elements ``e`` loads."""
        self._columns.add(target, rows, cols, values)
        if self.correction is None:
            return
        values = np.asarray(values, dtype=float)
        coarse = ((self._py[rows] * values[:, None]).T @ self._px[cols]).ravel()  # W_y^T e W_x
        loaded = np.flatnonzero(coarse)  # at most 4 coarse elements per changed one
        coarse = coarse[loaded] @ self.correction[loaded]  # K = K^T
        ncx, ncy = self.coarse_grid
        target += self._prolong(coarse.reshape(1, ncy, ncx))[0]

    def preconditioner(self):
        """The 13-tap stencil of Love's part, ``E* |q| / 2`` with ``E* = 1 / (1 - nu^2)``
        (:func:`roughcontact.elasticity.transforms.q_stencil`, not periodic)."""
        nx, ny = self.grid
        spacing = (self.size[0] / nx, self.size[1] / ny)
        return q_stencil(spacing, 1.0 / (1.0 - self.nu**2), periodic=False)

    def coarsened(self) -> BlockOperator:
        """The same body on the grid coarser by 2 per side, with the same correction."""
        nx, ny = self.grid
        if nx % 2 or ny % 2:
            raise ValueError(f"grid {self.grid} cannot be halved")
        return dataclasses.replace(self, grid=(nx // 2, ny // 2), correction=self._correction)

    def to_dense(self, max_elements: int = 6000) -> np.ndarray:
        """The (n, n) matrix, for small grids (checks and the exact solver)."""
        n = self.shape[0]
        if n > max_elements:
            raise ValueError(f"to_dense: n = {n} exceeds max_elements = {max_elements}")
        return self.matvec(np.eye(n))

    def nbytes(self) -> int:
        """Memory held by the operator [bytes]."""
        held = self._love.nbytes() + self._diagonal.nbytes
        if self._columns is not None:
            held += self._columns.nbytes()
        if self.correction is not None:
            held += self._correction.nbytes() + self._px.nbytes + self._py.nbytes
        return int(held)


def _interpolated_diagonal(correction, px, py) -> np.ndarray:
    """diag(W K W^T) for W = kron(py, px), using the two nonzeros per row of px and py."""
    def taps(matrix):
        width = min(2, matrix.shape[1])
        cols = np.argsort(-np.abs(matrix), axis=1, kind="stable")[:, :width]
        return cols, np.take_along_axis(matrix, cols, axis=1)

    cx, wx = taps(px)
    cy, wy = taps(py)
    ncx = px.shape[1]
    # coarse indices and weights of each fine element: (ny, nx, taps)
    idx = (cy[:, None, :, None] * ncx + cx[None, :, None, :]).reshape(py.shape[0], px.shape[0], -1)
    w = (wy[:, None, :, None] * wx[None, :, None, :]).reshape(idx.shape)
    idx = idx.reshape(-1, idx.shape[-1])
    w = w.reshape(idx.shape)
    values = correction[idx[:, :, None], idx[:, None, :]]
    return np.einsum("is,it,ist->i", w, w, values)


def halfspace_operator(grid, size, nu: float, *, workers: int = 1) -> BlockOperator:
    """Love's half-space at the contact grid (E = 1), matrix-free (no finite body);
    ``workers`` threads run its FFTs."""
    return BlockOperator(grid=tuple(grid), size=tuple(size), nu=nu, workers=workers)


def block_operator(geom, *, coarse_grid=None, solver: str = "auto",
                   max_bytes: float = 16e9) -> BlockOperator:
    """Build the matrix-free :class:`BlockOperator` of a block geometry.

    Parameters
    ----------
    geom : roughcontact.influence.BlockGeometry
        Block and fine contact grid; ``geom.mesh`` (one of ``HYBRID_MESHES``)
        is the finite-element mesh of the coarse model.
    coarse_grid : (int, int), optional
        Coarse contact grid of the correction; default
        :func:`default_coarse_grid` (at most ``COARSE_MAX`` per side).
    solver, max_bytes
        As in :func:`roughcontact.elasticity.influence.unit_modulus_influence`.
    """

    if geom.mesh not in HYBRID_MESHES:
        raise ValueError(
            f"the hybrid operator needs an accurate near field in its coarse model: mesh must "
            f"be one of {HYBRID_MESHES}, got {geom.mesh!r} (the paper and graded presets are "
            f"82 % and 51 % too stiff per element; use operator: dense for the paper's model)")
    if coarse_grid is None:
        coarse_grid = default_coarse_grid(geom.grid)
    coarse = dataclasses.replace(geom, grid=tuple(int(g) for g in coarse_grid))
    return hybrid_operator(geom, unit_modulus_influence(coarse, solver=solver,
                                                        max_bytes=max_bytes), coarse)


def coarse_geometry(geom, coarse_grid=None):
    """The coarse finite-element model of a hybrid operator, elastic or thermal: the
    block of ``geom`` on ``coarse_grid`` (default :func:`default_coarse_grid`) with its
    mesh where it is one of ``HYBRID_MESHES``, else "refined" (the inaccurate near
    fields of the paper and graded presets would be interpolated into the fine grid)."""
    grid = default_coarse_grid(geom.grid) if coarse_grid is None else \
        tuple(int(g) for g in coarse_grid)
    mesh = geom.mesh if isinstance(geom.mesh, str) and geom.mesh in HYBRID_MESHES else "refined"
    return dataclasses.replace(geom, grid=grid, mesh=mesh)


def hybrid_operator(geom, coarse_unit: np.ndarray, coarse) -> BlockOperator:
    """The matrix-free :class:`BlockOperator` of ``geom`` from its coarse model's ``E C`` [m].

    ``coarse_unit`` is the finite-element matrix of ``coarse`` (the same block
    on a coarser contact grid); it is turned into the correction in place
    (:func:`roughcontact.elasticity.hybrid.finite_body_correction`).
    """
    return BlockOperator(grid=geom.grid, size=geom.size, nu=geom.nu,
                         correction=finite_body_correction(coarse_unit, coarse),
                         coarse_grid=coarse.grid)


def choose_operator(geom, *, max_dense_bytes: float, halfspace_ok: bool = False) -> str:
    """The influence model ``operator: auto`` uses for a geometry: a decision rule.

    1. ``"halfspace"`` when the caller measured that the half-space meets the
       study's tolerance (``halfspace_ok``, see :func:`halfspace_errors`).
    2. ``"dense"`` (the finite-element matrix itself) up to
       ``DENSE_MAX_ELEMENTS`` contact elements, when its estimated build
       memory is below ``max_dense_bytes``.
    3. ``"hybrid"`` otherwise; the coarse model uses the geometry's mesh, or
       "refined" when that mesh cannot serve (paper, graded).
    """

    if halfspace_ok:
        return "halfspace"
    if geom.n_elements <= DENSE_MAX_ELEMENTS and \
            estimate_cost(geom).peak_bytes <= max_dense_bytes:
        return "dense"
    return "hybrid"
