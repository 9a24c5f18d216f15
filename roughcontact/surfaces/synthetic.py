"""Random rough surfaces with prescribed height moments and autocorrelation.

Implements Section 2 of Kumar, Sadeghi & Krousgrill (2006), after Patir (1978)
and Hu & Tonder (1992):

1. Gaussian white noise ``eta`` (seeded, ``numpy.random.default_rng``).
2. A Johnson translator (Eq 6-8, :mod:`roughcontact.surfaces.johnson`) turns ``eta`` into
   non-Gaussian white noise ``x`` with skewness ``Sk_x`` and kurtosis ``Ku_x``.
3. A zero-phase linear filter ``h`` (Eq 9-11) whose power spectrum is the
   Fourier transform of the target autocorrelation function (ACF, Eq 1) turns
   ``x`` into the surface ``z``.
4. ``Sk_x`` and ``Ku_x`` are chosen from the targets through the moment
   transfer of the filter (Eq 12-13), which also bounds the reachable
   kurtosis (Eq 15, the Fig 2 curve), and calibrated so that a window's
   expected sample moments are the targets.

All lengths are in metres. Surface arrays have shape ``(ny, nx)``: axis 0 is y,
axis 1 is x, so a flat index is ``iy * nx + ix`` (row-major over y then x), the
element ordering used by the influence matrices.

Beyond the paper, ``generate(..., method="exact")`` uses iterative amplitude
adjustment (Perez-Rafols & Almqvist 2019, Tribol. Int. 131, 591-604) to give
every realisation a height set whose sample sigma, Sk and Ku are exactly the
targets (corrected Johnson quantiles), with a spectrum matched as closely as
the rank constraint allows; it is not limited by the Fig 2 bound.

Also beyond the paper, ``SurfaceSpec(acf="self-affine", hurst=...,
rolloff_wavelength=..., cutoff_wavelength=...)`` replaces the ACF of Eq 1 by
an isotropic self-affine power spectrum with roll-off and short-wavelength
cut-off (:func:`roughcontact.surfaces.spectra.self_affine_psd`), usable with
both methods and any Johnson height law: with the cut-off resolved, the
surface has no roughness at the grid scale and contact results converge as
the grid is refined. ``SurfaceSpec(acf="psd", psd=((q1, C1), (q2, C2), ...))``
takes any isotropic PSD as a table (a measured one, for instance: see
:func:`roughcontact.surfaces.measured.psd_table_from_measurement`),
interpolated in log-log between its rows
(:func:`roughcontact.surfaces.spectra.tabulated_psd`).

This module holds the generators (:func:`generate`, :func:`generate_many`)
and the seeds (:func:`derive_seeds`). The rest lives where a reader looks for
it: what to generate in :mod:`~roughcontact.surfaces.spec`
(:class:`~roughcontact.surfaces.spec.SurfaceSpec`); the spectra and the filter
(steps 3) in :mod:`~roughcontact.surfaces.spectra`; the moment transfer and
calibration (step 4) in :mod:`~roughcontact.surfaces.calibration`; the exact
generator in :mod:`~roughcontact.surfaces.exact`; the memory estimate in
:mod:`~roughcontact.surfaces.memory`; sample statistics of height maps in
:mod:`~roughcontact.surfaces.statistics`.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import replace

import numpy as np

from roughcontact.surfaces.calibration import calibrate_filter, fit_input
from roughcontact.surfaces.exact import generate_exact
from roughcontact.surfaces.memory import MAX_GENERATION_BYTES, check_memory
from roughcontact.surfaces.spec import SurfaceSpec, check_method
from roughcontact.surfaces.spectra import (
    apply_filter,
    check_domain,
    filter_kernel,
    noise_shape,
    white_noise,
)


def derive_seeds(study_seed: int, cell_key: str, count: int) -> np.ndarray:
    """Per-surface seeds from one study seed and a cell's key.

    Seed ``i`` depends only on ``(study_seed, cell_key, i)``: adding a cell or
    more surfaces changes no existing surface. Returns ``count`` uint64 values
    (taken from SHA-256, independent of platform).
    """
    if count < 0:
        raise ValueError(f"count must be >= 0; got {count}")
    seeds = np.empty(count, dtype=np.uint64)
    for i in range(count):
        digest = hashlib.sha256(f"{int(study_seed)}|{cell_key}|{i}".encode()).digest()
        seeds[i] = int.from_bytes(digest[:8], "little") >> 1  # fits int64 for HDF5 tools
    return seeds


def generate(spec: SurfaceSpec, seed: int, method: str = "filter", *,
             max_bytes: float = MAX_GENERATION_BYTES, **options) -> np.ndarray:
    """One random surface of shape ``(ny, nx)`` [m] with zero mean.

    Parameters
    ----------
    spec : SurfaceSpec
    seed : int
        Seed of the Gaussian white noise (``numpy.random.default_rng``); the
        same seed gives the same bits for the same library versions.
    method : {"filter", "paper", "exact"}
        "filter": the Johnson translator and linear filter (Eq 6-13) with the
        white noise's moments calibrated so that the *expected sample*
        skewness and kurtosis of a surface on this grid are the targets
        (:func:`~roughcontact.surfaces.calibration.calibrate_filter`). "paper": the
        same filter with Eq 12-13 as the paper uses them: the targets are the
        moments of the infinite process, and a finite window's sample kurtosis
        is biased (-1.4 % at (0, 4.5) on 60 x 60 over 9 mm with b = 1 mm, -3 %
        on 30 x 30 over 4.5 mm). "exact": iterative amplitude adjustment, see
        :func:`~roughcontact.surfaces.exact.generate_exact`. For a Gaussian
        process (skew 0, kurt 3) use "paper": "filter" and "exact" are not
        Gaussian, least of all for a self-affine spectrum without roll-off
        (see :class:`~roughcontact.surfaces.spec.SurfaceSpec`).
    max_bytes : float
        Memory budget [bytes], default
        :data:`~roughcontact.surfaces.memory.MAX_GENERATION_BYTES` (8 GB).

    Raises
    ------
    SurfaceTooLarge
        Before allocating, if
        :func:`~roughcontact.surfaces.memory.estimate_generation_bytes` exceeds
        ``max_bytes``.
    """
    return generate_many(spec, [seed], method=method, max_bytes=max_bytes, **options)[0]


def generate_many(spec: SurfaceSpec, seeds, method: str = "filter", *,
                  max_bytes: float = MAX_GENERATION_BYTES, **options) -> np.ndarray:
    """Surfaces for each seed, shape ``(len(seeds), ny, nx)`` [m], zero mean each.

    Equivalent to stacking :func:`generate` per seed (bit for bit), but the
    Johnson fit, the calibration and the filter are computed once and the
    FFTs are batched. Refuses with
    :class:`~roughcontact.surfaces.memory.SurfaceTooLarge` before allocating
    when the estimated peak memory of all the surfaces
    (:func:`~roughcontact.surfaces.memory.estimate_generation_bytes`) exceeds
    ``max_bytes`` [bytes] (default
    :data:`~roughcontact.surfaces.memory.MAX_GENERATION_BYTES`).
    """
    seeds = [int(s) for s in np.atleast_1d(np.asarray(seeds, dtype=np.uint64))]
    check_method(method)
    check_memory(spec, len(seeds), method, max_bytes)
    return _GENERATORS[method](spec, seeds, max_bytes, **options)


def _exact_surfaces(spec: SurfaceSpec, seeds: list[int], max_bytes: float,
                    **options) -> np.ndarray:
    """:func:`~roughcontact.surfaces.exact.generate_exact` for each seed, stacked (the
    domain checked once)."""
    check_domain(spec)
    return np.stack([generate_exact(spec, s, max_bytes=max_bytes, **options)[0]
                     for s in seeds])


def _filter_surfaces(spec: SurfaceSpec, seeds: list[int], max_bytes: float, *, method: str,
                     calibrated: bool, **options) -> np.ndarray:
    """The Johnson translator and linear filter (Eq 6-13) for each seed.

    ``calibrated``: the white noise's moments are those of
    :func:`~roughcontact.surfaces.calibration.calibrate_filter` (``method="filter"``);
    otherwise the targets through Eq 12-13 (``method="paper"``).
    """
    if options:
        raise TypeError(f"unexpected options for method={method!r}: {sorted(options)}")
    kern = filter_kernel(spec)
    check_domain(spec, kern)
    process = spec
    if calibrated:
        cal = calibrate_filter(spec)
        process = replace(spec, skew=cal.skew, kurt=cal.kurt)
    curve = fit_input(process)
    mean_x, std_x, _, _ = curve.moments()
    shape = noise_shape(spec, kern.weights)
    out = np.empty((len(seeds), *spec.shape))
    for k, seed in enumerate(seeds):
        x = (curve.transform(white_noise(seed, shape)) - mean_x) / std_x
        out[k] = apply_filter(spec, kern, x)
    out -= out.mean(axis=(-2, -1), keepdims=True)
    out *= spec.sigma
    if not np.all(np.isfinite(out)):
        raise FloatingPointError(f"non-finite surface heights generated for {spec!r}")
    return out


#: The generator of each method of :data:`~roughcontact.surfaces.spec.GENERATION_METHODS`:
#: ``(spec, seeds, max_bytes, **options) -> surfaces``.
_GENERATORS = {
    "filter": functools.partial(_filter_surfaces, method="filter", calibrated=True),
    "paper": functools.partial(_filter_surfaces, method="paper", calibrated=False),
    "exact": _exact_surfaces,
}
