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
    E, nu : float
        Young's modulus [Pa] and Poisson's ratio [-] of the body.

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


#: Image columns whose nearest point lies farther than this many short periods
#: (or images + 1/2, if more) from an element, measured along the long period,
#: are summed along the short period as strips (:func:`_strip_column`).
_STRIP_DISTANCE = 4.0


def _short_images(images: int, long_period: float, short_period: float) -> int:
    """Image shells along the short period so that the block reaches (images + 1/2) long periods.

    The smallest ``m`` with ``(m + 1/2) short_period >= (images + 1/2) long_period``;
    ``images`` itself on a square cell.
    """
    reach = (images + 0.5) * long_period / short_period - 0.5
    return max(images, int(np.ceil(reach - 1e-9)))


def _strip_column(x, y, dx: float, dy: float, ly: float, half_height: float, E: float,
                  nu: float):
    """Image rows ``|m| <= M`` of the element kernel summed as a strip [m/Pa].

    Approximates ``sum_m K(x, y + m Ly)``, ``K`` the kernel of an element
    ``dx`` by ``dy`` (:func:`_element_kernel`) and ``B = (M + 1/2) Ly =
    half_height``, by the rows smeared along y,
    ``(dy / Ly) love_rectangle(x, y, dx/2, B)``, plus the Euler-Maclaurin end
    terms of the midpoint sum and of the element's extent, in point-load form
    ``f(t) = (1 - nu^2) dx dy / (pi E sqrt(x^2 + t^2))``:

        a1 [f1(y + B) - f1(y - B)] + a3 [f3(y + B) - f3(y - B)],
        a1 = -(Ly - dy^2/Ly) / 24,  a3 = 7 Ly^3/5760 - Ly dy^2/576 + dy^4/(1920 Ly),

    ``f1`` the first derivative in t averaged over the element's width
    (``f' + dx^2/24 d^2 f'/dx^2``), ``f3`` the third derivative. The smear
    misses the lattice by about ``4 K0(2 pi (|x| - dx/2) / Ly)`` of the
    strip (Poisson summation, ``K0`` the modified Bessel function; below
    1e-11 at 4 Ly); with the end terms a column ``4 Ly`` away is met to
    6e-8 of the peak kernel value for ``M = 4`` and 1e-11 for ``M >= 10``
    (measured). Both end terms vanish for ``dy = Ly``, where the elements
    tile the strip.
    """
    c = (1.0 - nu**2) / (np.pi * E) * dx * dy
    a1 = -(ly - dy**2 / ly) / 24.0
    a3 = 7.0 * ly**3 / 5760.0 - ly * dy**2 / 576.0 + dy**4 / (1920.0 * ly)

    def end_terms(t):
        r2 = x**2 + t**2
        r7 = r2**3.5
        f1 = -t / r2**1.5 - dx**2 / 24.0 * t * (12.0 * x**2 - 3.0 * t**2) / r7
        f3 = 3.0 * t * (3.0 * x**2 - 2.0 * t**2) / r7
        return a1 * f1 + a3 * f3

    strip = dy / ly * love_rectangle(x, y, dx / 2, half_height, E, nu)
    return strip + c * (end_terms(y + half_height) - end_terms(y - half_height))


#: Corner values evaluated at once when image rows are batched [-] (8 MB each).
_CORNER_BUDGET = 2**20


