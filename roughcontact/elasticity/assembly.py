"""Assembly of the block's stiffness and of its top-face load and observation operators.

The mesh is structured (``roughcontact.elasticity.mesh``): every element in
one layer has the same shape, so the global stiffness is the scatter of one
reference element stiffness per distinct element shape
(``roughcontact.elasticity.elements.reference_element``). Only this scatter
over the structured mesh is done here, because scikit-fem's generic vector
assembly is an order of magnitude slower for this regular mesh (it
recomputes the same element matrix for every element).
``assemble_stiffness_generic`` is the slow reference path used to check the
scatter.

The global stiffness [N/m] is for the modulus passed (per unit modulus when
``E = 1``); the load operators are in m^2 (force per unit pressure).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementVector, MeshHex, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

from roughcontact.elasticity.dofs import dof_map
from roughcontact.elasticity.elements import (
    ReferenceElement,
    dof_components,
    reference_element,
    reference_top_face,
)
from roughcontact.elasticity.mesh import HexMesh, node_numbers, numbered_slabs


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
    parts, numbers, n_nodes = numbered_slabs(mesh)
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
    kind = mesh.element_type
    p = kind.order
    skmesh = MeshHex.init_tensor(
        np.asarray(mesh.x_edges), np.asarray(mesh.y_edges), np.asarray(mesh.z_edges)
    )
    basis = Basis(skmesh, ElementVector(kind.basis()), intorder=kind.intorder)
    K = asm(linear_elasticity(*lame_parameters(E, nu)), basis).tocsr()
    lattice = [_axis_lattice(mesh.x_edges, p), _axis_lattice(mesh.y_edges, p),
               _axis_lattice(mesh.z_edges, p)]
    index = [np.abs(basis.doflocs[a][:, None] - lattice[a][None, :]).argmin(axis=1)
             for a in range(3)]
    numbers = node_numbers(mesh)
    nodes = numbers[index[2], index[1], index[0]]
    ours = dof_map(mesh, base).equation[3 * nodes + dof_components(basis)]
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


def top_face_layout(mesh: HexMesh, grid) -> tuple[int, int, float, float]:
    """How a mesh's top face covers the contact ``grid`` [nx, ny]: ``(r, p, dx, dy)``,
    ``r x r`` finite-element faces of order ``p`` per contact element, whose sides are
    ``dx`` and ``dy`` [m]; ValueError unless the mesh's plan refines the grid evenly."""
    nx, ny = grid
    ex, ey, _ = mesh.n_elements
    if ex % nx or ey % ny or ex // nx != ey // ny:
        raise ValueError(f"mesh plan {ex} x {ey} is not a refinement of the grid {nx} x {ny}")
    return (ex // nx, mesh.order, mesh.x_edges[1] - mesh.x_edges[0],
            mesh.y_edges[1] - mesh.y_edges[0])


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
    r, p, dx, dy = top_face_layout(mesh, grid)
    face = reference_top_face(mesh.element, dx, dy)
    _, numbers, _ = numbered_slabs(mesh)
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
