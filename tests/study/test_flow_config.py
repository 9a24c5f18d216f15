"""The configuration's flow section: off changes nothing, on reaches every contact job,
bad values are refused before any job with advice that works when followed."""

import copy

import numpy as np
import pandas as pd
import pytest

from roughcontact.study.config import ContactSettings, load_config, validated
from roughcontact.study.flow_settings import FLOW_OFF, check_flow, flow_settings
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.probes import PROBE_KINDS, probes_from_attrs, study_probes
from roughcontact.study.settings import Study
from roughcontact.transport import ARITHMETIC, NO_FLOW, SEALED, FlowProbe
from roughcontact.transport.probe import probe_from_params

STUDY = {"sigma_um": 10.0, "b_mm": 0.5, "pressure_MPa": [0.1, 2.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 500.0},
        "figures": {"fig07": STUDY}}
ON = {"enabled": True}


def config(**changes):
    raw = copy.deepcopy(BASE)
    for section, values in changes.items():
        raw.setdefault(section, {}).update(values)
    return validated(raw)


@pytest.mark.parametrize("path", ["config/config.yaml", "config/quick.yaml"])
def test_off_by_default_and_off_changes_no_job_parameter(path):
    shipped = load_config(path)
    assert shipped["flow"]["enabled"] is False
    assert flow_settings(shipped["flow"]) is FLOW_OFF and FLOW_OFF.params() == {}
    study = Study.from_config(shipped)
    settings = study.contact
    geometry = study_plan(study).jobs[next(iter(study_plan(study).jobs))].geometry
    assert settings.flow is NO_FLOW and settings.probes(geometry) == ()
    assert study_probes(FLOW_OFF) == () and study.probes == ()
    # the contact jobs' solver parameters as before the flow section existed
    assert set(settings.params()) == {"method", "tol", "precision", "steps", "pressure_levels"}


def test_on_every_contact_job_gets_the_probe_and_its_parameters_change():
    study = Study.from_config(config(flow={**ON, "directions": ["y"], "sides": "sealed",
                                           "face_rule": "arithmetic"}))
    settings = study.contact
    assert settings.flow == FlowProbe(directions=("y",), sides="sealed", face_rule=ARITHMETIC)
    params = settings.params()
    assert params["flow"] == {"directions": ["y"], "sides": "sealed",
                              "face_rule": "arithmetic", "closed_below": 1e-7,
                              "balance_tol": 1e-6}
    # the job reads its settings back from these parameters
    assert ContactSettings.from_section(params) == settings
    assert probe_from_params(params["flow"]) == settings.flow
    # the jobs record exactly that probe; a contact file's attribute makes it again
    geometry = next(iter(study_plan(study).jobs.values())).geometry
    assert settings.probes(geometry) == (settings.flow,) and study.probes == (study.flow,)
    assert PROBE_KINDS["flow"] is probe_from_params
    assert probes_from_attrs({"flow": '{"directions": ["y"], "sides": "sealed", '
                                      '"face_rule": "arithmetic", "closed_below": 1e-7}'}
                             ) == (settings.flow,)
    assert probes_from_attrs({"job": "{}"}) == ()
    assert SEALED.name == "sealed"


