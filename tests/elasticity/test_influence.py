"""Tests of the finite-element influence coefficients (roughcontact.elasticity: influence,
mesh, assembly, sparse_solve)."""

import numpy as np
import pytest
import scipy.sparse as sp

from roughcontact.elasticity import sparse_solve
from roughcontact.elasticity.assembly import (
    assemble_stiffness,
    assemble_stiffness_generic,
    top_face_operators,
)
from roughcontact.elasticity.dofs import dof_map
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.hybrid import hybrid_unit_modulus_influence
from roughcontact.elasticity.influence import (
    MESH_PRESETS,
    BlockGeometry,
    MeshSpec,
    ModelTooLarge,
    build_mesh,
    estimate_cost,
    influence_matrix,
    layer_coarsening,
    layer_thicknesses,
    unit_modulus_influence,
)
from roughcontact.elasticity.mesh import node_count, node_numbers, slabs, structured_mesh

H = 0.15e-3  # contact element size of the paper's model [m]
GRADED_R2 = MeshSpec(element="hex8", refinement=2, layers=None, top_layer=1.0, growth=1.5)


def small_block(grid=(8, 8), thickness=8 * H, **kwargs) -> BlockGeometry:
    size = (grid[0] * H, grid[1] * H)
    return BlockGeometry(size=size, thickness=thickness, grid=grid, **kwargs)


@pytest.fixture(scope="module")
def paper_8x8() -> tuple[BlockGeometry, np.ndarray]:
    geom = small_block(mesh="paper")
    return geom, influence_matrix(geom)


@pytest.fixture(scope="module")
def refined_raw() -> tuple[BlockGeometry, np.ndarray]:
    geom = small_block(grid=(6, 6), thickness=6 * H, mesh=GRADED_R2)
    return geom, influence_matrix(geom, symmetric=False)


# --- validation -------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"nu": 0.5}, "nu"),
        ({"nu": -0.1}, "nu"),
        ({"E": 0.0}, "E"),
        ({"thickness": -1.0}, "thickness"),
        ({"size": (1e-3, 0.0)}, "size"),
        ({"grid": (0, 4)}, "grid"),
        ({"grid": (2.5, 4)}, "grid"),
        ({"base": "glued"}, "base"),
        ({"mesh": "finest"}, "mesh"),
    ],
)
def test_geometry_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        BlockGeometry(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"element": "tet4"}, "element"),
        ({"refinement": 0}, "refinement"),
        ({"layers": 0}, "layers"),
        ({"layers": None, "top_layer": 1.0, "growth": 1.6}, "growth"),
        ({"layers": 5, "top_layer": 1.0}, "top_layer"),
    ],
)
def test_mesh_spec_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        MeshSpec(**kwargs)


def test_presets_and_paper_defaults():
    assert {"paper", "graded", "converged"} <= set(MESH_PRESETS)
    geom = BlockGeometry()
    assert geom.size == (9e-3, 9e-3) and geom.thickness == 10e-3 and geom.grid == (60, 60)
    assert geom.E == 5.11e8 and geom.nu == 0.0 and geom.base == "clamped"
    assert layer_thicknesses(geom) == pytest.approx((2e-3,) * 5)


def test_graded_layers_sum_to_thickness_and_grow_at_most_the_ratio():
    geom = BlockGeometry(mesh="graded")
    layers = np.array(layer_thicknesses(geom))
    assert layers.sum() == pytest.approx(geom.thickness, rel=1e-12, abs=0.0)
    assert layers[0] == pytest.approx(9e-3 / 60, rel=1e-12, abs=0.0)
    ratios = layers[1:] / layers[:-1]
    assert np.all(ratios <= 1.25 + 1e-12) and np.all(ratios > 1.0)


# --- assembly ---------------------------------------------------------------


@pytest.mark.parametrize("element", ["hex8", "hex20", "hex27"])
@pytest.mark.parametrize("base", ["clamped", "sliding"])
def test_scatter_assembly_equals_generic_asm(element, base):
    mesh = structured_mesh((1.2e-3, 0.9e-3), 1.0e-3, (4, 3), (0.1, 0.3, 0.6), element)
    fast = assemble_stiffness(mesh, 0.3, base, E=2.0)
    reference = assemble_stiffness_generic(mesh, 0.3, base, E=2.0)
    assert abs(fast - reference).max() <= 1e-12 * abs(reference).max()
    upper = assemble_stiffness(mesh, 0.3, base, E=2.0, upper=True)
    assert abs(sp.triu(fast) - upper).max() <= 1e-14 * abs(reference).max()


