"""Two rough, elastic bodies as one: the equivalent problem of Eq 17-18.

Kumar, Sadeghi & Krousgrill (2006) write the contact of two bodies with the
total displacement ``u_z = u_z1 + u_z2`` and the prescribed approach
``d_z = d_z1 + d_z2`` (Eq 17-18), and reduce it to "a rigid smooth surface and
an equivalent deforming rough surface". For frictionless contact with small
slopes the reduction is exact:

- the **equivalent surface** is the sum of the two height maps, each measured
  from its body's mean plane as a protrusion towards the other body, on the
  same ``(ny, nx)`` grid as seen from the first body (a map measured looking
  at the second body from outside is mirrored in x, or y, before it is
  given here);
- the **equivalent compliance** is the sum of the two bodies' influence
  operators, ``C = C1 + C2`` [m/Pa]: the same pressure acts on both surfaces,
  so their displacements add. On half-spaces this is the composite modulus
  ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2``; on finite blocks, the sum of
  the two finite-element models (the mean-plane deflection of Eq 44 becomes
  ``P (L1/E1 + L2/E2)`` for nu = 0).

A rigid counter body (``None``) adds nothing: the first operator and heights
are returned as they are, so a one-body problem gives today's numbers bit for
bit. The solution of the equivalent problem is that of the pair; each body's
share of the displacement is ``C_i p`` (:func:`body_displacements`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from roughcontact.contact.checks import as_operator
from roughcontact.elasticity.protocol import DenseInfluence, RestrictedInfluence

__all__ = ["SumInfluence", "body_displacements", "equivalent_heights",
           "equivalent_operator"]

#: Relative tolerance on the two operators' element areas.
AREA_RTOL = 1e-9


@dataclass(frozen=True)
class SumInfluence:
    """``C = C1 + C2`` of two influence operators on the same elements, without forming
    a dense matrix (an :class:`~roughcontact.elasticity.protocol.InfluenceOperator`).

    ``matrix`` is None (a dense pair is summed by :func:`equivalent_operator`);
    ``mean_compliance`` is the sum of the two when both fix it, else None.
    """

    first: Any
    second: Any
    matrix = None

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.first.shape)

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(float)

    @property
    def element_area(self) -> float:
        return float(self.first.element_area)

    @property
    def grid(self):
        return self.first.grid

    @property
    def mean_compliance(self) -> float | None:
        values = (self.first.mean_compliance, self.second.mean_compliance)
        return None if None in values else float(sum(values))

    def matvec(self, pressure) -> np.ndarray:
        """``C1 p + C2 p`` [m]."""
        return (np.asarray(self.first.matvec(pressure), dtype=float)
                + np.asarray(self.second.matvec(pressure), dtype=float))

    def __matmul__(self, pressure) -> np.ndarray:
        return self.matvec(pressure)

    def diagonal(self) -> np.ndarray:
        """``C1_ii + C2_ii`` [m/Pa]."""
        return (np.asarray(self.first.diagonal(), dtype=float)
                + np.asarray(self.second.diagonal(), dtype=float))

    def restrict(self, indices):
        """The sum restricted to the elements ``indices``."""
        return RestrictedInfluence(self, np.asarray(indices))


def equivalent_operator(first, second=None, *, element_area: float | None = None):
    """The equivalent compliance ``C1 + C2`` [m/Pa] of two bodies (module docstring).

    Parameters
    ----------
    first, second : ndarray (n, n) or influence operator
        The two bodies' influence operators on the same ``n`` contact elements
        (:class:`~roughcontact.elasticity.protocol.InfluenceOperator`; a dense
        ndarray needs ``element_area``). ``second`` None: a rigid counter body,
        ``first`` is returned unchanged.
    element_area : float, optional
        Element area [m^2] of dense ndarrays.

    Returns
    -------
    operator
        ``first`` (rigid counter body); a
        :class:`~roughcontact.elasticity.protocol.DenseInfluence` of ``C1 + C2``
        when both hold a dense matrix; else a :class:`SumInfluence`.

    Raises
    ------
    ValueError
        If the two operators do not act on the same elements (shape, grid or
        element area differ): the message names both.
    """
    if second is None:
        return first
    a, b = as_operator(first, element_area), as_operator(second, element_area)
    if tuple(a.shape) != tuple(b.shape):
        raise ValueError(f"the two bodies' operators act on different element counts: "
                         f"{tuple(a.shape)} and {tuple(b.shape)}; build both on the same "
                         f"contact grid")
    if a.grid is not None and b.grid is not None and tuple(a.grid) != tuple(b.grid):
        raise ValueError(f"the two bodies' contact grids differ: (nx, ny) = {tuple(a.grid)} "
                         f"and {tuple(b.grid)}; build both on the same grid")
    if abs(a.element_area - b.element_area) > AREA_RTOL * a.element_area:
        raise ValueError(f"the two bodies' contact elements differ in area: "
                         f"{a.element_area:.6g} and {b.element_area:.6g} m^2; both bodies "
                         f"need the same plan size and grid")
    if a.matrix is not None and b.matrix is not None:
        means = (a.mean_compliance, b.mean_compliance)
        return DenseInfluence(a.matrix + b.matrix, a.element_area,
                              a.grid if a.grid is not None else b.grid,
                              None if None in means else float(sum(means)))
    return SumInfluence(a, b)


def equivalent_heights(first, second=None) -> np.ndarray:
    """The equivalent surface ``h1 + h2`` [m] of two height maps (module docstring).

    ``first``, ``second``: heights (ny, nx) or stacks (m, ny, nx) [m], each a
    protrusion towards the other body on the first body's grid; ``second`` None
    (a smooth counter body) returns ``first`` unchanged. A single counter map is
    added to every surface of a stack.

    Raises
    ------
    ValueError
        If the grids differ (naming both shapes).
    """
    if second is None:
        return first
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    if a.shape[-2:] != b.shape[-2:] or b.ndim > a.ndim:
        raise ValueError(f"the counter surface's grid {b.shape} does not match the first "
                         f"surface's {a.shape} (ny, nx): both must be sampled on the same "
                         f"grid and size (resample the measured one)")
    if b.ndim == a.ndim and a.ndim == 3 and b.shape[0] != a.shape[0]:
        raise ValueError(f"{a.shape[0]} first surfaces but {b.shape[0]} counter surfaces: "
                         f"give one counter surface per surface, or a single one")
    return a + b


def body_displacements(first, second, pressure) -> tuple[np.ndarray, np.ndarray]:
    """Each body's displacement ``C1 p`` and ``C2 p`` [m] under the contact pressure
    ``p`` [Pa] of the equivalent problem (same shape as ``pressure``; the pair's
    displacement is their sum). ``second`` None (rigid): zeros for it."""
    p = np.asarray(pressure, dtype=float)
    flat = p.reshape(-1)
    u1 = np.asarray(first.matvec(flat), dtype=float).reshape(p.shape)
    if second is None:
        return u1, np.zeros_like(u1)
    return u1, np.asarray(second.matvec(flat), dtype=float).reshape(p.shape)
