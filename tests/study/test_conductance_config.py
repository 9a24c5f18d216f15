"""The configuration's conductance section: off changes nothing, on gives every contact
job the probe through its own body, bad values are refused before any job with advice
that plans when followed."""

import copy
import json
import logging
import re

import numpy as np
import pandas as pd
import pytest
from study_sections import planned, with_sections

from roughcontact.study.conductance_settings import (
    CONDUCTANCE_OFF,
    ConductanceSettings,
    conductance_settings,
)
from roughcontact.study.config import ConfigError, ContactSettings, load_config, validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.probes import (
    PROBE_KINDS,
    probes_from_attrs,
    study_probe_params,
    study_probes_from_params,
)
from roughcontact.study.settings import Study
from roughcontact.transport.conduction import (
    BlockBody,
    ConductanceProbe,
    HalfSpaceBody,
    conductance_probe_from_params,
)

STUDY = {"sigma_um": 1.0, "b_mm": 0.5, "pressure_MPa": [1.0, 20.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 210000.0, "nu": 0.3},
        "figures": {"fig07": STUDY}}
ON = {"enabled": True, "conductivity_W_mK": 50.0}


def config(**sections) -> dict:
    return with_sections(BASE, **sections)


plan = planned


def refusal(raw: dict) -> str:
    with pytest.raises(ConfigProblems) as caught:
        plan(raw)
    return str(caught.value)


def follow(raw: dict, advice: str) -> dict:
    """The configuration with one piece of advice (``<key path>: <YAML value>``) applied."""
    key, value = advice.split(": ", 1)
    *path, last = key.split(".")
    followed = copy.deepcopy(raw)
    entry = followed
    for part in path:
        entry = entry.setdefault(part, {})
    entry[last] = value if value.isalpha() else float(value)
    return followed


@pytest.mark.parametrize("path", ["config/config.yaml", "config/quick.yaml"])
def test_off_by_default_and_off_changes_no_job_parameter(path):
    shipped = load_config(path)
    assert shipped["conductance"] == {"enabled": False, "tol": 1e-10, "body": "block"}
    assert conductance_settings(shipped["conductance"]) is CONDUCTANCE_OFF
    study = Study.from_config(shipped)
    assert study.conductance is CONDUCTANCE_OFF and CONDUCTANCE_OFF.params() == {}
    assert "conductance" not in study.contact.params() and study.probes == ()
    assert study_probe_params(study.probes) == {}


def test_on_every_contact_job_records_the_probe_through_its_own_block():
    study = Study.from_config(validated(config(conductance={**ON, "resistivity_uohm_cm": 15.0})))
    jobs = study_plan(study).jobs
    assert jobs
    for job in jobs.values():
        (probe,) = study.contact.probes(job.geometry)
        assert isinstance(probe, ConductanceProbe)
        assert probe.conductivity == 50.0 and probe.resistivity == pytest.approx(15e-8)
        block = probe.body.geometry
        assert isinstance(probe.body, BlockBody)
        assert (block.size, block.thickness, block.grid, block.mesh) == (
            job.geometry.size, job.geometry.thickness, job.geometry.grid, job.geometry.mesh)
        # the contact file's attribute makes the same probe again
        stored = {"conductance": json.dumps(probe.params())}
        assert probes_from_attrs(stored) == (probe,)
    assert PROBE_KINDS["conductance"] is conductance_probe_from_params
    # the job reads its settings back from its parameters
    params = study.contact.params()
    assert params["conductance"] == {"conductivity": 50.0, "resistivity": pytest.approx(15e-8),
                                     "tol": 1e-10, "body": "block"}
    assert ContactSettings.from_section(params) == study.contact
    # and the aggregate rule its study-side record
    assert study_probes_from_params(study_probe_params(study.probes)) == (study.conductance,)


def test_the_heat_crosses_the_block_whatever_its_elastic_model_or_a_half_space():
    # the block's elastic influence a half-space: the heat still crosses the block
    study = Study.from_config(validated(config(conductance=ON,
                                               body={"operator": "halfspace"})))
    for job in study_plan(study).jobs.values():
        body = study.contact.probes(job.geometry)[0].body
        assert isinstance(body, BlockBody) and body.geometry.thickness == 2e-3
    # asked for: a free half-space, whatever the elastic model
    study = Study.from_config(validated(config(conductance={**ON, "body": "halfspace"})))
    for job in study_plan(study).jobs.values():
        assert study.contact.probes(job.geometry)[0].body == HalfSpaceBody(periodic=False)


def test_with_the_flow_both_probes_in_the_order_the_jobs_record_them():
    study = Study.from_config(validated(config(conductance=ON, flow={"enabled": True})))
    job = next(iter(study_plan(study).jobs.values()))
    kinds = [probe.kind for probe in study.contact.probes(job.geometry)]
    assert kinds == ["flow", "conductance"] == [record.kind for record in study.probes]


@pytest.mark.parametrize(("key", "typed", "advice"), [
    ("conductivity_W_mK", 0.05, "conductance.conductivity_W_mK: 50"),   # W/(mm K)
    ("resistivity_uohm_cm", 1.5e-5, "conductance.resistivity_uohm_cm: 15"),  # Ohm cm
    ("resistivity_uohm_cm", 1.5e-7, "conductance.resistivity_uohm_cm: 15"),  # Ohm m
])
def test_a_unit_slip_is_refused_naming_the_key_and_the_advice_plans(key, typed, advice):
    raw = config(conductance={"enabled": True, key: typed})
    message = refusal(raw)
    assert "no job was started" in message and f"conductance.{key}: {typed:g}" in message
    offered = re.findall(r"then write (conductance\.\w+: [\d.e+-]+)", message)
    assert advice in offered
    assert plan(follow(raw, advice)).jobs
    # and a value meant as typed is accepted with the check off
    assert plan(raw | {"plausibility_check": False}).jobs