def test_the_seal_in_si_units_and_its_leak_rate():
    flow = flow_settings(config(flow={**ON, "viscosity_Pa_s": 0.05, "pressure_drop_MPa": 2.0,
                                      "seal_width_mm": 80.0, "seal_length_mm": 4.0})["flow"])
    assert flow.params()["pressure_drop_Pa"] == 2.0e6
    rows = pd.DataFrame({f"flow_conductance_{d}_{part}": [1e-18, 2e-18, 4e-18]
                         for d in "xy" for part in ("mean", "half_width")}
                        | {f"flow_conductance_{d}_count": [3, 3, 3] for d in "xy"}
                        | {"nominal_pressure": [1.0e6, 2.0e6, 3.0e6]})
    columns, units = flow.table_columns(rows)
    # Q = K W dp / (12 eta L), by hand
    expected = np.array([1e-18, 2e-18, 4e-18]) * 80e-3 * 2.0e6 / (12 * 0.05 * 4e-3)
    np.testing.assert_allclose(columns["leak_rate_x_mean"], expected, rtol=1e-15)
    np.testing.assert_allclose(columns["leak_rate_y_half_width"], expected, rtol=1e-15)
    assert list(columns["leak_rate_x_count"]) == [3, 3, 3]
    # the faces open where the 2 MPa drop exceeds the contact pressure: at 1 MPa only
    # (at 2 MPa it equals it, at 3 MPa it is below)
    assert list(columns["faces_open"]) == [True, False, False]
    assert list(columns) == [f"leak_rate_{d}_{part}" for d in "xy"
                             for part in ("mean", "half_width", "count")] + ["faces_open"]
    assert units == {name: "1" if name.endswith("_count") else "-" if name == "faces_open"
                     else "m^3/s" for name in columns}
    assert FLOW_OFF.table_columns(rows) == ({}, {})


@pytest.mark.parametrize(("key", "value", "fixed"), [
    ("pressure_drop_MPa", 100000.0, 0.1),  # 1 bar typed in Pa
    ("seal_width_mm", 0.1, 100.0),  # metres meant
    ("viscosity_Pa_s", 1.0e5, 100.0),  # mPa s meant
])
def test_a_unit_slip_is_refused_naming_the_key_and_the_advice_works(key, value, fixed):
    with pytest.raises(ConfigProblems) as caught:
        study_plan(Study.from_config(config(flow={**ON, key: value})))
    message = str(caught.value)
    assert f"flow.{key}: {value:g}" in message and "no job was started" in message
    advice = f"flow.{key}: {fixed:g}"
    assert advice in message
    study_plan(Study.from_config(
            config(flow={**ON, key: fixed})))  # following the advice: the plan passes


def flow_problems(validated_config: dict, grids: dict) -> list[str]:
    """The flow checks of a configuration's study."""
    study = Study.from_config(validated_config)
    return check_flow(study.flow, study.plausibility_check, grids)


def test_a_zero_pressure_drop_is_refused():
    problems = flow_problems(config(flow={**ON, "pressure_drop_MPa": 0.0}), {})
    assert len(problems) == 1 and "flow.pressure_drop_MPa: 0" in problems[0]


def test_a_grid_of_one_row_cannot_carry_a_flow():
    problems = flow_problems(config(flow=ON), {"the contact grid of g": (16, 1)})
    assert len(problems) == 1 and "16 x 1" in problems[0] and "flow.enabled: false" in problems[0]
    assert flow_problems(config(), {"the contact grid of g": (16, 1)}) == []  # off: unchecked


@pytest.mark.parametrize("bad", [{"directions": ["z"]}, {"directions": []},
                                 {"directions": ["x", "x"]}, {"viscosity_Pa_s": -1.0},
                                 {"sides": "open"}, {"enabled": "yes"}])
def test_the_schema_refuses_bad_flow_values_naming_the_key(bad):
    with pytest.raises(ValueError, match="flow"):
        config(flow={**ON, **bad})


def test_a_cells_flow_rows_count_the_steps_off_balance():
    from types import SimpleNamespace

    settings = flow_settings(config(flow={**ON, "directions": ["x"]})["flow"])
    connected = np.array([[True, True, False], [True, False, False]])
    balance = np.array([[1e-14, 3e-3, 0.0], [np.nan, 0.0, 0.0]])  # NaN: not computed
    sweep = SimpleNamespace(
        probe_columns={"flow_connected_x": connected, "flow_balance_x": balance},
        real_area_fraction=np.array([[0.2, 0.4, 0.6], [0.3, 0.5, 0.7]]),
        nominal_pressure=np.array([[1e6, 2e6, 4e6], [1e6, 2e6, 4e6]]),
        converged=np.ones((2, 3), dtype=bool))
    (row,) = settings.cell_rows(sweep, {"cell": "c"})
    assert row["direction"] == "x" and row["unbalanced_steps"] == 2
