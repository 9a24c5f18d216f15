"""Study bookkeeping: the plan's records, their keys and params, and influence files."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import ndimage

from roughcontact.elasticity.influence import ModelTooLarge
from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings, load_config, validated
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.counter_records import PairGeometry
from roughcontact.study.jobs.influence import build_influence
from roughcontact.study.jobs.storage import read_influence
from roughcontact.study.plan.cells import drawn_with, figure_aggregates, study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.presets import ACCURACY_PRESETS
from roughcontact.study.records import Geometry, InfluenceModel, surface_cell_from_params
from roughcontact.study.settings import Study
from roughcontact.units import MM, MPA, UM

REPO = Path(__file__).resolve().parents[2]
#: A minimal config completed by the schema's defaults (base clamped, mesh paper, ...).
CONFIG = validated({"study_seed": 0, "figures": {},
                    "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 1},
                    "body": {"thickness_mm": 2.0, "E_MPa": 511.0, "nu": 0.0}})
BUILD = BuildSettings.from_section(CONFIG["body"])


def geometry(**change) -> Geometry:
    """The body's geometry with some of its configuration's values changed (mm)."""
    surfaces = CONFIG["surfaces"]
    return Geometry.from_params({**CONFIG["body"], "grid": surfaces["grid"],
                                 "size_mm": surfaces["size_mm"], **change})


def quick_config():
    return load_config(REPO / "config" / "quick.yaml")


def test_every_geometry_parameter_but_young_modulus_changes_the_key():
    keys = {geometry().key}
    for change in ({"nu": 0.3}, {"thickness_mm": 3.0}, {"mesh": "refined"},
                   {"base": "sliding"}, {"grid": [8, 10]}, {"size_mm": [1.2, 1.5]}):
        keys.add(geometry(**change).key)
    assert len(keys) == 7
    assert geometry(E_MPa=1.0).key == geometry().key == "nu0_L1.2x1.2mm_t2mm_g8x8_clamped_paper"
    assert Study.from_config(CONFIG).body.geometry == geometry()


def test_geometry_holds_si_values_and_its_params_the_configured_ones():
    geom = geometry(grid=[8, 10])
    assert geom.size == pytest.approx((1.2e-3, 1.2e-3))
    assert geom.thickness == pytest.approx(2e-3)
    assert geom.grid == (8, 10) and geom.operator is InfluenceModel.DENSE
    block = geom.block(E=5e8)
    assert (block.size, block.thickness, block.grid, block.E) == (geom.size, geom.thickness,
                                                                  (8, 10), 5e8)
    # the paper's dense model names no operator in its params: its files keep their names
    assert geom.params() == {"nu": 0.0, "size_mm": [1.2, 1.2], "thickness_mm": 2.0,
                             "grid": [8, 10], "base": "clamped", "mesh": "paper"}


@pytest.mark.parametrize("value", [0.7, 24.5, 2.325, 1e-3, 511.0, 9.0, 0.15, 123.456789012])
def test_values_come_back_in_their_unit_as_written(value):
    for unit in (MM, UM, MPA):
        assert in_unit(value * unit, unit) == value


def same_params(record, again) -> bool:
    """The same params, key order included (a rule's params are compared by repr)."""
    return repr(again.params()) == repr(record.params())


@pytest.mark.parametrize("name", ["quick", "two_bodies", "measured", "seal"])
def test_every_record_of_a_plan_round_trips_through_its_params(name):
    plan = study_plan(Study.from_config(load_config(REPO / "config" / f"{name}.yaml")))
    for job in plan.jobs.values():
        again = ContactJob.from_params(job.params())
        assert again == job and same_params(job, again) and again.key == job.key
        assert again.counter == job.counter and again.files() == job.files()
    for cells in plan.cells.values():
        for cell in cells:
            again = StudyCell.from_params(cell.params())
            assert again == cell and same_params(cell, again)
            assert again.counterface == cell.counterface and again.job == cell.job
    for key, cell in plan.surfaces.items():
        again = surface_cell_from_params(cell.params())
        assert again == cell and same_params(cell, again) and cell.key == key
    for key, geom in plan.geometries.items():
        again = Geometry.from_params(geom.params())
        assert again == geom and same_params(geom, again) and geom.key == key
    for key, pair in plan.pairs.items():
        again = PairGeometry.from_params(pair.params())
        assert again == pair and same_params(pair, again) and pair.key == key
    assert (name != "two_bodies") or plan.pairs  # the pairs are checked where there are


def test_the_plan_computes_each_study_once_and_its_jobs_from_its_cells():
    config = quick_config()
    plan = study_plan(Study.from_config(config))
    assert plan.cells["fig12"] is plan.cells["fig07"]  # fig12: {from: fig07}
    assert plan.aggregates == ("fig07", "fig09", "fig11", "fig14", "hardness", "table_Eu")
    keys = {cell.contact_key for name in plan.studies for cell in plan.cells[name]}
    assert keys == set(plan.jobs)
    assert plan.cells["fig07"] == contact_cells(Study.from_config(config), "fig07")
    # Fig 10 draws the surfaces of its cells (those of Fig 9), Figs 4 and 5 Fig 4's
    assert [s.key for s in plan.figure_surfaces["fig10"]] == \
        [c.surface.key for c in plan.cells["fig09"]]
    assert plan.figure_surfaces["fig05"] == plan.figure_surfaces["fig04"]
    assert plan.figure_surfaces["fig07"] == ()
    # and Fig 5 draws them in Fig 4's sigma: its notebook gets Fig 4's validated settings
    assert drawn_with(plan, "fig05") == {"fig04": config["figures"]["fig04"]}
    assert all(drawn_with(plan, name) == {} for name in plan.figures if name != "fig05")


def test_a_cells_sweep_end_and_key_follow_its_nondimensional_pressure():
    cell = study_plan(Study.from_config(quick_config())).cells["fig07"][0]
    # P L / (E sigma) = 5 MPa x 10 mm / (511 MPa x 24.5 um) = 3.99 -> 4
    assert cell.sweep_end == 4.0
    assert cell.contact_key == ("sk0_ku3_b0.5x0.5mm_L4.8x4.8mm_g32x32_exp_per_filter_n4"
                                "__nu0_L4.8x4.8mm_t10mm_g32x32_clamped_paper__end4")
    assert cell.params()["sigma_um"] == 24.5 and cell.params()["pressure_MPa"] == [0.1, 5.0]


def test_build_influence_writes_rows_summing_to_the_thickness(tmp_path):
    path = tmp_path / "g.h5"
    build_influence(geometry().params(), path, solver="auto", max_memory_gb=16.0)
    unit, attrs = read_influence(path)
    assert unit.shape == (64, 64)
    assert np.allclose(unit.sum(axis=1), 2e-3, rtol=1e-10)
    assert 0 < attrs["check_certificate_smallest_m"] < attrs["check_certificate_largest_m"]
    assert attrs["geometry"] == geometry().key


def test_build_influence_refuses_a_model_too_large_before_building(tmp_path):
    path = tmp_path / "g.h5"
    with pytest.raises(ModelTooLarge, match=r"GB.*Options"):
        build_influence(geometry().params(), path, solver="auto", max_memory_gb=0.001)
    assert not path.exists()


def test_accuracy_preset_sets_mesh_count_and_solver_and_records_its_errors():
    config = quick_config()
    plain = contact_cells(Study.from_config(config), "fig11")
    assert {c.geometry.mesh for c in plain} == {config["body"]["mesh"]}
    assert plain[0].accuracy.name == "as configured"
    assert "expected_error" not in plain[0].params()
    config["accuracy"] = "fast"
    preset = ACCURACY_PRESETS["fast"]
    cells = contact_cells(Study.from_config(config), "fig11")
    assert {c.geometry.mesh for c in cells} == {preset["mesh"]}
    assert {c.surface.count for c in cells} == {preset["surfaces"]}
    assert cells[0].params()["expected_error"]["real_area_error"] == preset["real_area_error"]
    assert Study.from_config(config).contact.tol == preset["tol"]
    # a figure that names its meshes keeps them
    named = contact_cells(Study.from_config(config), "fig07")
    assert {c.geometry.mesh for c in named} == set(config["figures"]["fig07"]["meshes"])
    job = cells[0].job.params()
    assert job["accuracy"] == "fast" and job["expected_error"]


def test_a_measured_map_too_large_for_the_dense_model_stops_when_the_plan_is_made(tmp_path):
    path = tmp_path / "big.npy"
    # a rough map correlated over a few points (white noise is refused as no surface)
    np.save(path, ndimage.uniform_filter(np.random.default_rng(3).standard_normal((1024, 1024)),
                                         4, mode="wrap"))
    surface = {"file": str(path), "format": "npy", "height_unit": "um",
               "spacing_mm": [0.01, 0.01]}
    config = {"study_seed": 0, "figures": {},
              "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1},
              "body": {"thickness_mm": 0.5, "E_MPa": 511.0, "nu": 0.0},
              "sweeps": {"big": {"surface": surface, "pressure_MPa": [1.0, 5.0]}}}
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(config)))
    message = str(raised.value)
    # the dense 1024 x 1024 model holds at least its own matrix, 8 n^2 bytes
    # (8.8 TB), against the 16 GB default
    peak_bytes = float(message.split("estimated peak memory ")[1].split(" GB")[0]) * 1e9
    assert peak_bytes >= 8.0 * (1024 * 1024) ** 2
    for key in ("body.operator: auto", "body.max_memory_gb", "surface.crop_mm",
                "surface.decimate", "surface.resample_grid", "1024 x 1024"):
        assert key in message, key
    # the matrix-free operator plans the same file within the limit
    config["body"]["operator"] = "auto"
    plan = study_plan(Study.from_config(validated(config)))
    (auto,) = plan.choices.values()
    assert auto.grid == (1024, 1024)
    assert auto.planned_model(16e9) is InfluenceModel.HYBRID
    # built: the planned hybrid operator, and the half-space if the choice picks it
    planned, halfspace = plan.geometries.values()
    assert (planned.operator, halfspace.operator) == (InfluenceModel.HYBRID,
                                                      InfluenceModel.HALFSPACE)
    assert plan.alternatives == {halfspace.key}
    assert {job.geometry.key for job in plan.jobs.values()} == {planned.key, halfspace.key}


