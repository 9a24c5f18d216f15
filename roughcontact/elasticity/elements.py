"""Hexahedral elements of the block: one box element's stiffness and top face.

Element and basis definitions come from scikit-fem (``ElementHex1``,
``ElementHexS2``, ``ElementHex2``) and the 3-D linear elasticity form
``sigma : eps(v)`` with Lame parameters from ``(E, nu)``. Each function here
integrates a single axis-aligned box; the structured mesh repeats it
(``roughcontact.elasticity.assembly``).

Local dofs are located on the element's lattice: ``p + 1`` points per edge
for lattice order ``p`` (1 for trilinear, 2 for the quadratic elements, whose
mid-edge, mid-face and centre nodes sit on the half-way points).

All lengths in metres; stiffnesses are for the modulus passed (N/m per unit
``E`` when ``E = 1``).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from skfem import (
    Basis,
    ElementHex1,
    ElementHex2,
    ElementHexS2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshHex,
    asm,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity


@dataclass(frozen=True)
class ElementType:
    """A hexahedral element: its scikit-fem basis and where its nodes sit.

    Attributes
    ----------
    basis : type
        scikit-fem element class of one displacement component.
    order : int
        Lattice order p: 1 for trilinear, 2 for quadratic elements.
    intorder : int
        Quadrature order; integrates the stiffness of an axis-aligned box
        exactly (2 x 2 x 2 Gauss points for trilinear, 3 x 3 x 3 for the
        quadratic elements).
    serendipity : bool
        Nodes only on the lattice points with at most one odd index (the
        20-node element: no face or body centres).
    """

    basis: type
    order: int
    intorder: int
    serendipity: bool = False


#: Element name -> its ``ElementType``.
ELEMENTS = MappingProxyType({
    "hex8": ElementType(ElementHex1, 1, 3),
    "hex20": ElementType(ElementHexS2, 2, 4, serendipity=True),
    "hex27": ElementType(ElementHex2, 2, 4),
})


def _unit_box(dx: float, dy: float, dz: float) -> MeshHex:
    """A one-element scikit-fem mesh of the box ``[0, dx] x [0, dy] x [0, dz]`` [m]."""
    return MeshHex.init_tensor(np.array([0.0, dx]), np.array([0.0, dy]), np.array([0.0, dz]))


def dof_components(basis: Basis) -> np.ndarray:
    """Displacement component (0: x, 1: y, 2: z) of each dof of a vector basis."""
    components = np.empty(basis.N, dtype=np.int64)
    for c, idx in enumerate(basis.split_indices()):
        components[idx] = c
    return components


def _lattice_offsets(doflocs: np.ndarray, steps: tuple[float, float, float]) -> np.ndarray:
    """Integer lattice offsets (x, y, z) of dof locations inside one element."""
    return np.rint(doflocs.T / np.asarray(steps)).astype(np.int64)


@dataclass(frozen=True)
class ReferenceElement:
    """Stiffness of one box element and where its dofs sit on the lattice.

    Attributes
    ----------
    offsets : ndarray of int, shape (q, 3)
        Lattice offsets (x, y, z) of each local dof from the element's lowest corner.
    components : ndarray of int, shape (q,)
        Displacement component of each local dof (0: x, 1: y, 2: z).
    stiffness : ndarray, shape (q, q)
        Element stiffness [N/m] for the modulus it was computed with.
    """

    offsets: np.ndarray
    components: np.ndarray
    stiffness: np.ndarray


def reference_element(
    element: str, dx: float, dy: float, dz: float, nu: float, E: float = 1.0
) -> ReferenceElement:
    """Stiffness of one ``dx x dy x dz`` box of isotropic linear elastic material.

    The bilinear form is ``int sigma(u) : eps(v) dV`` with Hooke's law and Lame
    parameters ``lambda = E nu / ((1 + nu)(1 - 2 nu))``, ``mu = E / (2 (1 + nu))``,
    assembled by scikit-fem on a one-element mesh.

    Parameters
    ----------
    element : str
        Element name, a key of ``ELEMENTS``.
    dx, dy, dz : float
        Element edge lengths [m].
    nu : float
        Poisson's ratio.
    E : float, optional
        Young's modulus [Pa]; 1 by default (stiffness per unit modulus).
    """
    kind = ELEMENTS[element]
    p = kind.order
    basis = Basis(_unit_box(dx, dy, dz), ElementVector(kind.basis()), intorder=kind.intorder)
    stiffness = asm(linear_elasticity(*lame_parameters(E, nu)), basis).toarray()
    offsets = _lattice_offsets(basis.doflocs, (dx / p, dy / p, dz / p))
    return ReferenceElement(offsets, dof_components(basis), stiffness)


@dataclass(frozen=True)
class ReferenceFace:
    """Top-face data of one element: consistent load and interpolation.

    Attributes
    ----------
    offsets : ndarray of int, shape (f, 2)
        Lattice offsets (x, y) of the face nodes from the face's lowest corner.
    load : ndarray, shape (f,)
        ``int_face N_a dA`` [m^2]: consistent nodal force per unit pressure.
    values : ndarray, shape (k, f)
        Shape function values ``N_a`` at the k points asked for.
    """

    offsets: np.ndarray
    load: np.ndarray
    values: np.ndarray


def reference_top_face(
    element: str, dx: float, dy: float, points: np.ndarray | None = None
) -> ReferenceFace:
    """Consistent load and interpolation weights of an element's top face.

    Parameters
    ----------
    element : str
        Element name, a key of ``ELEMENTS``.
    dx, dy : float
        Face edge lengths [m].
    points : ndarray, shape (k, 2), optional
        Points of the face, as fractions of (dx, dy), where the shape
        functions are evaluated; the face centre by default.
    """
    kind = ELEMENTS[element]
    p = kind.order
    dz = 0.5 * (dx + dy)
    box = _unit_box(dx, dy, dz)
    basis = Basis(box, kind.basis(), intorder=kind.intorder)
    top = box.facets_satisfying(lambda x: np.isclose(x[2], dz))
    face_basis = FacetBasis(box, kind.basis(), facets=top, intorder=kind.intorder)
    load = asm(LinearForm(lambda v, w: v), face_basis)
    points = np.array([[0.5, 0.5]]) if points is None else np.asarray(points, dtype=float)
    where = np.vstack([points[:, 0] * dx, points[:, 1] * dy, np.full(len(points), dz)])
    values = basis.probes(where).toarray()
    offsets = _lattice_offsets(basis.doflocs, (dx / p, dy / p, dz / p))
    on_top = offsets[:, 2] == p
    return ReferenceFace(offsets[on_top, :2], load[on_top], values[:, on_top])
