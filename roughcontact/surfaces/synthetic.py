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
   kurtosis (Eq 15, the Fig 2 curve).

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
cut-off (:func:`self_affine_psd`), usable with both methods and any Johnson
height law: with the cut-off resolved, the surface has no roughness at the
grid scale and contact results converge as the grid is refined.
``SurfaceSpec(acf="psd", psd=((q1, C1), (q2, C2), ...))`` takes any isotropic
PSD as a table (a measured one, for instance: see
:func:`roughcontact.surfaces.measured.psd_table_from_measurement`),
interpolated in log-log between its rows (:func:`tabulated_psd`).
"""

from __future__ import annotations

import functools
import hashlib
import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy import fft, signal, special

from roughcontact.errors import InfeasibleMoments
from roughcontact.surfaces import johnson

log = logging.getLogger(__name__)

ACF_DECAY = 2.3
"""Decay constant of Eq 1: the ACF falls to exp(-2.3) ~ 10 % at lag b."""

ACF_KINDS = ("exponential", "gaussian", "self-affine", "psd")
"""Spectrum kinds of :class:`SurfaceSpec`: two ACFs (Eq 1), a self-affine PSD and a
tabulated isotropic PSD."""

_SELF_AFFINE_FIELDS = ("hurst", "rolloff_wavelength", "cutoff_wavelength")
#: The fields of each spectrum kind defined by its PSD (None for every other kind).
_SPECTRUM_FIELDS = {"self-affine": _SELF_AFFINE_FIELDS, "psd": ("psd",)}
#: Relative tolerance of "above the largest wavenumber" (cut-offs, table ends).
_Q_RTOL = 1e-12


def _pair(value, name: str) -> tuple:
    if np.ndim(value) == 0:
        return (value, value)
    value = tuple(value)
    if len(value) != 2:
        raise ValueError(f"{name} must be a number or a pair (x, y); got {value!r}")
    return value


@dataclass(frozen=True)
class SurfaceSpec:
    """Statistics and sampling of a family of random rough surfaces.

    Parameters
    ----------
    grid : (nx, ny)
        Number of points along x and y (an int gives a square grid).
    size : (Lx, Ly)
        Side lengths of the surface [m]; the spacing is ``L / n``.
    corr_length : (bx, by)
        Autocorrelation lengths [m]: lags at which the ACF decays to 10 %
        (Eq 1).
    sigma : float
        Standard deviation of heights [m] (population value of the process).
    skew, kurt : float
        Target skewness Sk and Pearson kurtosis Ku (normal: 0 and 3) of the
        heights (Eq 4-5).
    acf : {"exponential", "gaussian", "self-affine", "psd"}
        ``exp(-2.3 r)`` (Eq 1) or ``exp(-2.3 r^2)``, with
        ``r = sqrt((x/bx)^2 + (y/by)^2)``; or ``"self-affine"``: the isotropic
        power spectral density of :func:`self_affine_psd` (constant below the
        roll-off wavenumber, ``q^(-2(1+H))`` up to the cut-off, zero above),
        set by ``hurst``, ``rolloff_wavelength`` and ``cutoff_wavelength``;
        or ``"psd"``: the isotropic PSD tabulated in ``psd``
        (:func:`tabulated_psd`).
    periodic : bool
        True: circular convolution, the surface tiles the plane. False: the
        paper's moving average over padded noise, no wrap-around
        (``"self-affine"`` and ``"psd"`` are periodic only).
    hurst : float, optional
        Hurst exponent H in (0, 1) of the self-affine band (``"self-affine"``
        only).
    rolloff_wavelength : float, optional
        Roll-off wavelength ``lambda_r = 2 pi / q_r`` [m]: the PSD is flat at
        longer wavelengths (``"self-affine"`` only). Must exceed
        ``cutoff_wavelength``.
    cutoff_wavelength : float, optional
        Short-wavelength cut-off ``lambda_s = 2 pi / q_s`` [m]: no power at
        shorter wavelengths, so the surface is smooth below it and contact
        results converge with the grid once it is resolved. At least two grid
        spacings along each axis (``"self-affine"`` only).
    psd : sequence of (q, C) pairs, optional
        The isotropic (2-D) power spectral density as a table (``"psd"``
        only): wavenumber magnitude ``q = 2 pi / lambda`` [1/m], positive and
        strictly increasing, and ``C(q) >= 0`` in any unit (only its shape
        matters: ``sigma`` sets the amplitude), at least two rows, some C
        positive. Stored as a tuple of float pairs, so the spec stays
        hashable (:func:`check_psd_table`).

    For ``"self-affine"`` and ``"psd"``, ``corr_length`` may be left out
    (None): it is then set along both axes to the longest wavelength of the
    spectrum's band, beyond which the PSD is flat and heights decorrelate: the
    roll-off wavelength, or ``2 pi / q_1`` of the table's first row. It enters
    only the domain checks and messages.
    """

    grid: tuple[int, int]
    size: tuple[float, float]
    corr_length: tuple[float, float] | None = None
    sigma: float = 1.0
    skew: float = 0.0
    kurt: float = 3.0
    acf: str = "exponential"
    periodic: bool = True
    hurst: float | None = None
    rolloff_wavelength: float | None = None
    cutoff_wavelength: float | None = None
    psd: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self):
        grid = _pair(self.grid, "grid")
        size = _pair(self.size, "size")
        if self.acf not in ACF_KINDS:
            raise ValueError(f"SurfaceSpec.acf must be one of {ACF_KINDS}; got {self.acf!r}")
        for kind, names in _SPECTRUM_FIELDS.items():
            for name in names:
                if self.acf != kind and getattr(self, name) is not None:
                    raise ValueError(
                        f"SurfaceSpec.{name} applies to acf={kind!r} only; got "
                        f"{name}={_short(getattr(self, name))} with acf={self.acf!r}"
                    )
        if self.acf == "self-affine":
            self._check_self_affine(grid, size)
            if self.corr_length is None:
                object.__setattr__(self, "corr_length", float(self.rolloff_wavelength))
        elif self.acf == "psd":
            self._check_psd(size)
            if self.corr_length is None:
                object.__setattr__(self, "corr_length", 2.0 * math.pi / self.psd[0][0])
        elif self.corr_length is None:
            raise ValueError(f"SurfaceSpec.corr_length [m] is required for acf={self.acf!r}")
        corr = _pair(self.corr_length, "corr_length")
        for name, pair in (("size", size), ("corr_length", corr)):
            for v in pair:
                if not (isinstance(v, int | float | np.number) and math.isfinite(v) and v > 0):
                    raise ValueError(
                        f"SurfaceSpec.{name} must be positive and finite [m]; got {pair!r}"
                    )
        for n in grid:
            if int(n) != n or n < 4:
                raise ValueError(
                    f"SurfaceSpec.grid must be integers >= 4 along each axis; got {grid!r}. "
                    "A surface needs at least 4 points per side to define its statistics."
                )
        if not (math.isfinite(self.sigma) and self.sigma > 0):
            raise ValueError(
                f"SurfaceSpec.sigma must be positive and finite [m]; got {self.sigma!r}"
            )
        for name in ("skew", "kurt"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"SurfaceSpec.{name} must be finite; got {getattr(self, name)!r}")
        object.__setattr__(self, "grid", (int(grid[0]), int(grid[1])))
        object.__setattr__(self, "size", (float(size[0]), float(size[1])))
        object.__setattr__(self, "corr_length", (float(corr[0]), float(corr[1])))
        object.__setattr__(self, "sigma", float(self.sigma))
        object.__setattr__(self, "skew", float(self.skew))
        object.__setattr__(self, "kurt", float(self.kurt))

    def _check_self_affine(self, grid, size) -> None:
        hurst, rolloff, cutoff = (getattr(self, name) for name in _SELF_AFFINE_FIELDS)
        if hurst is None or not (math.isfinite(hurst) and 0.0 < hurst < 1.0):
            raise ValueError(
                f"SurfaceSpec.hurst must be in (0, 1) for acf='self-affine'; got {hurst!r}"
            )
        for name, value in (("rolloff_wavelength", rolloff), ("cutoff_wavelength", cutoff)):
            if value is None or not (math.isfinite(value) and value > 0):
                raise ValueError(
                    f"SurfaceSpec.{name} must be positive and finite [m] for "
                    f"acf='self-affine'; got {value!r}"
                )
        spacing = max(float(size[0]) / int(grid[0]), float(size[1]) / int(grid[1]))
        if cutoff < 2.0 * spacing * (1.0 - 1e-12):
            raise ValueError(
                f"SurfaceSpec.cutoff_wavelength = {cutoff:.4g} m is shorter than two grid "
                f"spacings (2 x {spacing:.4g} m): the grid cannot carry it (Nyquist). Refine "
                "the grid or lengthen the cut-off."
            )
        if not rolloff > cutoff:
            raise ValueError(
                f"SurfaceSpec.rolloff_wavelength = {rolloff:.4g} m must be longer than "
                f"cutoff_wavelength = {cutoff:.4g} m"
            )
        if not self.periodic:
            raise ValueError("acf='self-affine' generates periodic surfaces only; "
                             "set periodic=True")
        object.__setattr__(self, "hurst", float(hurst))
        object.__setattr__(self, "rolloff_wavelength", float(rolloff))
        object.__setattr__(self, "cutoff_wavelength", float(cutoff))

    def _check_psd(self, size) -> None:
        table = check_psd_table(self.psd, "SurfaceSpec.psd")
        if not self.periodic:
            raise ValueError("acf='psd' generates periodic surfaces only; set periodic=True")
        q_top = max(q for q, c in table if c > 0)
        q_lowest = 2.0 * math.pi / max(float(v) for v in size)
        if q_top < q_lowest * (1.0 - _Q_RTOL):
            raise ValueError(
                f"SurfaceSpec.psd has power only up to q = {q_top:.4g} 1/m (wavelength "
                f"{2 * math.pi / q_top:.4g} m), below the smallest non-zero wavenumber of the "
                f"surface, 2 pi / L = {q_lowest:.4g} 1/m: the surface would be flat. Enlarge "
                "the surface to more than the longest wavelength with power, or check the "
                "unit of q (1/m, q = 2 pi / wavelength)."
            )
        object.__setattr__(self, "psd", table)

    @property
    def shape(self) -> tuple[int, int]:
        """Array shape ``(ny, nx)`` of one surface."""
        return (self.grid[1], self.grid[0])

    @property
    def spacing(self) -> tuple[float, float]:
        """Grid spacing ``(dx, dy)`` [m]."""
        return (self.size[0] / self.grid[0], self.size[1] / self.grid[1])

    def as_dict(self) -> dict:
        """Plain-type dictionary of the specification (for HDF5 attributes)."""
        return {
            "grid": list(self.grid),
            "size": list(self.size),
            "corr_length": list(self.corr_length),
            "sigma": self.sigma,
            "skew": self.skew,
            "kurt": self.kurt,
            "acf": self.acf,
            "periodic": self.periodic,
        } | {name: getattr(self, name) for name in _SELF_AFFINE_FIELDS
             if getattr(self, name) is not None
             } | ({"psd": [list(row) for row in self.psd]} if self.psd is not None else {})


def _short(value, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters (a PSD table can be long)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 5] + " ...)"


def check_psd_table(table, name: str = "psd") -> tuple[tuple[float, float], ...]:
    """A tabulated isotropic PSD as a tuple of ``(q, C)`` float pairs, checked.

    ``table`` holds rows ``(q, C)``: the wavenumber magnitude ``q`` [1/m],
    positive and strictly increasing, and ``C >= 0`` (any unit), at least two
    rows with some C positive; every value finite. ``name`` says where the
    table came from in the messages (a field, a file); rows are counted from 1.

    Raises
    ------
    ValueError
        Naming ``name``, the offending row, what was expected and what to do.
    """
    try:
        rows = np.asarray(table, dtype=float)
    except (TypeError, ValueError):
        rows = None
    if table is None or rows is None or rows.ndim != 2 or rows.shape[1] != 2:
        raise ValueError(
            f"{name} must be a table of (q, C) rows: wavenumber q [1/m] and PSD C; got "
            f"{_short(table)}. Give a sequence of pairs, e.g. ((1e3, 1.0), (1e4, 1e-4))."
        )
    if len(rows) < 2:
        raise ValueError(f"{name} needs at least 2 rows (q, C) to interpolate between; got "
                         f"{len(rows)}")
    bad = np.nonzero(~np.isfinite(rows).all(axis=1))[0]
    if bad.size:
        raise ValueError(f"{name}: row {bad[0] + 1} (q, C) = {tuple(rows[bad[0]])} is not "
                         "finite; drop the row or give its value")
    q, c = rows[:, 0], rows[:, 1]
    if not q[0] > 0:
        raise ValueError(f"{name}: row 1 has q = {q[0]:g} 1/m; wavenumbers must be positive "
                         "(drop the q = 0 row: the mean height is not part of the spectrum)")
    step = np.nonzero(np.diff(q) <= 0)[0]
    if step.size:
        i = int(step[0]) + 1
        raise ValueError(f"{name}: q must increase strictly from row to row; row {i + 1} has "
                         f"q = {q[i]:g} 1/m after q = {q[i - 1]:g}. Sort the table by q and "
                         "merge repeated q")
    negative = np.nonzero(c < 0)[0]
    if negative.size:
        raise ValueError(f"{name}: row {negative[0] + 1} has C = {c[negative[0]]:g}; a power "
                         "spectral density is >= 0")
    if not np.any(c > 0):
        raise ValueError(f"{name}: every C is zero (no power); give the PSD's values")
    return tuple((float(a), float(b)) for a, b in rows)


def tabulated_psd(q, table):
    """Isotropic PSD interpolated from a table of ``(q, C)`` rows, at wavenumbers ``q`` [1/m].

    Between two rows, ``log C`` is linear in ``log q`` (power laws are exact);
    where either row's C is zero, C itself is linear in ``q`` (the log is not
    defined there). Below the first row C is the first row's (a plateau, like
    the roll-off of :func:`self_affine_psd`); above the last row it is zero (a
    cut-off). ``table`` as :func:`check_psd_table` returns it (not checked
    here); the result has C's unit.
    """
    q = np.asarray(q, dtype=float)
    rows = np.asarray(table, dtype=float)
    qt, ct = rows[:, 0], rows[:, 1]
    out = np.zeros(q.shape)
    out[q < qt[0]] = ct[0]
    inside = (q >= qt[0]) & (q <= qt[-1] * (1.0 + _Q_RTOL))
    x = np.minimum(q[inside], qt[-1])
    i = np.clip(np.searchsorted(qt, x, side="right") - 1, 0, len(qt) - 2)
    q0, q1, c0, c1 = qt[i], qt[i + 1], ct[i], ct[i + 1]
    positive = (c0 > 0) & (c1 > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_log = np.log(x / q0) / np.log(q1 / q0)
        log_value = np.exp(np.log(c0) + t_log * (np.log(c1) - np.log(c0)))
    linear = c0 + (x - q0) / (q1 - q0) * (c1 - c0)
    out[inside] = np.where(positive, log_value, linear)
    return out


# --------------------------------------------------------------------------- filter


def self_affine_psd(q, hurst: float, rolloff_wavelength: float, cutoff_wavelength: float):
    """Isotropic self-affine PSD with roll-off and cut-off, up to a constant factor.

    ``C(q) = 1`` for ``q < q_r``, ``(q / q_r)^(-2 (1 + H))`` for
    ``q_r <= q <= q_s`` and ``0`` for ``q > q_s``, with ``q_r = 2 pi / lambda_r``
    and ``q_s = 2 pi / lambda_s`` (the form generated by Tamaas,
    SurfaceTopography and SlipPY; Persson et al. 2005, J. Phys. Condens.
    Matter 17, R1, Eq 4; Jacobs, Junge & Pastewka 2017, Surf. Topogr. Metrol.
    Prop. 5, 013001). ``q`` is the wavenumber magnitude [1/m]; the result is
    dimensionless (relative to the plateau ``C(0)``): :class:`SurfaceSpec`
    sets the amplitude through ``sigma``.
    """
    q = np.asarray(q, dtype=float)
    q_r = 2.0 * math.pi / rolloff_wavelength
    q_s = 2.0 * math.pi / cutoff_wavelength
    band = (np.maximum(q, q_r) / q_r) ** (-2.0 * (1.0 + hurst))
    return np.where(q > q_s * (1.0 + 1e-12), 0.0, band)


def _grid_wavenumber(spec: SurfaceSpec) -> np.ndarray:
    """Wavenumber magnitude ``|q|`` [1/m] of each full-FFT bin, shape ``(ny, nx)``."""
    ny, nx = spec.shape
    dx, dy = spec.spacing
    qx = 2.0 * math.pi * np.fft.fftfreq(nx, dx)
    qy = 2.0 * math.pi * np.fft.fftfreq(ny, dy)
    return np.hypot(qx[None, :], qy[:, None])


def autocorrelation(spec: SurfaceSpec, lag_x, lag_y):
    """Target ACF R(x, y) of Eq 1 [m^2] at lags ``lag_x``, ``lag_y`` [m].

    Exponential and Gaussian kinds only; a self-affine or tabulated spec is
    defined by its PSD (:func:`self_affine_psd`, :func:`tabulated_psd`), whose
    ACF on the grid is the inverse FFT of :func:`filter_kernel`'s power.
    """
    if spec.acf in _SPECTRUM_FIELDS:
        raise ValueError(f"autocorrelation: acf={spec.acf!r} is defined by its PSD, "
                         "see self_affine_psd and tabulated_psd")
    bx, by = spec.corr_length
    r2 = (np.asarray(lag_x) / bx) ** 2 + (np.asarray(lag_y) / by) ** 2
    shape = np.sqrt(r2) if spec.acf == "exponential" else r2
    return spec.sigma**2 * np.exp(-ACF_DECAY * shape)


def _pad_factor(spec: SurfaceSpec) -> int:
    """Lag-grid enlargement for non-periodic kernels: R(p L / 2) <= 1e-5 R(0)."""
    p = 2
    while True:
        half = [p * L / 2 for L in spec.size]
        if autocorrelation(spec, half[0], 0.0) <= 1e-5 * spec.sigma**2 and autocorrelation(
            spec, 0.0, half[1]
        ) <= 1e-5 * spec.sigma**2:
            return p
        p += 1


def kernel_shape(spec: SurfaceSpec) -> tuple[int, int]:
    """Shape ``(ky, kx)`` of the filter kernel used for this spec."""
    ny, nx = spec.shape
    if spec.periodic:
        return (ny, nx)
    p = _pad_factor(spec)
    return (p * ny, p * nx)


@dataclass(frozen=True)
class FilterKernel:
    """Zero-phase filter of Eq 9-11, normalised to unit output variance.

    Attributes
    ----------
    weights : ndarray (ky, kx)
        Filter weights h_kl in FFT order (lag 0 at ``[0, 0]``), dimensionless,
        with ``sum(h**2) == 1`` (Parseval).
    transfer : ndarray (ky, kx)
        Its real, non-negative transfer function H = FFT2(h).
    clipped : int
        Number of negative spectral values S_z set to zero.
    clipped_fraction : float
        Their share of the total spectral power (absolute value).
    """

    weights: np.ndarray
    transfer: np.ndarray
    clipped: int
    clipped_fraction: float


def filter_kernel(spec: SurfaceSpec) -> FilterKernel:
    """Filter weights h with |H|^2 = S_z / S_x for unit-variance white input.

    The target spectrum S_z is the 2-D FFT of the ACF of Eq 1 sampled on the
    lag grid (periodic: the surface grid; non-periodic: a grid enlarged until
    R has decayed below 1e-5). With S_x = 1 (white noise of unit variance),
    H = sqrt(S_z) with zero phase (Eq 11), h = IFFT2(H) is real and even.
    Negative values of S_z (from truncating R on a finite grid) are clipped to
    zero, counted and logged; h is then renormalised to ``sum(h^2) = 1``.

    Lengths in ``spec`` are in metres; ``spec.sigma`` does not enter (the
    kernel is normalised to unit variance, sigma scales the output).

    For ``acf="self-affine"`` S_z is :func:`self_affine_psd` at each bin's
    wavenumber ``|q|`` on the (periodic) surface grid, with no clipping needed;
    for ``acf="psd"`` it is :func:`tabulated_psd` of ``spec.psd`` there
    (divided by the table's largest C), and a table that leaves every bin but
    the mean (q = 0) without power is refused with a ValueError.
    """
    if spec.acf == "self-affine":
        spectrum = self_affine_psd(_grid_wavenumber(spec), spec.hurst, spec.rolloff_wavelength,
                                   spec.cutoff_wavelength)
    elif spec.acf == "psd":
        spectrum = tabulated_psd(_grid_wavenumber(spec), spec.psd)
        spectrum /= max(c for _, c in spec.psd)
        if not np.any(spectrum.ravel()[1:] > 0):
            raise ValueError(
                f"SurfaceSpec.psd puts no power on any wavenumber of the {spec.grid[0]} x "
                f"{spec.grid[1]} grid over {_mm(spec.size)} mm but the mean: its rows with "
                "C > 0 fall between the grid's wavenumbers. Refine the grid, enlarge the "
                "surface, or tabulate the PSD over the grid's wavenumbers "
                "(2 pi / L up to pi / spacing)."
            )
    if spec.acf in _SPECTRUM_FIELDS:
        transfer = np.sqrt(spectrum)
        weights = np.fft.ifft2(transfer).real
        norm = math.sqrt(float(np.sum(weights**2)))
        return FilterKernel(weights / norm, transfer / norm, 0, 0.0)
    ky, kx = kernel_shape(spec)
    dx, dy = spec.spacing
    lag_x = np.fft.fftfreq(kx, 1.0 / kx) * dx
    lag_y = np.fft.fftfreq(ky, 1.0 / ky) * dy
    acf = autocorrelation(spec, lag_x[None, :], lag_y[:, None]) / spec.sigma**2
    spectrum = np.fft.fft2(acf).real
    negative = spectrum < 0
    clipped = int(negative.sum())
    clipped_fraction = float(-spectrum[negative].sum() / np.abs(spectrum).sum()) if clipped else 0.0
    if clipped:
        log.warning(
            "filter_kernel: %d negative spectral values (%.3g %% of the spectral power) "
            "clipped to zero for b = (%.3g, %.3g) m on a %.3g x %.3g m %s lag grid; "
            "the realised ACF deviates from Eq 1. Use a larger surface or a shorter "
            "correlation length to avoid this.",
            clipped,
            100 * clipped_fraction,
            *spec.corr_length,
            kx * dx,
            ky * dy,
            "periodic" if spec.periodic else "padded",
        )
        spectrum = np.where(negative, 0.0, spectrum)
    transfer = np.sqrt(spectrum)
    weights = np.fft.ifft2(transfer).real
    norm = math.sqrt(float(np.sum(weights**2)))
    weights = weights / norm
    transfer = transfer / norm
    return FilterKernel(weights, transfer, clipped, clipped_fraction)


def _check_domain(spec: SurfaceSpec) -> None:
    if spec.acf == "psd":
        nyquist = math.pi / max(spec.spacing)
        q_top = max(q for q, c in spec.psd if c > 0)
        if q_top > nyquist * (1.0 + _Q_RTOL):
            log.warning(
                "the tabulated PSD has power up to q = %.4g 1/m, beyond the grid's Nyquist "
                "wavenumber pi / spacing = %.4g 1/m: shorter wavelengths are left out, or "
                "kept only along the diagonals (anisotropically). Refine the grid or end the "
                "table at q = %.4g 1/m.", q_top, nyquist, nyquist)
        return  # its corr_length (2 pi / q_1) only labels the spec: no length checks
    for axis, (b, L, d) in enumerate(zip(spec.corr_length, spec.size, spec.spacing, strict=True)):
        name = "xy"[axis]
        if b > L / 2:
            log.warning(
                "correlation length b%s = %.3g m exceeds half the domain (L%s / 2 = %.3g m): "
                "only %.2g correlation cells fit, so sample moments scatter widely and "
                "the realised sigma is biased low. Enlarge the surface to at least 2 b.",
                name,
                b,
                name,
                L / 2,
                L / b,
            )
        if b < d:
            log.warning(
                "correlation length b%s = %.3g m is shorter than the grid spacing "
                "d%s = %.3g m: the surface is nearly white noise on this grid.",
                name,
                b,
                name,
                d,
            )


def moment_transfer(spec: SurfaceSpec) -> tuple[float, float]:
    """Skewness and kurtosis transfer factors (S3, S4) of the filter (Eq 12-13).

    ``S3 = sum h^3 / (sum h^2)^(3/2)`` and ``S4 = sum h^4 / (sum h^2)^2``, so
    that ``Sk_z = S3 Sk_x`` and ``Ku_z - 3 = S4 (Ku_x - 3)`` for i.i.d. input.
    They depend on the ACF shape and on b/dx only.
    """
    h = filter_kernel(spec).weights
    s2 = float(np.sum(h**2))
    return float(np.sum(h**3) / s2**1.5), float(np.sum(h**4) / s2**2)


def kurt_min(spec: SurfaceSpec, skew=None):
    """Smallest reachable surface kurtosis at skewness ``skew`` (Fig 2).

    The white noise must satisfy Ku_x >= Sk_x^2 + 1 (Eq 15); through Eq 12-13
    this gives ``Ku_z,min = 3 + S4 (Sk_z^2 / S3^2 - 2)``. Vectorised in
    ``skew``; defaults to ``spec.skew``. Depends on the grid spacing through
    b/dx (the filter's S3, S4).
    """
    s3, s4 = moment_transfer(spec)
    skew = spec.skew if skew is None else np.asarray(skew, dtype=float)
    return 3.0 + s4 * (skew**2 / s3**2 - 2.0)


def _transfer_to_input(skew, kurt, s3, s4):
    return skew / s3, 3.0 + (kurt - 3.0) / s4


def input_moments(spec: SurfaceSpec) -> tuple[float, float]:
    """Skewness and kurtosis (Sk_x, Ku_x) of the white noise before filtering.

    Inverts Eq 12-13. Raises :class:`InfeasibleMoments` when the target lies
    below :func:`kurt_min` for this grid and ACF.
    """
    absolute = spec.skew**2 + 1.0
    if spec.kurt < absolute:
        raise InfeasibleMoments(
            f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is below the absolute limit "
            f"Ku >= Sk^2 + 1 = {absolute:g} (Eq 14): no distribution has these moments. "
            f"Raise kurt above {absolute:g}."
        )
    s3, s4 = moment_transfer(spec)
    skew_x, kurt_x = _transfer_to_input(spec.skew, spec.kurt, s3, s4)
    limit = skew_x**2 + 1.0
    if kurt_x < limit - 1e-12 * max(1.0, limit):
        kmin = 3.0 + s4 * (limit - 3.0)
        raise InfeasibleMoments(
            f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is not reachable with a linear "
            f"filter for a {spec.acf} ACF with corr_length = {_mm(spec.corr_length)} mm on a "
            f"{spec.grid[0]} x {spec.grid[1]} grid over {_mm(spec.size)} mm "
            f"(b/dx = {spec.corr_length[0] / spec.spacing[0]:.3g}): the minimum kurtosis at this "
            f"skewness is {kmin:.4f} (Eq 15 with Eq 12-13). Raise kurt to at least {kmin:.4f}, "
            "shorten the correlation length relative to the grid spacing, or use "
            "method='exact', which is limited only by Ku >= Sk^2 + 1."
        )
    return float(skew_x), float(max(kurt_x, limit))


def _mm(pair) -> str:
    return " x ".join(f"{1e3 * v:g}" for v in pair)


def input_family(spec: SurfaceSpec, skew, kurt):
    """Johnson family of the white noise needed for surface moments (skew, kurt).

    Maps (Sk_z, Ku_z) to (Sk_x, Ku_x) through Eq 12-13 and classifies with
    :func:`roughcontact.surfaces.johnson.family_of` (the regions of Fig 1). Vectorised.
    """
    s3, s4 = moment_transfer(spec)
    skew_x, kurt_x = _transfer_to_input(np.asarray(skew, float), np.asarray(kurt, float), s3, s4)
    return np.vectorize(johnson.family_of, otypes=[object])(skew_x, kurt_x)


def lognormal_line(spec: SurfaceSpec, skew):
    """Surface kurtosis on the SL line (Fig 1) at surface skewness ``skew``."""
    s3, s4 = moment_transfer(spec)
    skew_x = np.asarray(skew, float) / s3
    return 3.0 + s4 * (johnson.lognormal_kurt(skew_x) - 3.0)


# --------------------------------------------------------------------------- memory

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

    Counts the float64 work arrays :func:`generate_many` holds at its two
    peaks, with ``N = nx ny`` surface points, ``K`` kernel points
    (:func:`kernel_shape`), ``M`` noise points (the surface grid, or surface +
    kernel - 1 along each axis when padded) and ``F`` points of the padded
    FFT of ``scipy.signal.fftconvolve``, in bytes per point:

    - the filter (:func:`filter_kernel`, 65 K: ACF, its complex FFT, clip,
      transfer, complex inverse FFT, normalisation), run again by
      :func:`input_moments` while the first kernel (16 K: weights and
      transfer) is held: ``81 K``;
    - per surface: the output stack ``8 count N``, the kernel ``16 K``, and the
      larger of the Johnson transform (noise, transformed noise, a temporary
      and the previous surface's noise: ``32 M``) and the filter (the noise
      ``8 M`` plus complex FFT, product and inverse FFT ``48 N`` when
      periodic; the centred kernel ``8 K`` plus two half-spectra, their
      product and the output ``32 F`` when padded).

    ``method="filter"`` first calibrates (:func:`calibrate_filter`) on batches
    of about 2^19 noise points ``B``: ``16 K + 60 B`` (periodic) or
    ``16 K + 90 B`` (padded), if larger than the generation's peak.

    ``method="exact"`` (:func:`generate_exact`, periodic): ``120 N`` (the
    filter's 65 N, the moment correction of the height set and the
    iterations' surfaces, rankings and half spectra stay below it) plus ``8 N`` for each
    surface already made, or ``16 count N`` while they are stacked. These
    match the peaks traced with ``tracemalloc`` within 1 % (grids of 64 x 64
    to 1500 x 1200, periodic and padded, 1 and 3 surfaces). Only shapes are
    computed: nothing large is allocated.

    Parameters
    ----------
    spec : SurfaceSpec
    count : int
        Number of surfaces generated in one call (seeds of :func:`generate_many`).
    method : {"filter", "paper", "exact"}

    Returns
    -------
    int
        Bytes.
    """
    _check_method(method)
    count = max(int(count), 1)
    ny, nx = spec.shape
    points = ny * nx
    if method == "exact":
        return int(max(120 * points + 8 * (count - 1) * points, 16 * count * points))
    ky, kx = kernel_shape(spec)
    kernel = ky * kx
    if spec.periodic:
        noise = points
        convolution = 48 * points
    else:
        noise = (ny + ky - 1) * (nx + kx - 1)
        padded = (fft.next_fast_len(ny + 2 * ky - 2, True)
                  * fft.next_fast_len(nx + 2 * kx - 2, True))
        convolution = 8 * kernel + 32 * padded
    per_surface = 8 * count * points + 16 * kernel + max(32 * noise, 8 * noise + convolution)
    peak = max(81 * kernel, per_surface)
    if method == "filter":  # the calibration runs first, on batches of surfaces
        batch = max(1, _CALIBRATION_BATCH_POINTS // noise) * noise
        peak = max(peak, 16 * kernel + (60 if spec.periodic else 90) * batch)
    return int(peak)


def _check_memory(spec: SurfaceSpec, count: int, method: str, max_bytes) -> None:
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


# --------------------------------------------------------------------------- generation


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


def _white_noise(spec: SurfaceSpec, seed: int, shape) -> np.ndarray:
    return np.random.default_rng(int(seed)).standard_normal(shape)


def _noise_shape(spec: SurfaceSpec, kernel: np.ndarray) -> tuple[int, int]:
    ny, nx = spec.shape
    if spec.periodic:
        return (ny, nx)
    ky, kx = kernel.shape
    return (ny + ky - 1, nx + kx - 1)


def _apply_filter(spec: SurfaceSpec, kern: FilterKernel, x: np.ndarray) -> np.ndarray:
    """z = h * x (Eq 9) for a stack of noise fields x (..., rows, cols).

    Periodic: real FFTs (the transfer function is real and even), 13 times
    faster than complex ones on 60 x 60 and equal to 4e-15.
    """
    if spec.periodic:
        nx = x.shape[-1]
        half = kern.transfer[:, : nx // 2 + 1]
        return np.fft.irfft2(np.fft.rfft2(x) * half, s=x.shape[-2:])
    centred = np.fft.fftshift(kern.weights)
    centred = centred.reshape((1,) * (x.ndim - 2) + centred.shape)
    return signal.fftconvolve(x, centred, mode="valid", axes=(-2, -1))


def _fit_input(spec: SurfaceSpec) -> johnson.JohnsonCurve:
    skew_x, kurt_x = input_moments(spec)
    return johnson.fit(skew_x, kurt_x)


GENERATION_METHODS = ("filter", "paper", "exact")
"""Generators of :func:`generate_many`: the calibrated filter (default), the
paper's uncorrected filter, and iterative amplitude adjustment."""


def _check_method(method: str) -> None:
    if method not in GENERATION_METHODS:
        raise ValueError(f"method must be one of {GENERATION_METHODS}; got {method!r}")


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
        (:func:`calibrate_filter`). "paper": the same filter with Eq 12-13 as
        the paper uses them: the targets are the moments of the infinite
        process, and a finite window's sample kurtosis is biased (-1.4 % at
        (0, 4.5) on 60 x 60 over 9 mm with b = 1 mm, -3 % on 30 x 30 over
        4.5 mm). "exact": iterative amplitude adjustment, see
        :func:`generate_exact`.
    max_bytes : float
        Memory budget [bytes], default :data:`MAX_GENERATION_BYTES` (8 GB).

    Raises
    ------
    SurfaceTooLarge
        Before allocating, if :func:`estimate_generation_bytes` exceeds
        ``max_bytes``.
    """
    return generate_many(spec, [seed], method=method, max_bytes=max_bytes, **options)[0]


def generate_many(spec: SurfaceSpec, seeds, method: str = "filter", *,
                  max_bytes: float = MAX_GENERATION_BYTES, **options) -> np.ndarray:
    """Surfaces for each seed, shape ``(len(seeds), ny, nx)`` [m], zero mean each.

    Equivalent to stacking :func:`generate` per seed (bit for bit), but the
    Johnson fit, the calibration and the filter are computed once and the
    FFTs are batched. Refuses with :class:`SurfaceTooLarge` before allocating
    when the estimated peak memory of all the surfaces
    (:func:`estimate_generation_bytes`) exceeds ``max_bytes`` [bytes]
    (default :data:`MAX_GENERATION_BYTES`).
    """
    seeds = [int(s) for s in np.atleast_1d(np.asarray(seeds, dtype=np.uint64))]
    _check_method(method)
    _check_memory(spec, len(seeds), method, max_bytes)
    if method == "exact":
        return np.stack([generate_exact(spec, s, max_bytes=max_bytes, **options)[0]
                         for s in seeds])
    if options:
        raise TypeError(f"unexpected options for method={method!r}: {sorted(options)}")
    _check_domain(spec)
    process = spec
    if method == "filter":
        cal = calibrate_filter(spec)
        process = replace(spec, skew=cal.skew, kurt=cal.kurt)
    kern = filter_kernel(spec)
    curve = _fit_input(process)
    mean_x, std_x, _, _ = curve.moments()
    shape = _noise_shape(spec, kern.weights)
    out = np.empty((len(seeds), *spec.shape))
    for k, seed in enumerate(seeds):
        x = (curve.transform(_white_noise(spec, seed, shape)) - mean_x) / std_x
        out[k] = _apply_filter(spec, kern, x)
    out -= out.mean(axis=(-2, -1), keepdims=True)
    out *= spec.sigma
    if not np.all(np.isfinite(out)):
        raise FloatingPointError(f"non-finite surface heights generated for {spec!r}")
    return out


# --------------------------------------------------------------------------- calibration

#: Seed of the calibration's white noise: one fixed stream, so a spec's
#: calibration (and so its surfaces) is the same on every run.
CALIBRATION_SEED = 20061124
#: Standard error of the estimated expected sample moments at which the
#: calibration stops adding surfaces: relative to Ku, and to max(1, |Sk|).
CALIBRATION_RSE = 1e-3
#: Most surface points (surfaces x nx x ny) one calibration evaluation reads.
CALIBRATION_MAX_POINTS = 1e8
#: Fewest calibration surfaces.
CALIBRATION_MIN_SAMPLES = 2000
#: Relative distance of the estimated expected moments from the targets at
#: which the calibration's solve stops ...
CALIBRATION_SOLVE_TOL = 1e-5
#: ... or this fraction of the estimate's standard error, if larger (the
#: solve's error is then negligible against the calibration's own).
CALIBRATION_SOLVE_SE = 0.05
_CALIBRATION_BATCH_POINTS = 2**19
_CALIBRATION_MAX_EVALUATIONS = 12


@dataclass(frozen=True)
class FilterCalibration:
    """The process moments that give a window the target sample moments (:func:`calibrate_filter`).

    Attributes
    ----------
    skew, kurt : float
        Moments of the infinite process fed to Eq 12-13 (``SurfaceSpec.skew``,
        ``.kurt`` of the paper's method) so that the expected sample moments
        of one window equal the spec's targets.
    expected_skew, expected_kurt : float
        Estimated expected sample skewness and kurtosis of a window at the
        solution (control-variate mean over ``samples`` fixed-seed surfaces).
    skew_se, kurt_se : float
        Their standard errors: the calibration's own error.
    paper_skew, paper_kurt : float
        The same estimate for the paper's method (process moments = targets):
        its bias is ``paper_kurt - spec.kurt``.
    samples : int
        Calibration surfaces (fixed seed :data:`CALIBRATION_SEED`).
    evaluations : int
        Estimates made (each over the same ``samples`` surfaces).
    converged : bool
        The estimate met the targets to :data:`CALIBRATION_SOLVE_TOL`.
    seconds : float
        Wall time.
    """

    skew: float
    kurt: float
    expected_skew: float
    expected_kurt: float
    skew_se: float
    kurt_se: float
    paper_skew: float
    paper_kurt: float
    samples: int
    evaluations: int
    converged: bool
    seconds: float

    def as_attrs(self) -> dict:
        """Plain-type dictionary with ``calibration_`` keys (for HDF5 attributes)."""
        return {f"calibration_{k}": (v if isinstance(v, bool | int) else float(v))
                for k, v in self.__dict__.items()}


def _control_variate_mean(values: np.ndarray, controls: np.ndarray) -> tuple[float, float]:
    """Mean of ``values`` corrected by zero-mean ``controls`` (columns), and its SE."""
    centred = controls - controls.mean(axis=0)
    beta = np.linalg.lstsq(centred, values - values.mean(), rcond=None)[0]
    corrected = values - controls @ beta
    return float(corrected.mean()), float(corrected.std(ddof=1) / math.sqrt(len(values)))


class _SampleMoments:
    """Sample moments of fixed-seed filter surfaces for any process moments.

    The same white noise (common random numbers: batch ``k`` is seeded
    ``(CALIBRATION_SEED, k)``) is used for every (Sk, Ku), so the estimate is
    a smooth, deterministic function of them that a root finder can solve.
    """

    def __init__(self, spec: SurfaceSpec, seed: int):
        self.spec = replace(spec, sigma=1.0)
        self.seed = int(seed)
        self.kernel = filter_kernel(self.spec)
        self.noise_shape = _noise_shape(self.spec, self.kernel.weights)
        self.batch = max(1, _CALIBRATION_BATCH_POINTS // math.prod(self.noise_shape))
        self.s3, self.s4 = moment_transfer(self.spec)
        self._cache = None

    def draws(self, skew: float, kurt: float, count: int) -> np.ndarray:
        """Per-surface (Sk, Ku, z^3, z^4, z^2) of the first ``count`` surfaces, shape (count, 5).

        The last three are the raw moments minus their exact expectations
        (controls of zero mean). Batches already drawn for the same (Sk, Ku)
        are reused.
        """
        key = (float(skew), float(kurt))
        done = self._cache[1] if self._cache and self._cache[0] == key else np.empty((0, 5))
        batches = math.ceil(count / self.batch)
        have = len(done) // self.batch
        if batches > have:
            curve = _fit_input(replace(self.spec, skew=skew, kurt=kurt))
            mean_x, std_x, skew_x, kurt_x = curve.moments()
            # the fitted law's own moments, so the controls have exactly zero mean
            means = np.array([self.s3 * skew_x, 3.0 + self.s4 * (kurt_x - 3.0), 1.0])
            rows = [done]
            for k in range(have, batches):
                eta = np.random.default_rng([self.seed, k]).standard_normal(
                    (self.batch, *self.noise_shape))
                z = _apply_filter(self.spec, self.kernel,
                                  (curve.transform(eta) - mean_x) / std_x)
                axes = (-2, -1)
                z2 = z * z
                raw = np.stack([(z2 * z).mean(axis=axes), (z2 * z2).mean(axis=axes),
                                z2.mean(axis=axes)], axis=1) - means
                stats = height_stats(z)
                rows.append(np.column_stack([stats["skew"], stats["kurt"], raw]))
            done = np.concatenate(rows)
            self._cache = (key, done)
        return done[:count]

    def estimate(self, skew: float, kurt: float, count: int):
        """Expected sample (Sk, Ku) and their standard errors over ``count`` surfaces."""
        d = self.draws(skew, kurt, count)
        sk, sk_se = _control_variate_mean(d[:, 0], d[:, 2:])
        ku, ku_se = _control_variate_mean(d[:, 1], d[:, 2:])
        return np.array([sk, ku]), np.array([sk_se, ku_se])


def expected_sample_moments(spec: SurfaceSpec, count: int = 2000, *,
                            seed: int = CALIBRATION_SEED) -> tuple[np.ndarray, np.ndarray]:
    """Expected sample (Sk, Ku) of one window of the paper's filter generator.

    The process moments are ``spec.skew``, ``spec.kurt`` (Eq 12-13, as the
    paper uses them). Estimated over ``count`` fixed-seed surfaces with
    control variates (the raw third and fourth moments and the variance,
    whose expectations are known exactly from Eq 12-13): 2-5 times smaller
    standard errors than the plain mean. Returns ``(means, standard_errors)``,
    each ``[Sk, Ku]``.
    """
    return _SampleMoments(spec, seed).estimate(spec.skew, spec.kurt, int(count))


def _on_bound(spec: SurfaceSpec, skew: float) -> float:
    """The filter's smallest reachable kurtosis at process skewness ``skew`` (Eq 15),
    nudged inside so the white noise's Johnson law can still be fitted."""
    return float(kurt_min(spec, skew)) * (1.0 + 1e-9) + 1e-12


def sample_bound(spec: SurfaceSpec, skew, count: int = 1000, *,
                 seed: int = CALIBRATION_SEED) -> tuple[np.ndarray, np.ndarray]:
    """The reachable region's edge for a window's expected sample moments (Fig 2, same rule).

    For each process skewness in ``skew``, the process on the filter's bound
    (Eq 15: ``Ku = kurt_min(spec, skew)``, a two-point white noise) is
    sampled on ``spec``'s grid and its expected sample (Sk, Ku) estimated over
    ``count`` fixed-seed surfaces (:func:`expected_sample_moments`). The
    calibrated filter (``method="filter"``) reaches every target above the
    returned curve; the paper's method, every target above
    :func:`kurt_min`. Returns ``(sample_skew, sample_kurt)``, arrays like
    ``skew``.
    """
    skew = np.atleast_1d(np.asarray(skew, dtype=float))
    sampler = _SampleMoments(spec, seed)
    out = np.array([sampler.estimate(s, _on_bound(spec, s), int(count))[0] for s in skew])
    return out[:, 0], out[:, 1]


def _moment_scale(target: np.ndarray) -> np.ndarray:
    return np.array([max(1.0, abs(target[0])), abs(target[1])])


def calibrate_filter(spec: SurfaceSpec, *, rse: float = CALIBRATION_RSE,
                     max_points: float = CALIBRATION_MAX_POINTS,
                     seed: int = CALIBRATION_SEED) -> FilterCalibration:
    """Process moments whose windows have the target *sample* moments in expectation.

    Eq 12-13 give the skewness and kurtosis of the infinite filtered process.
    The sample moments of one finite window are biased: the window's mean is
    removed, and a ratio of sample moments is not the ratio of their
    expectations; the fewer correlation lengths the window holds, the larger
    the bias (kurtosis -1.4 % at (0, 4.5) on 60 x 60 over 9 mm with
    b = 1 mm, -3.1 % on 30 x 30 over 4.5 mm, +0.6 % at (2, 10)). This finds
    the process moments (Sk_p, Ku_p) for which the expected sample (Sk, Ku) of
    a window of ``spec`` equal ``(spec.skew, spec.kurt)``:

    1. The expectation is estimated over fixed-seed surfaces of the paper's
       generator with control variates (:func:`expected_sample_moments`);
       surfaces are added in batches until both standard errors are below
       ``rse`` (relative to Ku, and to max(1, |Sk|)), with at least
       :data:`CALIBRATION_MIN_SAMPLES` and at most ``max_points`` surface
       points.
    2. Broyden's method on the 2 x 2 system, starting from the targets, with
       the same surfaces for every estimate (a smooth, deterministic
       function), until the estimate is within :data:`CALIBRATION_SOLVE_TOL`
       (relative) or 5 % of its standard error of the targets; steps that would leave the filter's
       reachable region (Eq 15) stop on its edge.

    The result depends only on the spec's moments, grid, size, correlation
    length, ACF and periodicity (not on sigma), and is cached per process.
    Costs 0.1 ms per 60 x 60 surface and estimate: about 1-4 s per cell.

    Raises
    ------
    InfeasibleMoments
        When the target is below the absolute bound Ku >= Sk^2 + 1, or the
        expected sample moments cannot reach it without a process beyond the
        filter's bound (Eq 15): the message gives the nearest reachable
        kurtosis.
    """
    return _calibrate(replace(spec, sigma=1.0), float(rse), float(max_points), int(seed))


@functools.lru_cache(maxsize=256)
def _calibrate(spec: SurfaceSpec, rse: float, max_points: float, seed: int) -> FilterCalibration:
    start = time.perf_counter()
    absolute = spec.skew**2 + 1.0
    if spec.kurt < absolute:
        input_moments(spec)  # raises the absolute-bound message
    target = np.array([spec.skew, spec.kurt])
    scale = _moment_scale(target)
    sampler = _SampleMoments(spec, seed)
    # Sk = 0: the law and the filter are symmetric, so the expected sample
    # skewness is 0 exactly; only the kurtosis is estimated and solved
    symmetric = spec.skew == 0.0

    def estimate(theta, count):
        g, se = sampler.estimate(*theta, count)
        if symmetric:
            g[0], se[0] = 0.0, 0.0
        return g, se

    theta = np.array([spec.skew, max(spec.kurt, _on_bound(spec, spec.skew))])
    # 1. grow the sample at the targets until the standard errors are small enough
    most = max(sampler.batch, int(max_points // math.prod(spec.shape)) // sampler.batch
               * sampler.batch)
    count = min(most, math.ceil(CALIBRATION_MIN_SAMPLES / sampler.batch) * sampler.batch)
    while True:
        g, se = estimate(theta, count)
        if np.all(se <= rse * scale) or count >= most:
            break
        needed = 1.1 * float(np.max((se / (rse * scale)) ** 2)) * count
        count = min(most, max(count + sampler.batch,
                              math.ceil(needed / sampler.batch) * sampler.batch))
    if theta[1] == spec.kurt:
        paper = g
    else:  # the paper's method cannot make this target at all
        paper = np.array([math.nan, math.nan])
    # 2. Broyden on g(theta) = target with the same surfaces; a step below the
    # filter's bound stops on it, and the skewness is then solved along the bound
    jac = np.eye(2)
    evaluations, converged, on_edge, slope = 1, False, False, 1.0
    tol = np.maximum(CALIBRATION_SOLVE_TOL * scale, CALIBRATION_SOLVE_SE * se)
    while True:
        residual = target - g
        if np.all(np.abs(residual) <= tol):
            converged = True
            break
        if on_edge and abs(residual[0]) <= tol[0]:
            if residual[1] < 0:  # the skewness is right, the kurtosis cannot go lower
                raise InfeasibleMoments(
                    f"kurtosis {spec.kurt:g} at skewness {spec.skew:g} is not reachable in "
                    f"expectation by the filter generator for the {spec.acf} ACF with "
                    f"corr_length = {_mm(spec.corr_length)} mm on a {spec.grid[0]} x "
                    f"{spec.grid[1]} grid over {_mm(spec.size)} mm: on the filter's bound "
                    f"(Eq 15) a window's expected sample kurtosis at this skewness is "
                    f"{g[1]:.4f}. Raise kurt to at least {g[1]:.4f}, or use method='exact', "
                    "which is limited only by Ku >= Sk^2 + 1."
                )
            on_edge = False  # the target lies above the bound: leave it
        if evaluations >= _CALIBRATION_MAX_EVALUATIONS:
            break
        if on_edge:
            skew = theta[0] + residual[0] / slope
            proposal = np.array([skew, _on_bound(spec, skew)])
        else:
            proposal = theta + np.linalg.solve(jac, residual)
            if proposal[1] < _on_bound(spec, proposal[0]):
                proposal[1] = _on_bound(spec, proposal[0])
                on_edge = True
        new_g, se = estimate(proposal, count)
        evaluations += 1
        d_theta, d_g = proposal - theta, new_g - g
        if np.dot(d_theta, d_theta) > 0:
            jac = jac + np.outer(d_g - jac @ d_theta, d_theta) / np.dot(d_theta, d_theta)
        if d_theta[0] != 0 and d_g[0] != 0:
            slope = d_g[0] / d_theta[0]
        theta, g = proposal, new_g
    result = FilterCalibration(
        skew=float(theta[0]), kurt=float(theta[1]),
        expected_skew=float(g[0]), expected_kurt=float(g[1]),
        skew_se=float(se[0]), kurt_se=float(se[1]),
        paper_skew=float(paper[0]), paper_kurt=float(paper[1]),
        samples=int(count), evaluations=evaluations, converged=converged,
        seconds=time.perf_counter() - start,
    )
    if not converged:
        log.warning(
            "calibrate_filter: the expected sample moments (%.5f, %.5f) did not reach the "
            "targets (%g, %g) to %.0e in %d estimates; using the closest", g[0], g[1],
            spec.skew, spec.kurt, CALIBRATION_SOLVE_TOL, evaluations)
    log.info(
        "calibrate_filter: targets (%g, %g) -> process (%.5f, %.5f); paper's method gives "
        "(%.4f, %.4f); %d surfaces x %d estimates, SE (%.1e, %.1e), %.2f s",
        spec.skew, spec.kurt, theta[0], theta[1], paper[0], paper[1], count,
        evaluations, se[0], se[1], result.seconds)
    return result


#: Largest |error| of the standardized sample moments (mean, variance, Sk, Ku) of
#: :func:`target_heights` before scaling: the Newton correction stops below it.
HEIGHT_MOMENT_TOL = 1e-12
#: Default relative improvement of the spectral error per round below which
#: :func:`generate_exact` stops (stagnation).
EXACT_STAGNATION_RTOL = 1e-2


@dataclass(frozen=True)
class ExactResult:
    """Diagnostics of :func:`generate_exact`.

    Attributes
    ----------
    spectral_error : float
        Relative L2 distance between the realised Fourier amplitudes ``|Z|``
        and the target ``A`` of the zero-mean surface (DC term excluded):
        ``||(|Z| - A)|| / ||A||`` over the whole 2-D spectrum, dimensionless.
    iterations : int
        Amplitude / rank adjustment rounds made.
    converged : bool
        True when the iterations stopped because the spectral error stopped
        improving (relative gain below ``rtol`` over one round) or the ranking
        stopped changing; False when ``max_iter`` was reached first.
    """

    spectral_error: float
    iterations: int
    converged: bool


def _standard_height_set(skew: float, kurt: float, n: int) -> np.ndarray:
    """Sorted set of ``n`` numbers whose sample moments are (0, 1, skew, kurt).

    Starts from the target Johnson law's midpoint quantiles at probabilities
    ``(k + 1/2) / n``, standardized (zero mean, unit population standard
    deviation). Those alone have a kurtosis biased low (the tails beyond the
    outermost quantiles are cut: -3.8 % at (Sk, Ku) = (-1.5, 7), -35 % at
    (0, 20) for n = 3600), so the set is corrected by Gauss-Newton steps of
    minimum Euclidean norm on the four equations
    ``mean(x^j) = (0, 1, Sk, Ku)_j``, j = 1..4 (each step is a cubic
    polynomial in the current values: the tails move most), halved until the
    residual decreases, until the largest residual is below
    :data:`HEIGHT_MOMENT_TOL`; the set is then standardized again and sorted.
    Moments do not depend on the order, so sorting changes none of them.

    Raises
    ------
    FloatingPointError
        If the corrected set misses the moments by more than 1e-9.
    """
    curve = johnson.fit(skew, kurt)
    x = curve.transform(special.ndtri((np.arange(n) + 0.5) / n))
    x = (x - x.mean()) / x.std()
    target = np.array([0.0, 1.0, skew, kurt])

    def residual(y):
        y2 = y * y
        return np.array([y.mean(), y2.mean(), np.dot(y2, y) / n, np.dot(y2, y2) / n]) - target

    r = residual(x)
    for _ in range(50):
        if np.max(np.abs(r)) < HEIGHT_MOMENT_TOL:
            break
        x2 = x * x
        jac = np.stack([np.ones(n), 2 * x, 3 * x2, 4 * x2 * x]) / n
        step = -jac.T @ np.linalg.lstsq(jac @ jac.T, r, rcond=1e-14)[0]
        t = 1.0
        while True:
            y = x + t * step
            ry = residual(y)
            if np.linalg.norm(ry) < np.linalg.norm(r) or t < 1e-6:
                break
            t *= 0.5
        x, r = y, ry
    x = np.sort((x - x.mean()) / x.std())
    r = residual(x)
    if not np.max(np.abs(r)) < 1e-9:
        raise FloatingPointError(
            f"target_heights: could not give {n} heights the sample moments Sk = {skew:g}, "
            f"Ku = {kurt:g} (residual {np.max(np.abs(r)):.3g})"
        )
    return x


def target_heights(spec: SurfaceSpec) -> np.ndarray:
    """Sorted heights [m] whose sample moments are exactly the targets.

    The n = nx ny heights have zero mean, population standard deviation
    (1/n normalisation, as :func:`height_stats`) ``spec.sigma``, skewness
    ``spec.skew`` and kurtosis ``spec.kurt`` to rounding (about 1e-13). They
    are the Johnson law's (fitted directly to (Sk, Ku) of the surface)
    quantiles at probabilities (k + 1/2)/n, corrected so that the discrete
    set's own moments hit the targets (:func:`_standard_height_set`).
    """
    n = spec.grid[0] * spec.grid[1]
    return _standard_height_set(spec.skew, spec.kurt, n) * spec.sigma


def _half_spectrum_weights(shape) -> np.ndarray:
    """Multiplicity of each ``rfft2`` column in the full 2-D spectrum (1 or 2)."""
    nx = shape[1]
    weights = np.full(nx // 2 + 1, 2.0)
    weights[0] = 1.0
    if nx % 2 == 0:
        weights[-1] = 1.0
    return weights


def exact_target_amplitude(spec: SurfaceSpec) -> np.ndarray:
    """Target Fourier amplitude ``A`` of a zero-mean unit-variance surface, rfft2 layout.

    ``A = sqrt(n S_z)`` from the filter's transfer function (Eq 9-11) on the
    surface grid, with the DC term set to zero (every realisation has zero
    mean) and the rest rescaled so that Parseval gives unit variance:
    ``sum_full |A|^2 = n^2``. Dimensionless (heights in units of sigma).
    Shape ``(ny, nx // 2 + 1)``.
    """
    ny, nx = spec.shape
    n = nx * ny
    power = filter_kernel(spec).transfer[:, : nx // 2 + 1] ** 2
    power[0, 0] = 0.0
    total = float(np.sum(power * _half_spectrum_weights(spec.shape)))
    return np.sqrt(power * (n * n / total))


def generate_exact(
    spec: SurfaceSpec, seed: int, max_iter: int = 100, *, rtol: float = EXACT_STAGNATION_RTOL,
    max_bytes: float = MAX_GENERATION_BYTES,
) -> tuple[np.ndarray, ExactResult]:
    """Surface with exactly the target height moments and a matched spectrum (IAAFT).

    Iterative amplitude-adjusted Fourier transform after Schreiber & Schmitz
    (1996) as used for surfaces by Perez-Rafols & Almqvist (2019). Starts from
    a Gaussian filtered surface (Eq 9-11) rank-ordered onto
    :func:`target_heights`, then alternately (1) imposes the target Fourier
    amplitude ``A`` of :func:`exact_target_amplitude`, keeping the phases, and
    (2) rank-orders the result onto the height set. The relative spectral
    error ``e = ||(|Z| - A)|| / ||A||`` of each rank-ordered surface is
    measured; the iterations stop when a round improves it by less than
    ``rtol`` relatively (``e_new > (1 - rtol) e_old``: stagnation), when the
    ranking no longer changes, or after ``max_iter`` rounds. The surface with
    the smallest error is returned.

    Every realisation is a permutation of :func:`target_heights`, so its
    sample mean is zero and its sample sigma, Sk and Ku (1/n normalisation,
    :func:`height_stats`) equal the targets to rounding; it is not limited by
    the Fig 2 bound. The spectrum is matched as closely as the rank constraint
    allows. On a periodic grid a zero-mean surface's sample ACF is the target
    ACF minus its mean over the domain, so its 10 % lag is somewhat shorter
    than b (0.953 b for b = L/9, exponential ACF). Periodic surfaces only.
    Refuses with :class:`SurfaceTooLarge`, before allocating, when
    :func:`estimate_generation_bytes` exceeds ``max_bytes`` [bytes]
    (default :data:`MAX_GENERATION_BYTES`).

    Parameters
    ----------
    spec : SurfaceSpec
    seed : int
        Seed of the initial Gaussian white noise; same seed, same bits.
    max_iter : int
        Cap on the rounds.
    rtol : float
        Stagnation tolerance on the relative spectral error per round.

    Returns
    -------
    z : ndarray (ny, nx)
        Heights [m].
    info : ExactResult
    """
    if not spec.periodic:
        raise ValueError(
            "method='exact' generates periodic surfaces only; set periodic=True in the spec"
        )
    _check_memory(spec, 1, "exact", max_bytes)
    _check_domain(spec)
    heights = target_heights(spec) / spec.sigma
    target_amp = exact_target_amplitude(spec)
    kern = filter_kernel(spec)
    start = _apply_filter(spec, kern, _white_noise(spec, seed, spec.shape))
    z, info = _iaaft(spec.shape, heights, target_amp, start, int(max_iter), float(rtol))
    return z * spec.sigma, info


def _iaaft(shape, heights, target_amp, start, max_iter, rtol):
    """The IAAFT rounds of :func:`generate_exact` on unit-sigma arrays."""
    weights = _half_spectrum_weights(shape)
    norm = math.sqrt(float(np.sum(weights * target_amp**2)))

    def rank(values):
        order = np.argsort(values, axis=None)
        flat = np.empty(values.size)
        flat[order] = heights
        return flat.reshape(shape), order

    def error(spectrum):
        diff = np.abs(spectrum) - target_amp
        return math.sqrt(float(np.sum(weights * diff * diff))) / norm

    z, order = rank(start)
    spectrum = np.fft.rfft2(z)
    err = error(spectrum)
    best, best_err = z, err
    converged = False
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - iteration count is reported
        magnitude = np.abs(spectrum)
        phase = np.divide(spectrum, magnitude, out=np.ones_like(spectrum), where=magnitude > 0)
        z, new_order = rank(np.fft.irfft2(target_amp * phase, s=shape))
        spectrum = np.fft.rfft2(z)
        new_err = error(spectrum)
        if new_err < best_err:
            best, best_err = z, new_err
        if np.array_equal(new_order, order) or new_err > (1.0 - rtol) * err:
            converged = True
            break
        order, err = new_order, new_err
    return best, ExactResult(best_err, it, converged)


# --------------------------------------------------------------------------- statistics


def height_stats(z) -> dict:
    """Sample moments of heights (Eq 2-5), over the last two axes.

    Returns a dict of arrays (or floats for one surface): ``mean`` [m],
    ``sigma`` [m], ``skew``, ``kurt`` (Pearson), with 1/(NM) normalisation.
    """
    z = np.asarray(z, dtype=float)
    mean = z.mean(axis=(-2, -1))
    dev = z - mean[..., None, None]
    dev2 = dev * dev  # products, not float powers: 20 times faster
    m2 = np.mean(dev2, axis=(-2, -1))
    m3 = np.mean(dev2 * dev, axis=(-2, -1))
    m4 = np.mean(dev2 * dev2, axis=(-2, -1))
    with np.errstate(divide="ignore", invalid="ignore"):
        skew = np.where(m2 > 0, m3 / np.where(m2 > 0, m2, 1.0) ** 1.5, np.nan)
        kurt = np.where(m2 > 0, m4 / np.where(m2 > 0, m2, 1.0) ** 2, np.nan)
    out = {"mean": mean, "sigma": np.sqrt(m2), "skew": skew, "kurt": kurt}
    if z.ndim == 2:
        out = {k: float(v) for k, v in out.items()}
    return out


def autocorrelation_map(z, periodic: bool = True) -> np.ndarray:
    """Normalised sample ACF of a surface (ny, nx), FFT order, R[0, 0] = 1.

    Periodic: circular ACF. Otherwise the linear ACF from zero-padded FFTs,
    each lag divided by its number of overlapping pairs (unbiased).
    """
    z = np.asarray(z, float)
    z = z - z.mean()
    ny, nx = z.shape
    if periodic:
        f = np.fft.fft2(z)
        acf = np.fft.ifft2(f * np.conj(f)).real / z.size
    else:
        f = np.fft.fft2(z, s=(2 * ny, 2 * nx))
        acf = np.fft.ifft2(f * np.conj(f)).real
        ones = np.fft.fft2(np.ones_like(z), s=(2 * ny, 2 * nx))
        counts = np.rint(np.fft.ifft2(ones * np.conj(ones)).real)
        with np.errstate(divide="ignore", invalid="ignore"):
            acf = np.where(counts > 0, acf / counts, 0.0)
    return acf / acf[0, 0]


def _decay_lag(profile: np.ndarray, step: float, level: float) -> float:
    below = np.nonzero(profile <= level)[0]
    if below.size == 0:
        return math.nan
    k = int(below[0])
    r0, r1 = profile[k - 1], profile[k]
    return step * (k - 1 + (r0 - level) / (r0 - r1))


def correlation_length(z, spacing, periodic: bool = True, level: float = 0.1):
    """Lags (bx, by) [m] at which the sample ACF first decays to ``level`` (10 %).

    Linear interpolation between grid lags along each axis; NaN where the ACF
    does not decay to ``level`` within half the domain.
    """
    dx, dy = _pair(spacing, "spacing")
    acf = autocorrelation_map(z, periodic)
    ny, nx = np.shape(z)  # half the window, not of the zero-padded ACF's lags
    bx = _decay_lag(acf[0, : nx // 2 + 1], dx, level)
    by = _decay_lag(acf[: ny // 2 + 1, 0], dy, level)
    return bx, by
