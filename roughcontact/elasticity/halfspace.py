"""Influence coefficients of the elastic half-space.

Reference operators for the contact solver of :mod:`roughcontact.contact`:

- :func:`love_rectangle`: Love's (1929) closed form for the normal surface
  displacement due to a uniform pressure on a rectangle.
- :func:`halfspace_influence`: the dense influence matrix ``C`` of Eq 16 of
  Kumar et al. (2006) for the semi-infinite body, with piecewise-constant
  pressure on rectangular elements and displacements at the element centres.
- :class:`PeriodicHalfSpace`: the same discretization made periodic and applied
  by FFT, for large grids where a dense matrix does not fit.
- :class:`SpectralHalfSpace`: the periodic half-space with the spectral
  kernel ``2 / (E* |q|)`` sampled at grid points, the discrete problem of
  Tamaas, ContactMechanics and ASPHER, so that their results compare.

Both periodic operators apply in float32 or float64 with ``workers``
threads (:mod:`roughcontact.elasticity.transforms`) and offer what the
preconditioned CG needs
(:class:`roughcontact.elasticity.protocol.PreconditionedOperator`).

The paper computes ``C`` for a finite block by finite elements; the half-space
is the limit of a thick block and the standard check of the contact solver
(Hertz). All quantities are SI: lengths in metres, pressures and moduli in
pascals, compliances in m/Pa.

References
----------
A. E. H. Love, "The stress produced in a semi-infinite solid by pressure on
part of the boundary", Phil. Trans. R. Soc. A 228 (1929) 377-420.
K. L. Johnson, Contact Mechanics, Cambridge University Press (1985), Sec 3.2.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

from roughcontact.elasticity.protocol import GridOperator
from roughcontact.elasticity.transforms import CirculantConvolution, ColumnTable, q_stencil

__all__ = ["PeriodicHalfSpace", "SpectralHalfSpace", "halfspace_influence", "love_rectangle"]


def _check_material(E: float, nu: float) -> tuple[float, float]:
    """Validate Young's modulus ``E`` [Pa] and Poisson's ratio ``nu`` [-]."""
    E = float(E)
    nu = float(nu)
    if not np.isfinite(E) or E <= 0.0:
        raise ValueError(f"E must be a finite positive Young's modulus in Pa, got {E!r}")
    if not np.isfinite(nu) or not -1.0 < nu <= 0.5:
        raise ValueError(f"nu must be a Poisson's ratio in (-1, 0.5], got {nu!r}")
    return E, nu


def _check_grid(grid, size) -> tuple[int, int, float, float]:
    """Validate ``grid = (nx, ny)`` [-] and ``size = (Lx, Ly)`` [m]."""
    message = f"grid must be a pair of positive integers (nx, ny), got {grid!r}"
    try:
        nx, ny = (int(g) for g in grid)
        grid_ok = all(int(g) == g for g in grid)
    except (TypeError, ValueError):
        raise ValueError(message) from None
    if not grid_ok or nx < 1 or ny < 1:
        raise ValueError(message)
    try:
        lx, ly = (float(s) for s in size)
    except (TypeError, ValueError):
        raise ValueError(f"size must be a pair of lengths (Lx, Ly) in m, got {size!r}") from None
    if not (np.isfinite(lx) and np.isfinite(ly) and lx > 0.0 and ly > 0.0):
        raise ValueError(f"size must be a pair of finite positive lengths in m, got {size!r}")
    return nx, ny, lx, ly


def _corner_function(X, Y):
    """Double primitive of ``1/sqrt(X^2 + Y^2)`` [m].

    ``G(X, Y) = X asinh(Y/|X|) + Y asinh(X/|Y|)`` is odd in ``X`` and in ``Y``,
    zero on both axes, and ``d^2 G / dX dY = 1/sqrt(X^2 + Y^2)``; written with
    ``asinh`` it has no cancellation for any sign of the arguments.
    """
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    ax = np.abs(X)
    ay = np.abs(Y)
    # Where X == 0 the first term is 0 * finite = 0 (its limit); same for Y.
    first = X * np.arcsinh(Y / np.where(ax > 0.0, ax, 1.0))
    second = Y * np.arcsinh(X / np.where(ay > 0.0, ay, 1.0))
    return first + second


def love_rectangle(x, y, a: float, b: float, E: float, nu: float):
    """Normal surface displacement from unit pressure on a rectangle (Love 1929).

    The pressure ``p = 1 Pa`` acts on ``|x| <= a, |y| <= b`` of the surface of an
    elastic half-space. The displacement into the body at surface point (x, y) is

        u(x, y) = (1 - nu^2) / (pi E) * Int_rect dxi deta / sqrt((x-xi)^2 + (y-eta)^2)
                = (1 - nu^2) / (pi E) * [G(x+a, y+b) - G(x+a, y-b) - G(x-a, y+b) + G(x-a, y-b)]

    with ``G(X, Y) = X asinh(Y/|X|) + Y asinh(X/|Y|)`` (Johnson 1985, Eq 3.25).
    At the centre of a square of side 2a this is
    ``u = 8 (1 - nu^2) a ln(1 + sqrt 2) / (pi E)``; far away it tends to the
    Boussinesq point load ``(1 - nu^2) F / (pi E r)`` with ``F = 4 a b``.

    Parameters
    ----------
    x, y : array_like
        Surface coordinates [m] relative to the centre of the rectangle;
        broadcast against each other.
    a, b : float
        Half-widths of the rectangle along x and y [m], positive.
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].

    Returns
    -------
    ndarray
        Displacement per unit pressure [m/Pa], positive into the body, with the
        broadcast shape of ``x`` and ``y``.
    """
    E, nu = _check_material(E, nu)
    a = float(a)
    b = float(b)
    if not (np.isfinite(a) and np.isfinite(b) and a > 0.0 and b > 0.0):
        raise ValueError(f"a and b must be finite positive half-widths in m, got {a!r}, {b!r}")
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    integral = (
        _corner_function(x + a, y + b)
        - _corner_function(x + a, y - b)
        - _corner_function(x - a, y + b)
        + _corner_function(x - a, y - b)
    )
    return (1.0 - nu**2) / (np.pi * E) * integral


def _element_kernel(nx: int, ny: int, dx: float, dy: float, E: float, nu: float):
    """Love kernel ``K[jy, jx]`` [m/Pa] for element offsets ``jx = 0..nx-1, jy = 0..ny-1``.

    ``K[jy, jx]`` is the displacement at the centre of an element offset by
    (jx dx, jy dy) from a loaded element of size dx x dy. The corner function is
    evaluated once on the lattice of element corners and differenced, so each
    offset costs one corner evaluation.
    """
    xs = (np.arange(nx + 1) - 0.5) * dx
    ys = (np.arange(ny + 1) - 0.5) * dy
    g = _corner_function(xs[None, :], ys[:, None])
    k = g[1:, 1:] - g[:-1, 1:] - g[1:, :-1] + g[:-1, :-1]
    return (1.0 - nu**2) / (np.pi * E) * k


def halfspace_influence(grid, size, E: float, nu: float) -> np.ndarray:
    """Dense influence matrix of the elastic half-space (Eq 16, Love 1929).

    ``C[i, j]`` is the normal displacement at the centre of contact element
    ``i`` due to a unit uniform pressure on rectangular element ``j`` of a
    semi-infinite elastic body, so that ``u = C p`` (Eq 16 of Kumar et al.
    2006). The matrix is symmetric, positive definite, and block Toeplitz with
    Toeplitz blocks: the kernel is computed once for every element offset and
    then indexed.

    Parameters
    ----------
    grid : (int, int)
        Number of elements ``(nx, ny)``.
    size : (float, float)
        Nominal contact area ``(Lx, Ly)`` [m]; elements are ``dx = Lx/nx`` by
        ``dy = Ly/ny``.
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].

    Returns
    -------
    ndarray, shape (n, n), n = nx * ny
        Influence coefficients [m/Pa]. Elements are ordered row-major over y
        then x, flat index ``k = iy * nx + ix``, matching surface arrays of
        shape ``(ny, nx)`` flattened in C order.

    Notes
    -----
    Rows do not sum to a constant: the half-space has no bulk thickness, so
    Eq 38 (row sum L/E) of the finite block does not hold here.
    """
    E, nu = _check_material(E, nu)
    nx, ny, lx, ly = _check_grid(grid, size)
    kernel = _element_kernel(nx, ny, lx / nx, ly / ny, E, nu)
    ix = np.arange(nx)
    iy = np.arange(ny)
    offset_x = np.abs(ix[:, None] - ix[None, :])
    offset_y = np.abs(iy[:, None] - iy[None, :])
    blocks = kernel[offset_y[:, None, :, None], offset_x[None, :, None, :]]
    return blocks.reshape(nx * ny, nx * ny)


def _periodic_kernel(
    nx: int, ny: int, lx: float, ly: float, E: float, nu: float, images: int
) -> np.ndarray:
    """Periodically summed Love kernel [m/Pa] up to an additive constant.

    Sums the element kernel over the ``(2 images + 1)^2`` nearest periodic
    images and replaces the remaining (divergent) image sum by its continuum
    limit: the lattice of images beyond the block acts like a uniform pressure
    ``dA/(Lx Ly)`` outside the block, i.e. a constant minus Love's rectangle
    solution over the block. The constant is fixed later by the zero mode.
    Returns ``k[jy, jx]`` for periodic offsets ``jx = 0..nx-1``, ``jy = 0..ny-1``.
    """
    dx = lx / nx
    dy = ly / ny
    # Offsets in element units, the representative period [-n/2, n/2) first so
    # that the block of images is centred on the loaded element.
    jx0 = -(nx // 2)
    jy0 = -(ny // 2)
    span = 2 * images + 1
    xs = (jx0 - images * nx + np.arange(span * nx + 1) - 0.5) * dx
    c = (1.0 - nu**2) / (np.pi * E)
    folded = np.zeros((ny, nx))
    for my in range(-images, images + 1):
        ys = (jy0 + my * ny + np.arange(ny + 1) - 0.5) * dy
        g = _corner_function(xs[None, :], ys[:, None])
        k = g[1:, 1:] - g[:-1, 1:] - g[1:, :-1] + g[:-1, :-1]
        folded += c * k.reshape(ny, span, nx).sum(axis=1)
    rx = (jx0 + np.arange(nx)) * dx
    ry = (jy0 + np.arange(ny)) * dy
    block = love_rectangle(rx[None, :], ry[:, None], span * lx / 2, span * ly / 2, E, nu)
    folded -= dx * dy / (lx * ly) * block
    return np.roll(folded, (jy0, jx0), axis=(0, 1))


class _Circulant(GridOperator):
    """Members of the periodic (circulant) operators: ``grid``, ``size``, ``E``, ``nu``,
    ``workers``, and ``_product``, ``_columns`` from :meth:`_set_spectrum`."""

    #: A kernel column costs about 1/8 of a single-precision periodic product.
    column_budget = 8

    def _set_spectrum(self, spectrum: np.ndarray) -> None:
        """The product of ``spectrum`` [m/Pa] (both dtypes) and the kernel columns."""
        product = CirculantConvolution(spectrum, int(self.workers))
        object.__setattr__(self, "_product", product)
        object.__setattr__(self, "_columns", ColumnTable.periodic(product.kernel()))

    def _apply(self, fields: np.ndarray) -> np.ndarray:
        """Displacements [m] of pressure fields [Pa] of shape (m, ny, nx) (circulant ``C``),
        in their dtype (float32 or float64)."""
        return self._product(fields)

    def preconditioner(self):
        """The 13-tap stencil of ``E* |q| / 2`` (:func:`.transforms.q_stencil`), periodic."""
        nx, ny = self.grid
        spacing = (self.size[0] / nx, self.size[1] / ny)
        return q_stencil(spacing, self.E / (1.0 - self.nu**2), periodic=True)

    def coarsened(self):
        """The same periodic body on the grid coarser by 2 per side."""
        nx, ny = self.grid
        if nx % 2 or ny % 2:
            raise ValueError(f"grid {self.grid} cannot be halved")
        return dataclasses.replace(self, grid=(nx // 2, ny // 2))

    def nbytes(self) -> int:
        """Memory held by the operator [bytes]."""
        return int(self.spectrum.nbytes + self._product.nbytes() + self._columns.nbytes())


@dataclass(frozen=True)
class PeriodicHalfSpace(_Circulant):
    """Influence operator of the periodic elastic half-space, applied by FFT.

    Discretization as :func:`halfspace_influence` (uniform pressure on each
    rectangular element, displacement at element centres, Love 1929), made
    periodic with periods ``(Lx, Ly)``: ``u = C p`` with ``C`` circulant, so
    ``C p`` costs O(n log n) and no dense matrix is formed.

    Kernel: the *periodically summed Love kernel*. The nearest
    ``(2 images + 1)^2`` periodic images are summed exactly; the rest are
    replaced by their continuum limit (uniform pressure outside the image
    block); the error of that replacement is smooth and about 1e-5 of the
    peak kernel value for ``images = 3``, falling as ``images^-3``. So
    for a load patch much smaller than the period this operator equals the
    dense half-space matrix up to a constant and the (small, smooth)
    interaction with the periodic images. Unlike the spectral kernel
    ``2 / (E* |q|)`` sampled at grid points, this keeps the element-scale
    (diagonal) compliance of the dense matrix.

    Zero mode: on a periodic half-space uniform pressure produces unbounded
    displacement, so the mean displacement is a convention. Here the rows of
    ``C`` sum to ``mean_compliance`` [m/Pa]: a uniform pressure ``P`` gives
    ``u = mean_compliance * P`` (compare Eq 38 of Kumar et al. 2006, where
    the finite block gives ``L/E``). Consequences of the default
    ``mean_compliance = 0``: the mean of ``C p`` is always zero, so the rigid
    approach ``d`` is measured from the mean deflected plane (it is the
    asperity deflection ``d_a`` of Eq 45, and the mean-plane deflection of
    Eq 35 is identically zero); ``C`` is then only positive *semi*-definite
    (constant vectors are its null space): harmless for partial contact, but
    Eq 27 has a bounded solution only for approaches below the mean initial
    separation, ``d < mean(f)`` (the contact solver rejects larger ones).
    A positive ``mean_compliance`` removes that limit.

    Parameters
    ----------
    grid : (int, int)
        Number of elements ``(nx, ny)``.
    size : (float, float)
        Periods ``(Lx, Ly)`` [m].
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].
    mean_compliance : float, optional
        Row sum of ``C`` [m/Pa], the displacement per unit uniform pressure;
        non-negative, default 0.
    images : int, optional
        Image shells summed exactly, default 3 (kernel error about 1e-5 of
        its peak; construction cost grows as ``(2 images + 1)^2``, about 0.5 s
        for 512 x 512).
    workers : int, optional
        Threads of the FFTs, default 1.

    Attributes
    ----------
    shape : (int, int)
        ``(n, n)`` with ``n = nx * ny``.
    element_area : float
        ``dx * dy`` [m^2].
    spectrum : ndarray, shape (ny, nx // 2 + 1)
        Real eigenvalues of ``C`` [m/Pa] on the ``rfft2`` frequency grid.

    It is an :class:`roughcontact.elasticity.protocol.InfluenceOperator`
    (matrix-free: ``matrix`` is None).
    """

    grid: tuple[int, int]
    size: tuple[float, float]
    E: float
    nu: float
    mean_compliance: float = 0.0
    images: int = 3
    workers: int = 1
    spectrum: np.ndarray = field(init=False, repr=False, compare=False)
    _product: CirculantConvolution = field(init=False, repr=False, compare=False)
    _columns: ColumnTable = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        E, nu = _check_material(self.E, self.nu)
        nx, ny, lx, ly = _check_grid(self.grid, self.size)
        mean_compliance = float(self.mean_compliance)
        if not np.isfinite(mean_compliance) or mean_compliance < 0.0:
            raise ValueError(
                f"mean_compliance must be a finite non-negative m/Pa, got {self.mean_compliance!r}"
            )
        if int(self.images) != self.images or self.images < 0:
            raise ValueError(f"images must be a non-negative integer, got {self.images!r}")
        object.__setattr__(self, "grid", (nx, ny))
        object.__setattr__(self, "size", (lx, ly))
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "mean_compliance", mean_compliance)
        object.__setattr__(self, "images", int(self.images))
        kernel = _periodic_kernel(nx, ny, lx, ly, E, nu, int(self.images))
        kernel += mean_compliance / kernel.size - kernel.mean()
        spectrum = scipy.fft.rfft2(kernel).real
        spectrum.setflags(write=False)
        object.__setattr__(self, "spectrum", spectrum)
        self._set_spectrum(spectrum)

    def diagonal(self) -> np.ndarray:
        """Self-compliances ``C[i, i]`` [m/Pa], shape (n,), all equal."""
        nx, ny = self.grid
        c_ii = self.spectrum.sum() + self.spectrum[:, 1 : (nx + 1) // 2].sum()
        return np.full(nx * ny, c_ii / (nx * ny))



@dataclass(frozen=True)
class SpectralHalfSpace(_Circulant):
    """Periodic half-space with the spectral compliance ``2 / (E* |q|)`` [m/Pa], by FFT.

    Pressures and displacements are samples at the grid points of a periodic
    ``Lx x Ly`` cell; ``C`` is circulant with eigenvalues ``2 / (E* |q|)``
    (Johnson 1985, the half-space's response to a surface wave of
    wavenumber ``|q|``), ``E* = E / (1 - nu^2)``, and zero for the mean
    (``q = 0``): a uniform pressure produces no displacement, so the
    approach is measured from the mean deflected plane and Eq 27 has a
    bounded solution only for approaches below the mean initial separation
    (as :class:`PeriodicHalfSpace` with ``mean_compliance = 0``). This is
    the discrete problem of Tamaas (``basic_2d``), ContactMechanics
    (``PeriodicFFTElasticHalfSpace``) and ASPHER (``backend="periodic"``);
    unlike :class:`PeriodicHalfSpace` it does not integrate the pressure
    over the elements, so its self-compliance is softer by a few percent.

    Parameters
    ----------
    grid, size, E, nu, workers
        As :class:`PeriodicHalfSpace`: grid points ``(nx, ny)``, periods
        ``(Lx, Ly)`` [m], Young's modulus [Pa], Poisson's ratio [-], threads
        of the FFTs (default 1).

    Attributes
    ----------
    spectrum : ndarray, shape (ny, nx // 2 + 1)
        Eigenvalues ``2 / (E* |q|)`` [m/Pa] on the ``rfft2`` grid, 0 at ``q = 0``.

    It is an :class:`roughcontact.elasticity.protocol.InfluenceOperator`
    (matrix-free) and a
    :class:`roughcontact.elasticity.protocol.PreconditionedOperator`.

    References
    ----------
    K. L. Johnson, Contact Mechanics (1985), Sec 13.2; L. Frerot, G. Anciaux,
    V. Rey, S. Pham-Ba, J.-F. Molinari, J. Open Source Softw. 5 (2020) 2121.
    """

    grid: tuple[int, int]
    size: tuple[float, float]
    E: float
    nu: float
    workers: int = 1
    spectrum: np.ndarray = field(init=False, repr=False, compare=False)
    _product: CirculantConvolution = field(init=False, repr=False, compare=False)
    _columns: ColumnTable = field(init=False, repr=False, compare=False)
    mean_compliance = 0.0

    def __post_init__(self):
        E, nu = _check_material(self.E, self.nu)
        nx, ny, lx, ly = _check_grid(self.grid, self.size)
        object.__setattr__(self, "grid", (nx, ny))
        object.__setattr__(self, "size", (lx, ly))
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)
        qx = 2.0 * np.pi * np.fft.rfftfreq(nx, lx / nx)
        qy = 2.0 * np.pi * np.fft.fftfreq(ny, ly / ny)
        q = np.hypot(qx[None, :], qy[:, None])
        q[0, 0] = np.inf  # zero mode: no mean displacement
        spectrum = 2.0 * (1.0 - nu**2) / (E * q)
        spectrum.setflags(write=False)
        object.__setattr__(self, "spectrum", spectrum)
        self._set_spectrum(spectrum)

    def diagonal(self) -> np.ndarray:
        """Self-compliances ``C[i, i]`` [m/Pa] (the mean eigenvalue), shape (n,), all equal."""
        nx, ny = self.grid
        return np.full(nx * ny, float(self._product.kernel()[0, 0]))