def test_the_schema_fills_the_axes_of_a_generated_study_only():
    config = validated({"figures": {"fig07": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1.0]},
                                    "fig12": {"from": "fig07"}},
                        "sweeps": {"m": {"surface": {"file": "x.xyz"},
                                         "pressure_MPa": [1.0, 2.0]}}})
    # the paper's b = 1 mm and Gaussian moments; nothing for a study from another
    # or on a measured surface (whose statistics are the measurement's)
    assert config["figures"]["fig07"]["b_mm"] == 1.0
    assert config["figures"]["fig07"]["moments"] == [[0.0, 3.0]]
    assert config["figures"]["fig12"] == {"from": "fig07"}
    measured = config["sweeps"]["m"]
    assert "b_mm" not in measured and "moments" not in measured
    assert measured["compare_synthetic"] is False
    (cell,) = contact_cells(Study.from_config(config), "fig12")
    assert (cell.surface.skew, cell.surface.kurt, cell.surface.corr_length) == \
        (0.0, 3.0, (1e-3, 1e-3))


def test_a_two_bodies_figure_draws_the_aggregates_of_the_studies_it_lists():
    config = load_config(REPO / "config" / "two_bodies.yaml")
    plan = study_plan(Study.from_config(config))
    assert plan.figures == ("two_bodies",) and "two_bodies" not in plan.studies
    assert figure_aggregates(plan, "two_bodies") == ("pad_on_disc", "steel_plates")
    quick = study_plan(Study.from_config(quick_config()))
    assert figure_aggregates(quick, "fig01") == () and figure_aggregates(quick, "fig12") == (
        "fig07",)  # a surface figure draws none; a study from: another, its source's
    config["figures"]["two_bodies"]["studies"].append("pad_on_dsic")
    with pytest.raises(ConfigProblems, match="figures.two_bodies.studies: 'pad_on_dsic' is no "
                                             "sweep or contact figure"):
        study_plan(Study.from_config(config))


def test_a_leakage_figure_of_a_study_solved_without_the_flow_is_refused_before_any_job():
    """The leakage figure draws its studies' flow columns: with the flow off the plan
    names the key and the setting that turns it on; set so, it plans the seal's jobs."""
    raw = yaml.safe_load((REPO / "config" / "seal.yaml").read_text())
    raw["flow"]["enabled"] = False
    with pytest.raises(ConfigProblems) as refused:
        study_plan(Study.from_config(validated(raw)))
    (problem,) = refused.value.problems
    assert problem.startswith("figures.leakage.studies: 'seal' is solved without the flow")
    assert "set flow.enabled: true" in problem and "no job was started" in str(refused.value)
    raw["flow"]["enabled"] = True  # the advice, followed
    plan = study_plan(Study.from_config(validated(raw)))
    assert plan.figures == ("leakage",) and figure_aggregates(plan, "leakage") == ("seal",)
    assert plan.contact.flow.directions == ("x", "y")