def test_top_face_operators_integrate_pressure_and_interpolate_constants():
    for element, r in [("hex8", 1), ("hex8", 2), ("hex20", 1), ("hex27", 3)]:
        mesh = structured_mesh((0.6e-3, 0.4e-3), 1e-3, (3 * r, 2 * r), (1.0,), element)
        load, centre = top_face_operators(mesh, (3, 2))
        np.testing.assert_allclose(load.sum(axis=1), 0.2e-3 * 0.2e-3, rtol=1e-12)
        np.testing.assert_allclose(centre.sum(axis=1), 1.0, rtol=1e-12)


def test_coarsening_factors_divide_and_grow_downwards():
    for name in ("refined", "converged"):
        factors = layer_coarsening(BlockGeometry(mesh=name))
        assert factors[0] == 1 and factors[-1] > 1
        assert all(b % a == 0 for a, b in zip(factors, factors[1:], strict=False))
        assert all((60 * 2) % f == 0 and (60 * 2) // f >= 2 for f in factors)
    assert layer_coarsening(BlockGeometry(mesh="paper")) == (1,) * 5


def test_hex_mesh_rejects_inconsistent_coarsening():
    with pytest.raises(ValueError, match="coarsening"):
        structured_mesh((1e-3, 1e-3), 1e-3, (4, 4), (0.5, 0.5), "hex8", (2, 1))
    with pytest.raises(ValueError, match="coarsened"):
        structured_mesh((1e-3, 1e-3), 1e-3, (4, 4), (0.5, 0.5), "hex8", (1, 3))


@pytest.mark.parametrize("element", ["hex8", "hex20", "hex27"])
@pytest.mark.parametrize("base", ["clamped", "sliding"])
def test_cost_estimate_counts_the_equations_exactly(element, base):
    spec = MeshSpec(element, refinement=2, layers=None, top_layer=1.0, growth=1.5,
                    coarsen_at=1.0)
    geom = small_block(grid=(6, 4), thickness=6 * H, base=base, mesh=spec)
    mesh = build_mesh(geom)
    parts = slabs(mesh)
    assert len(parts) > 1  # coarsened: hanging nodes are tied
    for slab in parts:
        ex, ey, ez = slab.n_elements
        assert node_count(element, ex, ey, ez) == node_numbers(slab).max() + 1
    assert estimate_cost(geom).dofs == dof_map(mesh, base).n_free


@pytest.mark.parametrize("element", ["hex8", "hex20"])
def test_coarsened_mesh_passes_the_patch_test(element):
    # A frictionless base and free sides make uniform pressure a uniaxial
    # stress state (a linear displacement field) for any nu; the hanging-node
    # ties are conforming, so every row sums to L/E exactly. The 9 x 9 grid
    # with 2 x 2 elements per contact element coarsens by 2 and then by 3.
    spec = MeshSpec(element, refinement=2, layers=None, top_layer=1.0, growth=1.5,
                    coarsen_at=1.0)
    geom = small_block(grid=(9, 9), thickness=9 * H, nu=0.3, base="sliding", mesh=spec)
    assert {2, 6} <= set(layer_coarsening(geom))
    C = influence_matrix(geom, symmetric=False)
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=1e-10)


# --- properties of C (Eq 37-39) ---------------------------------------------


def test_paper_mesh_symmetric_positive_definite(paper_8x8):
    _, C = paper_8x8
    assert np.abs(C - C.T).max() <= 1e-10 * np.abs(C).max()
    assert np.linalg.eigvalsh(C).min() > 0.0


def test_paper_mesh_rows_sum_to_L_over_E(paper_8x8):
    geom, C = paper_8x8
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=1e-10)


def test_uniform_pressure_gives_uniform_compression(paper_8x8):
    geom, C = paper_8x8
    P = 2.0e6
    u = C @ np.full(geom.n_elements, P)
    np.testing.assert_allclose(u, P * geom.thickness / geom.E, rtol=1e-10)


def test_refined_centre_point_rows_sum_to_L_over_E(refined_raw):
    geom, C = refined_raw
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=1e-10)
    # near the free edges the centre-point matrix of a finite block is not
    # exactly symmetric (Betti's theorem holds for patch averages)
    asymmetry = np.abs(C - C.T).max() / np.abs(C).max()
    assert 1e-6 < asymmetry < 0.02


def test_default_matrix_is_the_symmetric_part(refined_raw):
    geom, raw = refined_raw
    C = influence_matrix(geom)
    np.testing.assert_allclose(C, 0.5 * (raw + raw.T), rtol=1e-10, atol=0)
    assert np.abs(C - C.T).max() <= 1e-10 * np.abs(C).max()
    assert np.linalg.eigvalsh(C).min() > 0.0
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=0.02)


def test_compliance_scales_with_inverse_modulus(paper_8x8):
    geom, C = paper_8x8
    np.testing.assert_allclose(unit_modulus_influence(geom) / geom.E, C, rtol=1e-12)


