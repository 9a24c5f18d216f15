"""The finite-body correction of the hybrid block on its coarse grid, ready for products.

The hybrid operator (:class:`roughcontact.elasticity.operators.BlockOperator`)
is ``E C = E C_love + A_f W K W^T``; :class:`CoarseCorrection` holds ``K``
[1/m], the correction per unit loaded area on the coarse contact grid
(:func:`roughcontact.elasticity.hybrid.finite_body_correction`), checked,
symmetrized and prepared once for its products ``K c`` in float32 and
float64, so that the same correction serves the operator on every grid of a
nested solve (:meth:`BlockOperator.coarsened`).

Mirror classes. The block, its structured mesh and a clamped base are
symmetric about the mid-planes ``x = Lx / 2`` and ``y = Ly / 2``
(:mod:`roughcontact.elasticity.symmetry`), so ``K`` commutes with the
reversals ``P_x``, ``P_y`` of the coarse grid. Then

    K = sum_chi W_chi K_chi W_chi^T,    K_chi = D W_chi^T K W_chi D,

over the four classes ``chi = (s_y, s_x)`` of fields symmetric (+1) or
antisymmetric (-1) about each mid-plane: ``W_chi^T`` takes the orbit sums
``c_i + s c_mirror(i)`` along each axis (:func:`fold`), ``D`` the inverse
orbit sizes, and ``K c`` costs four products with blocks of a quarter of
the unknowns each, a quarter of one with ``K`` (0.6 against 2.4 ms a
float32 product at 64 x 64 coarse elements, one thread). A correction
without that symmetry (a sliding base, whose corner pins are not
symmetric) is applied whole, on the coarse elements a field loads.

Units: ``K`` in 1/m, coarse fields in the units of the pressure [Pa].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.elasticity.transforms import DTYPES

__all__ = ["MIRROR_RTOL", "SPARSE_COARSE", "CoarseCorrection", "fold", "mirror_classes",
           "unfold"]

#: Largest ``max|K - P K P| / max|K|`` under the mirrors ``P`` (x and y reversed) for
#: which ``K`` is applied by mirror classes: the rounding of its finite-element model
#: (the clamped block's is symmetric to the last bit).
MIRROR_RTOL = 1e-12
#: Share of loaded coarse elements below which a correction without mirror classes uses
#: only the rows of K they load.
SPARSE_COARSE = 0.5


def fold(array: np.ndarray, axis: int, sign: int) -> np.ndarray:
    """Orbit sums ``a_i + sign a_(n-1-i)``, ``i < n // 2``, along ``axis`` (of length
    ``n``; the mirror reverses it), the middle entry of an odd ``n`` appended for
    ``sign = +1``."""
    a = np.moveaxis(array, axis, 0)
    n = a.shape[0]
    h = n // 2
    folded = a[:h] + sign * a[::-1][:h]
    if n % 2 and sign > 0:
        folded = np.concatenate([folded, a[h:h + 1]])
    return np.moveaxis(folded, 0, axis)


def unfold(array: np.ndarray, axis: int, sign: int, n: int) -> np.ndarray:
    """The transpose of :func:`fold`: each orbit's value on its element ``i`` and ``sign``
    times it on the mirror element ``n - 1 - i`` (length ``n`` along ``axis``)."""
    a = np.moveaxis(array, axis, 0)
    h = n // 2
    out = np.zeros((n, *a.shape[1:]), dtype=a.dtype)
    out[:h] = a[:h]
    out[::-1][:h] = a[:h] if sign > 0 else -a[:h]
    if n % 2 and sign > 0:
        out[h] = a[h]
    return np.moveaxis(out, 0, axis)


def _orbit_weights(n: int, sign: int) -> np.ndarray:
    """``1 / |orbit|`` of the entries :func:`fold` gives along a length ``n``: 1/2 for
    the pairs, 1 for the middle of an odd ``n`` (symmetric class only)."""
    weights = np.full(n // 2, 0.5)
    return np.append(weights, 1.0) if n % 2 and sign > 0 else weights


def mirror_classes(correction: np.ndarray, coarse_grid) -> list | None:
    """``K`` split by the block's mirror symmetry (module docstring), or None without it.

    Parameters
    ----------
    correction : ndarray (nc, nc)
        Symmetric ``K`` [1/m], coarse elements row-major over y then x.
    coarse_grid : (int, int)
        ``(ncx, ncy)``, ``nc = ncx * ncy``.

    Returns
    -------
    list of (int, int, ndarray) or None
        ``(s_y, s_x, K_chi)`` per class (float64; a grid of one element
        along an axis has no antisymmetric class there), or None when ``K``
        does not commute with both mirrors to :data:`MIRROR_RTOL`.
    """
    ncx, ncy = coarse_grid
    k4 = correction.reshape(ncy, ncx, ncy, ncx)
    scale = np.abs(correction).max()
    asymmetry = max(np.abs(k4 - k4[::-1, :, ::-1, :]).max(),
                    np.abs(k4 - k4[:, ::-1, :, ::-1]).max())
    if not asymmetry <= MIRROR_RTOL * scale:
        return None
    classes = []
    for sy in (1, -1):
        rows = fold(fold(k4, 0, sy), 2, sy)
        wy = _orbit_weights(ncy, sy)
        for sx in (1, -1):
            weights = (wy[:, None] * _orbit_weights(ncx, sx)[None, :]).ravel()
            if weights.size:
                block = fold(fold(rows, 1, sx), 3, sx).reshape(weights.size, weights.size)
                block *= weights[:, None] * weights[None, :]
                classes.append((sy, sx, block))
    return classes


@dataclass(frozen=True)
class CoarseCorrection:
    """The correction ``K`` [1/m] of a coarse grid, checked and ready for products.

    Build it with :meth:`of`. ``matrix`` is ``K`` symmetrized (float64,
    read-only), ``coarse_grid`` its ``(ncx, ncy)``; ``classes`` the
    :func:`mirror_classes` blocks in each dtype, or None, and then ``whole``
    holds ``K`` in each dtype.
    """

    matrix: np.ndarray
    coarse_grid: tuple[int, int]
    classes: dict | None
    whole: dict | None

    @classmethod
    def of(cls, correction, coarse_grid) -> CoarseCorrection:
        """``K`` (nc, nc) [1/m] on the coarse grid ``(ncx, ncy)``: checked (shape,
        finite), symmetrized, split by :func:`mirror_classes` when it can be."""
        ncx, ncy = coarse_grid
        nc = ncx * ncy
        matrix = np.ascontiguousarray(correction, dtype=float)
        if matrix.shape != (nc, nc):
            raise ValueError(f"correction must have shape ({nc}, {nc}) for coarse grid "
                             f"{coarse_grid}, got {matrix.shape}")
        if not np.isfinite(matrix).all():
            raise ValueError("correction has non-finite entries")
        matrix = 0.5 * (matrix + matrix.T)
        matrix.setflags(write=False)
        classes = mirror_classes(matrix, (ncx, ncy))
        if classes is None:
            return cls(matrix, (ncx, ncy), None, {t: matrix.astype(t, copy=False)
                                                  for t in DTYPES})
        return cls(matrix, (ncx, ncy),
                   {t: [(sy, sx, block.astype(t, copy=False)) for sy, sx, block in classes]
                    for t in DTYPES}, None)

    def apply(self, coarse: np.ndarray) -> np.ndarray:
        """``K c`` for coarse fields ``c`` (m, ncy, ncx), in their dtype."""
        m, ncy, ncx = coarse.shape
        if self.classes is None:
            flat = coarse.reshape(m, ncy * ncx)
            whole = self.whole[coarse.dtype]
            loaded = np.flatnonzero(flat.any(axis=0))
            if loaded.size < SPARSE_COARSE * flat.shape[1]:
                return (flat[:, loaded] @ whole[loaded]).reshape(coarse.shape)  # K = K^T
            return (flat @ whole).reshape(coarse.shape)
        out = np.zeros_like(coarse)
        for sy, sx, block in self.classes[coarse.dtype]:
            folded = fold(fold(coarse, 2, sx), 1, sy)
            ry, rx = folded.shape[1:]
            product = (block @ folded.reshape(m, ry * rx).T).T.reshape(m, ry, rx)
            out += unfold(unfold(product, 1, sy, ncy), 2, sx, ncx)
        return out

    def nbytes(self) -> int:
        """Memory held [bytes]."""
        arrays = {id(self.matrix): self.matrix}
        for dtype in DTYPES:
            parts = [self.whole[dtype]] if self.classes is None else \
                [block for _, _, block in self.classes[dtype]]
            arrays.update((id(a), a) for a in parts)
        return int(sum(a.nbytes for a in arrays.values()))
