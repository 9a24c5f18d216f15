"""Thermal influence of a finite block's contact face, by a scalar Laplace problem.

The block is the elastic model's (:class:`~roughcontact.elasticity.influence.BlockGeometry`:
its plan size, thickness, contact grid and mesh preset, the same structured
hexahedral mesh of :func:`~roughcontact.elasticity.influence.build_mesh`, graded
and coarsened in plan with depth, the coarse and fine slabs tied by the same
hanging-node interpolation); the field is the temperature ``T`` [K] of steady
conduction, ``div(k grad T) = 0``, with

- the bottom face ``z = -L`` isothermal (``T = 0``; the clamped base's nodes),
- the lateral faces insulated (no flux; the elastic block's sides are free,
  not periodic, so both models see the same finite body),
- a flux density ``q_j`` [W/m^2] into the body, uniform on each contact
  element ``j`` of the top face, and no flux elsewhere on it.

The influence (thermal compliance) ``R[i, j]`` [K m^2/W] is the mean
temperature of contact element ``i`` per unit flux density on element ``j``:

    R = F K^-1 F^T / (A k),

``K`` the conduction matrix for unit conductivity [m] (``int grad N_a . grad
N_b dV``, scikit-fem's ``laplace`` form on one box per element shape, scattered
over the structured mesh), ``F`` (n x N) the consistent nodal heat of a unit
flux density on each contact element (``int_k N_a dA`` [m^2]) and ``A`` the
element area. This Galerkin (patch-averaged) form is symmetric positive
definite with no symmetrization, and its rows sum to ``L / k`` exactly: a uniform
flux gives the linear field ``T = q (z + L) / k``, which every element and every
hanging-node tie reproduces, so full contact has the conductance ``k A_n / L``
to round-off (the bulk resistance). With one trilinear element per contact
element (the paper's mesh) ``F = A R_c`` (``R_c`` the centre evaluation), so
``R = A R_c K^-1 R_c^T / k``, the same form as the elastic matrix of that mesh
(Eq 39 of Kumar et al. 2006); on the finer presets the elastic matrix is the
symmetrized centre-point value and this one the patch average.

``R`` is proportional to ``1 / k`` for a given geometry, so
:func:`unit_conductivity_influence` returns ``k R`` [m] (a function of the
geometry and mesh only, worth storing as the elastic ``E C`` is) and
:func:`block_thermal_influence` divides it by ``k``. The electrical resistance
of the same face is the same problem with the electrical conductivity ``1 /
rho_e`` [S/m] in place of ``k`` (``R`` then in Ohm m^2).

Cost: one unknown a node (a third of the elastic model's), one sparse
factorization (MKL PARDISO or SuperLU, :mod:`roughcontact.elasticity.sparse_solve`)
condensed onto the ``n`` contact elements. Measured against the elastic build
in ``benchmarks/bench_thermal_influence.py``.

References
----------
H. S. Carslaw and J. C. Jaeger, Conduction of Heat in Solids, 2nd ed., Oxford
(1959), Ch 1 (the steady conduction equation and its boundary conditions).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, FacetBasis, LinearForm, MeshHex, asm
from skfem.models.poisson import laplace

from roughcontact.elasticity.assembly import top_face_layout
from roughcontact.elasticity.dofs import dof_map
from roughcontact.elasticity.elements import ELEMENTS
from roughcontact.elasticity.influence import BlockGeometry, build_mesh
from roughcontact.elasticity.mesh import HexMesh, numbered_slabs
from roughcontact.elasticity.sparse_solve import condensed_flexibility, resolve_solver

__all__ = ["assemble_conduction", "block_thermal_influence", "top_face_flux",
           "unit_conductivity_influence"]


def _box(dx: float, dy: float, dz: float) -> MeshHex:
    """One hexahedron ``[0, dx] x [0, dy] x [0, dz]`` [m] as a scikit-fem mesh."""
    return MeshHex.init_tensor(np.array([0.0, dx]), np.array([0.0, dy]), np.array([0.0, dz]))


def _reference_conduction(element: str, dx: float, dy: float, dz: float):
    """Conduction matrix of one box for unit conductivity [m] and its nodes' lattice offsets.

    Returns ``(offsets, matrix)``: ``offsets`` (q, 3) integer lattice offsets
    (x, y, z) of the local nodes from the box's lowest corner (lattice step
    ``edge / p``), ``matrix`` (q, q) ``int grad N_a . grad N_b dV``.
    """
    kind = ELEMENTS[element]
    p = kind.order
    basis = Basis(_box(dx, dy, dz), kind.basis(), intorder=kind.intorder)
    matrix = asm(laplace, basis).toarray()
    offsets = np.rint(basis.doflocs.T / (np.array([dx, dy, dz]) / p)).astype(np.int64)
    return offsets, matrix


def _node_conduction(mesh: HexMesh) -> sp.csr_array:
    """Conduction matrix over every node of the mesh (each slab's own copy of its
    interface plane; unit conductivity) [m], one layer's elements at a time."""
    parts, numbers, n_nodes = numbered_slabs(mesh)
    total = sp.csr_array((n_nodes, n_nodes))
    references = {}
    for slab, lattice in zip(parts, numbers, strict=True):
        ex, ey, ez = slab.n_elements
        p = slab.order
        dx = slab.x_edges[1] - slab.x_edges[0]
        dy = slab.y_edges[1] - slab.y_edges[0]
        iy, ix = np.divmod(np.arange(ex * ey), ex)
        for layer in range(ez):
            key = (dx, dy, slab.z_edges[layer + 1] - slab.z_edges[layer])
            if key not in references:
                references[key] = _reference_conduction(slab.element, *key)
            offsets, matrix = references[key]
            nodes = lattice[p * layer + offsets[:, 2], p * iy[:, None] + offsets[:, 1],
                            p * ix[:, None] + offsets[:, 0]]
            q = offsets.shape[0]
            rows = np.repeat(nodes, q, axis=1).ravel()
            cols = np.tile(nodes, (1, q)).ravel()
            values = np.tile(matrix.ravel(), nodes.shape[0])
            total = total + sp.coo_array((values, (rows, cols)), shape=total.shape).tocsr()
    return total


