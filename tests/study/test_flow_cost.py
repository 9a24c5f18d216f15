"""The flow through the gap in the contact jobs' planned memory and time, and the
warning before a job planned beyond a day."""

import json
import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest

from roughcontact.study.config import validated
from roughcontact.study.plan import machine, resources
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.settings import Study

ROOT = Path(__file__).resolve().parents[2]

#: A child process that records the flow of ``count`` smooth random gap fields on
#: ``side x side`` elements (5 % closed) with the default probe along x and y, and prints
#: the resident high-water mark during the call less the resident memory before [bytes]
#: (C libraries' memory included).
CHILD = r"""
import json, sys
import numpy as np
from roughcontact.contact.probes import SolvedFields
from roughcontact.transport import FlowProbe

side, count, periodic = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "periodic"
rng = np.random.default_rng(7)
x = np.arange(side)
bump = np.exp(-np.minimum(x, side - x) ** 2 / (2 * (side / 20) ** 2))
kernel = np.fft.fft2(bump[:, None] * bump[None, :])
heights = np.fft.ifft2(np.fft.fft2(rng.standard_normal((count, side, side))) * kernel).real
gap = np.maximum(heights - np.quantile(heights, 0.05, axis=(-2, -1), keepdims=True), 0.0)
fields = SolvedFields(np.where(gap > 0, 0.0, 1.0), gap, gap.mean(axis=(-2, -1)),
                      (1e-4, 1e-4), periodic)

def status(key):
    return next(int(l.split()[1]) * 1024 for l in open("/proc/self/status")
                if l.startswith(key))

before = status("VmRSS")
open("/proc/self/clear_refs", "w").write("5")
FlowProbe().measure(fields)
print(json.dumps(status("VmHWM") - before))
"""


def measured_flow_peak(side: int, count: int, sides: str) -> int:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, str(side), str(count), sides],
                         env=env, check=True, capture_output=True, text=True, timeout=600)
    return json.loads(out.stdout.strip().splitlines()[-1])


def flow_config(grid: int, count: int = 4, operator: str = "halfspace",
                directions=("x", "y")) -> dict:
    return validated({
        "study_seed": 0,
        "surfaces": {"grid": grid, "size_mm": 9.0, "count": count, "periodic": True},
        "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0, "mesh": "refined",
                 "operator": operator},
        "contact": {"steps": 20, "pressure_levels": 12},
        "flow": {"enabled": True, "directions": list(directions), "viscosity_Pa_s": 0.001,
                 "pressure_drop_MPa": 1.0, "seal_width_mm": 100.0, "seal_length_mm": 2.0},
        "figures": {},
        "sweeps": {"seal": {"sigma_um": 5.0, "b_mm": 0.5, "moments": [[0.0, 3.0]],
                            "pressure_MPa": [0.2, 20.0]}}})


def plan_of(config: dict):
    return study_plan(Study.from_config(config))


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="Linux /proc only")
@pytest.mark.parametrize("sides", ["sealed", "periodic"])
def test_the_planned_memory_covers_a_measured_flow(sides):
    """192 x 192 (the band Cholesky with sealed sides, SuperLU with periodic ones), 3
    fields: the job's planned memory with the flow exceeds the same job's without it by at
    least the flow's measured peak."""
    peak = measured_flow_peak(192, 3, sides)
    assert peak > 5e6  # the measurement sees the solve (tens of MB)
    assert resources.flow_memory_bytes((192, 192), 3, ("x", "y")) >= peak
    with_flow = plan_of(flow_config(192, count=3))
    without = plan_of({**flow_config(192, count=3), "flow": {"enabled": False}})
    (job,) = with_flow.jobs.values()
    (bare,) = without.jobs.values()
    planned = resources.job_memory_mb(with_flow, "contact", {"job": job.key})
    assert planned - resources.job_memory_mb(without, "contact", {"job": bare.key}) \
        >= peak / 1e6


def test_the_flow_memory_at_1024_is_the_issues_gigabyte_and_more():
    """One 1024 x 1024 flow solve peaked at 1.55-1.64 GB (results/benchmarks/flow_memory.md);
    the plan of a 1024 x 1024 job with the flow asks for more than that beyond its
    contact solve's memory."""
    with_flow = plan_of(flow_config(1024, count=2))
    without = plan_of({**flow_config(1024, count=2), "flow": {"enabled": False}})
    (job,) = with_flow.jobs.values()
    (bare,) = without.jobs.values()
    added = (resources.job_memory_mb(with_flow, "contact", {"job": job.key})
             - resources.job_memory_mb(without, "contact", {"job": bare.key}))
    assert added >= 1640
    # the flow's time: 2 surfaces x 20 steps x 2 directions, at least the 20 s measured
    seconds = (resources.contact_seconds(job, with_flow.contact, with_flow.build)
               - resources.contact_seconds(bare, without.contact, without.build))
    assert seconds >= 2 * 20 * 2 * 20.2


def test_no_flow_adds_nothing():
    assert resources.flow_memory_bytes((512, 512), 20, ()) == 0.0


def test_a_job_planned_beyond_a_day_is_named_once_with_what_to_change(caplog):
    """4096 x 4096 on the half-space with the flow, 20 surfaces x 20 steps: days."""
    plan = plan_of(flow_config(4096, count=20))
    (job,) = plan.jobs.values()
    caplog.clear()  # the plan's own warnings
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        machine.warn_long_jobs(plan)
    (record,) = [r for r in caplog.records if r.levelno == logging.WARNING]
    text = record.getMessage()
    assert text.startswith("Jobs planned to run longer than a day")
    assert f"contact job {job.key}: estimated " in text
    days = float(text.split(f"contact job {job.key}: estimated ")[1].split(" days")[0])
    assert days > 1.0
    assert "surfaces.count" in text and "surfaces.grid" in text
    assert "flow.directions: [x]" in text


@pytest.mark.parametrize("change", ["grid", "count"])
def test_the_advice_followed_brings_the_job_within_a_day(change, caplog):
    """A smaller grid or fewer surfaces, as the warning says: no warning."""
    config = flow_config(1024, count=2) if change == "grid" else flow_config(4096, count=1)
    config["contact"]["steps"] = 5
    plan = plan_of(config)
    assert machine.long_jobs(plan) == []
    caplog.clear()  # the plan's own warnings
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        machine.warn_long_jobs(plan)
    assert not [r for r in caplog.records if r.levelno == logging.WARNING]
