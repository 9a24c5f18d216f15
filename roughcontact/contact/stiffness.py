"""Tangent contact stiffness ``dF/dd`` on a fixed free set, by conjugate gradients.

On a fixed free set ``F`` (the elements with ``p > 0``; with a cap ``H``,
``0 < p < H``) the solution of Eq 27 satisfies ``C_FF p_F = d 1 - f_F``
(``- C_FU H`` with a cap, which does not change with ``d``), so
``dp_F/dd = x`` with ``C_FF x = 1`` and

    dF/dd = dA * 1^T x = dA * 1^T (C_FF)^-1 1.

It is the derivative of the load-approach curve between changes of the
contact set, and it feeds the normalized stiffness ``k_P = (L / A_n) dF/dd``
of Eq 33. :func:`free_set_cg` solves ``C_FF x = 1`` for many surfaces at
once (the sweeps of :mod:`roughcontact.contact.sweeps`), preconditioned on
a grid FFT operator by the 13-tap |q| stencil of its
:meth:`~roughcontact.elasticity.protocol.PreconditionedOperator.preconditioner`
restricted to ``F`` (symmetric positive definite: the stencil's symbol is
positive); :mod:`roughcontact.contact.pivot` takes ``x`` from its factor
instead.
"""

from __future__ import annotations

import logging

import numpy as np

from roughcontact.contact import cg
from roughcontact.contact.checks import (
    as_operator,
    check_hardness,
    check_max_iter,
    check_positive,
    check_pressure,
    preconditioned_operator,
)
from roughcontact.contact.free_stencil import FreeSetStencil
from roughcontact.contact.kkt import free_set
from roughcontact.contact.products import Products

__all__ = ["free_set_cg", "tangent_stiffness"]

logger = logging.getLogger("roughcontact.contact")


def free_set_cg(products: Products, free, start, tol: float, max_iter: int):
    """Solve ``C_FF x = 1`` on each surface's free set ``F`` by CG.

    ``free`` (m, n) bool; ``start`` (m, n) initial guess (used on ``F``).
    Stops when ``||1 - C_FF x|| <= tol ||1_F||`` (Euclidean), checked on a
    double-precision residual; with single-precision products
    (``products.mixed``) the solve restarts from the exact residual
    (iterative refinement) until it is met. Returns ``(x, converged, products)``.
    """
    m, n = free.shape
    mask = free.astype(float)
    x = start * mask
    count = np.zeros(m, dtype=int)
    target = np.sqrt(mask.sum(axis=1))
    converged = target == 0.0
    surfaces = np.flatnonzero(~converged)
    xs, ms = x[surfaces], mask[surfaces]
    limit = (tol * target[surfaces]) ** 2
    grid = preconditioned_operator(products.operator)
    precondition = None if grid is None else _StencilOnSets(grid, free)
    iteration = 0
    while surfaces.size and iteration < max_iter:
        # Exact residual, then CG until its recursive estimate meets tol.
        residual = ms - ms * products.exact(xs)
        count[surfaces] += 1
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
        iteration = _inner_cg(products, xs, ms, residual, rr, limit, count, surfaces,
                              iteration, max_iter, precondition)
    x[surfaces] = xs
    return x, converged, count


class _StencilOnSets:
    """``z = Pi_F S Pi_F r`` for residuals (k, n) of surfaces on their free sets ``F``
    (:class:`~roughcontact.contact.free_stencil.FreeSetStencil`, O(13 |F|) each)."""

    def __init__(self, operator, free):
        nx, ny = operator.grid
        self.stencil = FreeSetStencil(operator.preconditioner(), (ny, nx))
        self.free = [np.flatnonzero(row) for row in free]
        self.cells = [np.divmod(flat, nx) for flat in self.free]

    def __call__(self, residual, surfaces):
        """``z`` of the residuals (k, n) of ``surfaces`` (indices into the free sets)."""
        z = np.zeros_like(residual)
        for row, j in enumerate(surfaces.tolist()):
            flat = self.free[j]
            z[row, flat] = self.stencil(*self.cells[j], residual[row, flat])
        return z


def _inner_cg(products, xs, ms, residual, rr, limit, count, surfaces, iteration, max_iter,
              precondition=None):
    """CG from the exact ``residual`` until its recursive estimate meets ``limit``
    (``xs`` and ``residual`` updated in place), preconditioned when ``precondition``
    is given; returns the iteration count."""
    z = residual if precondition is None else precondition(residual, surfaces)
    rz = rr if precondition is None else np.einsum("ij,ij->i", residual, z)
    direction = z.copy()
    inner = np.ones(surfaces.size, dtype=bool)
    while inner.any() and iteration < max_iter:
        iteration += 1
        q = np.zeros_like(direction)  # the rows that met the estimate have t = 0: q = 0
        q[inner] = products.search(direction[inner])
        q *= ms
        count[surfaces] += inner
        curvature = np.einsum("ij,ij->i", direction, q)
        alpha = np.divide(rz, curvature, out=np.zeros_like(rz),
                          where=inner & (curvature > 0.0))
        xs += alpha[:, None] * direction
        residual -= alpha[:, None] * q
        rr_new = np.einsum("ij,ij->i", residual, residual)
        inner &= (rr_new > limit) & (alpha > 0.0)
        if precondition is None:
            z, rz_new = residual, rr_new
        else:
            z = precondition(residual, surfaces)
            rz_new = np.einsum("ij,ij->i", residual, z)
        beta = np.divide(rz_new, rz, out=np.zeros_like(rz), where=rz > 0.0)
        direction *= beta[:, None]
        direction += z
        direction[~inner] = 0.0
        rz = rz_new
    return iteration


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
        Influence coefficients ``C`` [m/Pa], see :func:`roughcontact.contact.solve`.
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
    hardness = check_hardness(hardness)
    op = as_operator(operator, element_area)
    n = op.shape[0]
    p = check_pressure(pressure, n)
    tol = check_positive(tol)
    check_max_iter(max_iter)
    start = np.zeros((1, n))
    if x0 is not None:
        start = np.asarray(x0, dtype=float).reshape(1, n)
    limit = cg.default_max_iter(n) if max_iter is None else int(max_iter)
    x, converged, _ = free_set_cg(Products(op), free_set(p, hardness), start, tol, limit)
    if not converged[0]:
        logger.warning("tangent stiffness: CG on the contact set did not reach tol %.3g", tol)
    return float(op.element_area * x.sum())
