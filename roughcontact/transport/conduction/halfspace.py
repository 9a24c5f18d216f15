"""Thermal influence of a half-space's contact face: dense, periodic (FFT) and free (FFT).

A flux density ``q`` [W/m^2] into a half-space of conductivity ``k`` [W/(m K)]
at a surface point raises the surface temperature at distance ``r`` by

    T(r) = q dA / (2 pi k r)

(the point source on an insulated half-space, Carslaw & Jaeger 1959, Sec 10.2).
The elastic half-space's surface compliance is ``(1 - nu^2) / (pi E r) = 2 /
(2 pi E* r)``: the same ``1/r``, so a thermal half-space of conductivity ``k``
is Love's elastic one with ``E* = 2 k``. That is the discrete ground of Barber's
(2003) analogy: on the same contact set the spot conductance is ``2 k / E*``
times the tangent stiffness.

- :func:`halfspace_thermal_influence`: the dense ``R[i, j]`` [K m^2/W], the
  temperature at the centre of element ``i`` per unit flux density uniform on
  rectangular element ``j`` (the element integral of the kernel, as the elastic
  :func:`~roughcontact.elasticity.halfspace.halfspace_influence`, here in its
  logarithmic form on the element's quarter-planes).
- :func:`periodic_thermal_halfspace`: the same discretization periodic, by FFT:
  :class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace` with ``E = 2 k``,
  ``nu = 0`` (its preconditioner, ``E* |q| / 2 = k |q|``, is the thermal symbol).
  A uniform flux raises a periodic half-space's temperature without bound, so
  its mean is a convention (``mean_compliance``, default 0): the conductance of
  partial contact is then the constriction alone, measured from the mean plane.
- :func:`free_thermal_halfspace`: the non-periodic half-space applied by a
  zero-padded FFT (:func:`~roughcontact.elasticity.operators.halfspace_operator`,
  ``1 / (pi r)`` per unit modulus at ``nu = 0``, times ``1 / (2 k)``).

All three take the electrical conductivity ``1 / rho_e`` [S/m] in place of ``k``
for the electrical influence [Ohm m^2].

References
----------
H. S. Carslaw and J. C. Jaeger, Conduction of Heat in Solids, 2nd ed., Oxford (1959).
J. R. Barber, "Bounds on the electrical resistance between contacting elastic
rough bodies", Proc. R. Soc. Lond. A 459 (2003) 53-66.
"""

from __future__ import annotations

import numpy as np

from roughcontact.contact.counterface import scaled
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.elasticity.operators import halfspace_operator

__all__ = ["free_thermal_halfspace", "halfspace_thermal_influence",
           "periodic_thermal_halfspace", "thermal_element_kernel"]


def _check_conductivity(conductivity: float) -> float:
    conductivity = float(conductivity)
    if not (np.isfinite(conductivity) and conductivity > 0.0):
        raise ValueError(f"conductivity must be a finite positive W/(m K) (or S/m), "
                         f"got {conductivity!r}")
    return conductivity


def _quarter_integral(x, y):
    """``int_0^x int_0^y ds dt / sqrt(s^2 + t^2)`` [m] for ``x, y >= 0``.

    ``x ln((y + r) / x) + y ln((x + r) / y)``, ``r = sqrt(x^2 + y^2)``, each term
    0 where its factor is 0 (its limit); no cancellation for non-negative arguments.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    r = np.hypot(x, y)
    safe_x = np.where(x > 0.0, x, 1.0)
    safe_y = np.where(y > 0.0, y, 1.0)
    first = np.where(x > 0.0, x * np.log((y + r) / safe_x), 0.0)
    second = np.where(y > 0.0, y * np.log((x + r) / safe_y), 0.0)
    return first + second


def _spans(count: int, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An element's extent at offsets ``j = 0..count-1`` as signed spans from 0 [m].

    The element spans ``[j step - step/2, j step + step/2]``; for an even
    integrand ``int_low^high f = int_0^high f + sign int_0^|low| f`` with sign
    -1 when the element lies on one side of 0 (``j > 0``) and +1 when it
    spans 0 (``j = 0``). Returns ``(high, 1, |low|, sign)`` as arrays.
    """
    offsets = np.arange(count, dtype=float) * step
    sign = np.where(offsets > 0.0, -1.0, 1.0)
    return offsets + step / 2, np.ones(count), np.abs(offsets - step / 2), sign


