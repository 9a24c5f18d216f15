"""Influence coefficients of a finite elastic block from a finite-element model.

The contact model (Eq 16 of Kumar et al. 2006) needs the influence matrix

    u_i = sum_j C[i, j] p_j,

where ``p_j`` [Pa] is the uniform pressure on contact element j of the top
face and ``u_i`` [m] the normal displacement, positive into the body (the
compression direction, the same sign as the half-space matrix), at the centre
point of contact element i. Elements are numbered row-major over y then x,
``k = iy * nx + ix``, so that ``C @ p.ravel()`` matches surface arrays of
shape ``(ny, nx)``.

The paper obtained C from an ANSYS model of the finite block (Table 1:
9 mm x 9 mm, L = 10 mm, 60 x 60 contact elements, 5 element layers, E =
5.11e8 Pa, nu = 0). ``BlockGeometry`` describes such a block and the mesh
used to model it; ``influence_matrix`` builds C from one sparse factorization
of the finite-element stiffness, condensed onto the contact loads and
observation points (a Schur complement, see
``roughcontact.elasticity.sparse_solve.condensed_flexibility``).

Scaling: C is proportional to 1/E for fixed geometry and nu, so
``unit_modulus_influence(geom)`` returns ``E * C`` (a function of geometry
and nu only, worth storing) and ``influence_matrix(geom)`` divides it by E.

Mesh presets (``MESH_PRESETS``) trade accuracy for cost. Measured at the
paper's 60 x 60 over 9 mm (``benchmarks/bench_influence.py``, 2 cores, MKL
PARDISO), self compliance E C_ii / h against the mesh-converged value:

============  =======  ======  ===========  ========================
preset        dofs     time    peak memory  diagonal
============  =======  ======  ===========  ========================
paper         55 815   4 s     0.7 GB       -82 %
graded        145 119  11 s    1.7 GB       -51 %
refined       118 458  11 s    1.7 GB       -2 % (nu <= 0.3)
converged     470 916  83 s    7.6 GB       within 2 % (nu <= 0.49)
============  =======  ======  ===========  ========================

The paper's mesh (5 trilinear layers 2 mm thick under 0.15 mm contact
elements) is far too stiff locally; it reproduces the bulk response (rows
summing to L/E) but not the near field that sets real contact area and peak
pressure. Reproducing the paper and being right are separate targets: use
``mesh="paper"`` for the former, ``mesh="converged"`` for the latter.

Thin blocks: a layer thinner than its in-plane finite elements has a near
field of width about L (for nu = 0 each column compresses on its own, so C
tends to (L / E) I), which such elements cannot resolve. The graded presets
therefore refine in plan until no finite element is wider than the block is
thick (``BlockGeometry.mesh_spec``). Measured on 6 x 6 contact elements of
0.15 mm over L = 10 um, before this rule: "converged" gave an indefinite C and
"refined" a diagonal 30-60 % too large; with it both give C_ii = L / E within
1e-4 and off-diagonal entries below 1e-4 of the diagonal. An explicit
``MeshSpec`` is used as given (a warning is logged when it does not resolve
the thickness); so is the "paper" preset, the paper's model.

``hybrid_unit_modulus_influence`` is a cheaper route to the converged
interior: Love's half-space near field plus the finite-body correction from a
finite-element model on a coarser contact grid (about 7 times cheaper at
60 x 60, contact quantities within 0.5 %; edge elements less accurate).
:class:`roughcontact.elasticity.operators.BlockOperator` applies the same operator
without forming it (FFT plus a coarse dense product), for grids whose dense
matrix would not fit (256 x 256: 34 GB).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from roughcontact.elasticity.assembly import assemble_stiffness, top_face_operators
from roughcontact.elasticity.dofs import SUPPORTS
from roughcontact.elasticity.elements import ELEMENTS
from roughcontact.elasticity.mesh import HexMesh, node_count, slabs, structured_mesh
from roughcontact.elasticity.sparse_solve import resolve_solver
from roughcontact.elasticity.symmetry import block_mirrors, mirror_condensed_flexibility

__all__ = [
    "MAX_ELEMENT_ASPECT",
    "MAX_SLENDERNESS",
    "MESH_PRESETS",
    "BlockGeometry",
    "CostEstimate",
    "MeshSpec",
    "ModelTooLarge",
    "build_mesh",
    "check_memory",
    "estimate_cost",
    "influence_matrix",
    "layer_coarsening",
    "layer_thicknesses",
    "mirror_classes",
    "shape_problems",
    "unit_modulus_influence",
]

logger = logging.getLogger("roughcontact.influence")

GB = 1e9


@dataclass(frozen=True)
class MeshSpec:
    """How the block is meshed.

    Attributes
    ----------
    element : {"hex8", "hex20", "hex27"}
        Trilinear, 20-node serendipity or 27-node triquadratic hexahedra.
        Trilinear elements lock as nu -> 0.5; use a quadratic element for nu
        near 0.5.
    refinement : int
        Finite elements per contact element along x and along y. The graded
        presets raise it for blocks thinner than their finite elements (see
        ``BlockGeometry.mesh_spec``); an explicit spec is used as given.
    layers : int or None
        Number of uniform layers through the thickness (the paper: 5); None
        for a graded mesh.
    top_layer : float or None
        Graded mesh only: thickness of the top layer as a multiple of the
        in-plane finite-element size.
    growth : float
        Graded mesh only: largest ratio of consecutive layer thicknesses
        (1 < growth <= 1.5); layers grow geometrically from the top face down.
    coarsen_at : float or None
        Plan coarsening with depth (None: the plan mesh is the same in every
        layer). Going down, the in-plane element size grows by 2 (or 3 or 5,
        whichever divides the element counts) before a layer whose thickness
        is at least ``coarsen_at`` times the coarsened size, keeping at least
        two elements per direction (``layer_coarsening``); the coarse and fine
        slabs are tied by hanging-node constraints. Keeps elements near cubic
        and the fine mesh near the surface, where the contact near field lives.
        Plan counts with no factor 2, 3 or 5 (a prime grid) cannot coarsen.
    """

    element: str = "hex8"
    refinement: int = 1
    layers: int | None = 5
    top_layer: float | None = None
    growth: float = 1.5
    coarsen_at: float | None = None

    def __post_init__(self) -> None:
        if self.element not in ELEMENTS:
            raise ValueError(f"MeshSpec.element must be one of {tuple(ELEMENTS)}, "
                             f"got {self.element!r}")
        if int(self.refinement) != self.refinement or self.refinement < 1:
            raise ValueError(f"MeshSpec.refinement must be a positive integer, "
                             f"got {self.refinement!r}")
        if (self.layers is None) == (self.top_layer is None):
            raise ValueError("MeshSpec: give exactly one of layers (uniform) and "
                             "top_layer (graded)")
        if self.layers is not None and (int(self.layers) != self.layers or self.layers < 1):
            raise ValueError(f"MeshSpec.layers must be a positive integer, got {self.layers!r}")
        if self.top_layer is not None and not self.top_layer > 0:
            raise ValueError(f"MeshSpec.top_layer must be positive, got {self.top_layer!r}")
        if not 1.0 < self.growth <= 1.5:
            raise ValueError(f"MeshSpec.growth must lie in (1, 1.5], got {self.growth!r}")
        if self.coarsen_at is not None and not self.coarsen_at > 0:
            raise ValueError(f"MeshSpec.coarsen_at must be positive or None, "
                             f"got {self.coarsen_at!r}")


#: Named meshes (cost and accuracy at the paper's 60 x 60 over 9 mm, L = 10 mm,
#: from ``benchmarks/bench_influence.py``; errors of the self compliance and the
#: nearest neighbours against a fine reference mesh):
#:
#: - ``"paper"``: Table 1 of Kumar et al. 2006, 5 uniform trilinear layers, one
#:   element per contact element. Diagonal 82 % too small.
#: - ``"graded"``: trilinear, one element per contact element, top layer the
#:   element size, growth 1.25 (the pre-project prototype). Diagonal 51 % too small.
#: - ``"refined"``: trilinear, 2 x 2 elements per contact element, graded
#:   (growth 1.5) and coarsened in plan with depth. Diagonal within 2 %, near
#:   neighbours within 8 % for nu <= 0.3; locks as nu -> 0.5 (-27 % at 0.49).
#: - ``"converged"``: 20-node serendipity, otherwise as "refined". Diagonal and
#:   near neighbours within 2.5 % for 0 <= nu <= 0.49.
MESH_PRESETS = MappingProxyType({
    "paper": MeshSpec(element="hex8", refinement=1, layers=5),
    "graded": MeshSpec(element="hex8", refinement=1, layers=None, top_layer=1.0, growth=1.25),
    "refined": MeshSpec(element="hex8", refinement=2, layers=None, top_layer=1.0, growth=1.5,
                        coarsen_at=1.0),
    "converged": MeshSpec(element="hex20", refinement=2, layers=None, top_layer=1.0,
                          growth=1.5, coarsen_at=1.0),
})


@dataclass(frozen=True)
class BlockGeometry:
    """A linear elastic block pressed on its top face, and the mesh modelling it.

    Attributes
    ----------
    size : (Lx, Ly)
        Plan size of the block (the nominal contact area) [m].
    thickness : float
        Block thickness L [m].
    grid : (nx, ny)
        Contact elements on the top face along x and y.
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio, 0 <= nu < 0.5.
    base : {"clamped", "sliding"}
        Bottom face bonded to a rigid plate (all displacements zero, the
        default) or resting on a frictionless rigid plate (normal displacement
        zero, in-plane rigid-body motion removed). Lateral faces are free.
    mesh : str or MeshSpec
        A key of ``MESH_PRESETS`` or an explicit ``MeshSpec``.

    The defaults are the paper's model (Table 1).
    """

    size: tuple[float, float] = (9e-3, 9e-3)
    thickness: float = 10e-3
    grid: tuple[int, int] = (60, 60)
    E: float = 5.11e8
    nu: float = 0.0
    base: str = "clamped"
    mesh: str | MeshSpec = field(default="paper")

    def __post_init__(self) -> None:
        # normalise lists from a config file to tuples and numbers to float/int
        converters = {
            "size": lambda v: tuple(float(s) for s in v),
            "grid": lambda v: tuple(int(g) if float(g) == int(g) else float(g) for g in v),
            "thickness": float, "E": float, "nu": float,
        }
        for name, convert in converters.items():
            try:
                object.__setattr__(self, name, convert(getattr(self, name)))
            except (TypeError, ValueError):
                raise ValueError(f"BlockGeometry.{name} must be numeric, "
                                 f"got {getattr(self, name)!r}") from None
        if len(self.size) != 2 or not all(s > 0 for s in self.size):
            raise ValueError(f"BlockGeometry.size must be two positive lengths [m], "
                             f"got {self.size!r}")
        if not self.thickness > 0:
            raise ValueError(f"BlockGeometry.thickness must be positive [m], "
                             f"got {self.thickness!r}")
        if len(self.grid) != 2 or not all(int(g) == g and g >= 1 for g in self.grid):
            raise ValueError(f"BlockGeometry.grid must be two integers >= 1, got {self.grid!r}")
        if not self.E > 0:
            raise ValueError(f"BlockGeometry.E must be positive [Pa], got {self.E!r}")
        if not 0.0 <= self.nu < 0.5:
            raise ValueError(f"BlockGeometry.nu must satisfy 0 <= nu < 0.5, got {self.nu!r}")
        if self.base not in SUPPORTS:
            raise ValueError(f"BlockGeometry.base must be one of {tuple(SUPPORTS)}, "
                             f"got {self.base!r}")
        if isinstance(self.mesh, str) and self.mesh not in MESH_PRESETS:
            raise ValueError(f"BlockGeometry.mesh must be one of {tuple(MESH_PRESETS)} "
                             f"or a MeshSpec, got {self.mesh!r}")
        if not isinstance(self.mesh, str | MeshSpec):
            raise ValueError(f"BlockGeometry.mesh must be a preset name or a MeshSpec, "
                             f"got {self.mesh!r}")

    @property
    def mesh_spec(self) -> MeshSpec:
        """The ``MeshSpec`` used: an explicit spec as given, a preset resolved by name.

        A graded preset (``layers=None``) on a block thinner than its in-plane
        finite-element size gets the refinement ``ceil(max(hx, hy) / L)``, so
        that no finite element is wider than the block is thick: the near
        field of a thin layer has width about L (module docstring). Blocks at
        least as thick as the finite elements (the paper's 10 mm under 0.15 mm
        elements) keep the preset unchanged.
        """
        if not isinstance(self.mesh, str):
            return self.mesh
        spec = MESH_PRESETS[self.mesh]
        if spec.layers is None:
            # smallest refinement whose elements are at most L wide (1e-9: rounding)
            needed = math.ceil(max(self.spacing) / self.thickness * (1.0 - 1e-9))
            if needed > spec.refinement:
                spec = dataclasses.replace(spec, refinement=needed)
        return spec

    @property
    def spacing(self) -> tuple[float, float]:
        """Contact element size (hx, hy) [m]."""
        return self.size[0] / self.grid[0], self.size[1] / self.grid[1]

    @property
    def n_elements(self) -> int:
        """Number of contact elements n = nx * ny."""
        return self.grid[0] * self.grid[1]

    @property
    def element_area(self) -> float:
        """Contact element area hx * hy [m^2]."""
        hx, hy = self.spacing
        return hx * hy


def layer_thicknesses(geom: BlockGeometry) -> tuple[float, ...]:
    """Thicknesses of the element layers from the top face down [m].

    Uniform meshes: ``layers`` equal layers. Graded meshes: the top layer is
    ``top_layer * h`` (h = in-plane finite-element size, the smaller of
    hx/r and hy/r) and the layers grow geometrically downwards; the number of
    layers is the smallest that reaches the thickness L with ratio ``growth``,
    and the ratio is then lowered so that the layers sum to L exactly (top
    layer unchanged). A block thinner than the top layer has one layer.
    """
    spec = geom.mesh_spec
    L = geom.thickness
    if spec.layers is not None:
        return (L / spec.layers,) * spec.layers
    t0 = spec.top_layer * min(geom.spacing) / spec.refinement
    if t0 >= L:
        return (L,)
    g = spec.growth
    count = math.ceil(math.log(1.0 + L * (g - 1.0) / t0) / math.log(g))

    def depth(ratio: float) -> float:
        return t0 * (ratio**count - 1.0) / (ratio - 1.0)

    if depth(1.0 + 1e-12) >= L:  # uniform layers of t0 already reach L
        count = math.ceil(L / t0)
        return (L / count,) * count
    low, high = 1.0 + 1e-12, g
    for _ in range(200):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if depth(mid) < L else (low, mid)
    ratio = 0.5 * (low + high)
    layers = t0 * ratio ** np.arange(count)
    layers *= L / layers.sum()
    return tuple(float(t) for t in layers)


def layer_coarsening(geom: BlockGeometry) -> tuple[int, ...]:
    """Plan coarsening factor of each layer from the top face down (``MeshSpec.coarsen_at``).

    Factor d: the layer's finite elements are d times larger in plan than the
    top layer's. Going down, the factor is multiplied by the smallest of 2, 3
    and 5 that divides both current plan element counts (leaving at least two
    elements per direction), before a layer at least ``coarsen_at`` times as
    thick as the coarsened element size. All 1 without coarsening.
    """
    spec = geom.mesh_spec
    layers = layer_thicknesses(geom)
    if spec.coarsen_at is None:
        return (1,) * len(layers)
    ex, ey = geom.grid[0] * spec.refinement, geom.grid[1] * spec.refinement
    size = min(geom.spacing) / spec.refinement
    factor = 1
    factors = [1]
    for t in layers[1:]:
        while True:
            step = next((f for f in (2, 3, 5) if (ex // factor) % f == 0
                         and (ey // factor) % f == 0
                         and min(ex, ey) // (factor * f) >= 2), None)
            if step is None or t < spec.coarsen_at * step * factor * size:
                break
            factor *= step
        factors.append(factor)
    return tuple(factors)


def build_mesh(geom: BlockGeometry) -> HexMesh:
    """The structured finite-element mesh of the block (``roughcontact.elasticity.mesh``)."""
    spec = geom.mesh_spec
    plan = (geom.grid[0] * spec.refinement, geom.grid[1] * spec.refinement)
    return structured_mesh(geom.size, geom.thickness, plan, layer_thicknesses(geom),
                           spec.element, layer_coarsening(geom))


#: Most times a block may be as thick as its narrower plan side. Beyond it the block
#: is a slender column with free sides: its stiffness is ill conditioned (measured on
#: a 0.126 x 0.094 mm patch: MKL PARDISO perturbs pivots, "stiffness not definite",
#: from about 40 times with the "converged" mesh, 85 "graded", 100 "refined") and
#: its response is the column's compression, not that of a body under a patch (the
#: paper's block: 10 mm under 9 mm, 1.1).
MAX_SLENDERNESS = 10.0
#: Most times the longest edge of a finite element may exceed its shortest. Beyond it
#: the elements under one contact element cannot carry its near field: on the same
#: patch, 32 x 32 contact elements, P = 0.1 MPa, the "paper" mesh put 70, 34, 14, 6
#: and 3 elements in contact at aspect ratios 7, 20, 68, 203 and 678 (blocks 0.1 to
#: 10 mm thick), the "refined" mesh 225 at every thickness. The paper's own mesh has
#: 13.3 (2 mm layers under 0.15 mm elements).
MAX_ELEMENT_ASPECT = 20.0


def shape_problems(geom: BlockGeometry) -> list[str]:
    """Why a block's finite-element model cannot be trusted, as sentences (none: usable).

    A block more than :data:`MAX_SLENDERNESS` times as thick as its narrower
    plan side, and a mesh whose elements are more than
    :data:`MAX_ELEMENT_ASPECT` times longer than wide
    (:attr:`~roughcontact.elasticity.mesh.HexMesh.aspect_ratio` of
    :func:`build_mesh`). Builds nothing but the element edges.
    """
    problems = []
    slenderness = geom.thickness / min(geom.size)
    if slenderness > MAX_SLENDERNESS * (1.0 + 1e-9):  # 1e-9: rounding of mm to m
        problems.append(f"the block is {slenderness:.4g} times as thick as its narrower side "
                        f"({geom.thickness:.3g} m under {geom.size[0]:.3g} x "
                        f"{geom.size[1]:.3g} m), more than {MAX_SLENDERNESS:g}: a slender "
                        "column, whose stiffness the sparse solver cannot factorize reliably")
    aspect = build_mesh(geom).aspect_ratio
    if aspect > MAX_ELEMENT_ASPECT * (1.0 + 1e-9):
        problems.append(f"the {geom.mesh if isinstance(geom.mesh, str) else 'given'} mesh has "
                        f"elements {aspect:.4g} times longer than wide, more than "
                        f"{MAX_ELEMENT_ASPECT:g}: they cannot carry the near field of one "
                        "contact element")
    return problems


@dataclass(frozen=True)
class CostEstimate:
    """Size of the finite-element problem and its predicted peak memory.

    Attributes
    ----------
    dofs : int
        Equations after the support constraints are removed.
    stiffness_nonzeros : int
        Upper bound on the stored entries of the stiffness's upper triangle.
    condensed_size : int
        Size of the dense condensed (Schur complement) matrix: n, or 2n when
        loads and observation points differ.
    peak_bytes : float
        Predicted peak memory of ``unit_modulus_influence`` [bytes].
    """

    dofs: int
    stiffness_nonzeros: int
    condensed_size: int
    peak_bytes: float


def _loads_match_observations(geom: BlockGeometry) -> bool:
    """True when the load operator is the element area times the centre evaluation.

    Holds for one trilinear element (lattice order 1: corner nodes only) per
    contact element: the consistent load of a uniform pressure puts A/4 on
    each corner node and the centre value is the mean of the four corner
    nodes. Then C = A R K^-1 R^T is symmetric.
    """
    spec = geom.mesh_spec
    return ELEMENTS[spec.element].order == 1 and spec.refinement == 1


#: Peak-memory model of one factorization of the whole bordered matrix (a
#: support without mirror symmetry, or ``split_by_mirrors=False``), fitted to
#: measured peaks (resident set) of ``unit_modulus_influence`` with MKL PARDISO
#: on these meshes (grids 20-60, 14k-480k dofs): bytes per dof at 1e5 dofs,
#: growing like dofs^0.2 (nested dissection fill of slab-like meshes). Fit
#: within 25 %; ``estimate_cost`` adds that margin. The SuperLU path stores L
#: and U. Condensed one mirror class at a time, each class's factorization
#: follows the same fit for its share of the dofs.
_BYTES_PER_DOF = {"hex8": 8.2e3, "hex20": 10.9e3, "hex27": 12.1e3}
_SUPERLU_FACTOR = 6.0

#: Peak of the stiffness assembly per dof [bytes], the largest measured on the
#: presets at grids 20-120 (hex27: 20 and 40 at refinement 2): triplets summed
#: 2e7 at a time plus the sparse matrices. With the split into mirror classes
#: the assembly, not a factorization, sets the peak of the smaller builds.
_ASSEMBLY_BYTES_PER_DOF = {"hex8": 4.4e3, "hex20": 5.5e3, "hex27": 4.7e3}

#: Bytes per stored entry of the stiffness's upper triangle (float64 value,
#: int64 column index), held while the classes are factorized.
_STORED_ENTRY_BYTES = 16

#: Nodes coupled to one node through the elements around it, per element.
_COUPLED_NODES = {"hex8": 27, "hex20": 65, "hex27": 125}


def _pardiso_memory(factor: float, nb: int) -> float:
    """Peak of the PARDISO path before the dense results [bytes]: its factor."""
    return factor


def _superlu_memory(factor: float, nb: int) -> float:
    """Peak of the SuperLU path before the dense results [bytes].

    L and U, the ordering pass, and the dense trailing blocks of L and U.
    """
    return _SUPERLU_FACTOR * factor + 0.3 * GB + 4 * 8.0 * nb * nb


#: Sparse solver (``resolve_solver``'s name) -> its memory from the PARDISO
#: factor estimate and the condensed size nb.
_SOLVER_MEMORY = {"pardiso": _pardiso_memory, "superlu": _superlu_memory}


def mirror_classes(geom: BlockGeometry) -> int:
    """Symmetry classes ``unit_modulus_influence`` condenses one at a time.

    4 (symmetric or antisymmetric about each mid-plane) when the support is
    mirror-symmetric, 1 when it pins corners (the sliding base); the count of
    ``roughcontact.elasticity.symmetry.block_mirrors``' classes, 2^mirrors,
    without building the mesh.
    """
    return 1 if SUPPORTS[geom.base].pins_rigid_body else 4


def estimate_cost(geom: BlockGeometry, solver: str = "auto",
                  split_by_mirrors: bool = True) -> CostEstimate:
    """Predict the problem size and peak memory without building anything.

    The dof count is exact (from the mesh layout); the stiffness nonzeros are
    an upper bound. The peak memory is the larger of the assembly
    (``_ASSEMBLY_BYTES_PER_DOF``) and the factorization of one symmetry class
    (``mirror_classes``: the fit ``_BYTES_PER_DOF`` with a 25 % margin for its
    share of the dofs, plus the whole stiffness held meanwhile), plus the
    dense matrices (the condensed class matrix, about 1.5 copies, and the
    result, 8 bytes per entry) and 0.15 GB for the interpreter and libraries.
    Measured against this estimate at grids 20-120 with the presets: 1.0-1.4
    times lower (60 x 60 "converged": 2.3 GB, estimated 2.9 GB).

    Parameters
    ----------
    geom : BlockGeometry
        Block and mesh.
    solver : {"auto", "pardiso", "superlu"}
        The SuperLU fallback needs about six times the factor memory plus
        the dense trailing blocks of its factors.
    split_by_mirrors : bool
        As in ``unit_modulus_influence``; False: one factorization of the
        whole bordered matrix.
    """
    spec = geom.mesh_spec
    parts = slabs(build_mesh(geom))  # edge tuples only, nothing large
    dofs = 0
    for slab in parts:
        ex, ey, ez = slab.n_elements
        nodes = node_count(spec.element, ex, ey, ez)
        dofs += 3 * (nodes - node_count(spec.element, ex, ey, 0))  # tied or fixed plane
    ex, ey, _ = parts[0].n_elements
    bottom = node_count(spec.element, ex, ey, 0)
    dofs += 3 * bottom - SUPPORTS[geom.base].fixed_count(bottom)  # left free by the support
    coupling = _COUPLED_NODES[spec.element] * 3 / 2
    nnz = int(dofs * coupling)
    nb = geom.n_elements * (1 if _loads_match_observations(geom) else 2)
    classes = mirror_classes(geom) if split_by_mirrors else 1
    share = dofs / classes
    factor = 1.25 * _BYTES_PER_DOF[spec.element] * share * (share / 1e5) ** 0.2
    work = _SOLVER_MEMORY[resolve_solver(solver)](factor, nb / classes)
    if classes > 1:  # the fit above includes the stiffness and the assembly of the whole
        work = max(_ASSEMBLY_BYTES_PER_DOF[spec.element] * dofs,
                   _STORED_ENTRY_BYTES * nnz + work)
    peak = work + 1.5 * 8.0 * (nb / classes) ** 2 + 8.0 * geom.n_elements**2 + 0.15 * GB
    return CostEstimate(dofs, nnz, nb, peak)


class ModelTooLarge(MemoryError):
    """The finite-element model would not fit in the allowed memory."""


def check_memory(geom: BlockGeometry, max_bytes: float, solver: str = "auto",
                 split_by_mirrors: bool = True) -> CostEstimate:
    """Raise ``ModelTooLarge`` before building when the estimate exceeds ``max_bytes``."""
    cost = estimate_cost(geom, solver, split_by_mirrors)
    if cost.peak_bytes > max_bytes:
        raise ModelTooLarge(
            f"influence matrix for grid {geom.grid} with mesh {geom.mesh!r} needs about "
            f"{cost.peak_bytes / GB:.1f} GB ({cost.dofs} dofs), more than the allowed "
            f"{max_bytes / GB:.1f} GB. Options: a coarser mesh preset, a smaller grid, "
            f"or raise the memory limit (max_bytes)."
        )
    return cost


def unit_modulus_influence(
    geom: BlockGeometry,
    *,
    symmetric: bool = True,
    solver: str = "auto",
    max_bytes: float = 16 * GB,
    split_by_mirrors: bool = True,
) -> np.ndarray:
    """Influence matrix of the block times Young's modulus, ``E * C`` [m].

    ``E * C[i, j]`` [m] depends on the geometry, the mesh and nu only (C is
    proportional to 1/E), so it is the quantity worth storing; ``geom.E`` is
    not used and ``C(E) = unit_modulus_influence(geom) / E``.

    Method: the stiffness K of the supported block (``roughcontact.elasticity.assembly``) is
    condensed onto the contact grid. With R (n x N) the interpolation of the
    normal displacement at the centre of each contact element and F (n x N)
    the consistent nodal forces of unit pressure on each contact element,

        C = R K^-1 F^T.

    For one trilinear element per contact element (the paper's mesh) F = A R
    (A = hx hy): the centre value is the mean of the face's four corner nodes
    and C = A R K^-1 R^T is symmetric (Eq 39 of Kumar et al. 2006) and, for
    nu = 0 and a clamped base, its rows sum to L/E exactly (Eq 37-38).

    The block is symmetric about its two mid-planes (unless the base pins
    corners), so C is condensed one symmetry class at a time
    (``roughcontact.elasticity.symmetry``): four factorizations of a quarter
    of the dofs, the same matrix to round-off (3e-14 of its largest entry);
    "converged" at 60 x 60: 2.3 GB instead of 7.4 GB.

    On finer meshes C converges to the centre-point displacement of the
    continuum (Love's value for a half-space). For a finite block with free
    sides that matrix is not exactly symmetric: Betti's theorem makes the
    patch-averaged displacement symmetric, not the centre value. Near the
    free edges ``C - C^T`` reaches about 1 % of the diagonal (0.8 % for the
    "refined" preset at 60 x 60); in the interior it vanishes. The rows of
    the centre-point matrix still sum to L/E for nu = 0 (to round-off). With
    ``symmetric=True`` (default) the symmetric part ``(C + C^T) / 2`` is
    returned: the complementary energy of the contact problem (Eq 27) only
    sees that part; its rows then sum to L/E to about 0.2 % at the edges
    and 1e-4 in the interior (60 x 60, "refined").

    Parameters
    ----------
    geom : BlockGeometry
        Block, support and mesh.
    symmetric : bool, optional
        Return the symmetric part (default) or the raw centre-point matrix.
    solver : {"auto", "pardiso", "superlu"}
        Sparse solver (``roughcontact.elasticity.sparse_solve.condensed_flexibility``).
    max_bytes : float, optional
        Memory allowed [bytes]; a larger estimate raises ``ModelTooLarge``
        before anything is built.
    split_by_mirrors : bool, optional
        Condense by mirror-symmetry class (default; a no-op for a support
        without mirror symmetry) or the whole bordered matrix at once.

    Returns
    -------
    ndarray, shape (n, n), n = nx * ny
        ``E * C`` [m], rows and columns row-major over y then x.
    """
    solver = resolve_solver(solver)
    check_memory(geom, max_bytes, solver, split_by_mirrors)
    _warn_thin_layer(geom)
    mesh = build_mesh(geom)
    stiffness = assemble_stiffness(mesh, geom.nu, geom.base, E=1.0, upper=True)
    load, centre = top_face_operators(mesh, geom.grid, geom.base)
    mirrors = block_mirrors(mesh, geom.base, geom.grid) if split_by_mirrors else ()
    if _loads_match_observations(geom):  # F = A R: condense R alone, scale by A
        load = None
    flexibility = mirror_condensed_flexibility(stiffness, centre, load, mirrors, solver)
    if load is None:
        flexibility *= geom.spacing[0] * geom.spacing[1]
    del stiffness
    if symmetric:
        _symmetrize(flexibility)
    return flexibility


def _warn_thin_layer(geom: BlockGeometry) -> None:
    """Warn when the finite elements are wider than the block is thick."""
    element_width = max(geom.spacing) / geom.mesh_spec.refinement
    if element_width > geom.thickness:
        logger.warning(
            "mesh %r: finite elements %.3g m wide on a block %.3g m thick do not resolve the "
            "near field of a thin layer (C is inaccurate and may be indefinite); use a "
            "refinement of at least %d", geom.mesh, element_width, geom.thickness,
            math.ceil(max(geom.spacing) / geom.thickness * (1.0 - 1e-9)))


def _symmetrize(matrix: np.ndarray, block: int = 512) -> None:
    """Replace a square matrix by its symmetric part ``(A + A^T) / 2`` in place.

    Square blocks at a time, so no second n x n array is held; every entry is
    ``0.5 * (a_ij + a_ji)``, bit for bit the value of the whole-matrix expression.
    """
    size = matrix.shape[0]
    for start in range(0, size, block):
        rows = slice(start, start + block)
        for other in range(start, size, block):
            cols = slice(other, other + block)
            part = 0.5 * (matrix[rows, cols] + matrix[cols, rows].T)
            matrix[rows, cols] = part
            matrix[cols, rows] = part.T


def influence_matrix(
    geom: BlockGeometry,
    *,
    symmetric: bool = True,
    solver: str = "auto",
    max_bytes: float = 16 * GB,
) -> np.ndarray:
    """Influence coefficients C[i, j] of the block [m/Pa] (Eq 16 of Kumar et al. 2006).

    ``C[i, j]`` is the normal displacement [m], positive into the body, at the
    centre point of contact element i per unit uniform pressure [Pa] on contact
    element j; elements row-major over y then x (``k = iy * nx + ix``). Equal
    to ``unit_modulus_influence(geom) / geom.E``; see there for the method,
    symmetry and parameters.
    """
    return unit_modulus_influence(geom, symmetric=symmetric, solver=solver,
                                  max_bytes=max_bytes) / geom.E
