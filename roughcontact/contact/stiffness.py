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

Accuracy. For any ``x`` with residual ``r = 1 - C_FF x`` the variational
estimate ``total = 1^T x + x^T r = 2 1^T x - x^T C_FF x`` errs by

    1^T (C_FF)^-1 1 - total = r^T (C_FF)^-1 r >= 0,

quadratic in the residual (``1^T x`` alone errs linearly). The CG stops
when ``2 r^T M r <= tol total``, ``M`` the preconditioner (``M ~
C_FF^-1``; ``32 r^T diag(C)^-1 r`` on an operator without one, the factors
:data:`STENCIL_SAFETY` and :data:`DIAGONAL_SAFETY`): ``tol`` bounds the
*relative error of the stiffness*, as estimated. Measured, the error is
then at most 0.4 tol (20 x 24 grids at 2-60 % contact and finite-element
matrices of the paper and refined meshes, tol 1e-2 to 1e-8);
on the hybrid 256^2 block at 0.5-9 % contact ``r^T M r`` alone is 2-4 times
the true error. Stopping on it takes fewer products than a residual test
of the same tolerance, whose error in ``total`` is its square.
"""

from __future__ import annotations

import logging
from typing import NamedTuple

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
from roughcontact.contact.pcg import IN_FLIGHT_ELEMENTS, ProductRequest, grid_operator, run_solves
from roughcontact.contact.products import Products

__all__ = ["DIAGONAL_SAFETY", "STENCIL_SAFETY", "FreeSetSolution", "free_set_cg",
           "tangent_stiffness"]

logger = logging.getLogger("roughcontact.contact")


#: Factor on the stencil's error estimate ``r^T M r``: measured 2-4 times the true error
#: on the hybrid 256^2 block, but up to 0.8 of it on 20 x 24 grids.
STENCIL_SAFETY = 2.0
#: Factor on the diagonal error estimate ``r^T diag(C)^-1 r`` of an operator without a
#: preconditioner (a dense matrix): it underestimates ``r^T C_FF^-1 r`` by up to 7x on
#: the paper mesh's finite-element matrices, whose neighbours couple strongly (the error
#: reached 1.7 tol with a factor 4 on 24 x 24; with 32, at most 0.30 tol there and 0.18
#: tol on the quick study's 32 x 32 paper and refined matrices, nu 0 and 0.3).
DIAGONAL_SAFETY = 32.0


class FreeSetSolution(NamedTuple):
    """What :func:`free_set_cg` returns for ``m`` surfaces.

    ``x`` (m, n) [Pa/m] (zero off ``F``); ``converged`` (m,) whether the
    estimated relative error of ``total`` met the tolerance; ``products`` (m,)
    the products taken; ``total`` (m,) the variational estimate of
    ``1^T (C_FF)^-1 1`` (module docstring), from which ``dF/dd = dA total``.
    """

    x: np.ndarray
    converged: np.ndarray
    products: np.ndarray
    total: np.ndarray


def free_set_cg(products: Products, free, start, tol: float, max_iter: int) -> FreeSetSolution:
    """Solve ``C_FF x = 1`` on each surface's free set ``F`` by CG, the surfaces together.

    ``free`` (m, n) bool; ``start`` (m, n) initial guess (used on ``F``; zero
    makes the first residual free and the CG iterates Galerkin, whose error
    in ``total`` is quadratic in the residual). Each surface stops when the
    estimated relative error of its ``total`` is at most ``tol`` (module
    docstring), checked on a double-precision residual; with single-precision
    products (``products.mixed``) its CG restarts from the exact residual
    (iterative refinement) until it is met, within ``max_iter`` iterations.
    On a grid FFT operator the CG is preconditioned by its stencil on ``F``
    (:class:`~roughcontact.contact.free_stencil.FreeSetStencil`). Each
    surface iterates on its free elements only; the products of the
    surfaces in flight are taken together
    (:func:`roughcontact.contact.pcg.run_solves`).
    """
    m, n = free.shape
    operator = grid_operator(products)
    nx, ny = operator.grid
    stencil = FreeSetStencil(operator.preconditioner(), (ny, nx))
    # without a preconditioner, the error estimate takes C^-1 r as r / diag(C)
    diagonal = None if preconditioned_operator(products.operator) is not None else \
        np.asarray(products.operator.diagonal(), dtype=float).reshape(-1)
    dtype = np.float32 if products.mixed else np.float64
    flats = [np.flatnonzero(row) for row in free]
    solves = (_solve_steps(operator, stencil, np.divmod(flat, nx), start[j, flat], tol,
                           max_iter, dtype, None if diagonal is None else diagonal[flat])
              for j, flat in enumerate(flats))
    x = np.zeros((m, n))
    converged = np.zeros(m, dtype=bool)
    count = np.zeros(m, dtype=int)
    total = np.zeros(m)
    for j, (x_free, ok, products_j, total_j) in enumerate(run_solves(solves,
                                                                     IN_FLIGHT_ELEMENTS // n)):
        x[j, flats[j]] = x_free
        converged[j], count[j], total[j] = ok, products_j, total_j
    return FreeSetSolution(x, converged, count, total)


def _solve_steps(operator, stencil, cells, x, tol: float, max_iter: int, dtype, diagonal):
    """:func:`free_set_cg` of one surface on its free elements ``cells = (rows, cols)``
    from ``x``, as a generator of its products; returns ``(x, converged, products,
    total)``. ``diagonal``: ``C_ii`` on ``F`` for the error estimate of an operator
    without a preconditioner, else None."""
    rows, cols = cells
    x = np.array(x, dtype=float)
    count = iteration = 0
    start = not x.any()  # from zero the residual is 1, exactly, without a product
    total = 0.0

    def met(residual, z) -> bool:
        """``total = 1^T x + x^T r``; whether ``r^T M r <= tol total`` (M ~ C_FF^-1)."""
        nonlocal total
        total = float(x.sum() + x @ residual)
        estimate = STENCIL_SAFETY * (z @ residual) if diagonal is None else \
            DIAGONAL_SAFETY * ((residual / diagonal) @ residual)
        return bool(estimate <= tol * total)

    while rows.size:
        # Exact residual, then CG until the error estimate on its recursive residual
        # meets tol.
        if start:
            residual, start = np.ones(rows.size), False
        else:
            product = yield ProductRequest(operator, rows, cols, x, np.float64)
            count += 1
            residual = 1.0 - product[rows, cols]
        z = stencil(rows, cols, residual)
        if met(residual, z):
            return x, True, count, total
        if iteration >= max_iter:
            break
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
            z = stencil(rows, cols, residual)
            if met(residual, z):
                break
            rz, rz_old = z @ residual, rz
            direction = z + (rz / rz_old if rz_old > 0.0 else 0.0) * direction
    return x, not rows.size, count, total


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
    ``A``, and ``dF/dd`` from its variational estimate (module docstring). It
    feeds the normalized stiffness ``k_P = (L / A_n) dF/dd`` of Eq 33.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`roughcontact.contact.solve`.
    pressure : ndarray
        Solved contact pressure [Pa]; only its support ``p > 0`` is used.
    element_area : float, optional
        Element area ``dA`` [m^2]; default ``operator.element_area``.
    tol : float
        Estimated relative error of ``dF/dd`` at which CG stops (module docstring).
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
    solution = free_set_cg(Products(op), free_set(p, hardness), start, tol, limit)
    if not solution.converged[0]:
        logger.warning("tangent stiffness: CG on the contact set did not reach tol %.3g", tol)
    return float(op.element_area * solution.total[0])
