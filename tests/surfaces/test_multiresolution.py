"""One band-limited surface resolved on several grids (roughcontact.surfaces.multiresolution).

References independent of the code under test: the trigonometric polynomial
summed point by point here from the band grid's coefficients, numpy's
central differences for the rms gradient, and the self-affine PSD's cut-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from roughcontact.surfaces.multiresolution import band_grid, embed_spectrum, generate_resolved
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.statistics import height_stats, spectral_moments

MM = 1e-3
SIZE = (1.0 * MM, 0.75 * MM)  # unequal sides: x and y cannot be swapped unseen
SEEDS = [11, 12, 13]


def spec(**fields) -> SurfaceSpec:
    """Self-affine, H 0.8, roll-off at L / 4, cut-off at Lx / 16 (a band grid of 34 x 26)."""
    return SurfaceSpec(grid=(32, 32), size=SIZE, acf="self-affine", hurst=0.8,
                       rolloff_wavelength=0.25 * MM, cutoff_wavelength=SIZE[0] / 16,
                       sigma=1e-6, **fields)


@pytest.fixture(scope="module")
def resolved():
    return generate_resolved(spec(), SEEDS, [(48, 32), (96, 64), (192, 128)], rms_gradient=0.1)


def test_band_grid_is_the_coarsest_even_grid_above_the_cutoff():
    nx, ny = band_grid(spec())
    q_s = 2 * math.pi / (SIZE[0] / 16)
    for n, length in ((nx, SIZE[0]), (ny, SIZE[1])):
        assert n % 2 == 0 and math.pi * n / length > q_s  # Nyquist above the cut-off
        assert math.pi * (n - 2) / length <= q_s  # two points fewer would not be
    assert (nx, ny) == (34, 26)


def test_coarse_maps_equal_the_fine_one_at_the_shared_points(resolved):
    fine = resolved[(192, 128)]
    scale = np.abs(fine).max()
    for grid, step in (((96, 64), 2), ((48, 32), 4)):
        np.testing.assert_allclose(resolved[grid], fine[:, ::step, ::step], rtol=0,
                                   atol=1e-12 * scale)


def test_every_grid_holds_the_same_fourier_modes_and_none_above_the_cutoff(resolved):
    coarse, fine = resolved[(48, 32)], resolved[(192, 128)]
    c = np.fft.fft2(coarse) / coarse[0].size  # coefficients of exp(i q.x), grid-independent
    f = np.fft.fft2(fine) / fine[0].size
    ky = np.fft.fftfreq(32, 1 / 32).astype(int)
    kx = np.fft.fftfreq(48, 1 / 48).astype(int)
    shared = f[:, ky[:, None] % 128, kx[None, :] % 192]
    np.testing.assert_allclose(shared, c, rtol=0, atol=1e-12 * np.abs(c).max())
    qx = 2 * math.pi * np.fft.fftfreq(192, SIZE[0] / 192)
    qy = 2 * math.pi * np.fft.fftfreq(128, SIZE[1] / 128)
    beyond = np.hypot(qx[None, :], qy[:, None]) > 2 * math.pi / (SIZE[0] / 16) * (1 + 1e-9)
    assert np.abs(f[:, beyond]).max() < 1e-12 * np.abs(f).max()
    assert np.abs(f[:, ~beyond]).max() > 0


def test_the_fine_map_is_the_trigonometric_polynomial_of_the_band_grid():
    """Summed point by point from the band grid's coefficients, off the band grid's points."""
    s = spec()
    nx, ny = band_grid(s)
    band = generate_resolved(s, SEEDS[:1], [(nx, ny)])[(nx, ny)][0]
    coefficients = np.fft.fft2(band) / band.size
    kx = np.fft.fftfreq(nx, 1 / nx)
    ky = np.fft.fftfreq(ny, 1 / ny)
    fine = embed_spectrum(band[None], (3 * ny, 3 * nx))[0]
    rng = np.random.default_rng(0)
    for iy, ix in zip(rng.integers(0, 3 * ny, 6), rng.integers(0, 3 * nx, 6), strict=True):
        x, y = ix * SIZE[0] / (3 * nx), iy * SIZE[1] / (3 * ny)
        phase = np.exp(2j * math.pi * (kx[None, :] * x / SIZE[0] + ky[:, None] * y / SIZE[1]))
        assert fine[iy, ix] == pytest.approx(float(np.sum(coefficients * phase).real),
                                             rel=1e-10, abs=1e-12 * np.abs(band).max())


def test_the_surface_does_not_depend_on_which_grids_are_asked_for(resolved):
    alone = generate_resolved(spec(), SEEDS, [(96, 64)], rms_gradient=0.1)[(96, 64)]
    np.testing.assert_array_equal(alone, resolved[(96, 64)])


def test_each_surface_has_the_target_rms_gradient_on_every_grid(resolved):
    for maps in resolved.values():
        for z in maps:
            assert spectral_moments(z, SIZE).rms_gradient == pytest.approx(0.1, rel=1e-12)
    # an independent derivative: numpy's central differences on the finest grid
    z = resolved[(192, 128)][0]
    gy, gx = (np.gradient(np.pad(z, 1, mode="wrap"), SIZE[1] / 128, SIZE[0] / 192))
    slopes = np.mean(gx[1:-1, 1:-1] ** 2 + gy[1:-1, 1:-1] ** 2)
    assert math.sqrt(slopes) == pytest.approx(0.1, rel=0.02)


def test_the_sample_variance_is_the_same_on_every_grid(resolved):
    sigmas = [height_stats(maps)["sigma"] for maps in resolved.values()]
    for other in sigmas[1:]:
        np.testing.assert_allclose(other, sigmas[0], rtol=1e-12)


def test_the_paper_method_gives_gaussian_heights():
    """Gaussian noise through a linear filter: pooled kurtosis 3, skewness 0 (400 surfaces)."""
    s = spec()
    heights = generate_resolved(s, range(400), [band_grid(s)])[band_grid(s)]
    pooled = height_stats(heights.reshape(1, -1))
    assert pooled["skew"] == pytest.approx(0.0, abs=0.05)
    assert pooled["kurt"] == pytest.approx(3.0, abs=0.08)


def test_refusals():
    with pytest.raises(ValueError, match="band-limited"):
        generate_resolved(SurfaceSpec(grid=32, size=1e-3, corr_length=1e-4), [1], [64])
    with pytest.raises(ValueError, match="method"):
        generate_resolved(spec(), [1], [(96, 64)], method="exact")
    with pytest.raises(ValueError, match="at least the band grid"):
        generate_resolved(spec(), [1], [(32, 32)])
    with pytest.raises(ValueError, match="rms_gradient"):
        generate_resolved(spec(), [1], [(96, 64)], rms_gradient=-1.0)
