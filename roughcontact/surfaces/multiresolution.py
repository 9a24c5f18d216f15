"""The same band-limited random surface resolved on several grids (grid-convergence studies).

A surface whose power spectrum vanishes above a wavenumber ``q_s`` (the
self-affine spectrum's short-wavelength cut-off,
:func:`~roughcontact.surfaces.spectra.self_affine_psd`) is a trigonometric
polynomial: it is fixed by its Fourier coefficients at ``q = 2 pi k / L``,
``|q| <= q_s``, and it is the same continuous function whatever grid finer
than its Nyquist limit samples it (Nyquist-Shannon). This module draws those
coefficients once per seed and evaluates the surface on any grid that
carries them, so a contact quantity changes from grid to grid by the
discretization of the contact problem alone, not by a new random surface.

How. The coefficients are those of one surface on the *band grid*
(:func:`band_grid`), the coarsest grid whose Nyquist wavenumber ``pi / dx``
lies above ``q_s`` along each axis: the seeded generator of the package
(:func:`~roughcontact.surfaces.synthetic.generate_many`) draws it there, and
its spectrum is embedded into each requested grid's spectrum (zero padding of
the ``rfft2`` coefficients, scaled by the ratio of the numbers of points).
Two equivalent choices were open: point-subsampling one band-limited map of
the finest grid, or this embedding. Embedding was chosen because the surface
then depends on the spectrum, the size and the seed only (not on which grids
are asked for, nor on the finest one), any grid with at least the band
grid's points per side can be served (not only divisors of the finest), and
each grid costs one FFT of its own size. For a band-limited map both give the
same numbers: a coarse map equals the fine one at the shared points and holds
the same Fourier coefficients (the tests check both), since no mode reaches
either grid's Nyquist wavenumber (no aliasing, no Nyquist term to split).

Consequences. Every mean square that Parseval's theorem gives from the
coefficients, the sample variance and the spectral rms gradient and curvature
of :func:`~roughcontact.surfaces.statistics.spectral_moments` (Fourier
derivatives), is the same on every grid (to rounding); the sample skewness
and kurtosis are not (they are not quadratic in the coefficients), and
neither are finite-difference slopes.

Gaussian or not. ``method="paper"`` with ``skew=0, kurt=3`` (the default
here) filters Gaussian white noise: the surface is a sample of a Gaussian
process with the spec's PSD. The library's default ``method="filter"``
calibrates the band grid's *sample* kurtosis to the target by feeding the
filter non-Gaussian noise, which makes the process non-Gaussian, strongly so
for a self-affine spectrum without roll-off (see
:class:`~roughcontact.surfaces.spec.SurfaceSpec`); ``"exact"`` (IAAFT) is
refused, its rank-ordered surfaces are not band-limited. ``rms_gradient``
rescales each surface to that rms gradient h'_rms: each surface's shape is
still a Gaussian-process sample, the ensemble is a scale mixture of them
(the usual normalisation of contact studies of self-affine surfaces, which
report the contact area against ``p0 / (E* h'_rms)``).

Lengths in metres; arrays ``(m, ny, nx)``, axis 0 is y.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from roughcontact.surfaces.spec import SurfaceSpec, as_pair
from roughcontact.surfaces.statistics import spectral_moments
from roughcontact.surfaces.synthetic import generate_many

__all__ = ["BAND_LIMITED", "band_grid", "band_wavenumber", "embed_spectrum", "generate_resolved"]

#: The largest wavenumber with power [1/m] of each band-limited spectrum kind.
BAND_LIMITED = {"self-affine": lambda spec: 2.0 * math.pi / spec.cutoff_wavelength}
#: Generation methods whose surfaces are band-limited (a linear filter of white noise).
_BAND_METHODS = ("paper", "filter")


def band_wavenumber(spec: SurfaceSpec) -> float:
    """The wavenumber ``q_s`` [1/m] above which ``spec``'s PSD has no power.

    Raises ValueError for a spectrum without such a cut-off (the ACFs of Eq 1).
    """
    top = BAND_LIMITED.get(spec.acf)
    if top is None:
        raise ValueError(f"acf={spec.acf!r} has power at every wavenumber: a surface resolved "
                         f"on several grids needs a band-limited spectrum, one of "
                         f"{tuple(BAND_LIMITED)} (e.g. acf='self-affine' with a "
                         "cutoff_wavelength)")
    return top(spec)


def band_grid(spec: SurfaceSpec) -> tuple[int, int]:
    """The coarsest even grid ``(nx, ny)`` whose Nyquist wavenumbers exceed ``q_s``.

    Along each axis the smallest even ``n`` with ``pi n / L > q_s``
    (:func:`band_wavenumber`), i.e. more than two points per cut-off
    wavelength: every mode with power lies strictly inside the grid's
    spectrum, none on its Nyquist line.
    """
    q_top = band_wavenumber(spec)
    grid = []
    for length in spec.size:
        n = math.floor(q_top * length / math.pi * (1.0 + 1e-12)) + 1
        grid.append(n + n % 2)
    return (grid[0], grid[1])


def embed_spectrum(maps: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Band-limited maps (m, ny, nx) evaluated on a finer grid of ``shape`` (ny', nx').

    The ``rfft2`` coefficients of ``maps`` (wavenumbers ``2 pi k / L``, with
    zero Nyquist rows and columns) are placed at the same wavenumbers of the
    larger spectrum, the rest zero, and scaled by ``ny' nx' / (ny nx)``: the
    trigonometric interpolant of the maps sampled on the new grid. Raises
    ValueError if ``shape`` is smaller along an axis or odd.
    """
    ny, nx = maps.shape[-2:]
    fy, fx = shape
    if fy < ny or fx < nx or fy % 2 or fx % 2 or ny % 2 or nx % 2:
        raise ValueError(f"the grid {fx} x {fy} must be even and at least the band grid "
                         f"{nx} x {ny} along each axis")
    coefficients = np.fft.rfft2(maps)
    embedded = np.zeros((*maps.shape[:-2], fy, fx // 2 + 1), dtype=complex)
    low = ny // 2  # rows 0 .. ny/2 - 1 and -(ny/2 - 1) .. -1; the Nyquist row has no power
    embedded[..., :low, : nx // 2] = coefficients[..., :low, : nx // 2]
    embedded[..., fy - low + 1:, : nx // 2] = coefficients[..., ny - low + 1:, : nx // 2]
    return np.fft.irfft2(embedded * (fy * fx / (ny * nx)), s=shape)


def generate_resolved(spec: SurfaceSpec, seeds, grids: Sequence, method: str = "paper", *,
                      rms_gradient: float | None = None) -> dict:
    """The surfaces of ``seeds`` resolved on every grid of ``grids``: ``{grid: (m, ny, nx)}`` [m].

    Parameters
    ----------
    spec : SurfaceSpec
        A band-limited spectrum (``acf="self-affine"``), its ``size`` [m],
        ``sigma`` [m] and height moments; its ``grid`` is not used (the
        surfaces are drawn on :func:`band_grid`).
    seeds : sequence of int
        One surface per seed (:func:`~roughcontact.surfaces.synthetic.generate_many`
        on the band grid).
    grids : sequence of int or (nx, ny)
        Grids to evaluate the surfaces on (a number: a square grid); each even
        and at least the band grid along each axis. The keys of the result are
        the items as given.
    method : {"paper", "filter"}
        The generator on the band grid. ``"paper"`` with ``skew=0, kurt=3``:
        a Gaussian process (module docstring).
    rms_gradient : float, optional
        Scale each surface so that its rms gradient h'_rms
        (:func:`~roughcontact.surfaces.statistics.spectral_moments`, Fourier
        derivatives; the same on every grid) is this [-]; default: the
        process's ``spec.sigma``.

    Returns
    -------
    dict
        grid -> heights (m, ny, nx) [m], zero mean each.
    """
    if method not in _BAND_METHODS:
        raise ValueError(f"method must be one of {_BAND_METHODS} (band-limited surfaces); "
                         f"got {method!r}")
    band = replace(spec, grid=band_grid(spec))
    coarse = generate_many(band, seeds, method=method)
    if rms_gradient is not None:
        if not (math.isfinite(rms_gradient) and rms_gradient > 0):
            raise ValueError(f"rms_gradient must be positive and finite; got {rms_gradient!r}")
        for z in coarse:
            z *= rms_gradient / spectral_moments(z, band.size).rms_gradient
    out = {}
    for grid in grids:
        nx, ny = (int(v) for v in as_pair(grid, "grid"))
        if (nx, ny) == band.grid:
            out[grid] = coarse.copy()
        else:
            out[grid] = embed_spectrum(coarse, (ny, nx))
    return out
