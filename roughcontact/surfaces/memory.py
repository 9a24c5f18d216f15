"""Memory needed to generate surfaces, estimated before anything large is allocated.

:func:`estimate_generation_bytes` counts the work arrays of each generator
of :mod:`roughcontact.surfaces.synthetic`; the generators refuse a spec
whose estimate exceeds their ``max_bytes`` with :class:`SurfaceTooLarge`
(:func:`check_memory`).
"""

from __future__ import annotations

import functools

import scipy  # its submodules load on first use (scipy's lazy attributes)

from roughcontact.surfaces.calibration import CALIBRATION_BATCH_POINTS
from roughcontact.surfaces.spec import SurfaceSpec, check_method
from roughcontact.surfaces.spectra import kernel_shape

MAX_GENERATION_BYTES = 8e9
"""Default ``max_bytes`` of the generators [bytes]: 8 GB.

A fixed budget, so that a spec is refused or generated the same way on every
machine (the memory free at the moment would make that depend on the load);
8 GB fits a laptop or a typical cluster job and is about 10^8 points
(~ 9900 x 9900) of one periodic surface, far above the study's grids
(config: up to 240 x 240, 5 MB). Pass a larger ``max_bytes`` on a bigger
machine, or ``math.inf`` to skip the check.
"""


class SurfaceTooLarge(MemoryError):
    """Generating the surfaces would need more memory than ``max_bytes``.

    A MemoryError, like ``roughcontact.elasticity.influence.ModelTooLarge``:
    it is the failure numpy would raise (after allocating for seconds), only
    raised before anything large is allocated, and code that already handles
    MemoryError handles it. The message states the estimate, the grid and what
    to change.
    """


def estimate_generation_bytes(spec: SurfaceSpec, count: int = 1, method: str = "filter") -> int:
    """Estimated peak memory [bytes] of generating ``count`` surfaces of ``spec``.

    Counts the float64 work arrays :func:`synthetic.generate_many` holds at
    its two peaks, with ``N = nx ny`` surface points, ``K`` kernel points
    (:func:`spectra.kernel_shape`), ``M`` noise points (the surface grid, or
    surface + kernel - 1 along each axis when padded) and ``F`` points of the
    padded FFT of ``scipy.signal.fftconvolve``, in bytes per point:

    - the filter (:func:`spectra.filter_kernel`, 65 K: ACF, its complex FFT,
      clip, transfer, complex inverse FFT, normalisation), run again by
      :func:`calibration.input_moments` while the first kernel (16 K: weights
      and transfer) is held: ``81 K``;
    - per surface: the output stack ``8 count N``, the kernel ``16 K``, and the
      larger of the Johnson transform (noise, transformed noise, a temporary
      and the previous surface's noise: ``32 M``) and the filter (the noise
      ``8 M`` plus complex FFT, product and inverse FFT ``48 N`` when
      periodic; the centred kernel ``8 K`` plus two half-spectra, their
      product and the output ``32 F`` when padded).

    ``method="filter"`` first calibrates (:func:`calibration.calibrate_filter`)
    on batches of about 2^19 noise points ``B``: ``16 K + 60 B`` (periodic) or,
    padded, ``16 K + 45 L`` with ``L`` the batch's points on the fast FFT grid
    of its noise (:class:`spectra.CircularValidFilter`; 2-8 % above the traced
    peak on four grids of 60 x 60 to 128 x 128), if larger than the
    generation's peak.

    ``method="exact"`` (:func:`exact.generate_exact`, periodic): ``120 N`` (the
    filter's 65 N, the moment correction of the height set and the
    iterations' surfaces, rankings and half spectra stay below it) plus ``8 N``
    for each surface already made, or ``16 count N`` while they are stacked. These
    match the peaks traced with ``tracemalloc`` within 1 % (grids of 64 x 64
    to 1500 x 1200, periodic and padded, 1 and 3 surfaces). Only shapes are
    computed: nothing large is allocated.

    Parameters
    ----------
    spec : SurfaceSpec
    count : int
        Number of surfaces generated in one call (its seeds).
    method : {"filter", "paper", "exact"}

    Returns
    -------
    int
        Bytes.
    """
    check_method(method)
    return int(_PEAK_BYTES[method](spec, max(int(count), 1)))


def _exact_bytes(spec: SurfaceSpec, count: int) -> int:
    """Peak of :func:`exact.generate_exact` for ``count`` surfaces."""
    ny, nx = spec.shape
    points = ny * nx
    return max(120 * points + 8 * (count - 1) * points, 16 * count * points)


def _filter_bytes(spec: SurfaceSpec, count: int, calibrated: bool = False) -> int:
    """Peak of the filter generator for ``count`` surfaces; ``calibrated``: calibration first."""
    ny, nx = spec.shape
    points = ny * nx
    ky, kx = kernel_shape(spec)
    kernel = ky * kx
    if spec.periodic:
        noise = points
        convolution = 48 * points
    else:
        noise = (ny + ky - 1) * (nx + kx - 1)
        padded = (scipy.fft.next_fast_len(ny + 2 * ky - 2, True)
                  * scipy.fft.next_fast_len(nx + 2 * kx - 2, True))
        convolution = 8 * kernel + 32 * padded
    per_surface = 8 * count * points + 16 * kernel + max(32 * noise, 8 * noise + convolution)
    peak = max(81 * kernel, per_surface)
    if calibrated:  # the calibration runs first, on batches of surfaces
        fields = max(1, CALIBRATION_BATCH_POINTS // noise)
        if spec.periodic:
            peak = max(peak, 16 * kernel + 60 * fields * noise)
        else:  # the circular filter on the noise's fast grid (spectra.CircularValidFilter)
            fast = (scipy.fft.next_fast_len(ny + ky - 1, True)
                    * scipy.fft.next_fast_len(nx + kx - 1, True))
            peak = max(peak, 16 * kernel + 45 * fields * fast)
    return peak


#: The peak-memory estimate of each generation method, ``(spec, count) -> bytes``.
_PEAK_BYTES = {"filter": functools.partial(_filter_bytes, calibrated=True),
               "paper": _filter_bytes, "exact": _exact_bytes}


def check_memory(spec: SurfaceSpec, count: int, method: str, max_bytes) -> None:
    """Raise :class:`SurfaceTooLarge` if the estimate exceeds ``max_bytes`` [bytes]."""
    try:
        limit = float(max_bytes)
    except (TypeError, ValueError):
        raise ValueError(f"max_bytes must be a number of bytes; got {max_bytes!r}") from None
    if not limit > 0:
        raise ValueError(f"max_bytes must be positive; got {max_bytes!r}")
    needed = estimate_generation_bytes(spec, count, method)
    if needed <= limit:
        return
    nx, ny = spec.grid
    raise SurfaceTooLarge(
        f"generating {count} surface(s) on a {nx} x {ny} grid "
        f"({'periodic' if spec.periodic else 'padded, non-periodic'}, method={method!r}) "
        f"needs about {needed / 1e9:.3g} GB ({needed:.4g} bytes) of work arrays, more than "
        f"max_bytes = {limit / 1e9:.3g} GB; nothing was allocated. Use a smaller grid "
        f"(memory grows with nx * ny), fewer surfaces per call, or pass a larger max_bytes "
        f"if the machine has that much memory free."
    )