def _tying(mesh: HexMesh) -> sp.csr_array:
    """``T`` (nodes x unknowns): every node's temperature from the unknowns.

    The unknowns are the nodes neither on the isothermal base nor hanging;
    their numbering and the hanging-node interpolation are the elastic
    model's (:func:`~roughcontact.elasticity.dofs.dof_map` of the clamped base,
    whose fixed nodes are the base's), read off its first displacement
    component.
    """
    dofs = dof_map(mesh, "clamped")
    equation = dofs.equation[0::3]
    free = equation >= 0
    columns = np.full(dofs.n_free, -1, dtype=np.int64)
    columns[equation[free]] = np.arange(np.count_nonzero(free))
    if dofs.tying is None:
        nodes = np.flatnonzero(free)
        return sp.csr_array((np.ones(nodes.size), (nodes, columns[equation[free]])),
                            shape=(equation.size, nodes.size))
    first = dofs.tying[0::3].tocoo()  # rows: nodes; columns: equations of component x
    keep = columns[first.col] >= 0
    return sp.csr_array((first.data[keep], (first.row[keep], columns[first.col[keep]])),
                        shape=(equation.size, int(np.count_nonzero(free))))


def assemble_conduction(mesh: HexMesh) -> tuple[sp.csr_array, sp.csr_array]:
    """Conduction matrix of the block on its unknowns, and the tying ``T``.

    Returns ``(matrix, tying)``: ``matrix`` (N, N) ``T^T K_nodes T`` [m] for unit
    conductivity, symmetric positive definite (the isothermal base removes the
    constant), sorted indices; ``tying`` (nodes, N) as :func:`_tying`.
    """
    tying = _tying(mesh)
    matrix = (tying.T @ (_node_conduction(mesh) @ tying)).tocsr()
    matrix.sum_duplicates()
    matrix.sort_indices()
    return matrix, tying