def test_element_ordering_is_row_major_over_y_then_x():
    # elements twice as long in y as in x: the x neighbour (k + 1) is closer
    # than the y neighbour (k + nx)
    geom = BlockGeometry(size=(5 * H, 8 * H), thickness=5 * H, grid=(5, 4), mesh="paper")
    C = influence_matrix(geom)
    k = 2 * 5 + 2  # ix = 2, iy = 2
    assert C[k, k + 1] > C[k, k + 5]
    hs = halfspace_influence(geom.grid, geom.size, geom.E, geom.nu)
    assert hs[k, k + 1] > hs[k, k + 5]


# --- boundary conditions ----------------------------------------------------


def test_sliding_base_against_clamped():
    clamped = small_block(grid=(6, 6), thickness=4 * H, nu=0.3, mesh="paper")
    sliding = small_block(grid=(6, 6), thickness=4 * H, nu=0.3, base="sliding", mesh="paper")
    Cc, Cs = influence_matrix(clamped), influence_matrix(sliding)
    L_over_E = clamped.thickness / clamped.E
    # frictionless base, free sides: uniform pressure is uniaxial stress
    np.testing.assert_allclose(Cs.sum(axis=1), L_over_E, rtol=1e-10)
    # bonded base restrains the lateral expansion: stiffer
    assert np.all(Cc.sum(axis=1) < L_over_E)
    assert np.linalg.eigvalsh(Cs - Cc).min() > -1e-12 * np.abs(Cc).max()
    # nu = 0: no lateral expansion, the base condition does not matter for uniform load
    c0 = influence_matrix(small_block(grid=(6, 6), thickness=4 * H, base="sliding"))
    np.testing.assert_allclose(c0.sum(axis=1), 4 * H / clamped.E, rtol=1e-10)


# --- accuracy against the half-space (Love) -----------------------------------


def test_thick_wide_block_approaches_half_space():
    # 12 x 12 contact elements, thickness = width; quadratic elements.
    # Measured: centre-row entries within 2.5 % of Love's, differences from
    # the diagonal (the near-field shape) within 1.5 %.
    geom = small_block(grid=(12, 12), thickness=12 * H, nu=0.3,
                       mesh=MeshSpec("hex27", 1, layers=None, top_layer=1.0, growth=1.5))
    C = influence_matrix(geom)
    hs = halfspace_influence(geom.grid, geom.size, geom.E, geom.nu)
    c = 6 * 12 + 6
    near = [c, c + 1, c + 13, c + 2, c + 3]
    np.testing.assert_allclose(C[c, near], hs[c, near], rtol=0.04)
    shape_fe = C[c, c] - C[c, near[1:]]
    shape_hs = hs[c, c] - hs[c, near[1:]]
    np.testing.assert_allclose(shape_fe, shape_hs, rtol=0.02)


def test_converged_preset_handles_near_incompressible_material():
    # nu = 0.49: trilinear elements lock (the "refined" preset's diagonal is
    # about 26 % low); the 20-node "converged" preset is within 0.5 % of Love
    # for the diagonal and 2 % for the near-field shape (measured).
    kwargs = {"grid": (12, 12), "thickness": 12 * H, "nu": 0.49}
    hs = halfspace_influence((12, 12), (12 * H, 12 * H), BlockGeometry().E, 0.49)
    c = 6 * 12 + 6
    near = [c, c + 1, c + 13, c + 2]
    C = influence_matrix(small_block(mesh="converged", **kwargs))
    # abs=0: approx's default abs=1e-12 would pass any m/Pa value
    assert C[c, c] == pytest.approx(hs[c, c], rel=0.02, abs=0.0)
    np.testing.assert_allclose(C[c, c] - C[c, near[1:]], hs[c, c] - hs[c, near[1:]], rtol=0.03)
    locked = influence_matrix(small_block(mesh="refined", **kwargs))
    assert locked[c, c] < 0.8 * hs[c, c]


def test_paper_mesh_underestimates_self_compliance():
    geom = small_block(grid=(8, 8), thickness=10e-3 * 8 / 60, mesh="paper")
    C = influence_matrix(geom)
    hs = halfspace_influence(geom.grid, geom.size, geom.E, geom.nu)
    assert C[36, 36] < 0.7 * hs[36, 36]


# --- solvers and memory guard -------------------------------------------------


@pytest.mark.skipif(not sparse_solve.pardiso_available(),
                    reason="PARDISO (pypardiso) not installed")
def test_superlu_fallback_matches_pardiso():
    geom = small_block(grid=(4, 4), thickness=4 * H, nu=0.3, mesh=GRADED_R2)
    a = unit_modulus_influence(geom, solver="pardiso", symmetric=False)
    b = unit_modulus_influence(geom, solver="superlu", symmetric=False)
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12 * np.abs(a).max())


