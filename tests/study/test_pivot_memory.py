"""Block principal pivoting's factors in the contact jobs' planned memory: one Cholesky
factor of C on the contact set of every surface in flight, (a n)^2 doubles at the
contact fraction a the sweep reaches (roughcontact.study.plan.resources)."""

import dataclasses
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from roughcontact.study.config import BuildSettings, ContactSettings, validated
from roughcontact.study.contact_records import ContactJob
from roughcontact.study.counter_records import JobCounter
from roughcontact.study.jobs.contact import BATCH_SIZE
from roughcontact.study.plan import resources
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.records import GeneratedCell, Generator, Geometry, InfluenceModel
from roughcontact.study.settings import load_study

ROOT = Path(__file__).resolve().parents[2]
AUTO = ContactSettings(method="auto", tol=1e-8, precision="mixed", steps=24,
                       pressure_levels=16)
CG = dataclasses.replace(AUTO, method="cg")
#: The influence builds of a minimal config, completed by the schema's defaults (16 GB).
BUILD = BuildSettings.from_section(validated({
    "study_seed": 0, "figures": {}, "surfaces": {"grid": 60, "size_mm": 9.0, "count": 60},
    "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0}})["body"])


def job(grid=60, count=60, pressure_end=4.0, b_mm=1.0, acf="exponential",
        operator=InfluenceModel.DENSE) -> ContactJob:
    cell = GeneratedCell(skew=0.0, kurt=3.0, corr_length=(b_mm * 1e-3, b_mm * 1e-3),
                         grid=(grid, grid), size=(9e-3, 9e-3), acf=acf, periodic=True,
                         method=Generator.FILTER, count=count)
    geometry = Geometry(nu=0.0, size=(9e-3, 9e-3), thickness=10e-3, grid=(grid, grid),
                        base="clamped", mesh="refined", operator=operator)
    return ContactJob(surface=cell, geometry=geometry, pressure_end=pressure_end)


def test_the_contact_fraction_from_the_slope_worked_by_hand():
    # exponential ACF exp(-2.3 r / b), b = 1 mm, spacing 0.15 mm: the finite-difference
    # slope variance per sigma^2 is 2 (1 - exp(-0.345)) / 0.15 mm^2 along each axis
    spacing = 0.15e-3
    slope = math.sqrt(2 * 2 * (1 - math.exp(-2.3 * 0.15)) / spacing**2)
    assert resources.slope_per_height(job().surface) == pytest.approx(slope, rel=1e-12)
    # kappa 4 (cost_model.yaml) x P L / (E sigma) 4 / (L 10 mm x slope)
    assert resources.contact_fraction_bound(job()) == pytest.approx(4 * 4 / (0.01 * slope))
    # Gaussian ACF exp(-2.3 r^2 / b^2): smoother, more contact at the same load
    gaussian = math.sqrt(2 * 2 * (1 - math.exp(-2.3 * 0.15**2)) / spacing**2)
    assert resources.contact_fraction_bound(job(acf="gaussian")) == \
        pytest.approx(4 * 4 / (0.01 * gaussian))
    # a compliant counter body of the same modulus halves E*: twice the contact
    soft = dataclasses.replace(job(), counter=JobCounter(modulus_ratio=1.0))
    assert resources.contact_fraction_bound(soft) == \
        pytest.approx(2 * resources.contact_fraction_bound(job()))
    # the seal's sweep (to 128, b = 0.5 mm) reaches full contact: the bound stops at 1
    assert resources.contact_fraction_bound(job(pressure_end=128.0, b_mm=0.5)) == 1.0


def test_pivoting_adds_its_factors_to_a_dense_job_only():
    n = 3600
    plain = resources.contact_mem_mb(job(), CG, BUILD)
    assert plain == int(400 + (24 * n**2 + 80 * 60 * n) / 1e6)
    fraction = resources.contact_fraction_bound(job())
    # auto on a dense matrix pivots: 20 surfaces in flight (the job's batch) and 3
    # factors' worth while one is factored, (a n)^2 doubles each
    factors = (20 + 3) * 8 * (fraction * n) ** 2
    assert resources.contact_mem_mb(job(), AUTO, BUILD) == \
        int(400 + (24 * n**2 + 80 * 60 * n + factors) / 1e6)
    # a cell of 5 surfaces has 5 in flight
    assert resources.pivot_factor_bytes(job(count=5), AUTO, True) == \
        pytest.approx((5 + 3) * 8 * (fraction * n) ** 2)
    # auto on a matrix-free model solves by CG: nothing; pivot asked for: counted
    hybrid = job(grid=256, count=20, operator=InfluenceModel.HYBRID)
    assert resources.pivot_factor_bytes(hybrid, AUTO, False) == 0.0
    assert resources.pivot_factor_bytes(hybrid, dataclasses.replace(AUTO, method="pivot"),
                                        False) > 0.0
    for method in ("cg", "pcg", "steepest"):
        assert resources.pivot_factor_bytes(job(), dataclasses.replace(AUTO, method=method),
                                            True) == 0.0


def test_the_planned_batch_is_the_contact_jobs():
    assert resources._MODEL["contact"]["pivot_batch_surfaces"] == BATCH_SIZE


def test_the_seal_study_plans_its_measured_peak_and_the_default_study_little_more():
    """The seal's contact jobs (60 x 60, 20 surfaces to near full contact) peaked at
    2.19-2.43 GB (Snakemake's max_rss) and 2.53 GB (the resident high-water mark of one
    job run alone; docs/performance/run-time.md), the two-body study's at 0.61-1.05 GB;
    the default study's 60 x 60 jobs at 0.33-0.68 GB."""
    seal = study_plan(load_study(ROOT / "config" / "seal.yaml"))
    planned = [resources.job_memory_mb(seal, "contact", {"job": key}) for key in seal.jobs]
    assert min(planned) >= 2530
    assert max(planned) <= 1.25 * 2530
    # config/two_bodies.yaml (60 x 60, 20 surfaces to 30-54 % contact): 609-1045 MB
    pairs = study_plan(load_study(ROOT / "config" / "two_bodies.yaml"))
    assert min(resources.job_memory_mb(pairs, "contact", {"job": key})
               for key in pairs.jobs) >= 1045
    default = study_plan(load_study(ROOT / "config" / "config.yaml"))
    largest = max(resources.job_memory_mb(default, "contact", {"job": key})
                  for key in default.jobs)
    assert largest <= 1.6 * 675


#: A child process that sweeps ``count`` random gap fields on ``side x side`` elements
#: by block principal pivoting to full contact (a diagonally dominant positive definite
#: influence matrix, approaches to three times the deepest gap) and prints the resident
#: high-water mark during the sweep less the resident memory before [bytes] and the
#: least contact fraction at the last step.
CHILD = r"""
import json, sys
import numpy as np
from roughcontact import contact

side, count = int(sys.argv[1]), int(sys.argv[2])
x, y = np.meshgrid(np.arange(side), np.arange(side))
points = np.column_stack([x.ravel(), y.ravel()]).astype(float)
distance2 = ((points[:, None, :] - points[None, :, :]) ** 2).sum(axis=-1)
matrix = 1e-9 * (0.3 * np.exp(-distance2 / 2.0) + np.eye(side * side))
del distance2
gaps = np.random.default_rng(3).random((count, side * side)) * 1e-6
approaches = np.linspace(0.0, 3e-6, 12)

def status(key):
    return next(int(l.split()[1]) * 1024 for l in open("/proc/self/status")
                if l.startswith(key))

before = status("VmRSS")
open("/proc/self/clear_refs", "w").write("5")
result = contact.sweep(matrix, gaps, approaches, element_area=1e-8,
                       options=contact.SolverOptions(method="pivot"))
print(json.dumps({"peak": status("VmHWM") - before,
                  "fraction": float(result.real_area_fraction[:, -1].min())}))
"""


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="Linux /proc only")
def test_the_planned_memory_covers_a_measured_pivot_sweep_to_full_contact():
    """40 x 40 elements, 6 surfaces swept to full contact: the planned memory beyond the
    interpreter's covers the sweep's measured peak, and would not without the factors."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, "40", "6"], env=env, check=True,
                         capture_output=True, text=True, timeout=600)
    measured = json.loads(out.stdout.strip().splitlines()[-1])
    assert measured["fraction"] == 1.0  # every element in contact at the end
    swept = job(grid=40, count=6, pressure_end=1024.0)
    assert resources.contact_fraction_bound(swept) == 1.0
    base = resources._MODEL["contact"]["memory_base_mb"]
    planned = (resources.contact_mem_mb(swept, AUTO, BUILD) - base) * 1e6
    without = (resources.contact_mem_mb(swept, CG, BUILD) - base) * 1e6
    # 6 factors of 1600^2 doubles held at once: 123 MB and more
    assert measured["peak"] > 6 * 8 * 1600**2 > without
    assert planned >= measured["peak"]
