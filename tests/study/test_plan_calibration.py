"""The plan never calibrates the filter of a cell it accepts; the surface job does, and a
target near the reachable region's edge that it cannot reach ends the job with the
message the plan would have given.

The grid: 16 x 16 elements over 9 mm with b = 1 mm, skewness -1. The filter's bound
(Eq 15) is Ku = 2.3637 there, and a window's expected sample kurtosis on it is about
2.365: a target of 2.33 lies within the plan's band of the bound (left to the job) and
cannot be reached; 2.0 lies far below it (refused by the plan).
"""

import copy
import logging

import pytest

from roughcontact import InfeasibleMoments
from roughcontact.study import logs
from roughcontact.study.config import validated
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan import checks
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.records import GeneratedCell
from roughcontact.study.settings import Study
from roughcontact.surfaces import calibration
from roughcontact.surfaces.spec import SurfaceSpec

MM = 1e-3

BASE = {"study_seed": 0, "surfaces": {"grid": 16, "size_mm": 9.0, "count": 2,
                                      "method": "filter"},
        "figures": {}, "sweeps": {"edge": {"sigma_um": 24.5, "b_mm": 1.0,
                                           "moments": [[-1.0, 2.33]],
                                           "pressure_MPa": [0.1, 5.0]}}}


def _with_kurt(kurt: float) -> dict:
    raw = copy.deepcopy(BASE)
    raw["sweeps"]["edge"]["moments"] = [[-1.0, kurt]]
    return raw


def _cell(plan) -> GeneratedCell:
    (cell,) = plan.surfaces.values()
    return cell


def test_the_target_lies_where_the_module_docstring_says():
    """The referee of the other tests: the bound by Eq 15 and the calibration's refusal
    of 2.33, computed on the surface spec directly."""
    spec = SurfaceSpec(grid=(16, 16), size=(9 * MM, 9 * MM), corr_length=(MM, MM),
                       sigma=1.0, skew=-1.0, kurt=2.33)
    bound = float(calibration.kurt_min(spec, -1.0))
    assert bound == pytest.approx(2.3637, abs=1e-4)
    assert bound - checks.NEAR_BOUND * (2.33 - 1.0) < 2.33 < bound
    assert 2.0 < bound - checks.NEAR_BOUND * (2.0 - 1.0)
    with pytest.raises(InfeasibleMoments, match="not reachable in expectation"):
        calibration.calibrate_filter(spec)


@pytest.mark.parametrize("kurt", [2.33, 2.5, 6.0])
def test_a_plan_it_accepts_never_calibrates(monkeypatch, kurt):
    def refuse(spec, **_):
        raise AssertionError(f"the plan calibrated {spec}")

    monkeypatch.setattr(checks, "calibrate_filter", refuse)
    monkeypatch.setattr(calibration, "calibrate_filter", refuse)
    plan = study_plan(Study.from_config(validated(_with_kurt(kurt))))
    assert _cell(plan).kurt == kurt


def test_a_target_far_below_the_edge_is_refused_by_the_plan():
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(_with_kurt(2.0))))
    (problem,) = raised.value.problems
    assert "kurtosis 2 at skewness -1 is not reachable in expectation" in problem
    assert "Raise kurt to at least 2.3" in problem


def test_the_job_refuses_an_unreachable_target_near_the_edge_with_the_plans_message(
        tmp_path, caplog):
    plan = study_plan(Study.from_config(validated(_with_kurt(2.33))))
    cell = _cell(plan)
    with pytest.raises(InfeasibleMoments) as raised:
        build_surface_cell(cell.params(), 0, tmp_path / "cell.h5")
    message = str(raised.value)
    assert message.startswith(f"{cell.key}: kurtosis 2.33 at skewness -1 is not reachable "
                              "in expectation by the filter generator")
    # the text the plan gives a refused cell (check_feasible: the key, then the refusal)
    with pytest.raises(InfeasibleMoments) as direct:
        calibration.calibrate_filter(cell.spec())
    assert message == f"{cell.key}: {direct.value}"
    assert not (tmp_path / "cell.h5").exists()
    # the job's log ends on the message alone, no traceback
    with caplog.at_level(logging.ERROR, logger="roughcontact"):
        logs._excepthook(InfeasibleMoments, raised.value, raised.value.__traceback__)
    assert caplog.records[-1].getMessage() == message