def top_face_flux(mesh: HexMesh, grid: tuple[int, int]) -> sp.csr_array:
    """``F`` (n, nodes): nodal heat [W] of a unit flux density [W/m^2] on each contact element.

    Row ``k = iy * nx + ix``: ``int_k N_a dA`` [m^2] over the finite-element
    faces of the top face that contact element ``k`` covers (``r x r`` of them,
    ``r`` the in-plane refinement).
    """
    nx, ny = grid
    ex, ey, _ = mesh.n_elements
    r, p, dx, dy = top_face_layout(mesh, grid)
    kind = mesh.element_type
    dz = 0.5 * (dx + dy)
    box = _box(dx, dy, dz)
    face = FacetBasis(box, kind.basis(), facets=box.facets_satisfying(
        lambda x: np.isclose(x[2], dz)), intorder=kind.intorder)
    load = asm(LinearForm(lambda v, w: v), face)
    offsets = np.rint(face.doflocs.T / (np.array([dx, dy, dz]) / p)).astype(np.int64)
    on_top = offsets[:, 2] == p
    offsets, load = offsets[on_top], load[on_top]
    _, numbers, n_nodes = numbered_slabs(mesh)
    top = numbers[-1][-1]
    fy, fx = np.meshgrid(np.arange(ey), np.arange(ex), indexing="ij")
    owner = ((fy // r) * nx + fx // r).reshape(-1, 1)
    nodes = top[p * fy.reshape(-1, 1) + offsets[:, 1], p * fx.reshape(-1, 1) + offsets[:, 0]]
    return sp.coo_array((np.broadcast_to(load, nodes.shape).ravel(),
                         (np.broadcast_to(owner, nodes.shape).ravel(), nodes.ravel())),
                        shape=(nx * ny, n_nodes)).tocsr()


def unit_conductivity_influence(geom: BlockGeometry, *, solver: str = "auto") -> np.ndarray:
    """Thermal influence of the block times its conductivity, ``k R`` [m] (module docstring).

    ``k R[i, j]`` [m] is the mean temperature rise of contact element ``i``
    times ``k`` per unit flux density on element ``j``: a function of the
    geometry and mesh only (``geom.E``, ``geom.nu`` and ``geom.base`` are not
    used: the base is isothermal, the sides insulated). Rows sum to the
    thickness ``L`` (to round-off) and the matrix is symmetric positive definite.

    Parameters
    ----------
    geom : BlockGeometry
        The block, its contact grid and mesh preset, as for the elastic influence.
    solver : {"auto", "pardiso", "superlu"}
        Sparse solver of the condensation
        (:func:`roughcontact.elasticity.sparse_solve.condensed_flexibility`).

    Returns
    -------
    ndarray, shape (n, n), n = nx * ny
        ``k R`` [m], rows and columns row-major over y then x.
    """
    solver = resolve_solver(solver)
    mesh = build_mesh(geom)
    matrix, tying = assemble_conduction(mesh)
    flux = (top_face_flux(mesh, geom.grid) @ tying).tocsr()
    result = condensed_flexibility(sp.triu(matrix, format="csr"), flux, None, solver)
    result /= geom.element_area
    return result


def block_thermal_influence(geom: BlockGeometry, conductivity: float, *,
                            solver: str = "auto") -> np.ndarray:
    """Thermal influence ``R`` [K m^2/W] of the block of conductivity ``k`` [W/(m K)].

    ``unit_conductivity_influence(geom) / k``; with the electrical conductivity
    ``1 / rho_e`` [S/m] it is the electrical one [Ohm m^2].
    """
    conductivity = float(conductivity)
    if not (np.isfinite(conductivity) and conductivity > 0.0):
        raise ValueError(f"conductivity must be a finite positive W/(m K), got {conductivity!r}")
    return unit_conductivity_influence(geom, solver=solver) / conductivity