def test_on_without_a_material_is_refused_naming_both_keys():
    with pytest.raises(ConfigError, match="conductance: needs one of: 'conductivity_W_mK'; "
                                          "'resistivity_uohm_cm'"):
        validated(config(conductance={"enabled": True}))


def test_a_block_beyond_the_dense_limit_gets_the_matrix_free_thermal_block(caplog):
    raw = config(conductance=ON, surfaces={"grid": [72, 72], "size_mm": [10.8, 10.8],
                                           "count": 2},
                 body={"thickness_mm": 10.0, "operator": "hybrid", "mesh": "refined"})
    with caplog.at_level(logging.INFO):
        planned = plan(raw)
    assert "gets the matrix-free thermal block" in caplog.text
    (thermal,) = planned.thermal.values()
    assert thermal.grid == (72, 72)
    # its job builds the coarse block's (36 x 36), not a 72^2 x 72^2 matrix
    from roughcontact.study.plan import resources
    assert resources.job_memory_mb(planned, "thermal", {"thermal": thermal.key}) < 1000


def test_a_figure_of_the_conductance_with_it_off_is_refused():
    raw = config(sweeps={"hot": STUDY}, figures={"conductance": {"studies": ["hot"]}})
    message = refusal(raw)
    assert ("figures.conductance.studies: 'hot' is solved without the conductance" in message
            and "set conductance.enabled: true" in message)
    assert plan(config(sweeps={"hot": STUDY}, conductance=ON,
                       figures={"conductance": {"studies": ["hot"]}})).figures


def test_a_compliant_counter_body_is_warned_about(caplog):
    raw = config(conductance=ON, counterface={"body": {"kind": "halfspace",
                                                       "E_MPa": 210000.0, "nu": 0.3}})
    with caplog.at_level(logging.WARNING):
        plan(raw)
    assert "is taken as a perfect conductor" in caplog.text


def test_a_generated_study_names_its_blocks_thickness():
    raw = config(sweeps={"thin": {**STUDY, "thickness_mm": 0.5}})
    cells = plan(raw).cells
    assert {c.geometry.thickness for c in cells["thin"]} == {0.5e-3}
    assert {c.geometry.thickness for c in cells["fig07"]} == {2e-3}


def test_the_table_gets_the_constriction_share_beside_the_bulks():
    settings = ConductanceSettings.from_params({"conductivity": 50.0, "resistivity": None,
                                                "tol": 1e-10, "body": "block"})
    rows = pd.DataFrame({"conduction_bulk_share_mean": [0.25, 0.5],
                         "conduction_bulk_share_half_width": [0.01, 0.02],
                         "conduction_bulk_share_count": [4, 4]})
    columns, units = settings.table_columns(rows)
    np.testing.assert_array_equal(columns["conduction_constriction_share_mean"], [0.75, 0.5])
    np.testing.assert_array_equal(columns["conduction_constriction_share_half_width"],
                                  [0.01, 0.02])
    assert set(units) == set(columns)
    electrical = ConductanceSettings.from_params({"conductivity": None, "resistivity": 1e-7,
                                                  "tol": 1e-10, "body": "block"})
    assert electrical.table_columns(rows) == ({}, {})


def test_the_counter_bodys_material_puts_a_half_space_in_series():
    from roughcontact.transport.conduction import SeriesBody

    study = Study.from_config(validated(config(conductance={
        **ON, "counter_conductivity_W_mK": 16.0, "resistivity_uohm_cm": 15.0,
        "counter_resistivity_uohm_cm": 1.7})))
    job = next(iter(study_plan(study).jobs.values()))
    (probe,) = study.contact.probes(job.geometry)
    thermal, electrical = probe.thermal_body, probe.electrical_body
    assert isinstance(thermal, SeriesBody) and isinstance(thermal.first, BlockBody)
    assert thermal.counter == HalfSpaceBody(dense=True)  # one matrix with the block's
    assert thermal.ratio == pytest.approx(50.0 / 16.0)
    assert electrical.ratio == pytest.approx(1.7 / 15.0)
    assert study.conductance.sidecar([])["counter_body"] == (
        "a half-space of thermal conductivity 16 W/(m K) and electrical resistivity "
        "1.7 uOhm cm in series")
    # the counter's material needs the body's own: refused by the schema, naming both
    with pytest.raises(ConfigError, match="'conductivity_W_mK' is a dependency of "
                                          "'counter_conductivity_W_mK'"):
        validated(config(conductance={"enabled": True, "resistivity_uohm_cm": 15.0,
                                      "counter_conductivity_W_mK": 16.0}))
    # and its unit slips are refused as the body's are
    raw = config(conductance={**ON, "counter_conductivity_W_mK": 0.016})
    message = refusal(raw)
    assert "conductance.counter_conductivity_W_mK: 0.016 is outside" in message
    assert plan(follow(raw, "conductance.counter_conductivity_W_mK: 16")).jobs