def test_auto_solver_falls_back_to_superlu(monkeypatch):
    geom = small_block(grid=(4, 4), thickness=4 * H, mesh="paper")
    expected = unit_modulus_influence(geom, solver="superlu")

    def missing():
        raise ImportError("no MKL")

    monkeypatch.setattr(sparse_solve, "_pardiso_library", missing)
    assert not sparse_solve.pardiso_available()
    np.testing.assert_allclose(unit_modulus_influence(geom), expected, rtol=1e-12)
    with pytest.raises(ValueError, match="solver"):
        unit_modulus_influence(geom, solver="cholmod")


def test_memory_guard_raises_before_building():
    geom = BlockGeometry(grid=(400, 400), mesh="converged")
    cost = estimate_cost(geom)
    assert cost.peak_bytes > 16e9
    with pytest.raises(ModelTooLarge, match="GB"):
        influence_matrix(geom, max_bytes=16e9)


# --- hybrid operator ----------------------------------------------------------


def test_hybrid_without_coarsening_is_the_finite_element_matrix():
    geom = small_block(grid=(6, 6), thickness=6 * H, mesh="paper")
    np.testing.assert_allclose(hybrid_unit_modulus_influence(geom, coarsening=1),
                               unit_modulus_influence(geom), rtol=1e-12, atol=1e-18)


def test_hybrid_matches_the_fine_model_away_from_the_edges():
    geom = small_block(grid=(16, 16), thickness=16 * H, mesh="converged")
    fine = unit_modulus_influence(geom)
    hybrid = hybrid_unit_modulus_influence(geom, coarsening=2)
    np.testing.assert_allclose(hybrid, hybrid.T, rtol=0, atol=1e-15 * hybrid.max())
    diag = (np.diag(hybrid) / np.diag(fine) - 1).reshape(16, 16)
    assert np.abs(diag[3:-3, 3:-3]).max() < 0.01
    c = 8 * 16 + 8
    for j in (c + 1, c + 17, c + 2, c + 6):
        assert hybrid[c, j] == pytest.approx(fine[c, j], rel=0.03)
    # the documented limitation: free edges are worse than the interior
    assert np.abs(diag[0]).max() > np.abs(diag[3:-3, 3:-3]).max()
    # rows still sum to about L (nu = 0, Eq 38)
    assert hybrid.sum(axis=1) / geom.thickness == pytest.approx(1.0, abs=0.05)


def test_hybrid_checks_the_coarsening():
    geom = small_block(grid=(6, 6), mesh="paper")
    with pytest.raises(ValueError, match="coarsening"):
        hybrid_unit_modulus_influence(geom, coarsening=4)


@pytest.mark.parametrize("solver", ["superlu", "pardiso"])
def test_a_singular_stiffness_matrix_is_refused_with_its_cause_and_advice(solver):
    """A stiffness matrix with a free rigid mode (a chain of springs held nowhere) is
    singular: both solvers raise FactorizationError naming the solver and the mesh
    advice, not a bare RuntimeError."""
    from roughcontact.errors import FactorizationError

    if solver == "pardiso" and not sparse_solve.pardiso_available():
        pytest.skip("MKL PARDISO does not load here")
    n = 12  # springs between consecutive dofs, none to ground: K 1 = 0
    main = np.full(n, 2.0)
    main[[0, -1]] = 1.0
    stiffness = sp.diags([main, -np.ones(n - 1), -np.ones(n - 1)], [0, 1, -1], format="csr")
    upper = sp.csr_array(sp.triu(stiffness))
    load = sp.csr_array(np.eye(n)[:2])
    with pytest.raises(FactorizationError) as info:
        sparse_solve.condensed_flexibility(upper, load, solver=solver)
    assert info.value.solver == solver
    assert "body.mesh" in str(info.value) or "body.solver" in str(info.value)
    # the same chain held at one end factorizes
    main[0] = 2.0
    held = sp.diags([main, -np.ones(n - 1), -np.ones(n - 1)], [0, 1, -1], format="csr")
    flexibility = sparse_solve.condensed_flexibility(sp.csr_array(sp.triu(held)), load,
                                                     solver=solver)
    assert np.allclose(flexibility, np.linalg.inv(held.toarray())[:2, :2])


def test_pardiso_error_codes_are_named_with_advice_that_fits():
    memory = sparse_solve._pardiso_error(-2)
    assert memory.code == -2 and "not enough memory" in str(memory)
    assert "body.solver: superlu" in str(memory)
    singular = sparse_solve._pardiso_error(-4)
    assert "zero pivot" in str(singular) and "body.mesh" in str(singular)
    assert "unknown error" in str(sparse_solve._pardiso_error(-99))
