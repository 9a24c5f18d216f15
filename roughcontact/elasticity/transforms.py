"""The FFT products of the grid operators, at the cost they must have.

Two convolutions of element pressures ``p`` [Pa] on an ``nx x ny`` grid
with an influence kernel [m/Pa], shared by the matrix-free operators of
:mod:`roughcontact.elasticity.halfspace` and
:mod:`roughcontact.elasticity.operators`:

- :class:`PaddedConvolution`, the *free-space* (linear) convolution with a
  kernel that is even in both offsets (Love's elements on a half-space):
  a circular convolution on the zero-padded ``2 ny x 2 nx`` grid. Three
  quarters of the padded input are zero, so the product is *pruned*: the
  real-to-complex pass along x runs on the ``ny`` loaded rows only
  (``scipy.fft.rfft(..., n=2 nx)`` pads each row), the complex pass along y
  on the ``nx + 1`` columns of length ``2 ny``, and the inverse keeps the
  first ``ny`` rows before its complex-to-real pass. The kernel's spectrum
  is real (even kernel) and stored transposed, in the layout of the column
  pass.
- :class:`CirculantConvolution`, the *periodic* convolution: ``rfft2``,
  product with the real spectrum, ``irfft2``.

Both apply in the dtype of the pressure, ``float32`` or ``float64`` (a
spectrum of each dtype is precomputed), so a single-precision product never
touches a double-precision array; ``workers`` threads run every
``scipy.fft`` call. Single-precision products round to about 1e-7 of the
displacement change they produce; the contact solvers take them for search
directions only and decide convergence on double-precision products.

Two aids of the preconditioned CG (:mod:`roughcontact.contact.pcg`) live
here too: :func:`q_stencil`, the 13-tap real-space stencil of the
half-space's inverse symbol ``E* |q| / 2``, and :class:`ColumnTable`, the
kernel laid out so that the displacement of a few changed elements is a sum
of shifted slices (cheaper than a product for a handful of elements).

All quantities are SI: lengths in m, pressures and moduli in Pa,
compliances in m/Pa.

References
----------
A. E. H. Love, Phil. Trans. R. Soc. A 228 (1929) 377-420.
V. A. Yastrebov, ASPHER 0.1.3 (2025): the stencil preconditioner.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

__all__ = [
    "CHUNK_BYTES",
    "DTYPES",
    "STENCIL_GRID",
    "STENCIL_RADIUS",
    "CirculantConvolution",
    "ColumnTable",
    "PaddedConvolution",
    "Stencil",
    "product_dtype",
    "q_stencil",
]

#: Dtypes a product can be taken in.
DTYPES = (np.dtype(np.float32), np.dtype(np.float64))
#: Radius (elements) of the stencil preconditioner: 13 taps, ``jx^2 + jy^2 <= 4``.
STENCIL_RADIUS = 2
#: Side of the periodic grid on which the stencil's |q| kernel is sampled.
STENCIL_GRID = 64
#: Bytes of the padded spectra a batched free-space product transforms at a time
#: (three 256^2 fields in float32, one in float64: measured best on this 2-core machine).
CHUNK_BYTES = 2**22


def product_dtype(pressure: np.ndarray) -> np.ndarray:
    """``pressure`` as float32 or float64 (anything else as float64)."""
    p = np.asarray(pressure)
    return p if p.dtype in DTYPES else p.astype(np.float64)


class _Spectra:
    """A real spectrum kept in both dtypes (``spectra``), with ``workers`` threads."""

    def _keep(self, spectrum: np.ndarray) -> None:
        object.__setattr__(self, "spectra", {t: spectrum.astype(t) for t in DTYPES})

    def nbytes(self) -> int:
        """Memory of the spectra [bytes]."""
        return int(sum(s.nbytes for s in self.spectra.values()))


@dataclass(frozen=True)
class PaddedConvolution(_Spectra):
    """Linear convolution of ``(..., ny, nx)`` fields with an even kernel, pruned.

    Parameters
    ----------
    kernel : ndarray (ny, nx)
        ``K[jy, jx]`` [m/Pa] for non-negative element offsets; the kernel of
        offset ``(-jx, -jy)`` is the same (even in both offsets).
    workers : int
        Threads of every ``scipy.fft`` call.
    """

    kernel: np.ndarray = field(repr=False)
    workers: int = 1
    spectra: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        kernel = np.asarray(self.kernel, dtype=float)
        ny, nx = kernel.shape
        full = np.zeros((2 * ny, 2 * nx))
        full[:ny, :nx] = kernel
        full[:ny, nx + 1:] = kernel[:, 1:][:, ::-1]  # offsets -(nx-1) .. -1
        full[ny + 1:, :] = full[1:ny, :][::-1]  # offsets -(ny-1) .. -1
        self._keep(np.ascontiguousarray(scipy.fft.rfft2(full).real.T))  # (nx+1, 2ny)

    def __call__(self, fields: np.ndarray) -> np.ndarray:
        """``K * p`` [m] of fields ``(..., ny, nx)`` [Pa], in their dtype.

        A batch of fields ``(m, ny, nx)`` is transformed a few fields at a
        time, whose padded spectra fill about :data:`CHUNK_BYTES` (measured
        10-15 % faster than the whole batch at once, which leaves the cache).
        """
        fields = product_dtype(fields)
        ny, nx = fields.shape[-2:]
        chunk = max(1, CHUNK_BYTES // ((nx + 1) * 2 * ny * 2 * fields.itemsize))
        if fields.ndim != 3 or fields.shape[0] <= chunk:
            return self._convolve(fields)
        out = np.empty(fields.shape, dtype=fields.dtype)
        for start in range(0, fields.shape[0], chunk):
            out[start:start + chunk] = self._convolve(fields[start:start + chunk])
        return out

    def _convolve(self, fields: np.ndarray) -> np.ndarray:
        """:meth:`__call__` in one pass (a view)."""
        ny, nx = fields.shape[-2:]
        w = self.workers
        rows = scipy.fft.rfft(fields, n=2 * nx, axis=-1, workers=w)  # (..., ny, nx+1)
        cols = scipy.fft.fft(np.swapaxes(rows, -1, -2), n=2 * ny, axis=-1, workers=w)
        del rows
        cols *= self.spectra[fields.dtype]
        cols = scipy.fft.ifft(cols, axis=-1, overwrite_x=True, workers=w)
        out = scipy.fft.irfft(np.swapaxes(cols[..., :ny], -1, -2), n=2 * nx, axis=-1,
                              workers=w)
        return out[..., :nx]


@dataclass(frozen=True)
class CirculantConvolution(_Spectra):
    """Periodic convolution of ``(..., ny, nx)`` fields given the kernel's real spectrum.

    Parameters
    ----------
    spectrum : ndarray (ny, nx // 2 + 1)
        Eigenvalues [m/Pa] on the ``rfft2`` grid (real: the kernel is even);
        ``workers`` as :class:`PaddedConvolution`.
    """

    spectrum: np.ndarray = field(repr=False)
    workers: int = 1
    spectra: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        self._keep(np.asarray(self.spectrum, dtype=float))

    def __call__(self, fields: np.ndarray) -> np.ndarray:
        """``K * p`` [m] of fields ``(..., ny, nx)`` [Pa], in their dtype."""
        fields = product_dtype(fields)
        w = self.workers
        spectrum = scipy.fft.rfft2(fields, workers=w)
        spectrum *= self.spectra[fields.dtype]
        return scipy.fft.irfft2(spectrum, s=fields.shape[-2:], overwrite_x=True, workers=w)

    def kernel(self) -> np.ndarray:
        """The kernel ``k[jy, jx]`` [m/Pa] for periodic offsets (float64)."""
        ny = self.spectrum.shape[0]
        nx = 2 * (self.spectrum.shape[1] - 1)
        return scipy.fft.irfft2(self.spectra[DTYPES[1]], s=(ny, nx))


@dataclass(frozen=True)
class ColumnTable:
    """The influence of every element offset, for sums of a few columns of ``C``.

    ``table[iy - jy + ny - 1, ix - jx + nx - 1]`` [m/Pa] is the displacement
    at element ``(iy, ix)`` under unit pressure on element ``(jy, jx)``;
    stored in float32 (it serves the single-precision corrections of the
    preconditioned CG), ``(2 ny - 1) x (2 nx - 1)``.
    """

    table: np.ndarray = field(repr=False)

    @classmethod
    def even(cls, kernel: np.ndarray) -> ColumnTable:
        """From a free-space kernel ``K[|jy|, |jx|]`` (ny, nx) [m/Pa], even in both offsets."""
        ny, nx = kernel.shape
        iy = np.abs(np.arange(1 - ny, ny))
        ix = np.abs(np.arange(1 - nx, nx))
        return cls(np.ascontiguousarray(kernel[iy[:, None], ix[None, :]], dtype=np.float32))

    @classmethod
    def periodic(cls, kernel: np.ndarray) -> ColumnTable:
        """From a periodic kernel ``k[jy mod ny, jx mod nx]`` (ny, nx) [m/Pa]."""
        ny, nx = kernel.shape
        iy = np.arange(1 - ny, ny) % ny
        ix = np.arange(1 - nx, nx) % nx
        return cls(np.ascontiguousarray(kernel[iy[:, None], ix[None, :]], dtype=np.float32))

    def add(self, target: np.ndarray, rows, cols, values) -> None:
        """``target += C e`` [m] for ``e[rows, cols] = values`` [Pa], in place, O(k n)."""
        ny, nx = target.shape
        table = self.table
        for jy, jx, value in zip(np.asarray(rows).tolist(), np.asarray(cols).tolist(),
                                 np.asarray(values).tolist(), strict=True):
            target += value * table[ny - 1 - jy: 2 * ny - 1 - jy, nx - 1 - jx: 2 * nx - 1 - jx]

    def nbytes(self) -> int:
        """Memory of the table [bytes]."""
        return int(self.table.nbytes)


@dataclass(frozen=True)
class Stencil:
    """A real-space stencil on the element grid: ``z_i = sum_k w_k r_{i + o_k}``.

    ``offsets`` (k, 2) holds ``(jy, jx)``, ``weights`` (k,) the taps
    [Pa/m]; ``periodic`` says whether the grid wraps around (else values
    beyond it are zero).
    """

    offsets: np.ndarray
    weights: np.ndarray
    periodic: bool


def q_stencil(spacing, modulus: float, periodic: bool) -> Stencil:
    """The 13-tap stencil of ``E* |q| / 2`` [Pa/m], the inverse of the half-space symbol.

    The real-space kernel of ``E* |q| / 2`` on a periodic
    :data:`STENCIL_GRID` x :data:`STENCIL_GRID` grid of the element
    ``spacing = (dx, dy)`` [m], cut to the offsets with ``jx^2 + jy^2 <=
    STENCIL_RADIUS^2`` (ASPHER's StencilPreconditioner): a cheap
    approximate inverse of the half-space compliance ``2 / (E* |q|)``, the
    preconditioner of :mod:`roughcontact.contact.pcg`.

    Parameters
    ----------
    spacing : (float, float)
        Element sizes ``(dx, dy)`` [m].
    modulus : float
        Plane-strain modulus ``E*`` [Pa] (only scales the taps).
    periodic : bool
        Whether the operator it preconditions is periodic.
    """
    m = STENCIL_GRID
    dx, dy = (float(s) for s in spacing)
    qx = 2.0 * np.pi * np.fft.rfftfreq(m, dx)
    qy = 2.0 * np.pi * np.fft.fftfreq(m, dy)
    symbol = 0.5 * float(modulus) * np.hypot(qx[None, :], qy[:, None])
    kernel = np.fft.irfft2(symbol, s=(m, m))
    r = STENCIL_RADIUS
    offsets = np.array([(jy, jx) for jy in range(-r, r + 1) for jx in range(-r, r + 1)
                        if jx * jx + jy * jy <= r * r])
    weights = kernel[offsets[:, 0] % m, offsets[:, 1] % m]
    return Stencil(offsets, weights, bool(periodic))