def thermal_element_kernel(nx: int, ny: int, dx: float, dy: float) -> np.ndarray:
    """``K[jy, jx] = int_element dA / (2 pi r)`` [m] for element offsets ``(jx dx, jy dy)``.

    The temperature times ``k`` at the centre of an element offset by
    ``(jx, jy)`` elements from one carrying a unit flux density, for ``jx =
    0..nx-1``, ``jy = 0..ny-1``. The kernel is even in each offset, so the
    integral over the element is a signed sum of four quarter-plane integrals
    (:func:`_quarter_integral`) at non-negative corners (:func:`_spans`).
    """
    x_high, x_one, x_low, x_sign = _spans(nx, dx)
    y_high, y_one, y_low, y_sign = _spans(ny, dy)
    total = np.zeros((ny, nx))
    for ux, sx in ((x_high, x_one), (x_low, x_sign)):
        for uy, sy in ((y_high, y_one), (y_low, y_sign)):
            total += sy[:, None] * sx[None, :] * _quarter_integral(ux[None, :], uy[:, None])
    return total / (2.0 * np.pi)


def halfspace_thermal_influence(grid, size, conductivity: float = 1.0) -> np.ndarray:
    """Dense thermal influence of a half-space, ``R[i, j]`` [K m^2/W].

    The temperature at the centre of contact element ``i`` per unit flux
    density [W/m^2] uniform on element ``j`` of a half-space of conductivity
    ``k`` [W/(m K)] (module docstring); elements row-major over y then x
    (``k = iy * nx + ix``). Symmetric, positive definite, block Toeplitz.

    Parameters
    ----------
    grid : (int, int)
        Elements ``(nx, ny)``.
    size : (float, float)
        Nominal area ``(Lx, Ly)`` [m].
    conductivity : float, optional
        ``k`` [W/(m K)]; 1 gives ``k R`` [m].
    """
    conductivity = _check_conductivity(conductivity)
    nx, ny = (int(g) for g in grid)
    lx, ly = (float(s) for s in size)
    kernel = thermal_element_kernel(nx, ny, lx / nx, ly / ny) / conductivity
    ix, iy = np.arange(nx), np.arange(ny)
    offset_x = np.abs(ix[:, None] - ix[None, :])
    offset_y = np.abs(iy[:, None] - iy[None, :])
    blocks = kernel[offset_y[:, None, :, None], offset_x[None, :, None, :]]
    return blocks.reshape(nx * ny, nx * ny)


def periodic_thermal_halfspace(grid, size, conductivity: float = 1.0, *,
                               mean_compliance: float = 0.0, images: int = 3,
                               workers: int = 1) -> PeriodicHalfSpace:
    """The periodic half-space's thermal influence [K m^2/W], by FFT.

    :class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace` with ``E = 2 k``
    and ``nu = 0`` (module docstring): its kernel ``1 / (pi E r)`` is ``1 / (2 pi
    k r)``. ``mean_compliance`` [K m^2/W] is the temperature per unit uniform
    flux density (0: the mean temperature of the face is the reference).
    """
    conductivity = _check_conductivity(conductivity)
    return PeriodicHalfSpace(grid=tuple(grid), size=tuple(size), E=2.0 * conductivity,
                             nu=0.0, mean_compliance=mean_compliance, images=images,
                             workers=workers)


def free_thermal_halfspace(grid, size, conductivity: float = 1.0, *, workers: int = 1):
    """The (non-periodic) half-space's thermal influence [K m^2/W], matrix-free.

    Love's unit-modulus operator at ``nu = 0`` (kernel ``1 / (pi r)``, applied by
    a zero-padded FFT) times ``1 / (2 k)``: a
    :class:`~roughcontact.contact.counterface.ScaledInfluence`.
    """
    conductivity = _check_conductivity(conductivity)
    return scaled(halfspace_operator(grid, size, 0.0, workers=workers), 0.5 / conductivity)
