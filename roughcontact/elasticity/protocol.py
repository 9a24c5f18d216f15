"""The interface every influence operator offers the contact solver.

An influence operator maps element pressures ``p`` [Pa] to normal surface
displacements ``u = C p`` [m] (Eq 16 of Kumar et al. 2006), elements in
row-major order over y then x (``k = iy * nx + ix``). The contact solvers of
:mod:`roughcontact.contact` use only the members of
:class:`InfluenceOperator`, so a dense matrix (:class:`DenseInfluence`), the
periodic half-space applied by FFT
(:class:`roughcontact.elasticity.halfspace.PeriodicHalfSpace`) and the
matrix-free block (:class:`roughcontact.elasticity.operators.BlockOperator`)
serve alike; :class:`MatrixFreeInfluence` gives the interface to any other
object with a ``matvec``, and :class:`RestrictedInfluence` is the
sub-operator of a matrix-free operator on a set of elements.

The FFT operators of a grid also offer what the preconditioned CG of
:mod:`roughcontact.contact.pcg` needs (:class:`PreconditionedOperator`):
products of ``(ny, nx)`` fields in float32 or float64 (:meth:`apply`), the
stencil of their preconditioner, sums of a few kernel columns and a copy of
themselves on a grid coarser by 2.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "DenseInfluence",
    "GridOperator",
    "InfluenceOperator",
    "MatrixFreeInfluence",
    "PreconditionedOperator",
    "RestrictedInfluence",
]


@runtime_checkable
class InfluenceOperator(Protocol):
    """A symmetric influence operator ``C`` [m/Pa] of ``n`` contact elements.

    Attributes
    ----------
    shape : (int, int)
        ``(n, n)``.
    dtype : numpy.dtype
        Type of the products (float64).
    element_area : float
        Area ``dA`` of one contact element [m^2].
    grid : (int, int) or None
        ``(nx, ny)`` when the elements form that grid (surfaces are then
        ``(ny, nx)``); None when any surface shape of ``n`` elements fits.
    matrix : ndarray (n, n) or None
        The dense matrix when the operator holds one (block principal
        pivoting factors its blocks ``C_AA``); None for a matrix-free operator.
    mean_compliance : float or None
        The common row sum of ``C`` [m/Pa] (a uniform pressure ``P`` gives
        ``u = mean_compliance P``) when the operator fixes it, else None.
        Zero means the mean displacement is always zero: Eq 27 is then
        bounded only for approaches below the mean initial separation.

    ``C`` must be positive definite (Eq 39; on the complement of the uniform
    pressure when ``mean_compliance`` is 0). The solvers certify it once
    (:mod:`roughcontact.elasticity.definiteness`) and keep the certificate
    on the operator as ``spd_certificate``.
    """

    @property
    def shape(self) -> tuple[int, int]: ...

    @property
    def dtype(self) -> np.dtype: ...

    @property
    def element_area(self) -> float: ...

    @property
    def grid(self) -> tuple[int, int] | None: ...

    @property
    def matrix(self) -> np.ndarray | None: ...

    @property
    def mean_compliance(self) -> float | None: ...

    def matvec(self, pressure) -> np.ndarray:
        """``C p`` [m] for pressures [Pa] of shape (n,) or (n, m) (one field per column)."""

    def __matmul__(self, pressure) -> np.ndarray:
        """``C @ p``, the same as :meth:`matvec`."""

    def diagonal(self) -> np.ndarray:
        """Self-compliances ``C_ii`` [m/Pa], shape (n,)."""

    def restrict(self, indices) -> InfluenceOperator:
        """The operator ``C_AA`` on the elements ``indices`` (a contact set ``A``)."""


@runtime_checkable
class PreconditionedOperator(Protocol):
    """A grid operator the preconditioned CG (:mod:`roughcontact.contact.pcg`) can drive.

    Attributes
    ----------
    grid : (int, int)
        ``(nx, ny)``; surfaces are ``(ny, nx)``.
    size : (float, float)
        ``(Lx, Ly)`` [m].
    column_budget : int
        Largest number of changed elements whose displacement is cheaper as a
        sum of kernel columns (:meth:`add_columns`) than as one product; 0
        when the operator offers no columns.
    """

    @property
    def grid(self) -> tuple[int, int]: ...

    @property
    def size(self) -> tuple[float, float]: ...

    @property
    def column_budget(self) -> int: ...

    def apply(self, pressure: np.ndarray) -> np.ndarray:
        """``C p`` [m] of a ``(ny, nx)`` pressure [Pa] (or ``(m, ny, nx)`` fields), in
        its dtype (float32 or float64)."""

    def diagonal(self) -> np.ndarray:
        """Self-compliances ``C_ii`` [m/Pa], shape (n,)."""

    def preconditioner(self):
        """The stencil (:class:`roughcontact.elasticity.transforms.Stencil`) of the
        approximate inverse of ``C`` the CG preconditions with."""

    def add_columns(self, target, rows, cols, values) -> None:
        """``target += C e`` [m] for the sparse ``e[rows, cols] = values`` [Pa]."""

    def coarsened(self) -> PreconditionedOperator:
        """The same body on the grid coarser by 2 per side (same ``size``)."""


@dataclass(frozen=True)
class DenseInfluence:
    """A dense symmetric influence matrix ``C`` [m/Pa] as an :class:`InfluenceOperator`.

    Parameters
    ----------
    matrix : ndarray (n, n)
        Influence coefficients [m/Pa], symmetric positive definite (not
        checked here; the contact solver checks and certifies what it is
        given, once per object).
    element_area : float
        Contact element area [m^2].
    grid : (int, int), optional
        ``(nx, ny)`` of the elements, when known.
    mean_compliance : float, optional
        The row sum of ``C`` [m/Pa] when it is known to be the same for every
        row (``C 1 = mean_compliance 1``), e.g. the dense form of a periodic
        half-space; ``0.0`` declares the uniform pressure a zero mode (the
        mean displacement fixed to zero), which the certificate leaves out
        and the contact solver bounds the approach for, as for the periodic
        operator itself. None (the default): not known.
    """

    matrix: np.ndarray = field(repr=False)
    element_area: float
    grid: tuple[int, int] | None = None
    mean_compliance: float | None = None
    #: Its :class:`~roughcontact.elasticity.definiteness.Certificate`, once certified.
    spd_certificate = None

    def __post_init__(self):
        object.__setattr__(self, "matrix", np.ascontiguousarray(self.matrix, dtype=float))

    @property
    def shape(self) -> tuple[int, int]:
        """``(n, n)``."""
        return self.matrix.shape

    @property
    def dtype(self) -> np.dtype:
        """float64."""
        return self.matrix.dtype

    def matvec(self, pressure) -> np.ndarray:
        """``C p`` [m]; for (n, m) pressures the rows of ``p^T C`` (C is symmetric), transposed."""
        p = np.asarray(pressure, dtype=float)
        if p.ndim == 1:
            return self.matrix @ p
        return (p.T @ self.matrix).T

    def __matmul__(self, pressure) -> np.ndarray:
        return self.matvec(pressure)

    def diagonal(self) -> np.ndarray:
        """``C_ii`` [m/Pa], shape (n,)."""
        return np.diag(self.matrix).copy()

    def restrict(self, indices) -> DenseInfluence:
        """The submatrix ``C_AA`` on the elements ``indices``."""
        index = np.asarray(indices)
        return DenseInfluence(self.matrix[np.ix_(index, index)], self.element_area)


@dataclass(frozen=True)
class RestrictedInfluence:
    """The sub-operator ``C_AA`` of a matrix-free operator on the elements ``indices``.

    Its product scatters the pressures of ``A`` into the full grid, applies
    the parent operator and gathers the displacements of ``A``.
    """

    parent: Any
    indices: np.ndarray
    grid = None
    matrix = None
    mean_compliance = None

    def __post_init__(self):
        object.__setattr__(self, "indices", np.asarray(self.indices, dtype=np.intp))

    @property
    def shape(self) -> tuple[int, int]:
        return (self.indices.size, self.indices.size)

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(float)

    @property
    def element_area(self) -> float:
        return self.parent.element_area

    def matvec(self, pressure) -> np.ndarray:
        p = np.asarray(pressure, dtype=float)
        full = np.zeros((self.parent.shape[0], *p.shape[1:]))
        full[self.indices] = p
        return np.asarray(self.parent.matvec(full), dtype=float)[self.indices]

    def __matmul__(self, pressure) -> np.ndarray:
        return self.matvec(pressure)

    def diagonal(self) -> np.ndarray:
        return np.asarray(self.parent.diagonal(), dtype=float)[self.indices]

    def restrict(self, indices) -> RestrictedInfluence:
        return RestrictedInfluence(self.parent, self.indices[np.asarray(indices)])


@dataclass(frozen=True)
class MatrixFreeInfluence:
    """Any object with ``shape`` and ``matvec`` as an :class:`InfluenceOperator`.

    Parameters
    ----------
    base : object
        Has ``shape == (n, n)`` and ``matvec`` accepting (n,) and (n, m).
    element_area : float
        Contact element area [m^2].
    self_compliance : ndarray (n,)
        ``C_ii`` [m/Pa], returned by :meth:`diagonal`.
    grid : (int, int), optional
        ``(nx, ny)`` of the elements.
    mean_compliance : float, optional
        Common row sum of ``C`` [m/Pa] (:class:`InfluenceOperator`).
    """

    base: Any
    element_area: float
    self_compliance: np.ndarray = field(repr=False)
    grid: tuple[int, int] | None = None
    mean_compliance: float | None = None
    matrix = None
    #: Its :class:`~roughcontact.elasticity.definiteness.Certificate`, once certified.
    spd_certificate = None

    @property
    def shape(self) -> tuple[int, int]:
        n = self.self_compliance.size
        return (n, n)

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(float)

    def matvec(self, pressure) -> np.ndarray:
        return np.asarray(self.base.matvec(pressure), dtype=float)

    def __matmul__(self, pressure) -> np.ndarray:
        return self.matvec(pressure)

    def diagonal(self) -> np.ndarray:
        return self.self_compliance

    def restrict(self, indices) -> RestrictedInfluence:
        return RestrictedInfluence(self, indices)


class GridOperator:
    """Members shared by the matrix-free operators of a regular grid of elements.

    A subclass holds ``grid = (nx, ny)`` and ``size = (Lx, Ly)`` [m] and
    defines ``_apply(fields)``, the displacements [m] of pressure fields [Pa]
    of shape (m, ny, nx); this base gives the rest of
    :class:`InfluenceOperator`: ``shape``, ``dtype``, ``element_area``,
    ``matrix`` (None: matrix-free), ``matvec`` and ``@`` on (n,) and (n, m)
    pressures, and ``restrict``; and the products of one ``(ny, nx)`` field
    in its own dtype (:meth:`apply`) and sums of kernel columns
    (:meth:`add_columns`, from a ``_columns`` table when the subclass holds
    one) of :class:`PreconditionedOperator`.
    """

    matrix = None
    _columns = None
    #: Its :class:`~roughcontact.elasticity.definiteness.Certificate`, once certified.
    spd_certificate = None
    #: Changed elements worth one product when summed column by column
    #: (a column costs about 1/25 of a free-space and 1/8 of a periodic
    #: single-precision product at 512^2 and 1024^2); 0: no columns.
    column_budget = 0

    def apply(self, pressure: np.ndarray) -> np.ndarray:
        """``u = C p`` [m] of a ``(ny, nx)`` pressure field [Pa] (or ``(m, ny, nx)``
        fields), in its dtype.

        float32 pressures give a single-precision product (about half the
        cost, rounding about 1e-7 of ``u``), anything else float64. The
        result may be a non-contiguous view.
        """
        p = np.asarray(pressure)
        if p.dtype not in (np.float32, np.float64):
            p = p.astype(np.float64)
        return self._apply(p) if p.ndim == 3 else self._apply(p[None])[0]

    def add_columns(self, target: np.ndarray, rows, cols, values) -> None:
        """``target += C e`` [m], ``e[rows, cols] = values`` [Pa], by kernel columns (float32)."""
        if self._columns is None:
            raise ValueError(f"{type(self).__name__} offers no kernel columns (column_budget 0)")
        self._columns.add(target, rows, cols, values)

    @property
    def shape(self) -> tuple[int, int]:
        """``(n, n)``, ``n = nx * ny`` elements."""
        n = self.grid[0] * self.grid[1]
        return (n, n)

    @property
    def element_area(self) -> float:
        """Area of one contact element ``dx * dy`` [m^2]."""
        return self.size[0] * self.size[1] / (self.grid[0] * self.grid[1])

    @property
    def dtype(self) -> np.dtype:
        """float64."""
        return np.dtype(float)

    def matvec(self, pressure) -> np.ndarray:
        """Displacement ``u = C p`` [m] for pressure ``p`` [Pa] (Eq 16).

        Parameters
        ----------
        pressure : array_like, shape (n,) or (n, m)
            Element pressures [Pa], flat index ``k = iy * nx + ix``; a second
            axis holds ``m`` independent pressure fields.

        Returns
        -------
        ndarray
            Displacements [m], same shape as ``pressure``.
        """
        nx, ny = self.grid
        n = nx * ny
        p = np.asarray(pressure, dtype=float)
        if p.ndim not in (1, 2) or p.shape[0] != n:
            raise ValueError(f"pressure must have shape (n,) or (n, m) with n = {n}, got {p.shape}")
        u = self._apply(p.reshape(n, -1).T.reshape(-1, ny, nx))
        return np.ascontiguousarray(u).reshape(-1, n).T.reshape(p.shape)

    def __matmul__(self, pressure) -> np.ndarray:
        """``C @ p``, see :meth:`matvec`."""
        return self.matvec(pressure)

    def restrict(self, indices) -> RestrictedInfluence:
        """``C_AA`` on the elements ``indices``, matrix-free."""
        return RestrictedInfluence(self, indices)
