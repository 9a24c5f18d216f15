"""Closed-form contact solutions the solver is checked against.

Pure functions of their arguments, SI units (lengths m, pressures Pa, forces N):

- :func:`hertz`: a rigid sphere on an elastic half-space (Hertz 1882; Johnson 1985,
  Sec 4.2);
- :func:`westergaard_pressure`: a wavy surface on an elastic half-space in partial
  contact (Westergaard 1939; Johnson 1985, Sec 13.2);
- :func:`sphere_gap`: the initial separation of a sphere on a grid.

The tests compare :mod:`roughcontact.contact`'s solutions with these (and the
verification matrix, ``tests/contact/test_verification_matrix.py``, under every
method and control).

References
----------
K. L. Johnson, Contact Mechanics, Cambridge University Press (1985).
H. M. Westergaard, "Bearing pressures and cracks", J. Appl. Mech. 6 (1939) A49-A53.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Hertz", "hertz", "sphere_gap", "westergaard_pressure"]


@dataclass(frozen=True)
class Hertz:
    """Hertz's contact of a rigid sphere: radius ``a`` [m], peak pressure ``p0`` [Pa]
    and approach ``d`` [m] at the force ``load`` [N]."""

    load: float
    a: float
    p0: float
    d: float


def hertz(load: float, radius: float, e_star: float) -> Hertz:
    """Hertz's solution for a rigid sphere of ``radius`` [m] pressed with ``load`` [N]
    on a half-space of effective modulus ``e_star`` = E / (1 - nu^2) [Pa]:
    ``a = (3 F R / (4 E*))^(1/3)``, ``p0 = 3 F / (2 pi a^2)``, ``d = a^2 / R``
    (Johnson 1985, Eq 4.22-4.23)."""
    a = (3.0 * load * radius / (4.0 * e_star)) ** (1.0 / 3.0)
    return Hertz(float(load), float(a), float(3.0 * load / (2.0 * np.pi * a**2)),
                 float(a**2 / radius))


def sphere_gap(n: int, dx: float, radius: float) -> np.ndarray:
    """The gap ``r^2 / 2R`` [m] (n, n) of a sphere of ``radius`` [m] centred on a grid of
    ``n`` x ``n`` elements of side ``dx`` [m] (element centres)."""
    x = (np.arange(n) - (n - 1) / 2) * dx
    return (x[None, :] ** 2 + x[:, None] ** 2) / (2.0 * radius)


def westergaard_pressure(s, wavelength: float, half_width: float, mean_pressure: float):
    """Westergaard's pressure [Pa] under a wavy surface in partial contact.

    A rigid flat on an elastic half-space (E*) whose surface is the wave
    ``h (1 - cos(2 pi s / lambda))``: at mean pressure
    ``P = p* sin^2(pi a / lambda)``, ``p* = pi E* h / lambda`` (the pressure of
    full contact), the contact is ``|s| < a`` (mod lambda) and

        p(s) = 2 P cos(pi s / lambda) sqrt(sin^2(pi a / lambda) - sin^2(pi s / lambda))
               / sin^2(pi a / lambda)

    (Johnson 1985, Sec 13.2; Westergaard 1939). ``s`` [m] is measured from the
    wave's trough (its lowest point, where contact starts).
    """
    edge = np.sin(np.pi * half_width / wavelength) ** 2
    inside = np.clip(edge - np.sin(np.pi * np.asarray(s) / wavelength) ** 2, 0.0, None)
    return 2.0 * mean_pressure * np.cos(np.pi * np.asarray(s) / wavelength) * \
        np.sqrt(inside) / edge
