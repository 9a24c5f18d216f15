"""Users' scripts keep working: every module name and public name the library had
before it was split into stage folders still imports under its old name."""

from __future__ import annotations

import importlib

import pytest

#: The public names of each former flat module (its ``__all__`` before the split).
FORMER = {
    "johnson": ["FAMILIES", "JohnsonCurve", "family_of", "fit", "lognormal_kurt"],
    "surface": ["ACF_DECAY", "ACF_KINDS", "ExactResult", "FilterKernel", "SurfaceSpec",
                "autocorrelation", "autocorrelation_map", "correlation_length", "derive_seeds",
                "filter_kernel", "generate", "generate_exact", "generate_many", "height_stats",
                "input_family", "input_moments", "kernel_shape", "kurt_min", "lognormal_line",
                "moment_transfer", "target_heights"],
    "influence": ["BlockGeometry", "CostEstimate", "MESH_PRESETS", "MeshSpec", "ModelTooLarge",
                  "build_mesh", "centre_interpolation", "check_memory", "estimate_cost",
                  "halfspace_influence", "hybrid_unit_modulus_influence", "influence_matrix",
                  "layer_coarsening", "layer_thicknesses", "unit_modulus_influence"],
    "halfspace": ["PeriodicHalfSpace", "halfspace_influence", "love_rectangle"],
    "operators": ["BlockOperator", "COARSE_MAX", "DENSE_MAX_ELEMENTS", "HYBRID_MESHES",
                  "OPERATORS", "block_operator", "choose_operator", "content_sha256",
                  "default_coarse_grid", "halfspace_errors", "halfspace_meets",
                  "halfspace_operator", "operator_datasets", "read_operator"],
    "contact": ["ContactResult", "METHODS", "PRECISIONS", "SweepResult", "kkt_residual",
                "solve", "solve_many", "sweep", "tangent_stiffness"],
    "nondim": ["NondimSweep", "PhysicalSweep", "SweepProgress", "approach_grid",
               "dimensionless_operator", "initial_separation", "solve_cell", "to_physical"],
    "aggregate": ["QUANTITIES", "aggregate_cell", "covered_range", "mean_plane_modulus",
                  "modulus_summary", "pressure_axis", "surface_curves"],
    "measured": ["FORMATS", "HEIGHT_UNITS", "LATERAL_UNITS", "Measurement", "file_sha256",
                 "fill_missing", "load_measurement", "read_npy", "read_text_grid", "read_xyz",
                 "remove_plane", "statistics"],
}

#: Where each former module lives now (the old name is that very module).
HOMES = {
    "johnson": "roughcontact.surfaces.johnson",
    "surface": "roughcontact.surfaces.synthetic",
    "measured": "roughcontact.surfaces.measured",
    "halfspace": "roughcontact.elasticity.halfspace",
    "influence": "roughcontact.elasticity.influence",
    "nondim": "roughcontact.contact.nondim",
    "aggregate": "roughcontact.contact.aggregate",
}


@pytest.mark.parametrize("module", sorted(FORMER))
def test_former_module_keeps_its_public_names(module):
    mod = importlib.import_module(f"roughcontact.{module}")
    missing = [name for name in FORMER[module] if not hasattr(mod, name)]
    assert not missing, f"roughcontact.{module} lost {missing}"
    for name in FORMER[module]:  # and `from roughcontact.X import name` works
        namespace: dict = {}
        exec(f"from roughcontact.{module} import {name}", namespace)
        assert namespace[name] is getattr(mod, name)


@pytest.mark.parametrize("module", sorted(HOMES))
def test_former_name_is_the_new_module(module):
    assert importlib.import_module(f"roughcontact.{module}") is \
        importlib.import_module(HOMES[module])


def test_readme_examples_import():
    from roughcontact import aggregate, johnson, nondim, surface
    from roughcontact.influence import BlockGeometry, unit_modulus_influence

    assert johnson.fit(skew=-0.8, kurt=4.0).family == johnson.family_of(-0.8, 4.0)
    spec = surface.SurfaceSpec(grid=8, size=1e-3, corr_length=2e-4)
    assert surface.generate_many(spec, range(2)).shape == (2, 8, 8)
    assert callable(nondim.solve_cell) and callable(aggregate.aggregate_cell)
    assert BlockGeometry().grid == (60, 60) and callable(unit_modulus_influence)


def test_moved_operator_names_behave_as_before(tmp_path):
    """The storage and criterion names that left ``operators`` answer as they did."""
    from roughcontact import operators

    op = operators.halfspace_operator((8, 8), (1e-3, 1e-3), 0.3)
    datasets, attrs = operators.operator_datasets(op)
    assert datasets == {} and attrs["operator"] == "halfspace"
    assert len(operators.content_sha256(op)) == 64
    assert not operators.halfspace_meets({"k_P": 0.1}, {"k_P": 0.02})
