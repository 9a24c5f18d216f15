"""Spectral moments of a height map: rms gradient, rms curvature, Nayak's parameter.

References, each independent of the code under test: closed forms of
sinusoids written out here; central differences computed here with numpy on a
band-limited surface whose moments are known in closed form; SurfaceTopography
(its finite-difference ``rms_gradient``, ``Rdq``, ``rms_laplacian``,
``rms_curvature_from_area``, its spectral ``moment_power_spectrum`` and its
``SelfAffine`` model); the PSD of the generator's self-affine spectrum summed
over the grid here.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from roughcontact.surfaces import synthetic
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.spectra import self_affine_moments
from roughcontact.surfaces.statistics import SpectralMoments, spectral_moments

MM = 1e-3
#: Side lengths (Lx, Ly) [m] of the test maps: unequal, so x and y cannot be swapped unseen.
SIZE = (2.0 * MM, 1.5 * MM)


def approx(expected, rel=1e-6, absolute=0.0):
    """``pytest.approx`` without its default absolute tolerance of 1e-12 (heights are ~1e-6 m)."""
    return pytest.approx(expected, rel=rel, abs=absolute)


@pytest.fixture(autouse=True)
def _quiet(caplog):
    caplog.set_level(logging.ERROR)


def grid_xy(nx, ny, size=SIZE):
    """Coordinates x, y [m] of a (ny, nx) map, broadcast to its shape."""
    x = np.arange(nx) * size[0] / nx
    y = np.arange(ny) * size[1] / ny
    return np.meshgrid(x, y)


def sinusoid(nx, ny, kx, ky, amplitude, size=SIZE, phase=0.3):
    """``A sin(qx x + qy y + phase)`` with ``q = 2 pi (kx / Lx, ky / Ly)``; also returns |q|."""
    x, y = grid_xy(nx, ny, size)
    qx, qy = 2 * math.pi * kx / size[0], 2 * math.pi * ky / size[1]
    return amplitude * np.sin(qx * x + qy * y + phase), (qx, qy)


# --------------------------------------------------------------------------- closed forms


@pytest.mark.parametrize("kx, ky", [(4, 0), (0, 3), (5, -2), (7, 6)])
def test_a_sinusoid_has_its_closed_form_moments(kx, ky):
    amplitude = 1.3e-6
    z, (qx, qy) = sinusoid(64, 48, kx, ky, amplitude)
    q = math.hypot(qx, qy)
    s = spectral_moments(z, SIZE)
    wavelength = 2 * math.pi / q
    assert s.rms_gradient == approx(2 * math.pi * amplitude / (wavelength * math.sqrt(2)),
                                           rel=1e-12)
    assert s.rms_slope_x == approx(amplitude * abs(qx) / math.sqrt(2), rel=1e-12, absolute=1e-18)
    assert s.rms_slope_y == approx(amplitude * abs(qy) / math.sqrt(2), rel=1e-12, absolute=1e-18)
    # lap h = -q^2 h: h''_rms = q^2 A / (2 sqrt 2)
    assert s.rms_curvature == approx(q**2 * amplitude / (2 * math.sqrt(2)), rel=1e-12)
    assert s.m0 == approx(amplitude**2 / 2, rel=1e-12)
    # direction-averaged profile moments of one wavelength: m2 = A^2 q^2 / 4, m4 = 3 A^2 q^4 / 16
    assert s.m2 == approx(amplitude**2 * q**2 / 4, rel=1e-12)
    assert s.m4 == approx(3 * amplitude**2 * q**4 / 16, rel=1e-12)
    assert s.nayak_alpha == approx(1.5, rel=1e-12)


@pytest.mark.parametrize("kx, ky", [(4, 0), (5, -2), (7, 6)])
def test_finite_differences_of_a_sinusoid_have_the_stencils_closed_form(kx, ky):
    # forward differences and the five-point Laplacian multiply a mode by
    # |exp(i q d) - 1| / d = 2 sin(q d / 2) / d along each axis
    amplitude = 0.7e-6
    nx, ny = 40, 30
    z, (qx, qy) = sinusoid(nx, ny, kx, ky, amplitude)
    dx, dy = SIZE[0] / nx, SIZE[1] / ny
    sx = 2 * math.sin(qx * dx / 2) / dx
    sy = 2 * math.sin(qy * dy / 2) / dy
    s = spectral_moments(z, SIZE, derivative="difference")
    assert s.rms_slope_x == approx(amplitude * abs(sx) / math.sqrt(2), rel=1e-12, absolute=1e-18)
    assert s.rms_slope_y == approx(amplitude * abs(sy) / math.sqrt(2), rel=1e-12, absolute=1e-18)
    assert s.rms_curvature == approx((sx**2 + sy**2) * amplitude / (2 * math.sqrt(2)),
                                            rel=1e-12)
    assert s.nayak_alpha == approx(1.5, rel=1e-12)


def test_nayak_alpha_of_two_sinusoids_by_hand():
    # h = A sin(q x) + A cos(2 q y): M0 = A^2, <|grad h|^2> = (1 + 4) A^2 q^2 / 2,
    # <(lap h)^2> = (1 + 16) A^2 q^4 / 2, so alpha = (3/2) M0 M4 / M2^2 = 1.5 * 8.5 / 6.25
    size = (1.0 * MM, 1.0 * MM)
    x, y = grid_xy(32, 32, size)
    q = 2 * math.pi * 3 / size[0]
    amplitude = 2e-6
    z = amplitude * (np.sin(q * x) + np.cos(2 * q * y))
    s = spectral_moments(z, size)
    assert s.nayak_alpha == approx(2.04, rel=1e-12)
    assert s.m0 == approx(amplitude**2, rel=1e-12)
    assert s.rms_gradient == approx(amplitude * q * math.sqrt(2.5), rel=1e-12)
    assert s.rms_curvature == approx(amplitude * q**2 * math.sqrt(8.5) / 2, rel=1e-12)
    # and an anisotropic pair: the slopes along each axis apart
    assert s.rms_slope_x == approx(amplitude * q / math.sqrt(2), rel=1e-12)
    assert s.rms_slope_y == approx(amplitude * 2 * q / math.sqrt(2), rel=1e-12)


def test_the_nyquist_mode_has_no_slope_and_full_curvature():
    # a (-1)^i along x is the real interpolant a cos(pi x / dx): zero slope at the
    # grid points, curvature -(pi / dx)^2 a (-1)^i; finite differences see 2a / dx, 4a / dx^2
    nx, ny, a = 16, 12, 1e-6
    dx = SIZE[0] / nx
    z = np.tile(a * (-1.0) ** np.arange(nx), (ny, 1))
    fourier = spectral_moments(z, SIZE)
    assert fourier.rms_gradient == 0.0 and fourier.rms_slope_x == 0.0
    assert fourier.rms_curvature == approx((math.pi / dx) ** 2 * a / 2, rel=1e-12)
    assert math.isnan(fourier.nayak_alpha)
    difference = spectral_moments(z, SIZE, derivative="difference")
    assert difference.rms_slope_x == approx(2 * a / dx, rel=1e-12)
    assert difference.rms_curvature == approx(4 * a / dx**2 / 2, rel=1e-12)


def test_mean_offset_and_odd_grids_change_nothing():
    rng = np.random.default_rng(4)
    z = rng.standard_normal((27, 33)) * 1e-6
    base = spectral_moments(z, SIZE)
    shifted = spectral_moments(z + 5e-3, SIZE)
    for name in ("m0", "m2", "m4", "rms_gradient", "rms_curvature", "nayak_alpha"):
        assert getattr(shifted, name) == approx(getattr(base, name), rel=1e-9)
    # the odd grid has no Nyquist mode: Parseval over the half spectrum equals the field's
    hx = np.fft.ifft(1j * 2 * np.pi * np.fft.fftfreq(33, SIZE[0] / 33) * np.fft.fft(z, axis=1),
                     axis=1).real
    assert base.rms_slope_x == approx(np.sqrt(np.mean(hx**2)), rel=1e-12)


@pytest.mark.parametrize("kw, match", [
    (dict(derivative="central"), "derivative"),
    (dict(derivative="fourier", periodic=False), "periodic"),
])
def test_bad_options_raise(kw, match):
    with pytest.raises(ValueError, match=match):
        spectral_moments(np.zeros((8, 8)), SIZE, **kw)


@pytest.mark.parametrize("z, size, match", [
    (np.zeros(8), SIZE, "height map"),
    (np.zeros((2, 8)), SIZE, "height map"),
    (np.full((8, 8), np.nan), SIZE, "non-finite"),
    (np.zeros((8, 8)), (1e-3, -1e-3), "size"),
])
def test_bad_inputs_raise(z, size, match):
    with pytest.raises(ValueError, match=match):
        spectral_moments(z, size)


# --------------------------------------------------------------------------- finite differences


def band_limited(n, size, seed=11, k_max=6):
    """A smooth periodic surface sampled on n x n, and its exact (M0, M2, M4).

    Twenty modes with distinct wavevectors ``|k| <= k_max`` (half plane, so no
    mode is another's mirror) and random amplitudes and phases: the heights are
    the same continuous function on every grid; M2 = <|grad h|^2>, M4 = <(lap h)^2>.
    """
    rng = np.random.default_rng(seed)
    modes = [(kx, ky) for kx in range(0, k_max + 1) for ky in range(-k_max, k_max + 1)
             if (kx > 0 or ky > 0) and math.hypot(kx, ky) <= k_max]
    chosen = rng.choice(len(modes), 20, replace=False)
    x, y = grid_xy(n, n, size)
    z = np.zeros((n, n))
    m0 = m2 = m4 = 0.0
    for index in chosen:
        kx, ky = modes[index]
        amplitude, phase = rng.uniform(0.2e-6, 1e-6), rng.uniform(0, 2 * np.pi)
        qx, qy = 2 * np.pi * kx / size[0], 2 * np.pi * ky / size[1]
        z += amplitude * np.cos(qx * x + qy * y + phase)
        q2 = qx**2 + qy**2
        m0 += amplitude**2 / 2
        m2 += amplitude**2 * q2 / 2
        m4 += amplitude**2 * q2**2 / 2
    return z, (m0, m2, m4)


def central_differences(z, size):
    """<|grad h|^2> and <(lap h)^2> by periodic central differences (numpy only)."""
    ny, nx = z.shape
    dx, dy = size[0] / nx, size[1] / ny
    hx = (np.roll(z, -1, axis=1) - np.roll(z, 1, axis=1)) / (2 * dx)
    hy = (np.roll(z, -1, axis=0) - np.roll(z, 1, axis=0)) / (2 * dy)
    lap = ((np.roll(z, -1, axis=1) - 2 * z + np.roll(z, 1, axis=1)) / dx**2
           + (np.roll(z, -1, axis=0) - 2 * z + np.roll(z, 1, axis=0)) / dy**2)
    return np.mean(hx**2 + hy**2), np.mean(lap**2)


def test_finite_differences_converge_to_the_fourier_moments_at_second_order():
    errors = {"central": [], "difference": []}
    for n in (16, 32, 64, 128, 256):
        z, (m0, gradient, laplacian) = band_limited(n, SIZE)
        s = spectral_moments(z, SIZE)
        # the Fourier derivative is exact for a band-limited surface on every grid
        assert s.rms_gradient**2 == approx(gradient, rel=1e-11)
        assert (2 * s.rms_curvature) ** 2 == approx(laplacian, rel=1e-11)
        assert s.nayak_alpha == approx(1.5 * m0 * laplacian / gradient**2, rel=1e-11)
        cd_gradient, cd_laplacian = central_differences(z, SIZE)
        d = spectral_moments(z, SIZE, derivative="difference")
        errors["central"].append((abs(cd_gradient / gradient - 1),
                                  abs(cd_laplacian / laplacian - 1)))
        errors["difference"].append((abs(d.rms_gradient**2 / gradient - 1),
                                     abs((2 * d.rms_curvature) ** 2 / laplacian - 1)))
    for name, e in errors.items():
        e = np.array(e)
        ratios = e[:-1] / e[1:]  # halving the spacing divides a second-order error by 4
        assert np.all((ratios[1:] > 3.5) & (ratios[1:] < 4.5)), (name, ratios)
        assert np.all(np.abs(ratios[-1] - 4) < 0.05), (name, ratios)
        assert np.all(e[-1] < 4e-3), (name, e[-1])
    # forward differences err by -q^2 d^2 / 12 on the mean square slope, central ones by
    # -q^2 d^2 / 3: four times less
    assert errors["difference"][-1][0] == approx(errors["central"][-1][0] / 4, rel=0.01)


# --------------------------------------------------------------------------- SurfaceTopography


@pytest.fixture(scope="module")
def topography_class():
    surface_topography = pytest.importorskip("SurfaceTopography")
    return surface_topography.Topography


def rough_map(ny=48, nx=64, seed=2):
    """Correlated random heights [m] (white noise smoothed by two neighbours), any spectrum."""
    z = np.random.default_rng(seed).standard_normal((ny, nx)) * 1e-6
    return z + 0.5 * (np.roll(z, 1, axis=1) + np.roll(z, 1, axis=0))


@pytest.mark.parametrize("periodic", [True, False])
def test_differences_match_surfacetopography_to_rounding(topography_class, periodic):
    z = rough_map()
    # SurfaceTopography's arrays are (nx, ny), x first
    topography = topography_class(z.T, SIZE, periodic=periodic)
    s = spectral_moments(z, SIZE, derivative="difference", periodic=periodic)
    assert s.rms_gradient == approx(topography.rms_gradient(), rel=1e-12)
    assert s.rms_slope_x == approx(topography.Rdq(), rel=1e-12)
    # h''_rms is half SurfaceTopography's rms Laplacian, i.e. its rms_curvature_from_area
    assert 2 * s.rms_curvature == approx(topography.rms_laplacian(), rel=1e-12)
    assert s.rms_curvature == approx(topography.rms_curvature_from_area(), rel=1e-12)
    transposed = topography_class(z, SIZE[::-1], periodic=periodic)
    assert s.rms_slope_y == approx(transposed.Rdq(), rel=1e-12)


def without_nyquist(z):
    """``z`` with the Nyquist row and column of its spectrum removed (even sides)."""
    spectrum = np.fft.fft2(z)
    spectrum[z.shape[0] // 2, :] = 0.0
    spectrum[:, z.shape[1] // 2] = 0.0
    return np.fft.ifft2(spectrum).real


def test_fourier_moments_match_surfacetopography_spectral_moments(topography_class):
    # SurfaceTopography's areal moments M_n = sum |q|^n C / A: M2 = 2 m2, M4 = (8/3) m4
    z = rough_map()
    z -= z.mean()  # its M0 includes the mean (the q = 0 bin)
    topography = topography_class(without_nyquist(z).T, SIZE, periodic=True)
    s = spectral_moments(without_nyquist(z), SIZE)
    m0, m2, m4 = (topography.moment_power_spectrum(order, reliable=False) for order in (0, 2, 4))
    assert s.m0 == approx(m0, rel=1e-12)
    assert 2 * s.m2 == approx(m2, rel=1e-12)
    assert 8 / 3 * s.m4 == approx(m4, rel=1e-12)
    assert s.nayak_alpha == approx(1.5 * m0 * m4 / m2**2, rel=1e-12)
    # with power at the Nyquist wavenumber the conventions part: SurfaceTopography weighs
    # its bins by |q|^2 also in M2, the grid's Fourier derivative drops them
    full = topography_class(z.T, SIZE, periodic=True)
    s = spectral_moments(z, SIZE)
    assert 8 / 3 * s.m4 == approx(full.moment_power_spectrum(4, reliable=False), rel=1e-12)
    assert 2 * s.m2 < full.moment_power_spectrum(2, reliable=False) * (1 - 1e-3)


def test_self_affine_moments_match_surfacetopography_model():
    models = pytest.importorskip("SurfaceTopography.Models.SelfAffine")
    for hurst, rolloff, cutoff in ((0.8, 1 * MM, 10e-6), (0.3, 0.5 * MM, 40e-6),
                                   (0.5, 2 * MM, 1 * MM)):
        model = models.SelfAffine(1.0, rolloff, hurst, shortcut_wavelength=cutoff)
        variance = [model.variance_derivative(order) for order in (0, 1, 2)]
        sigma = 3e-6
        s = self_affine_moments(hurst, rolloff, cutoff, sigma)
        assert s.m0 == approx(sigma**2, rel=1e-14)
        assert s.rms_gradient**2 == approx(sigma**2 * variance[1] / variance[0], rel=1e-12)
        assert (2 * s.rms_curvature) ** 2 == approx(sigma**2 * variance[2] / variance[0],
                                                          rel=1e-12)
        assert s.rms_slope_x == s.rms_slope_y == approx(s.rms_gradient / math.sqrt(2))


# --------------------------------------------------------------------------- generated surfaces


def grid_expectation(spec: SurfaceSpec):
    """The expected (m0, <|grad h|^2>, <(lap h)^2>) of the generator's self-affine surfaces.

    The filter gives bin k the power ``S(q_k) / sum S`` of unit variance (the mean bin
    included, then removed from each surface): ``S = 1`` below q_r, ``(q / q_r)^(-2 (1 + H))``
    up to q_s, 0 above.
    """
    nx, ny = spec.grid
    qx = 2 * np.pi * np.fft.fftfreq(nx, spec.size[0] / nx)
    qy = 2 * np.pi * np.fft.fftfreq(ny, spec.size[1] / ny)
    q = np.hypot(qx[None, :], qy[:, None])
    q_r, q_s = 2 * np.pi / spec.rolloff_wavelength, 2 * np.pi / spec.cutoff_wavelength
    power = np.where(q <= q_s * (1 + 1e-12), (np.maximum(q, q_r) / q_r) ** (-2 * (1 + spec.hurst)),
                     0.0)
    power *= spec.sigma**2 / power.sum()
    return power.sum() - power[0, 0], float(np.sum(q**2 * power)), float(np.sum(q**4 * power))


@pytest.mark.parametrize("hurst", [0.3, 0.8])
def test_generated_self_affine_surfaces_have_their_spectrum_moments(hurst):
    spec = SurfaceSpec(grid=128, size=8 * MM, sigma=2e-6, acf="self-affine", hurst=hurst,
                       rolloff_wavelength=1 * MM, cutoff_wavelength=0.25 * MM)
    surfaces = synthetic.generate_many(spec, range(24), method="paper")
    stats = [spectral_moments(z, spec.size) for z in surfaces]
    m0, gradient, laplacian = (np.array([getattr(s, n) for s in stats]) for n in
                               ("m0", "m2", "m4"))
    gradient, laplacian = 2 * gradient, 8 / 3 * laplacian
    expected = grid_expectation(spec)
    for values, target in zip((m0, gradient, laplacian), expected, strict=True):
        standard_error = values.std(ddof=1) / math.sqrt(len(values))
        assert abs(values.mean() - target) < 4 * standard_error, (values.mean(), target)
    # the continuous PSD's closed form: the grid's sampling of the PSD (bins 2 pi / L
    # apart, 8 across the roll-off) is 0.5 % off in M2, 1 % in M4
    exact = self_affine_moments(hurst, spec.rolloff_wavelength, spec.cutoff_wavelength,
                                spec.sigma)
    assert expected[1] == approx(exact.rms_gradient**2, rel=5e-3)
    assert expected[2] == approx((2 * exact.rms_curvature) ** 2, rel=1.2e-2)
    h_rms = np.sqrt(gradient.mean())
    assert h_rms == approx(exact.rms_gradient, rel=5e-3 + 4 * gradient.std() / (
        2 * gradient.mean() * math.sqrt(len(gradient))))
    assert isinstance(stats[0], SpectralMoments)
