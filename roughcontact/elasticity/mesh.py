"""Structured hexahedral mesh of an elastic block, its slabs and node numbering.

The block occupies ``0 <= x <= Lx``, ``0 <= y <= Ly``, ``-L <= z <= 0``; its
top face ``z = 0`` carries the contact grid. The mesh is a tensor product of
element edges (uniform in plan, arbitrary layers through the thickness), so
every element in one layer has the same shape. Optionally the plan mesh is
coarsened by factors of two with depth (slabs tied by hanging-node
constraints, ``roughcontact.elasticity.dofs``), so that the fine surface mesh
needed for the near field does not extend through the whole thickness.

Nodes live on a lattice: ``p * N + 1`` points per axis for ``N`` elements and
element order ``p`` (1 for trilinear, 2 for the quadratic elements, whose
mid-edge, mid-face and centre nodes sit on the half-way lattice points; the
20-node serendipity element uses only the lattice points with at most one odd
index). Node numbers run over each slab's lattice in C order ``(z, y, x)``,
slab after slab from the bottom; the dof of component ``c`` (0: x, 1: y, 2: z)
of node ``a`` is ``3 * a + c`` before the constrained dofs are removed.

All lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.elasticity.elements import ELEMENTS, ElementType


@dataclass(frozen=True)
class HexMesh:
    """A structured hexahedral mesh of the block, optionally coarsened with depth.

    Attributes
    ----------
    x_edges, y_edges : tuple of float
        Element boundaries in plan [m] of the finest (top) layers, increasing,
        uniform spacing.
    z_edges : tuple of float
        Layer boundaries [m], increasing from the base ``-L`` to the top ``0``.
    element : str
        ``"hex8"`` (trilinear), ``"hex20"`` (serendipity quadratic) or
        ``"hex27"`` (triquadratic).
    coarsening : tuple of int
        Plan coarsening factor d of each layer, bottom to top (empty: all 1).
        A layer of factor d has elements d times larger in plan than the top
        layer. The top layer has d = 1, and each factor divides the factor of
        every layer below it and the plan element counts.
        Layers of equal factor form a *slab*; where a fine slab rests on a
        coarser one, the fine slab's bottom nodes are constrained to the
        coarse face's interpolation (hanging nodes), which keeps the
        displacement field continuous (a conforming mesh).
    """

    x_edges: tuple[float, ...]
    y_edges: tuple[float, ...]
    z_edges: tuple[float, ...]
    element: str = "hex8"
    coarsening: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.element not in ELEMENTS:
            raise ValueError(f"element must be one of {tuple(ELEMENTS)}, got {self.element!r}")
        factors = self.factors
        if len(factors) != len(self.z_edges) - 1:
            raise ValueError("coarsening needs one factor per layer")
        if factors[-1] != 1 or any(a % b for a, b in zip(factors, factors[1:], strict=False)):
            raise ValueError("coarsening factors must end at 1 on top and each must divide "
                             "the factors below it")
        ex, ey = len(self.x_edges) - 1, len(self.y_edges) - 1
        if ex % factors[0] or ey % factors[0]:
            raise ValueError(f"plan {ex} x {ey} elements cannot be coarsened by {factors[0]}")

    @property
    def element_type(self) -> ElementType:
        """The element's basis, lattice order and node layout."""
        return ELEMENTS[self.element]

    @property
    def order(self) -> int:
        """Lattice order p: 1 for trilinear, 2 for quadratic elements."""
        return self.element_type.order

    @property
    def factors(self) -> tuple[int, ...]:
        """Plan coarsening factor of each layer, bottom to top."""
        return self.coarsening or (1,) * (len(self.z_edges) - 1)

    @property
    def n_elements(self) -> tuple[int, int, int]:
        """Elements along x and y (top layers) and layers along z."""
        return len(self.x_edges) - 1, len(self.y_edges) - 1, len(self.z_edges) - 1

    @property
    def aspect_ratio(self) -> float:
        """Largest ratio of two edges of one element (1: cubes), over every layer.

        An element of layer k has the plan edges of the top layer times its
        coarsening factor and the layer's thickness as its third edge.
        """
        hx = (self.x_edges[-1] - self.x_edges[0]) / (len(self.x_edges) - 1)
        hy = (self.y_edges[-1] - self.y_edges[0]) / (len(self.y_edges) - 1)
        worst = 1.0
        for low, high, factor in zip(self.z_edges[:-1], self.z_edges[1:], self.factors,
                                     strict=True):
            edges = (hx * factor, hy * factor, high - low)
            worst = max(worst, max(edges) / min(edges))
        return worst

    @property
    def lattice_shape(self) -> tuple[int, int, int]:
        """Lattice points along (z, y, x) of a single-slab mesh (``node_numbers``' shape)."""
        ex, ey, ez = self.n_elements
        p = self.order
        return p * ez + 1, p * ey + 1, p * ex + 1


