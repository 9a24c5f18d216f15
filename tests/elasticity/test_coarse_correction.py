"""The hybrid block's correction by mirror classes (roughcontact.elasticity.coarse_correction)
against the plain product with K."""

from __future__ import annotations

import numpy as np
import pytest

from roughcontact.elasticity import coarse_correction
from roughcontact.elasticity.coarse_correction import CoarseCorrection
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.elasticity.operators import block_operator


def mirrored(coarse_grid, seed=0):
    """A random symmetric K that commutes with both mirrors of the coarse grid."""
    ncx, ncy = coarse_grid
    nc = ncx * ncy
    a = np.random.default_rng(seed).random((nc, nc))
    k4 = (a + a.T).reshape(ncy, ncx, ncy, ncx)
    k4 = k4 + k4[::-1, :, ::-1, :]
    return (k4 + k4[:, ::-1, :, ::-1]).reshape(nc, nc)


@pytest.mark.parametrize("coarse_grid", [(6, 4), (5, 7), (1, 4), (3, 1)])
def test_mirror_classes_give_the_product_with_k(coarse_grid):
    """Even and odd sides (a middle row or column of its own), one-element sides (no
    antisymmetric class there): K c by the classes equals c K, in both dtypes."""
    ncx, ncy = coarse_grid
    k = mirrored(coarse_grid)
    prepared = CoarseCorrection.of(k, coarse_grid)
    assert prepared.classes is not None and prepared.whole is None
    blocks = sum(block.shape[0] for _, _, block in prepared.classes[np.dtype(np.float64)])
    assert blocks == ncx * ncy  # the classes split the unknowns
    fields = np.random.default_rng(1).standard_normal((3, ncy, ncx))
    expected = (fields.reshape(3, -1) @ k).reshape(fields.shape)
    got = prepared.apply(fields)
    assert np.abs(got - expected).max() <= 1e-13 * np.abs(expected).max()
    single = prepared.apply(fields.astype(np.float32))
    assert single.dtype == np.float32
    assert np.abs(single - expected).max() <= 1e-5 * np.abs(expected).max()


def test_a_correction_without_the_symmetry_is_applied_whole():
    a = np.random.default_rng(2).random((24, 24))
    k = a + a.T
    prepared = CoarseCorrection.of(k, (6, 4))
    assert prepared.classes is None
    fields = np.zeros((2, 4, 6))
    fields[0, 1, 2] = 1.0  # few loaded coarse elements: the rows of K they load
    fields[1] = np.random.default_rng(3).random((4, 6))
    expected = (fields.reshape(2, -1) @ k).reshape(fields.shape)
    assert np.abs(prepared.apply(fields) - expected).max() <= 1e-13 * np.abs(expected).max()
    # asymmetric beyond the rounding of a finite-element model: no classes
    assert coarse_correction.mirror_classes(mirrored((6, 4)) + 1e-9 * k, (6, 4)) is None


def test_correction_is_checked():
    with pytest.raises(ValueError, match=r"shape \(24, 24\)"):
        CoarseCorrection.of(np.eye(20), (6, 4))
    with pytest.raises(ValueError, match="non-finite"):
        CoarseCorrection.of(np.full((24, 24), np.nan), (6, 4))


def test_the_clamped_block_correction_has_the_mirror_symmetry():
    """The finite-element model of the clamped block is symmetric about its mid-planes,
    so its correction is applied by classes."""
    geom = BlockGeometry(grid=(16, 12), size=(9e-3, 7.5e-3), mesh="refined")
    op = block_operator(geom, coarse_grid=(8, 6))
    assert CoarseCorrection.of(op.correction, op.coarse_grid).classes is not None
    assert op.coarsened().correction is op.correction  # prepared once, shared
