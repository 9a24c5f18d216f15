"""Structured hexahedral finite-element model of an elastic block.

The block occupies ``0 <= x <= Lx``, ``0 <= y <= Ly``, ``-L <= z <= 0``; its
top face ``z = 0`` carries the contact grid. The mesh is a tensor product of
element edges (uniform in plan, arbitrary layers through the thickness), so
every element in one layer has the same shape and the global stiffness is the
scatter of one reference element stiffness per distinct element shape.
Optionally the plan mesh is coarsened by factors of two with depth (slabs tied
by hanging-node constraints), so that the fine surface mesh needed for the
near field does not extend through the whole thickness.

Element and basis definitions come from scikit-fem (``ElementHex1``,
``ElementHexS2``, ``ElementHex2``) and the 3-D linear elasticity form
``sigma : eps(v)`` with Lame parameters from ``(E, nu)``; only the scatter over
the structured mesh is done here, because the generic vector assembly is an
order of magnitude slower for this regular mesh (it recomputes the same element
matrix for every element). ``assemble_stiffness_generic`` is the slow
reference path used to check the scatter.

Nodes live on a lattice: ``p * N + 1`` points per axis for ``N`` elements and
element order ``p`` (1 for trilinear, 2 for the quadratic elements, whose
mid-edge, mid-face and centre nodes sit on the half-way lattice points; the
20-node serendipity element uses only the lattice points with at most one odd
index). Node numbers run over each slab's lattice in C order ``(z, y, x)``,
slab after slab from the bottom; the dof of component ``c`` (0: x, 1: y, 2: z)
of node ``a`` is ``3 * a + c`` before the constrained dofs are removed.

All lengths in metres; stiffnesses are for the modulus passed (N/m per unit
``E`` when ``E = 1``).
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import os
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu
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

#: Element name -> (scikit-fem element class, lattice order p, quadrature order).
#: The quadrature orders integrate the stiffness of an axis-aligned box exactly
#: (2 x 2 x 2 Gauss points for trilinear, 3 x 3 x 3 for the quadratic elements).
ELEMENTS = {
    "hex8": (ElementHex1, 1, 3),
    "hex20": (ElementHexS2, 2, 4),
    "hex27": (ElementHex2, 2, 4),
}

BASES = ("clamped", "sliding")


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
    def order(self) -> int:
        """Lattice order p: 1 for trilinear, 2 for quadratic elements."""
        return ELEMENTS[self.element][1]

    @property
    def factors(self) -> tuple[int, ...]:
        """Plan coarsening factor of each layer, bottom to top."""
        return self.coarsening or (1,) * (len(self.z_edges) - 1)

    @property
    def n_elements(self) -> tuple[int, int, int]:
        """Elements along x and y (top layers) and layers along z."""
        return len(self.x_edges) - 1, len(self.y_edges) - 1, len(self.z_edges) - 1

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
        Element name, a key of ``ELEMENTS``.
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


def _unit_box(dx: float, dy: float, dz: float) -> MeshHex:
    return MeshHex.init_tensor(np.array([0.0, dx]), np.array([0.0, dy]), np.array([0.0, dz]))


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
    element_cls, p, intorder = ELEMENTS[element]
    basis = Basis(_unit_box(dx, dy, dz), ElementVector(element_cls()), intorder=intorder)
    stiffness = asm(linear_elasticity(*lame_parameters(E, nu)), basis).toarray()
    components = np.empty(basis.N, dtype=np.int64)
    for c, idx in enumerate(basis.split_indices()):
        components[idx] = c
    offsets = _lattice_offsets(basis.doflocs, (dx / p, dy / p, dz / p))
    return ReferenceElement(offsets, components, stiffness)


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
    element_cls, p, intorder = ELEMENTS[element]
    dz = 0.5 * (dx + dy)
    box = _unit_box(dx, dy, dz)
    basis = Basis(box, element_cls(), intorder=intorder)
    top = box.facets_satisfying(lambda x: np.isclose(x[2], dz))
    face_basis = FacetBasis(box, element_cls(), facets=top, intorder=intorder)
    load = asm(LinearForm(lambda v, w: v), face_basis)
    points = np.array([[0.5, 0.5]]) if points is None else np.asarray(points, dtype=float)
    where = np.vstack([points[:, 0] * dx, points[:, 1] * dy, np.full(len(points), dz)])
    values = basis.probes(where).toarray()
    offsets = _lattice_offsets(basis.doflocs, (dx / p, dy / p, dz / p))
    on_top = offsets[:, 2] == p
    return ReferenceFace(offsets[on_top, :2], load[on_top], values[:, on_top])


def node_numbers(slab: HexMesh) -> np.ndarray:
    """Node number at each lattice point of a single-level slab, -1 where there is none.

    Returns
    -------
    ndarray of int, shape ``slab.lattice_shape`` (z, y, x)
        Nodes numbered in C order from 0; for ``hex20`` the lattice points with
        two or three odd indices (face and body centres) carry no node.
    """
    shape = slab.lattice_shape
    present = np.ones(shape, dtype=bool)
    if slab.element == "hex20":
        kz, ky, kx = np.indices(shape, sparse=True)
        present = np.broadcast_to((kz % 2 + ky % 2 + kx % 2) <= 1, shape)
    numbers = np.full(shape, -1, dtype=np.int64)
    numbers[present] = np.arange(np.count_nonzero(present))
    return numbers


def _slab_numbers(mesh: HexMesh) -> tuple[list[HexMesh], list[np.ndarray], int]:
    """Slabs, their lattice node numbers offset to a global numbering, node count."""
    parts = slabs(mesh)
    numbers = []
    offset = 0
    for slab in parts:
        local = node_numbers(slab)
        numbers.append(np.where(local >= 0, local + offset, -1))
        offset += int(local.max()) + 1
    return parts, numbers, offset


def constrained_dofs(mesh: HexMesh, base: str) -> np.ndarray:
    """Dofs fixed by the support on the bottom face ``z = -L`` (global numbering).

    ``"clamped"``: all three components of every bottom node (bonded to a rigid
    plate). ``"sliding"``: the normal component of every bottom node (frictionless
    rigid support) plus the three in-plane rigid-body motions, removed by a
    statically determinate set: ``ux = uy = 0`` at the bottom corner
    ``(0, 0)`` and ``uy = 0`` at ``(Lx, 0)``. Normal loads on the top face
    exert no in-plane force or moment, so these constraints carry no reaction
    and do not change the normal displacements.

    Returns
    -------
    ndarray of int
        Sorted dof numbers ``3 * node + component``.
    """
    if base not in BASES:
        raise ValueError(f"base must be one of {BASES}, got {base!r}")
    _, numbers, _ = _slab_numbers(mesh)
    plane = numbers[0][0]
    bottom = plane[plane >= 0]
    if base == "clamped":
        fixed = (3 * bottom[:, None] + np.arange(3)).ravel()
    else:
        corner_a, corner_b = plane[0, 0], plane[0, -1]
        fixed = np.concatenate(
            [3 * bottom + 2, [3 * corner_a, 3 * corner_a + 1, 3 * corner_b + 1]]
        )
    return np.unique(fixed)


def _hanging_nodes(
    fine: HexMesh, fine_numbers: np.ndarray, coarse: HexMesh, coarse_numbers: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node-level constraints tying a fine slab's bottom plane to the coarse slab below.

    Returns
    -------
    slave, master, weight : ndarray
        Triplets: the displacement of node ``slave`` is the sum of
        ``weight * displacement of master`` over its rows (the coarse top face's
        interpolation at the fine node).
    """
    p = fine.order
    ratio = (len(fine.x_edges) - 1) // (len(coarse.x_edges) - 1)
    span = p * ratio  # fine lattice steps per coarse element
    dx = coarse.x_edges[1] - coarse.x_edges[0]
    dy = coarse.y_edges[1] - coarse.y_edges[0]
    local = np.arange(span + 1) / span
    gy, gx = np.meshgrid(local, local, indexing="ij")
    face = reference_top_face(coarse.element, dx, dy, np.column_stack([gx.ravel(), gy.ravel()]))
    plane = fine_numbers[0]
    ky, kx = np.nonzero(plane >= 0)
    ecx = np.minimum(kx // span, len(coarse.x_edges) - 2)
    ecy = np.minimum(ky // span, len(coarse.y_edges) - 2)
    point = (ky - ecy * span) * (span + 1) + (kx - ecx * span)
    weight = face.values[point]  # (slaves, face nodes)
    top = coarse_numbers[-1]
    master = top[p * ecy[:, None] + face.offsets[:, 1], p * ecx[:, None] + face.offsets[:, 0]]
    slave = np.broadcast_to(plane[ky, kx][:, None], weight.shape)
    keep = np.abs(weight) > 1e-13
    return slave[keep], master[keep], weight[keep]


@dataclass(frozen=True)
class DofMap:
    """From the global node dofs to the equations of the supported, tied block.

    Attributes
    ----------
    equation : ndarray of int, shape (n_dofs,)
        Equation number of each dof ``3 * node + component``; -1 for dofs fixed
        by the support and for hanging (constrained) dofs.
    tying : scipy.sparse.csr_array or None, shape (n_dofs, n_free)
        ``u_all = tying @ u_free`` (None for a single-slab mesh, where it is
        the selection given by ``equation``).
    n_free : int
        Number of equations.
    """

    equation: np.ndarray
    tying: sp.csr_array | None
    n_free: int


def dof_map(mesh: HexMesh, base: str) -> DofMap:
    """Equation numbering after the support and the coarse-fine ties are applied."""
    parts, numbers, n_nodes = _slab_numbers(mesh)
    is_free = np.ones(3 * n_nodes, dtype=bool)
    is_free[constrained_dofs(mesh, base)] = False
    ties = [_hanging_nodes(parts[k], numbers[k], parts[k - 1], numbers[k - 1])
            for k in range(1, len(parts))]
    for slave, _, _ in ties:
        is_free[(3 * slave[:, None] + np.arange(3)).ravel()] = False
    equation = np.full(3 * n_nodes, -1, dtype=np.int64)
    n_free = int(np.count_nonzero(is_free))
    equation[is_free] = np.arange(n_free)
    if not ties:
        return DofMap(equation, None, n_free)
    rows = [np.flatnonzero(is_free)]
    cols = [equation[is_free]]
    vals = [np.ones(n_free)]
    for slave, master, weight in ties:
        for c in range(3):
            rows.append(3 * slave + c)
            cols.append(equation[3 * master + c])
            vals.append(weight)
    tying = sp.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(3 * n_nodes, n_free),
    ).tocsr()
    return DofMap(equation, tying, n_free)


def _element_dofs(
    slab: HexMesh,
    ref: ReferenceElement,
    layer: int,
    numbers: np.ndarray,
    equation: np.ndarray,
    elements: slice = slice(None),
) -> np.ndarray:
    """Equation numbers (-1: dropped) of elements of one slab layer, shape (k, q).

    Elements are numbered ``iy * Nx + ix`` within the layer; ``elements``
    selects a contiguous range of them.
    """
    ex, ey, _ = slab.n_elements
    p = slab.order
    flat = np.arange(ex * ey)[elements]
    iy, ix = np.divmod(flat, ex)
    kx = p * ix.reshape(-1, 1) + ref.offsets[:, 0]
    ky = p * iy.reshape(-1, 1) + ref.offsets[:, 1]
    kz = p * layer + ref.offsets[:, 2]
    nodes = numbers[np.broadcast_to(kz, kx.shape), ky, kx]
    return equation[3 * nodes + ref.components]


def _scatter(
    parts: list[HexMesh],
    numbers: list[np.ndarray],
    equation: np.ndarray,
    n_rows: int,
    nu: float,
    E: float,
    upper: bool,
    chunk_entries: int,
    layers: list[tuple[int, int]] | None = None,
    tied: np.ndarray | None = None,
) -> sp.csr_array:
    """Sum of reference element stiffnesses scattered to ``equation`` numbers.

    Entries whose row or column equation is -1 are dropped. ``layers`` limits
    the scatter to some (slab, layer) pairs; with ``tied`` (a boolean mask over
    equation numbers) only entries with a tied row or column are kept.
    Triplets are summed ``chunk_entries`` at a time.
    """
    references: dict[tuple[float, float, float], ReferenceElement] = {}
    total = sp.csr_array((n_rows, n_rows))
    rows, cols, vals, pending = [], [], [], 0
    if layers is None:
        layers = [(k, j) for k, slab in enumerate(parts) for j in range(slab.n_elements[2])]
    for k, layer in layers:
        slab = parts[k]
        key = (slab.x_edges[1] - slab.x_edges[0], slab.y_edges[1] - slab.y_edges[0],
               slab.z_edges[layer + 1] - slab.z_edges[layer])
        if key not in references:
            references[key] = reference_element(slab.element, *key, nu, E)
        ref = references[key]
        q = ref.stiffness.shape[0]
        per_block = max(1, chunk_entries // (4 * q * q))
        n_elements = slab.n_elements[0] * slab.n_elements[1]
        for first in range(0, n_elements, per_block):
            dofs = _element_dofs(slab, ref, layer, numbers[k], equation,
                                 slice(first, first + per_block)).astype(np.int32)
            r = np.repeat(dofs, q, axis=1).ravel()
            c = np.tile(dofs, (1, q)).ravel()
            keep = (r >= 0) & (c >= 0)
            if upper:
                keep &= r <= c
            if tied is not None:
                keep &= tied[np.maximum(r, 0)] | tied[np.maximum(c, 0)]
            rows.append(r[keep])
            cols.append(c[keep])
            vals.append(np.tile(ref.stiffness.ravel(), dofs.shape[0])[keep])
            del r, c, keep
            pending += rows[-1].size
            if pending >= chunk_entries:
                total = _add_triplets(total, rows, cols, vals)
                rows, cols, vals, pending = [], [], [], 0
    return _add_triplets(total, rows, cols, vals)


def _add_triplets(total: sp.csr_array, rows: list, cols: list, vals: list) -> sp.csr_array:
    """``total`` plus the (summed) triplets."""
    if not rows:
        return total
    part = sp.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=total.shape,
    ).tocsr()
    return part if total.nnz == 0 else total + part


def assemble_stiffness(
    mesh: HexMesh,
    nu: float,
    base: str = "clamped",
    E: float = 1.0,
    upper: bool = False,
    chunk_entries: int = 20_000_000,
) -> sp.csr_array:
    """Global stiffness of the supported block by scattering reference elements.

    One reference element stiffness is computed per distinct element shape
    (``reference_element``) and scattered to every element of that shape;
    constrained dofs are dropped during the scatter (their equations are
    removed, not penalised). With plan coarsening, entries between free dofs
    are scattered directly and the few involving hanging dofs (bottom layers
    of the finer slabs) are transformed by the ties, ``T^T K_tied T``
    (``dof_map``).

    Parameters
    ----------
    mesh : HexMesh
        The structured mesh.
    nu : float
        Poisson's ratio.
    base : {"clamped", "sliding"}
        Support of the bottom face (see ``constrained_dofs``).
    E : float, optional
        Young's modulus [Pa]; 1 gives the stiffness per unit modulus.
    upper : bool, optional
        Keep only the upper triangle (for symmetric solvers).
    chunk_entries : int, optional
        Triplets summed at a time; bounds the assembly's temporary memory
        (about 50 bytes per triplet).

    Returns
    -------
    scipy.sparse.csr_array, shape (n_free, n_free)
        Symmetric positive definite stiffness [N/m] with sorted indices.
    """
    parts, numbers, n_nodes = _slab_numbers(mesh)
    dofs = dof_map(mesh, base)
    total = _scatter(parts, numbers, dofs.equation, dofs.n_free, nu, E, upper, chunk_entries)
    if dofs.tying is not None:
        every = np.arange(3 * n_nodes)
        tied = np.zeros(3 * n_nodes, dtype=bool)
        tied[np.diff(dofs.tying.indptr) > 0] = True
        tied &= dofs.equation < 0
        interface = [(k, 0) for k in range(1, len(parts))]
        raw = _scatter(parts, numbers, every, 3 * n_nodes, nu, E, False, chunk_entries,
                       layers=interface, tied=tied)
        extra = (dofs.tying.T @ (raw @ dofs.tying)).tocsr()
        if upper:
            extra = sp.triu(extra, format="csr")
        total = total + extra
    total.sum_duplicates()
    total.sort_indices()
    return total


def assemble_stiffness_generic(
    mesh: HexMesh, nu: float, base: str = "clamped", E: float = 1.0
) -> sp.csr_array:
    """Same matrix as ``assemble_stiffness`` by scikit-fem's generic vector ``asm``.

    Slow reference path (every element integrated separately) for single-slab
    meshes; the dofs are matched to this module's numbering by location and
    component.
    """
    if any(f != 1 for f in mesh.factors):
        raise ValueError("the generic assembly supports meshes without plan coarsening")
    element_cls, p, intorder = ELEMENTS[mesh.element]
    skmesh = MeshHex.init_tensor(
        np.asarray(mesh.x_edges), np.asarray(mesh.y_edges), np.asarray(mesh.z_edges)
    )
    basis = Basis(skmesh, ElementVector(element_cls()), intorder=intorder)
    K = asm(linear_elasticity(*lame_parameters(E, nu)), basis).tocsr()
    lattice = [_axis_lattice(mesh.x_edges, p), _axis_lattice(mesh.y_edges, p),
               _axis_lattice(mesh.z_edges, p)]
    index = [np.abs(basis.doflocs[a][:, None] - lattice[a][None, :]).argmin(axis=1)
             for a in range(3)]
    numbers = node_numbers(mesh)
    components = np.empty(basis.N, dtype=np.int64)
    for c, idx in enumerate(basis.split_indices()):
        components[idx] = c
    ours = dof_map(mesh, base).equation[3 * numbers[index[2], index[1], index[0]] + components]
    keep = np.flatnonzero(ours >= 0)
    n_free = int(ours.max() + 1)
    perm = sp.csr_array((np.ones(keep.size), (ours[keep], keep)), shape=(n_free, basis.N))
    return (perm @ K @ perm.T).tocsr()


def _axis_lattice(edges: tuple[float, ...], p: int) -> np.ndarray:
    """Lattice coordinates along one axis: element edges plus midpoints when p = 2."""
    edges = np.asarray(edges)
    if p == 1:
        return edges
    out = np.empty(2 * edges.size - 1)
    out[0::2] = edges
    out[1::2] = 0.5 * (edges[:-1] + edges[1:])
    return out


def top_face_operators(
    mesh: HexMesh, grid: tuple[int, int], base: str = "clamped"
) -> tuple[sp.csr_array, sp.csr_array]:
    """Load and centre-evaluation operators of the contact grid on the top face.

    Contact element ``k = iy * nx + ix`` covers ``r x r`` finite-element faces,
    ``r = Nx / nx`` (the in-plane refinement).

    Returns
    -------
    load : scipy.sparse.csr_array, shape (n, n_free)
        Row k: consistent nodal forces [N] on the normal (z) dofs of a unit
        uniform pressure [Pa] on contact element k, ``int_k N_a dA``.
    centre : scipy.sparse.csr_array, shape (n, n_free)
        Row k: interpolation weights giving the normal displacement at the
        centre point of contact element k from the nodal values. With one
        trilinear element per contact element this is the mean of the face's
        four corner nodes.
    """
    nx, ny = grid
    ex, ey, _ = mesh.n_elements
    if ex % nx or ey % ny or ex // nx != ey // ny:
        raise ValueError(f"mesh plan {ex} x {ey} is not a refinement of the grid {nx} x {ny}")
    r = ex // nx
    p = mesh.order
    dx = mesh.x_edges[1] - mesh.x_edges[0]
    dy = mesh.y_edges[1] - mesh.y_edges[0]
    face = reference_top_face(mesh.element, dx, dy)
    _, numbers, _ = _slab_numbers(mesh)
    top = numbers[-1][-1]
    dofs = dof_map(mesh, base)

    def z_equation(kx: np.ndarray, ky: np.ndarray) -> np.ndarray:
        return dofs.equation[3 * top[ky, kx] + 2]

    # load: every finite-element face of the top, attributed to its contact element
    fy, fx = np.meshgrid(np.arange(ey), np.arange(ex), indexing="ij")
    owner = ((fy // r) * nx + fx // r).reshape(-1, 1)
    kx = p * fx.reshape(-1, 1) + face.offsets[:, 0]
    ky = p * fy.reshape(-1, 1) + face.offsets[:, 1]
    load = sp.coo_array(
        (np.broadcast_to(face.load, kx.shape).ravel(),
         (np.broadcast_to(owner, kx.shape).ravel(), z_equation(kx, ky).ravel())),
        shape=(nx * ny, dofs.n_free),
    ).tocsr()

    iy, ix = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    rows = (iy * nx + ix).reshape(-1, 1)
    if r % 2 == 0:  # the centre is a corner node of the finite-element faces
        kx = p * (r * ix + r // 2).reshape(-1, 1)
        ky = p * (r * iy + r // 2).reshape(-1, 1)
        weights = np.ones((1, 1))
    else:  # the centre is the centre of the middle finite-element face
        kx = p * (r * ix + r // 2).reshape(-1, 1) + face.offsets[:, 0]
        ky = p * (r * iy + r // 2).reshape(-1, 1) + face.offsets[:, 1]
        weights = face.values
    keep = np.abs(weights[0]) > 1e-14
    kx, ky = np.broadcast_arrays(kx, ky)
    kx, ky = kx[:, keep], ky[:, keep]
    centre = sp.coo_array(
        (np.broadcast_to(weights[:, keep], kx.shape).ravel(),
         (np.broadcast_to(rows, kx.shape).ravel(), z_equation(kx, ky).ravel())),
        shape=(nx * ny, dofs.n_free),
    ).tocsr()
    return load, centre


# --------------------------------------------------------------------------
# Condensation: left K^-1 right^T without forming K^-1


SOLVERS = ("auto", "pardiso", "superlu")


def pardiso_available() -> bool:
    """True when MKL PARDISO loads (PyPI package ``mkl``, a dependency of ``pypardiso``)."""
    try:
        _pardiso_library()
    except (ImportError, OSError):
        return False
    return True


def _mkl_runtime_path() -> str | None:
    """Path of MKL's single runtime library, from the environment or the ``mkl`` wheel."""
    path = os.environ.get("PYPARDISO_MKL_RT")
    if path:
        return path
    try:
        files = importlib.metadata.files("mkl") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    found = sorted(str(f.locate()) for f in files if f.name.startswith(("libmkl_rt", "mkl_rt")))
    return found[0] if found else None


def _pardiso_library():
    """The ``pardiso`` entry point of MKL with its argument types (raises ImportError)."""
    path = _mkl_runtime_path()
    if path is not None:
        library = ctypes.CDLL(path)
    else:  # let pypardiso search (slower: it may run the system linker cache)
        from pypardiso import PyPardisoSolver

        library = PyPardisoSolver().libmkl
    pardiso = library.pardiso
    i32 = ctypes.POINTER(ctypes.c_int32)
    pardiso.argtypes = (
        [ctypes.POINTER(ctypes.c_int64)] + [i32] * 5 + [ctypes.c_void_p] + [i32] * 6
        + [ctypes.c_void_p, ctypes.c_void_p, i32]
    )
    pardiso.restype = None
    return pardiso


def _augmented_upper(stiffness_upper: sp.csr_array, coupling: sp.csr_array) -> sp.csr_array:
    """Upper triangle of ``[[K, B], [B^T, 0]]`` with the zero diagonal stored explicitly."""
    n, nb = stiffness_upper.shape[0], coupling.shape[1]
    top = sp.hstack([stiffness_upper, coupling], format="csr")
    top.sort_indices()
    indptr = np.concatenate([top.indptr, top.indptr[-1] + np.arange(1, nb + 1)])
    indices = np.concatenate([top.indices, np.arange(n, n + nb)])
    data = np.concatenate([top.data, np.zeros(nb)])
    return sp.csr_array(
        (data, indices.astype(np.int32), indptr.astype(np.int32)), shape=(n + nb, n + nb)
    )


def _pardiso_schur(
    stiffness_upper: sp.csr_array, coupling: sp.csr_array, stats: dict | None = None
) -> np.ndarray:
    """``B^T K^-1 B`` as the (negated) Schur complement of ``[[K, B], [B^T, 0]]``.

    MKL PARDISO factorizes the K block (nested-dissection ordering, symmetric
    indefinite driver; K itself is positive definite so no pivot is perturbed)
    and returns the dense Schur complement ``0 - B^T K^-1 B`` of the trailing
    block (``iparm[35] = 1``), so no right-hand side is ever solved.
    """
    pardiso = _pardiso_library()
    a = _augmented_upper(stiffness_upper, coupling)
    n, nb = a.shape[0], coupling.shape[1]
    pt = np.zeros(64, dtype=np.int64)
    iparm = np.zeros(64, dtype=np.int32)
    iparm[0] = 1  # use the values below, defaults elsewhere
    iparm[1] = 2  # METIS nested dissection
    iparm[9] = 8  # pivot perturbation 1e-8 (never triggered for an SPD block)
    iparm[34] = 1  # zero-based indices
    iparm[35] = 1  # Schur complement of the rows flagged in perm
    perm = np.zeros(n, dtype=np.int32)
    perm[n - nb:] = 1
    schur = np.zeros((nb, nb))
    rhs = np.zeros(n)
    error = ctypes.c_int32(0)
    i32 = ctypes.POINTER(ctypes.c_int32)

    def call(phase: int) -> None:
        pardiso(
            pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(-2)),
            ctypes.byref(ctypes.c_int32(phase)),
            ctypes.byref(ctypes.c_int32(n)),
            a.data.ctypes.data,
            a.indptr.ctypes.data_as(i32),
            a.indices.ctypes.data_as(i32),
            perm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(1)),
            iparm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(0)),
            rhs.ctypes.data,
            schur.ctypes.data,
            ctypes.byref(error),
        )

    try:
        call(12)
        if error.value != 0:
            raise RuntimeError(f"PARDISO factorization failed with error {error.value}")
        if iparm[13] != 0:
            raise RuntimeError(f"PARDISO perturbed {iparm[13]} pivots: stiffness not definite")
        if stats is not None:
            stats.update(factor_nonzeros=int(iparm[17]), gflop=float(iparm[18]) / 1e3,
                         peak_kb=int(max(iparm[14], iparm[15] + iparm[16])))
    finally:
        call(-1)
    return np.negative(schur, out=schur)


def _full_from_upper(upper: sp.csr_array) -> sp.csc_array:
    """Symmetric matrix from its upper triangle, keeping explicitly stored zeros.

    The stored pattern is the element connectivity; with nu = 0 some
    stiffness entries are exactly zero, and dropping them misleads the
    minimum-degree ordering (four times the fill at 60 x 60).
    """
    coo = upper.tocoo()
    off = coo.row != coo.col
    rows = np.concatenate([coo.row, coo.col[off]])
    cols = np.concatenate([coo.col, coo.row[off]])
    vals = np.concatenate([coo.data, coo.data[off]])
    return sp.coo_array((vals, (rows, cols)), shape=upper.shape).tocsc()


def _superlu_schur(stiffness_upper: sp.csr_array, coupling: sp.csr_array) -> np.ndarray:
    """``B^T K^-1 B`` with scipy's SuperLU, as the Schur complement of ``[[K, B], [B^T, 0]]``.

    SuperLU has no Schur-complement option, so the bordered matrix is factorized
    in a fixed order (``permc_spec="NATURAL"``, diagonal pivots): K's dofs in
    the fill-reducing order SuperLU chooses for K alone (minimum degree on
    ``K^T + K``, from a first factorization of K), then the border. The trailing
    blocks of the factors then hold the Schur complement, ``L22 U22 =
    -B^T K^-1 B``. About ten times faster than block solves with n
    right-hand sides.
    """
    full = _full_from_upper(stiffness_upper)
    options = {"SymmetricMode": True}
    first = splu(full, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=options)
    position = first.perm_c.copy()
    del first
    n, nb = full.shape[0], coupling.shape[1]
    order = np.concatenate([np.argsort(position), np.arange(n, n + nb)])
    bordered = sp.bmat([[full, coupling], [coupling.T, None]], format="csr")
    del full
    bordered = bordered[order][:, order].tocsc()
    lu = splu(bordered, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=options)
    del bordered
    tail = np.arange(n, n + nb)
    if not (np.array_equal(lu.perm_c[n:], tail) and np.array_equal(lu.perm_r[n:], tail)):
        raise RuntimeError("SuperLU reordered the border; the Schur complement is not trailing")
    lower = lu.L[n:, n:].toarray()
    upper = lu.U[n:, n:].toarray()
    del lu
    schur = lower @ upper
    return np.negative(schur, out=schur)


def condensed_flexibility(
    stiffness_upper: sp.csr_array,
    left: sp.csr_array,
    right: sp.csr_array | None = None,
    solver: str = "auto",
) -> np.ndarray:
    """Dense ``left K^-1 right^T`` from one sparse factorization of K.

    Parameters
    ----------
    stiffness_upper : scipy.sparse.csr_array, shape (N, N)
        Upper triangle of the symmetric positive definite stiffness [N/m].
    left, right : scipy.sparse.csr_array, shape (n, N)
        Observation and load operators; ``right = left`` when omitted (then the
        result is symmetric and the PARDISO path condenses onto n, not 2n, dofs).
    solver : {"auto", "pardiso", "superlu"}
        Both compute the Schur complement of the bordered matrix
        ``[[K, B], [B^T, 0]]``, ``B = [right^T, left^T]`` (or ``left^T``),
        which is ``-B^T K^-1 B``; no right-hand side is solved.
        ``"pardiso"``: during one factorization by MKL PARDISO (the PyPI
        package ``mkl``, which ``pypardiso`` installs; called directly because
        ``pypardiso`` does not expose the Schur option), multithreaded;
        ``"superlu"``: scipy's SuperLU with the border ordered last (two
        factorizations, single-threaded, about 5-10 times slower and 3-4 times
        the memory); ``"auto"``: PARDISO when it loads, SuperLU otherwise.

    Returns
    -------
    ndarray, shape (n, n)
        ``left K^-1 right^T`` [m/N for a stiffness in N/m].
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if solver == "auto":
        solver = "pardiso" if pardiso_available() else "superlu"
    schur = _pardiso_schur if solver == "pardiso" else _superlu_schur
    if right is None:
        return schur(stiffness_upper, sp.csr_array(left.T))
    n = left.shape[0]
    full = schur(stiffness_upper, sp.csr_array(sp.vstack([right, left]).T))
    return np.ascontiguousarray(full[n:, :n])
