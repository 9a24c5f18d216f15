"""The hybrid influence model: Love's half-space plus the finite body's correction.

The near field of C (self compliance, nearest neighbours) is what a
finite-element mesh gets wrong and Love's closed form gets right; the finite
body adds a correction that varies on the scale of its thickness, computed by
:func:`roughcontact.elasticity.influence.unit_modulus_influence` on a coarser
contact grid and interpolated. The dense form is
:func:`hybrid_unit_modulus_influence`; the matrix-free one is
:func:`roughcontact.elasticity.operators.hybrid_operator`, which shares
:func:`finite_body_correction` and :func:`centre_interpolation`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import GB, BlockGeometry, unit_modulus_influence

__all__ = ["centre_interpolation", "finite_body_correction", "hybrid_unit_modulus_influence"]


def centre_interpolation(fine: int, coarse: int) -> np.ndarray:
    """Linear interpolation (extrapolation at the ends) from coarse to fine element centres.

    Both grids cover the same length with ``coarse`` and ``fine`` equal
    elements; returns the (fine, coarse) matrix acting on centre values.
    """
    x = (np.arange(fine) + 0.5) / fine * coarse - 0.5  # fine centres in coarse index units
    if coarse == 1:
        return np.ones((fine, 1))
    left = np.clip(np.floor(x).astype(int), 0, coarse - 2)
    weight = x - left
    matrix = np.zeros((fine, coarse))
    rows = np.arange(fine)
    matrix[rows, left] = 1.0 - weight
    matrix[rows, left + 1] = weight
    return matrix


def finite_body_correction(coarse_unit: np.ndarray, coarse: BlockGeometry) -> np.ndarray:
    """The finite body's correction to Love's half-space per unit loaded area [1/m].

    ``K = (E C_fe - E C_love) / A_c`` on the coarse contact grid of ``coarse``,
    from its finite-element ``E C_fe`` (``coarse_unit``, [m]; overwritten):
    the one recipe of the hybrid models, dense
    (:func:`hybrid_unit_modulus_influence`) and matrix-free
    (:func:`roughcontact.elasticity.operators.hybrid_operator`).
    """
    coarse_unit -= halfspace_influence(coarse.grid, coarse.size, 1.0, coarse.nu)
    coarse_unit /= coarse.spacing[0] * coarse.spacing[1]
    return coarse_unit


def hybrid_unit_modulus_influence(
    geom: BlockGeometry,
    *,
    coarsening: int = 2,
    solver: str = "auto",
    max_bytes: float = 16 * GB,
) -> np.ndarray:
    """``E * C`` [m] from Love's half-space plus a finite-body correction from a coarser grid.

    The near field of C (self compliance, nearest neighbours) is what a
    finite-element mesh gets wrong and what Love's closed form gets right; the
    finite body (rigid base at depth L, free lateral faces) only adds a
    correction that varies on the scale of L. So

        E C = E C_love(grid) + A * interp(K),   K = (E C_fe(coarse) - E C_love(coarse)) / A_c,

    where ``C_fe(coarse)`` is ``unit_modulus_influence`` for the same block and
    mesh (``geom.mesh``, e.g. "converged") on a contact grid ``coarsening``
    times coarser, ``C_love`` is ``halfspace_influence`` on each grid, K the
    correction per unit loaded area [1/m] at the coarse element
    centres, A and A_c the fine and coarse element areas, and ``interp`` the
    separable linear interpolation of K in both the observation and the load
    position (``(Py kron Px) K (Py kron Px)^T``, linear extrapolation at the
    edges). The cost is that of the coarse model (about ``coarsening^2``
    fewer dofs).

    ``coarsening=1`` returns the finite-element matrix itself.

    Accuracy, measured at the paper's 60 x 60 block (nu = 0, 3 Gaussian
    surfaces, sigma 24.5 um, b 1 mm) against the "converged" preset (102 s,
    7.6 GB on 2 loaded cores): with ``mesh="converged"``, ``coarsening=2``
    (15 s, 1.6 GB) the centre diagonal is within 0.2 %, the neighbours
    within 1.2 %, every diagonal entry at least 3 elements from the free
    lateral faces within 0.3 %, and k_P, real area, peak pressure and
    asperity deflection at P = 0.3, 1, 2 MPa within 0.5 %. With
    ``mesh="refined"`` (2.8 s, 0.5 GB): neighbours within 3.6 %, contact
    quantities within 1.2 %. Limitation: the correction is not smooth next
    to the free lateral faces (the block lacks the material the half-space
    has there), so the diagonal of the outermost elements is off by up to
    14 % (corners, "converged") or 18 % ("refined"); rows sum to L within
    1 % for nu = 0 (the finite-element matrix: 0.1 %).

    Parameters
    ----------
    geom : BlockGeometry
        Block and fine contact grid; ``geom.mesh`` is used for the coarse model.
    coarsening : int
        Ratio of fine to coarse contact elements per direction; must divide the grid.
    solver, max_bytes
        As in ``unit_modulus_influence`` (for the coarse model).

    Returns
    -------
    ndarray, shape (n, n)
        Symmetric ``E * C`` [m], row-major over y then x.
    """
    nx, ny = geom.grid
    k = int(coarsening)
    if k != coarsening or k < 1 or nx % k or ny % k:
        raise ValueError(f"coarsening must be a positive integer dividing the grid {geom.grid}, "
                         f"got {coarsening!r}")
    coarse = dataclasses.replace(geom, grid=(nx // k, ny // k))
    fe = finite_body_correction(unit_modulus_influence(coarse, solver=solver,
                                                       max_bytes=max_bytes), coarse)
    interp = sp.csr_array(sp.kron(sp.csr_array(centre_interpolation(ny, ny // k)),
                                  sp.csr_array(centre_interpolation(nx, nx // k))))
    correction = interp @ np.ascontiguousarray((interp @ fe).T)  # fe is symmetric
    del fe
    correction *= geom.spacing[0] * geom.spacing[1]
    result = halfspace_influence(geom.grid, geom.size, 1.0, geom.nu)
    result += correction
    return 0.5 * (result + result.T)
