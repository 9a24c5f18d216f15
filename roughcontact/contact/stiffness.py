"""Tangent contact stiffness ``dF/dd`` on a fixed free set, by conjugate gradients.

On a fixed free set ``F`` (the elements with ``p > 0``; with a cap ``H``,
``0 < p < H``) the solution of Eq 27 satisfies ``C_FF p_F = d 1 - f_F``
(``- C_FU H`` with a cap, which does not change with ``d``), so
``dp_F/dd = x`` with ``C_FF x = 1`` and

    dF/dd = dA * 1^T x = dA * 1^T (C_FF)^-1 1.

It is the derivative of the load-approach curve between changes of the
contact set, and it feeds the normalized stiffness ``k_P = (L / A_n) dF/dd``
of Eq 33. :func:`free_set_cg` solves ``C_FF x = 1`` for many surfaces
together (the sweeps of :mod:`roughcontact.contact.sweeps`), each on its
free elements only, their products batched, preconditioned on
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
)
from roughcontact.contact.free_stencil import FreeSetStencil
from roughcontact.contact.kkt import free_set
from roughcontact.contact.pcg import IN_FLIGHT_ELEMENTS, ProductRequest, grid_operator, run_solves
from roughcontact.contact.products import Products

__all__ = ["free_set_cg", "tangent_stiffness"]

logger = logging.getLogger("roughcontact.contact")


def free_set_cg(products: Products, free, start, tol: float, max_iter: int):
    """Solve ``C_FF x = 1`` on each surface's free set ``F`` by CG, the surfaces together.

    ``free`` (m, n) bool; ``start`` (m, n) initial guess (used on ``F``).
    Each surface stops when ``||1 - C_FF x|| <= tol ||1_F||`` (Euclidean),
    checked on a double-precision residual; with single-precision products
    (``products.mixed``) its CG restarts from the exact residual (iterative
    refinement) until it is met, within ``max_iter`` iterations. On a grid
    FFT operator the CG is preconditioned by its stencil on ``F``
    (:class:`~roughcontact.contact.free_stencil.FreeSetStencil`). Each
    surface iterates on its free elements only; the products of the
    surfaces in flight are taken together
    (:func:`roughcontact.contact.pcg.run_solves`).

    Returns
    -------
    (ndarray (m, n), ndarray (m,) of bool, ndarray (m,) of int)
        ``x`` [Pa/m] (zero off ``F``), whether each surface met ``tol``, and
        its products.
    """
    m, n = free.shape
    operator = grid_operator(products)
    nx, ny = operator.grid
    stencil = FreeSetStencil(operator.preconditioner(), (ny, nx))
    dtype = np.float32 if products.mixed else np.float64
    flats = [np.flatnonzero(row) for row in free]
    solves = (_solve_steps(operator, stencil, np.divmod(flat, nx), start[j, flat], tol,
                           max_iter, dtype) for j, flat in enumerate(flats))
    x = np.zeros((m, n))
    converged = np.zeros(m, dtype=bool)
    count = np.zeros(m, dtype=int)
    for j, (x_free, ok, products_j) in enumerate(run_solves(solves,
                                                             IN_FLIGHT_ELEMENTS // n)):
        x[j, flats[j]] = x_free
        converged[j], count[j] = ok, products_j
    return x, converged, count


def _solve_steps(operator, stencil, cells, x, tol: float, max_iter: int, dtype):
    """:func:`free_set_cg` of one surface on its free elements ``cells = (rows, cols)``
    from ``x``, as a generator of its products; returns ``(x, converged, products)``."""
    rows, cols = cells
    x = np.array(x, dtype=float)
    limit = tol * tol * rows.size
    count = iteration = 0
    start = not x.any()  # from zero the residual is 1, exactly, without a product
    while rows.size:
        # Exact residual, then CG until its recursive estimate meets tol.
        if start:
            residual, start = np.ones(rows.size), False
        else:
            product = yield ProductRequest(operator, rows, cols, x, np.float64)
            count += 1
            residual = 1.0 - product[rows, cols]
        rr = residual @ residual
        if rr <= limit:
            return x, True, count
        if iteration >= max_iter:
            break
        z = stencil(rows, cols, residual)
        rz, direction = z @ residual, z
        while iteration < max_iter:
            iteration += 1
            product = yield ProductRequest(operator, rows, cols, direction, dtype)
            count += 1
            q = product[rows, cols].astype(float)
            curvature = direction @ q
            if not curvature > 0.0:
                break
            alpha = rz / curvature
            x += alpha * direction
            residual -= alpha * q
            if residual @ residual <= limit:
                break
            z = stencil(rows, cols, residual)
            rz, rz_old = z @ residual, rz
            direction = z + (rz / rz_old if rz_old > 0.0 else 0.0) * direction
    return x, not rows.size, count


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
