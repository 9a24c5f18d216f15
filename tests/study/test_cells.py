"""Study bookkeeping: geometry keys, and building influence files."""

import numpy as np
import pytest

from roughcontact.elasticity.influence import ModelTooLarge
from roughcontact.study.cells import block_geometry, geometry_key, geometry_params
from roughcontact.study.config import load_config, validated
from roughcontact.study.jobs import build_influence
from roughcontact.study.storage import read_influence

#: A minimal config completed by the schema's defaults (base clamped, mesh paper, ...).
CONFIG = validated({"study_seed": 0, "figures": {},
                    "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 1},
                    "body": {"thickness_mm": 2.0, "E_MPa": 511.0, "nu": 0.0}})
BODY, SURFACES = CONFIG["body"], CONFIG["surfaces"]


def test_every_geometry_parameter_but_young_modulus_changes_the_key():
    base = geometry_params(BODY, SURFACES)
    keys = {geometry_key(base)}
    for change in ({"nu": 0.3}, {"thickness_mm": 3.0}, {"mesh": "refined"},
                   {"base": "sliding"}, {"grid": [8, 10]}, {"size_mm": [1.2, 1.5]}):
        keys.add(geometry_key(geometry_params(BODY, SURFACES, **change)))
    assert len(keys) == 7
    assert geometry_key(geometry_params({**BODY, "E_MPa": 1.0}, SURFACES)) == geometry_key(base)


def test_block_geometry_converts_millimetres():
    geom = block_geometry(geometry_params(BODY, SURFACES, grid=[8, 10]))
    assert geom.size == pytest.approx((1.2e-3, 1.2e-3))
    assert geom.thickness == pytest.approx(2e-3)
    assert geom.grid == (8, 10)


def test_build_influence_writes_rows_summing_to_the_thickness(tmp_path):
    params = geometry_params(BODY, SURFACES)
    path = tmp_path / "g.h5"
    build_influence(params, path, solver="auto", max_memory_gb=16.0)
    unit, attrs = read_influence(path)
    assert unit.shape == (64, 64)
    assert np.allclose(unit.sum(axis=1), 2e-3, rtol=1e-10)
    assert attrs["check_min_eigenvalue_m"] > 0
    assert attrs["geometry"] == geometry_key(params)


def test_build_influence_refuses_a_model_too_large_before_building(tmp_path):
    params = geometry_params(BODY, SURFACES)
    path = tmp_path / "g.h5"
    with pytest.raises(ModelTooLarge, match=r"GB.*Options"):
        build_influence(params, path, solver="auto", max_memory_gb=0.001)
    assert not path.exists()


def quick_config():
    from pathlib import Path

    return load_config(Path(__file__).resolve().parents[2] / "config" / "quick.yaml")


def test_accuracy_preset_sets_mesh_count_and_solver_and_records_its_errors():
    from roughcontact.study.cells import contact_cells, contact_jobs, contact_settings
    from roughcontact.study.presets import ACCURACY_PRESETS

    config = quick_config()
    plain = contact_cells(config, "fig11")
    assert {c["geometry"]["mesh"] for c in plain} == {config["body"]["mesh"]}
    assert plain[0]["accuracy"] == "as configured"
    config["accuracy"] = "fast"
    preset = ACCURACY_PRESETS["fast"]
    cells = contact_cells(config, "fig11")
    assert {c["geometry"]["mesh"] for c in cells} == {preset["mesh"]}
    assert {c["surface"]["count"] for c in cells} == {preset["surfaces"]}
    assert cells[0]["expected_error"]["real_area_error"] == preset["real_area_error"]
    assert contact_settings(config)["tol"] == preset["tol"]
    # a figure that names its meshes keeps them
    named = contact_cells(config, "fig07")
    assert {c["geometry"]["mesh"] for c in named} == set(config["figures"]["fig07"]["meshes"])
    job = next(iter(contact_jobs(config, ["fig11"]).values()))
    assert job["accuracy"] == "fast" and job["expected_error"]


def test_a_measured_map_too_large_for_the_dense_model_stops_when_the_plan_is_made(tmp_path):
    from roughcontact.study.cells import ConfigProblems, planned_operator, study_plan

    path = tmp_path / "big.npy"
    np.save(path, np.random.default_rng(3).standard_normal((1024, 1024)))
    surface = {"file": str(path), "format": "npy", "height_unit": "um",
               "spacing_mm": [0.01, 0.01]}
    config = {"study_seed": 0, "figures": {},
              "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1},
              "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0},
              "sweeps": {"big": {"surface": surface, "pressure_MPa": [1.0, 5.0]}}}
    with pytest.raises(ConfigProblems) as raised:
        study_plan(validated(config))
    message = str(raised.value)
    # the dense 1024 x 1024 model: tens of TB, against the 16 GB default
    peak_tb = float(message.split("estimated peak memory ")[1].split(" GB")[0]) / 1e3
    assert peak_tb > 10
    for key in ("body.operator: auto", "body.max_memory_gb", "surface.crop_mm",
                "surface.decimate", "surface.resample_grid", "1024 x 1024"):
        assert key in message, key
    # the matrix-free operator plans the same file within the limit
    config["body"]["operator"] = "auto"
    plan = study_plan(validated(config))
    (params,) = plan.geometries.values()
    assert params["grid"] == [1024, 1024]
    assert planned_operator(params, 16.0) == "hybrid"
