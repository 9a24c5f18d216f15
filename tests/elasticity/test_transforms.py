"""FFT products of the grid operators: pruned, float32 and float64, kernel columns, coarsening."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft

from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    SpectralHalfSpace,
    _element_kernel,
    halfspace_influence,
)
from roughcontact.elasticity.protocol import InfluenceOperator, PreconditionedOperator

SIZE = (9e-3, 7.5e-3)
E, NU = 5.11e8, 0.3


def _hybrid(grid=(24, 20), coarse=(6, 5), seed=0):
    """A block operator with a smooth random symmetric correction (positive diagonal)."""
    nc = coarse[0] * coarse[1]
    rng = np.random.default_rng(seed)
    a = rng.random((nc, nc))
    return operators.BlockOperator(grid=grid, size=SIZE, nu=NU, correction=(a + a.T) * 1e-3,
                                   coarse_grid=coarse)


def _unpruned_love(p, nx, ny):
    """Independent product: full rfft2 of the zero-padded grid with the embedded kernel."""
    dx, dy = SIZE[0] / nx, SIZE[1] / ny
    kernel = _element_kernel(nx, ny, dx, dy, 1.0, NU)
    ix = np.abs(np.fft.fftfreq(2 * nx, 1.0 / (2 * nx))).astype(int)
    iy = np.abs(np.fft.fftfreq(2 * ny, 1.0 / (2 * ny))).astype(int)
    full = np.where((ix[None, :] < nx) & (iy[:, None] < ny),
                    kernel[np.minimum(iy, ny - 1)[:, None], np.minimum(ix, nx - 1)[None, :]], 0.0)
    padded = np.fft.irfft2(np.fft.rfft2(p, s=(2 * ny, 2 * nx)) * np.fft.rfft2(full),
                           s=(2 * ny, 2 * nx))
    return padded[:ny, :nx]


@pytest.mark.parametrize("grid", [(17, 11), (32, 32)])
def test_pruned_halfspace_product_equals_unpruned_and_dense(grid):
    nx, ny = grid
    op = operators.halfspace_operator(grid, SIZE, NU, workers=2)
    p = np.random.default_rng(1).random((ny, nx))
    u = op.apply(p)
    assert u.dtype == np.float64
    reference = _unpruned_love(p, nx, ny)
    assert np.abs(u - reference).max() <= 1e-13 * np.abs(reference).max()
    dense = halfspace_influence(grid, SIZE, 1.0, NU) @ p.ravel()
    assert np.abs(u.ravel() - dense).max() <= 1e-13 * np.abs(dense).max()


@pytest.mark.parametrize("build", [
    lambda: operators.halfspace_operator((24, 20), SIZE, NU),
    _hybrid,
    lambda: PeriodicHalfSpace((24, 20), SIZE, E, NU, images=1),
    lambda: SpectralHalfSpace((24, 20), SIZE, E, NU),
], ids=["halfspace", "hybrid", "periodic", "spectral"])
def test_single_precision_products_match_double(build):
    op = build()
    assert isinstance(op, InfluenceOperator)
    assert isinstance(op, PreconditionedOperator)
    p = np.random.default_rng(2).random((20, 24))
    double = op.apply(p)
    single = op.apply(p.astype(np.float32))
    assert single.dtype == np.float32
    assert np.abs(single - double).max() <= 2e-6 * np.abs(double).max()
    # the float64 product is the operator's matvec
    np.testing.assert_allclose(double.ravel(), op.matvec(p.ravel()), rtol=1e-14, atol=0)
    assert op.nbytes() > 2 * double.nbytes


def test_hybrid_float32_correction_matches_dense_to_single_precision():
    op = _hybrid()
    dense = op.to_dense()
    p = np.random.default_rng(3).random((20, 24)).astype(np.float32)
    reference = dense @ p.ravel().astype(float)
    assert np.abs(op.apply(p).ravel() - reference).max() <= 2e-6 * np.abs(reference).max()


@pytest.mark.parametrize("mode", [(1, 0), (3, 2), (5, -4)])
def test_spectral_halfspace_applies_its_symbol_to_a_cosine(mode):
    """A single Fourier mode p = cos(q.x) gives u = 2 (1 - nu^2) / (E |q|) p exactly."""
    grid, size = (32, 24), (2e-3, 1.5e-3)
    op = SpectralHalfSpace(grid, size, E, NU)
    kx, ky = mode
    x = np.arange(grid[0]) * size[0] / grid[0]
    y = np.arange(grid[1]) * size[1] / grid[1]
    qx, qy = 2 * np.pi * kx / size[0], 2 * np.pi * ky / size[1]
    p = np.cos(qx * x[None, :] + qy * y[:, None])
    expected = 2.0 * (1.0 - NU**2) / (E * np.hypot(qx, qy)) * p
    np.testing.assert_allclose(op.apply(p), expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    # a uniform pressure gives no displacement (zero mode)
    assert np.abs(op.apply(np.ones((24, 32)))).max() < 1e-25


def test_spectral_halfspace_is_symmetric_with_its_mean_eigenvalue_on_the_diagonal():
    op = SpectralHalfSpace((16, 12), SIZE, E, NU)
    rng = np.random.default_rng(4)
    a, b = rng.random((2, 16 * 12))
    assert abs(a @ op.matvec(b) - b @ op.matvec(a)) <= 1e-13 * abs(a @ op.matvec(b))
    column = op.matvec(np.eye(16 * 12)[:, 37])
    # abs=0: approx's default abs=1e-12 would pass any m/Pa value
    assert column[37] == pytest.approx(op.diagonal()[0], rel=1e-12, abs=0.0)
    # C_ii is the mean of the eigenvalues 2 / (E* |q|) over the full grid
    qx = 2 * np.pi * np.fft.fftfreq(16, SIZE[0] / 16)
    qy = 2 * np.pi * np.fft.fftfreq(12, SIZE[1] / 12)
    q = np.hypot(qx[None, :], qy[:, None])
    eig = np.where(q > 0, 2 * (1 - NU**2) / (E * np.where(q > 0, q, 1.0)), 0.0)
    assert op.diagonal()[0] == pytest.approx(eig.mean(), rel=1e-12, abs=0.0)


def _mirrored_hybrid(grid=(24, 20), coarse=(6, 5)):
    """A block operator whose correction has the block's mirror symmetry."""
    nc = coarse[0] * coarse[1]
    a = np.random.default_rng(1).random((nc, nc))
    k4 = (a + a.T).reshape(coarse[1], coarse[0], coarse[1], coarse[0])
    k4 = k4 + k4[::-1, :, ::-1, :]
    k4 = k4 + k4[:, ::-1, :, ::-1]
    return operators.BlockOperator(grid=grid, size=SIZE, nu=NU, correction=k4.reshape(nc, nc)
                                   * 1e-3, coarse_grid=coarse)


