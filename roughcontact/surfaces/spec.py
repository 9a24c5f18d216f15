"""What to generate: the specification of a family of random rough surfaces.

:class:`SurfaceSpec` holds the grid, the size, the height moments (sigma, Sk,
Ku: Eq 2-5 of Kumar, Sadeghi & Krousgrill 2006) and the spectrum of the
surfaces: the autocorrelation function of Eq 1 (``acf="exponential"`` or
``"gaussian"``), a self-affine power spectrum or a tabulated one (checked by
:func:`check_psd_table`). The spectra themselves and the filter built from
them are in :mod:`roughcontact.surfaces.spectra`; the generators in
:mod:`roughcontact.surfaces.synthetic`.

All lengths are in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ACF_KINDS = ("exponential", "gaussian", "self-affine", "psd")
"""Spectrum kinds of :class:`SurfaceSpec`: two ACFs (Eq 1), a self-affine PSD and a
tabulated isotropic PSD."""

GENERATION_METHODS = ("filter", "paper", "exact")
"""Generators of :func:`roughcontact.surfaces.synthetic.generate_many`: the calibrated
filter (default), the paper's uncorrected filter, and iterative amplitude adjustment."""


def check_method(method: str) -> None:
    """Raise ValueError unless ``method`` is one of :data:`GENERATION_METHODS`."""
    if method not in GENERATION_METHODS:
        raise ValueError(f"method must be one of {GENERATION_METHODS}; got {method!r}")


def as_pair(value, name: str) -> tuple:
    """``(value, value)`` for a number, else ``value`` as a 2-tuple (ValueError naming ``name``)."""
    if np.ndim(value) == 0:
        return (value, value)
    value = tuple(value)
    if len(value) != 2:
        raise ValueError(f"{name} must be a number or a pair (x, y); got {value!r}")
    return value


_SELF_AFFINE_FIELDS = ("hurst", "rolloff_wavelength", "cutoff_wavelength")
#: The fields of each spectrum kind defined by its PSD (None for every other kind).
_SPECTRUM_FIELDS = {"self-affine": _SELF_AFFINE_FIELDS, "psd": ("psd",)}
#: Relative tolerance of "above the largest wavenumber" (cut-offs, table ends).
Q_RTOL = 1e-12


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
        power spectral density of :func:`spectra.self_affine_psd` (constant below the
        roll-off wavenumber, ``q^(-2(1+H))`` up to the cut-off, zero above),
        set by ``hurst``, ``rolloff_wavelength`` and ``cutoff_wavelength``;
        or ``"psd"``: the isotropic PSD tabulated in ``psd``
        (:func:`spectra.tabulated_psd`).
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

    Notes
    -----
    For ``"self-affine"`` and ``"psd"``, ``corr_length`` may be left out
    (None): it is then set along both axes to the longest wavelength of the
    spectrum's band, beyond which the PSD is flat and heights decorrelate: the
    roll-off wavelength, or ``2 pi / q_1`` of the table's first row. It enters
    only the domain checks and messages.

    Gaussian surfaces. ``skew=0, kurt=3`` with ``method="paper"`` gives a
    Gaussian process: the Johnson law of the white noise at (0, 3) is the
    normal one, and the surface is a linear filter of Gaussian noise, with
    the PSD of the spec (for any spectrum kind, with or without roll-off).
    Its windows' sample kurtosis then scatters about a value below 3, as a
    Gaussian window's does: 2.6 on average when the spectrum has no roll-off
    (``rolloff_wavelength`` at the surface's size; a few long wavelengths
    carry most of the variance), 2.99 with a roll-off at L / 8. The default
    ``method="filter"`` calibrates that *sample* kurtosis to 3 instead: it
    feeds the filter non-Gaussian noise, so its surfaces are not a Gaussian
    process. Without a roll-off the departure is large: on 128 x 128 (H 0.8,
    cut-off at 8 spacings) the process kurtosis is 4.7 (white noise of
    kurtosis 1300), the heights of 1000 surfaces pooled have kurtosis 3.5,
    and a surface's sample kurtosis scatters with standard deviation 1.06
    against 0.40 for the Gaussian process. With a roll-off at L / 8 the
    process kurtosis is 3.012, close to Gaussian. ``method="exact"`` gives
    every surface a sample kurtosis of exactly 3: not a Gaussian process
    either.
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
        grid = as_pair(self.grid, "grid")
        size = as_pair(self.size, "size")
        if self.acf not in ACF_KINDS:
            raise ValueError(f"SurfaceSpec.acf must be one of {ACF_KINDS}; got {self.acf!r}")
        for kind, names in _SPECTRUM_FIELDS.items():
            for name in names:
                if self.acf != kind and getattr(self, name) is not None:
                    raise ValueError(
                        f"SurfaceSpec.{name} applies to acf={kind!r} only; got "
                        f"{name}={_short(getattr(self, name))} with acf={self.acf!r}"
                    )
        check_spectrum = _SPECTRUM_CHECKS.get(self.acf)
        band = None if check_spectrum is None else check_spectrum(self, grid, size)
        if self.corr_length is None:
            if band is None:
                raise ValueError(f"SurfaceSpec.corr_length [m] is required for acf={self.acf!r}")
            object.__setattr__(self, "corr_length", band)
        corr = as_pair(self.corr_length, "corr_length")
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

    def _check_self_affine(self, grid, size) -> float:
        """Check the self-affine fields; returns the roll-off wavelength [m]."""
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
        return self.rolloff_wavelength

    def _check_psd(self, grid, size) -> float:
        """Check the PSD table; returns the longest wavelength of its band, 2 pi / q_1 [m]."""
        table = check_psd_table(self.psd, "SurfaceSpec.psd")
        if not self.periodic:
            raise ValueError("acf='psd' generates periodic surfaces only; set periodic=True")
        q_top = max(q for q, c in table if c > 0)
        q_lowest = 2.0 * math.pi / max(float(v) for v in size)
        if q_top < q_lowest * (1.0 - Q_RTOL):
            raise ValueError(
                f"SurfaceSpec.psd has power only up to q = {q_top:.4g} 1/m (wavelength "
                f"{2 * math.pi / q_top:.4g} m), below the smallest non-zero wavenumber of the "
                f"surface, 2 pi / L = {q_lowest:.4g} 1/m: the surface would be flat. Enlarge "
                "the surface to more than the longest wavelength with power, or check the "
                "unit of q (1/m, q = 2 pi / wavelength)."
            )
        object.__setattr__(self, "psd", table)
        return 2.0 * math.pi / self.psd[0][0]

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


#: The checks of each spectrum kind defined by its PSD: ``(spec, grid, size)`` -> the
#: default correlation length [m] (the longest wavelength of the band).
_SPECTRUM_CHECKS = {"self-affine": SurfaceSpec._check_self_affine, "psd": SurfaceSpec._check_psd}


def mm_text(pair) -> str:
    """A pair of lengths [m] as text in millimetres, ``"9 x 9"``, for messages."""
    return " x ".join(f"{1e3 * v:g}" for v in pair)


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