def _add_folded(folded: np.ndarray, values: np.ndarray, start: int, scale: float) -> None:
    """Add ``scale`` times the columns of ``values`` (ny, m), folded periodically, to
    ``folded`` (ny, n) in place, column 0 of ``values`` landing on column
    ``start`` (0 <= start < n)."""
    n = folded.shape[-1]
    width = values.shape[-1]
    if width <= n:  # each column receives at most one value: two slices
        head = min(width, n - start)
        folded[:, start : start + head] += scale * values[:, :head]
        folded[:, : width - head] += scale * values[:, head:]
        return
    periods = -(-(start + width) // n)
    if start or periods * n != width:
        padded = np.zeros((values.shape[0], periods * n))
        padded[:, start : start + width] = values
        values = padded
    folded += scale * values.reshape(values.shape[0], periods, n).sum(axis=1)


def _add_image_rows(folded: np.ndarray, xs: np.ndarray, start: int, images_y: int, jy0: int,
                    dy: float, c: float) -> None:
    """Add the near image columns' element kernels, image row by image row, to
    ``folded`` (ny, nx) in place: the corner function at the columns' corners ``xs``
    [m] and the rows ``|m| <= images_y`` (offset ``jy0`` elements of ``dy`` [m]),
    times ``c`` = (1 - nu^2) / (pi E), folded from column ``start``. Rows in batches
    of at most :data:`_CORNER_BUDGET` corners (at least one row), added in order."""
    ny = folded.shape[0]
    width = xs.size - 1
    batch = max(1, _CORNER_BUDGET // ((ny + 1) * (width + 1)))
    rows = np.arange(-images_y, images_y + 1)
    for first_row in range(0, rows.size, batch):
        my = rows[first_row : first_row + batch, None, None]
        ys = (jy0 + my * ny + np.arange(ny + 1)[None, :, None] - 0.5) * dy
        g = _corner_function(xs[None, None, :], ys)
        k = g[:, 1:, 1:] - g[:, :-1, 1:] - g[:, 1:, :-1] + g[:, :-1, :-1]
        for row in k:
            _add_folded(folded, row, start, c)


def _periodic_kernel(
    nx: int, ny: int, lx: float, ly: float, E: float, nu: float, images: int
) -> np.ndarray:
    """Periodically summed Love kernel [m/Pa] up to an additive constant.

    Returns ``k[jy, jx]`` for periodic offsets ``jx = 0..nx-1``, ``jy = 0..ny-1``:
    the element kernel summed over a block of periodic images, the images
    beyond it replaced by their continuum limit. With x the longer period
    (a cell with ``Ly > Lx`` is computed transposed):

    - the block has ``2 images + 1`` images along x and ``2 m + 1`` along y,
      ``m`` (:func:`_short_images`) the smallest with
      ``(m + 1/2) Ly >= (images + 1/2) Lx``, so that it reaches at least
      ``(images + 1/2) Lx`` in both directions (``m = images`` on a square
      cell). With the same count along y, a block only ``(images + 1/2) Ly``
      high, the lattice just beyond it is rows ``Lx`` apart seen from less
      than ``Lx``: nothing like the uniform smear below (so counted, the
      lowest mode of a 2048 x 4 cell, aspect 512, came out at 0.12 of its
      compliance);
    - in the block, an image column (the images at one x offset ``X``)
      whose nearest point is ``|X| - dx/2 >= max(4, images + 1/2) Ly`` away
      is summed along y as a strip (:func:`_strip_column`: the rows smeared
      along y plus the end terms that make the smear equal the row-by-row
      sum, to 1e-11 of the peak kernel value for ``M >= 10`` rows); the
      other columns are summed image by image. On a square cell no column
      is that far, so its kernel is the image-by-image sum over
      ``(2 images + 1)^2`` images;
    - beyond the block the lattice of images acts like a uniform pressure
      ``dA/(Lx Ly)`` outside it: a constant minus Love's rectangle solution
      over the block. The constant is fixed later by the zero mode.
    """
    if ly > lx:
        return np.ascontiguousarray(_periodic_kernel(ny, nx, ly, lx, E, nu, images).T)
    dx = lx / nx
    dy = ly / ny
    images_y = _short_images(images, lx, ly)
    # Offsets in element units, the representative period [-n/2, n/2) first so
    # that the block of images is centred on the loaded element.
    jx0 = -(nx // 2)
    jy0 = -(ny // 2)
    span_x = 2 * images + 1
    span_y = 2 * images_y + 1
    offsets = jx0 - images * nx + np.arange(span_x * nx)
    strip_distance = max(_STRIP_DISTANCE, images + 0.5) * ly
    near = np.abs(offsets) * dx - dx / 2 < strip_distance
    first, last = np.flatnonzero(near)[[0, -1]]  # near columns: contiguous around 0
    lo = int(offsets[first])
    width = int(last - first + 1)
    start = (lo - jx0) % nx
    xs = (lo + np.arange(width + 1) - 0.5) * dx
    folded = np.zeros((ny, nx))
    _add_image_rows(folded, xs, start, images_y, jy0, dy, (1.0 - nu**2) / (np.pi * E))
    rx = (jx0 + np.arange(nx)) * dx
    ry = (jy0 + np.arange(ny)) * dy
    half_height = span_y * ly / 2
    for piece in (slice(0, first), slice(last + 1, None)):
        far = offsets[piece]
        if far.size:
            strip = _strip_column(far[None, :] * dx, ry[:, None], dx, dy, ly, half_height, E, nu)
            _add_folded(folded, strip, int(far[0] - jx0) % nx, 1.0)
    block = love_rectangle(rx[None, :], ry[:, None], span_x * lx / 2, half_height, E, nu)
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

    Kernel: the *periodically summed Love kernel*. The periodic images in a
    block reaching at least ``(images + 1/2) max(Lx, Ly)`` from the loaded
    element in both directions are summed exactly: ``2 images + 1`` images
    along the longer period and, along the shorter one, as many as reach
    as far (the same count on a square cell); image columns farther than
    ``max(4, images + 1/2)`` short periods along the long one are summed
    along the short period as continuous strips (Poisson summation, error
    below 1e-11 of the strip). The images beyond the block are replaced by
    their continuum limit (uniform pressure outside the block). So for a
    load patch much smaller than the period this operator equals the dense
    half-space matrix up to a constant and the (small, smooth) interaction
    with the periodic images. Unlike the spectral kernel ``2 / (E* |q|)``
    sampled at grid points, this keeps the element-scale (diagonal)
    compliance of the dense matrix.

    Accuracy (measured, ``images = 3``): for element-constant pressure
    ``p_j = cos(q x_j)``, uniform in y, ``q = 2 pi / Lx``, the exact periodic
    operator gives displacement ``lambda p_j`` with

        lambda E* q / 2 = R(theta)
                        = theta sin(theta) sum_m (-1)^m / ((theta + pi m) |theta + pi m|),

    ``theta = q dx / 2``, ``R = 1 - theta^2/6 + O(theta^3)`` (the aliases
    ``q + 2 pi m / dx`` of the element-constant field, each with amplitude
    ``sin(theta + pi m) / (theta + pi m)`` and the half-space compliance
    ``2 / (E* |q + 2 pi m / dx|)``); the same along y with ``dy``. This
    operator's ``lambda`` along the longer period is below ``R`` by 1.72e-4
    on a square cell and by 1.8e-4 to 2.24e-4 on cells of aspect 1.05 to
    4096 (either orientation, element aspects 1/4 to 4), along the shorter
    period by less (below 1e-5 from aspect 1.6 on). The kernel error is
    smooth, about 1e-5 of the peak kernel value on a square cell and up to
    5e-5 on elongated cells with a few elements across the short period.
    Both fall about as ``images^-2.7`` (the square cell's lowest mode:
    2.1e-3, 4.5e-5, 1.2e-5 for ``images = 1, 5, 8``).

    Cost: the construction evaluates ``(2 images + 1)^2 n`` corner values
    on a square cell, ``n = nx ny``, and about
    ``2 max(4, images + 1/2) (2 images + 1) n`` on an elongated one (at
    most 63 n for ``images = 3``, whatever the aspect), in batches of image
    rows of at most 2^20 values (or one row, ``(ny + 1)`` by up to
    ``(2 images + 1) nx + 1``, as before). Measured on 2 shared cores:
    0.1 s for 2048 x 4 (aspect 512), 0.02 s for 1024 x 4, 0.01 s for
    512 x 8, 0.06 s for 512 x 64, 0.3-0.5 s for 512 x 512, 1.5-2.5 s for
    1024 x 1024 and 0.4 s for 16384 x 4 (aspect 4096).

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
        Image shells summed exactly along the longer period, default 3; along
        the shorter period the count is scaled up to reach as far, ``m``
        the smallest with ``(m + 1/2) L_short >= (images + 1/2) L_long``
        (accuracy and cost above).
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