@pytest.mark.parametrize("build", [
    lambda: operators.halfspace_operator((24, 20), SIZE, NU),
    _hybrid,
    _mirrored_hybrid,
    lambda: PeriodicHalfSpace((24, 20), SIZE, E, NU, images=1),
    lambda: SpectralHalfSpace((24, 20), SIZE, E, NU),
], ids=["halfspace", "hybrid", "mirrored-hybrid", "periodic", "spectral"])
def test_kernel_columns_equal_the_product_of_a_sparse_pressure(build):
    op = build()
    assert op.column_budget > 0
    rows, cols = np.array([0, 7, 19, 19]), np.array([23, 4, 0, 23])
    values = np.array([1.5, -2.0, 0.7, 3.0])
    e = np.zeros((20, 24))
    e[rows, cols] = values
    expected = op.matvec(e.ravel()).reshape(20, 24)
    target = np.zeros((20, 24))
    op.add_columns(target, rows, cols, values)
    assert np.abs(target - expected).max() <= 1e-6 * np.abs(expected).max()


@pytest.mark.parametrize("build", [
    lambda g: operators.halfspace_operator(g, SIZE, NU),
    lambda g: _hybrid(g, (6, 5)),
    lambda g: PeriodicHalfSpace(g, SIZE, E, NU, images=1),
    lambda g: SpectralHalfSpace(g, SIZE, E, NU),
], ids=["halfspace", "hybrid", "periodic", "spectral"])
def test_coarsened_is_the_same_body_on_half_the_grid(build):
    fine, coarse = build((24, 20)), build((12, 10))
    halved = fine.coarsened()
    assert halved.grid == (12, 10) and halved.size == fine.size
    p = np.random.default_rng(5).random(120)
    np.testing.assert_allclose(halved.matvec(p), coarse.matvec(p), rtol=1e-13)
    with pytest.raises(ValueError, match="cannot be halved"):
        build((13, 10)).coarsened()


def test_stencil_approximates_the_inverse_symbol_on_a_smooth_mode():
    """The 13 taps of E* |q| / 2 applied to a long cosine give about E* |q| / 2 times it."""
    op = SpectralHalfSpace((64, 64), (1e-3, 1e-3), E, NU)
    stencil = op.preconditioner()
    assert stencil.periodic and stencil.weights.size == 13
    x = np.arange(64) * 1e-3 / 64
    q = 2 * np.pi * 4 / 1e-3
    p = np.cos(q * x)[None, :] * np.ones((64, 1))
    z = sum(w * np.roll(p, (-jy, -jx), axis=(0, 1))
            for (jy, jx), w in zip(stencil.offsets, stencil.weights, strict=True))
    symbol = 0.5 * E / (1 - NU**2) * q
    ratio = (z * p).sum() / (p * p).sum() / symbol
    assert 0.5 < ratio < 2.0
    assert not operators.halfspace_operator((8, 8), SIZE, NU).preconditioner().periodic


def test_scipy_fft_is_what_the_products_use():
    """float32 transforms stay float32 (no silent promotion to double)."""
    assert scipy.fft.rfft(np.zeros(8, dtype=np.float32)).dtype == np.complex64


def test_apply_takes_a_batch_of_fields():
    op = _hybrid()
    fields = np.random.default_rng(6).random((3, 20, 24)).astype(np.float32)
    batch = op.apply(fields)
    assert batch.shape == fields.shape and batch.dtype == np.float32
    for field, u in zip(fields, batch, strict=True):
        np.testing.assert_allclose(u, op.apply(field), rtol=1e-6, atol=1e-6 * np.abs(u).max())


def test_hybrid_product_of_a_small_contact_set_equals_the_dense_matrix():
    """A pressure on few elements loads few coarse elements: K is applied on those only."""
    op = _hybrid((48, 40), (12, 10))
    dense = op.to_dense()
    p = np.zeros((40, 48))
    p[3:6, 30:34] = np.random.default_rng(7).random((3, 4))
    reference = dense @ p.ravel()
    assert np.abs(op.apply(p).ravel() - reference).max() <= 1e-12 * np.abs(reference).max()
    single = op.apply(p.astype(np.float32)).ravel()
    assert np.abs(single - reference).max() <= 2e-6 * np.abs(reference).max()
