"""The stencil preconditioner of a grid operator, applied on a free set only.

The preconditioned CGs of the grid FFT operators (the contact solve of
:mod:`roughcontact.contact.pcg`, the tangent stiffness of
:mod:`roughcontact.contact.stiffness`) precondition with ``Pi_F S Pi_F``:
``S`` the operator's real-space stencil
(:meth:`~roughcontact.elasticity.protocol.PreconditionedOperator.preconditioner`,
13 taps of ``E* |q| / 2``, the inverse of the half-space symbol), ``Pi_F``
the restriction to the free set ``F`` (the elements in contact). Applied
to the residual on ``F`` only, it costs O(13 |F|), not O(13 n).

Units: the residual in m, the preconditioned residual in Pa (the taps in
Pa/m).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FreeSetStencil"]


class FreeSetStencil:
    """``z_F = Pi_F S Pi_F r_F`` for residuals given on a free set ``F``.

    The residual is scattered into a persistent grid with a halo of the
    stencil's radius (wrapped for a periodic operator, zero otherwise) and
    gathered back at the stencil's offsets.

    Parameters
    ----------
    stencil : roughcontact.elasticity.transforms.Stencil
        Offsets and weights [Pa/m] of ``S``.
    shape : (int, int)
        ``(ny, nx)`` of the grid.
    """

    def __init__(self, stencil, shape):
        ny, nx = shape
        self.radius = r = max(1, int(np.abs(stencil.offsets).max()))
        self.weights = stencil.weights.tolist()
        self.periodic = stencil.periodic
        self.grid = np.zeros((ny + 2 * r, nx + 2 * r))
        self.flat = self.grid.reshape(-1)
        self.offsets = (stencil.offsets[:, 0] * (nx + 2 * r) + stencil.offsets[:, 1]).tolist()
        self.base = None

    def __call__(self, rows, cols, residual, centred: bool = False) -> np.ndarray:
        """``z`` on the elements ``(rows, cols)`` of ``F`` for the residual ``r`` there.

        ``centred``: ``Pi_F S Pi_F (r - mean r)`` less its mean, for a CG that
        keeps the mean of its iterate fixed (the mean mode of
        :mod:`roughcontact.contact.pcg`).
        """
        r, g = self.radius, self.grid
        if self.base is not None:
            self.flat[self.base] = 0.0
            if self.periodic:
                g[:r], g[-r:], g[:, :r], g[:, -r:] = 0.0, 0.0, 0.0, 0.0
        self.base = (rows + r) * g.shape[1] + (cols + r)
        self.flat[self.base] = residual - residual.mean() if centred else residual
        if self.periodic:
            g[:r], g[-r:] = g[-2 * r:-r], g[r:2 * r]
            g[:, :r], g[:, -r:] = g[:, -2 * r:-r], g[:, r:2 * r]
        z = np.zeros(rows.size)
        for weight, offset in zip(self.weights, self.offsets, strict=True):
            z += weight * self.flat[self.base + offset]
        if centred:
            z -= z.mean()
        return z