def structured_mesh(
    size: tuple[float, float],
    thickness: float,
    plan_elements: tuple[int, int],
    layers_top_down: tuple[float, ...],
    element: str,
    factors_top_down: tuple[int, ...] = (),
) -> HexMesh:
    """Build the tensor-product mesh of the block.

    Parameters
    ----------
    size : (Lx, Ly)
        Plan size [m].
    thickness : float
        Block thickness L [m]; the layers are scaled to sum to it.
    plan_elements : (Nx, Ny)
        Finite elements along x and y in the top layers.
    layers_top_down : tuple of float
        Layer thicknesses [m] from the top face down.
    element : str
        Element name, a key of ``roughcontact.elasticity.elements.ELEMENTS``.
    factors_top_down : tuple of int, optional
        Plan coarsening factor of each layer from the top down (see ``HexMesh``);
        empty for a uniform plan mesh.
    """
    depth = np.concatenate([[0.0], np.cumsum(layers_top_down)])
    depth *= thickness / depth[-1]
    z_edges = tuple(float(z) for z in (-depth)[::-1])
    x_edges = tuple(float(x) for x in np.linspace(0.0, size[0], plan_elements[0] + 1))
    y_edges = tuple(float(y) for y in np.linspace(0.0, size[1], plan_elements[1] + 1))
    return HexMesh(x_edges, y_edges, z_edges, element, tuple(factors_top_down)[::-1])


def slabs(mesh: HexMesh) -> list[HexMesh]:
    """The mesh split into single-level slabs, bottom to top.

    Consecutive slabs share their interface plane (each slab has its own copy
    of the nodes there).
    """
    factors = mesh.factors
    out = []
    start = 0
    for stop in range(1, len(factors) + 1):
        if stop == len(factors) or factors[stop] != factors[start]:
            step = factors[start]
            out.append(HexMesh(mesh.x_edges[::step], mesh.y_edges[::step],
                               mesh.z_edges[start:stop + 1], mesh.element))
            start = stop
    return out


def node_numbers(slab: HexMesh) -> np.ndarray:
    """Node number at each lattice point of a single-level slab, -1 where there is none.

    Returns
    -------
    ndarray of int, shape ``slab.lattice_shape`` (z, y, x)
        Nodes numbered in C order from 0; for serendipity elements (``hex20``)
        the lattice points with two or three odd indices (face and body
        centres) carry no node.
    """
    shape = slab.lattice_shape
    present = np.ones(shape, dtype=bool)
    if slab.element_type.serendipity:
        kz, ky, kx = np.indices(shape, sparse=True)
        present = np.broadcast_to((kz % 2 + ky % 2 + kx % 2) <= 1, shape)
    numbers = np.full(shape, -1, dtype=np.int64)
    numbers[present] = np.arange(np.count_nonzero(present))
    return numbers


def node_count(element: str, ex: int, ey: int, ez: int) -> int:
    """Nodes of a single-slab mesh of ex x ey x ez elements (ez = 0: one plane).

    The count of ``node_numbers`` without building the lattice.
    """
    kind = ELEMENTS[element]
    p = kind.order
    lattice = (p * ex + 1) * (p * ey + 1) * (p * ez + 1)
    if not kind.serendipity:
        return lattice
    face_centres = ex * ey * (ez + 1) + ex * ez * (ey + 1) + ey * ez * (ex + 1)
    return lattice - face_centres - ex * ey * ez


def numbered_slabs(mesh: HexMesh) -> tuple[list[HexMesh], list[np.ndarray], int]:
    """Slabs, their lattice node numbers offset to a global numbering, node count."""
    parts = slabs(mesh)
    numbers = []
    offset = 0
    for slab in parts:
        local = node_numbers(slab)
        numbers.append(np.where(local >= 0, local + offset, -1))
        offset += int(local.max()) + 1
    return parts, numbers, offset
