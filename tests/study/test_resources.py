"""The cost model of the job resources (roughcontact.study.plan.resources): values
worked by hand from the documented formulas and config/cost_model.yaml."""

import dataclasses
import math

import pytest
import yaml
from snakemake.utils import validate

from roughcontact.study.config import (
    BuildSettings,
    ContactSettings,
    ConvergenceSettings,
    validated,
)
from roughcontact.study.contact_records import ContactJob
from roughcontact.study.plan import cost_drift, machine, resources
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.records import GeneratedCell, Generator, Geometry, InfluenceModel
from roughcontact.study.settings import Study

CG = ContactSettings(method="cg", tol=1e-8, precision="mixed", steps=30, pressure_levels=30)
#: The influence builds of a minimal config, completed by the schema's defaults (16 GB).
BUILD = BuildSettings.from_section(validated({
    "study_seed": 0, "figures": {}, "surfaces": {"grid": 60, "size_mm": 9.0, "count": 60},
    "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0}})["body"])


def cell(grid=60, count=60, method=Generator.FILTER) -> GeneratedCell:
    return GeneratedCell(skew=0.0, kurt=3.0, corr_length=(1e-3, 1e-3), grid=(grid, grid),
                         size=(9e-3, 9e-3), acf="exponential", periodic=True, method=method,
                         count=count)


def dense_job(grid=60, count=60, pressure_end=4.0, operator=InfluenceModel.DENSE):
    geometry = Geometry(nu=0.0, size=(9e-3, 9e-3), thickness=10e-3, grid=(grid, grid),
                        base="clamped", mesh="paper", operator=operator)
    return ContactJob(surface=cell(grid, count), geometry=geometry, pressure_end=pressure_end)


def hybrid_job(grid=256, count=20):
    return dense_job(grid, count, operator=InfluenceModel.HYBRID)


def test_contact_runtime_at_the_measured_cell():
    # 60 surfaces x 30 steps x 0.11 s = 198 s; 3 x 198 / 60 = 9.9 -> 10 min, + 5 min start
    assert resources.contact_seconds(dense_job(), CG, BUILD) == pytest.approx(198.0)
    assert resources.contact_runtime(dense_job(), CG, BUILD) == 15
    assert resources.contact_runtime(dense_job(), CG, BUILD, attempt=2) == 30


def test_contact_runtime_scales_with_surfaces_steps_grid_and_reach():
    base = resources.contact_seconds(dense_job(), CG, BUILD)
    assert resources.contact_seconds(dense_job(count=30), CG, BUILD) == pytest.approx(base / 2)
    assert resources.contact_seconds(dense_job(), dataclasses.replace(CG, steps=60), BUILD) == \
        pytest.approx(2 * base)
    # a quarter of the elements: (900 / 3600)^2.5 = 1/32
    assert resources.contact_seconds(dense_job(grid=30), CG, BUILD) == pytest.approx(base / 32)
    # a sweep to P L / (E sigma) = 12 reaches three times the study's 4
    assert resources.contact_seconds(dense_job(pressure_end=12.0), CG, BUILD) == \
        pytest.approx(3 * base)
    # pivoting: its steps stay about as cheap beyond the study's reach
    pivot = dataclasses.replace(CG, method="pivot")
    assert resources.contact_seconds(dense_job(pressure_end=12.0), pivot, BUILD) == \
        pytest.approx(resources.contact_seconds(dense_job(), pivot, BUILD))
    # steepest descent: 3 times the products; tol 1e-12: 12 / 8 digits
    steepest = dataclasses.replace(CG, method="steepest")
    assert resources.contact_seconds(dense_job(), steepest, BUILD) == pytest.approx(3 * base)
    assert resources.contact_seconds(dense_job(), dataclasses.replace(CG, tol=1e-12), BUILD) == \
        pytest.approx(1.5 * base)


def test_the_flow_adds_its_solves_to_a_contact_job():
    from roughcontact.transport import FlowProbe

    base = resources.contact_seconds(dense_job(), CG, BUILD)
    both = dataclasses.replace(CG, flow=FlowProbe())
    # 60 surfaces x 30 steps x 2 directions x 55 ms on the 60 x 60 reference grid
    assert resources.contact_seconds(dense_job(), both, BUILD) == pytest.approx(base + 198.0)
    one = dataclasses.replace(CG, flow=FlowProbe(directions=("x",)))
    # 120 x 120: four times the elements, 4^1.1 the time per solve
    assert (resources.contact_seconds(dense_job(grid=120), one, BUILD)
            - resources.contact_seconds(dense_job(grid=120), CG, BUILD)) == \
        pytest.approx(1800 * 0.055 * 4**1.1)


def test_matrix_free_contact_runtime_in_proportion_to_n():
    # 20 surfaces x 30 steps x 0.62 s at 256 x 256
    assert resources.contact_seconds(hybrid_job(), CG, BUILD) == pytest.approx(20 * 30 * 0.62)
    # 128 x 128: a quarter of n; 16 x 16 hits the 0.05 s floor
    assert resources.contact_seconds(hybrid_job(128), CG, BUILD) == pytest.approx(600 * 0.62 / 4)
    assert resources.contact_seconds(hybrid_job(16), CG, BUILD) == pytest.approx(600 * 0.05)


def test_contact_memory_dense_and_matrix_free():
    n = 60 * 60
    assert resources.contact_mem_mb(dense_job(), CG, BUILD) == \
        int(400 + (24 * n**2 + 80 * 60 * n) / 1e6)
    n = 256 * 256
    # the 64 x 64 coarse correction, not a 34 GB dense matrix
    assert resources.contact_mem_mb(hybrid_job(), CG, BUILD) == \
        int(400 + (8 * 4096**2 + 240 * 20 * n) / 1e6)
    assert resources.contact_mem_mb(hybrid_job(), CG, BUILD) < 1000


def test_the_body_memory_limit_plans_the_model_of_every_estimate():
    # operator auto on 60 x 60: dense within the default 16 GB, hybrid when the
    # body allows less than the dense build's estimated peak (about 0.9 GB)
    job = dense_job(operator=InfluenceModel.AUTO)
    tight = dataclasses.replace(BUILD, max_bytes=0.1e9)
    assert resources.contact_mem_mb(job, CG, BUILD) == \
        resources.contact_mem_mb(dense_job(), CG, BUILD)
    hybrid = hybrid_job(60, 60)
    assert resources.contact_mem_mb(job, CG, tight) == resources.contact_mem_mb(hybrid, CG, BUILD)
    assert resources.contact_seconds(job, CG, tight) == \
        pytest.approx(resources.contact_seconds(hybrid, CG, BUILD))
    # stored: the dense matrix, or the coarse correction bound (64^2 x 64^2 doubles)
    assert resources.stored_bytes(job.geometry, BUILD) == 8 * 3600**2
    assert resources.stored_bytes(job.geometry, tight) == 8 * 4096**2


def test_memory_and_time_grow_with_the_grid():
    grids = [16, 30, 60, 120]
    for small, large in zip(grids, grids[1:], strict=False):
        assert resources.contact_mem_mb(dense_job(small), CG, BUILD) < \
            resources.contact_mem_mb(dense_job(large), CG, BUILD)
        assert resources.contact_seconds(dense_job(small), CG, BUILD) < \
            resources.contact_seconds(dense_job(large), CG, BUILD)
        assert resources.surfaces_mem_mb(cell(small)) <= resources.surfaces_mem_mb(cell(large))


def test_influence_runtime_through_the_measured_anchor():
    geometry = dense_job().geometry
    peak_gb = geometry.influence_cost(BUILD).peak_bytes / 1e9
    expected = 4.2 * (peak_gb / 0.92) ** 1.56
    assert resources.influence_seconds(geometry, BUILD) == pytest.approx(expected)
    # at the anchor itself (0.92 GB -> 4.2 s): 3 x 4.2 / 60 -> 1 min, + 5 min start
    assert resources.runtime_minutes(4.2 * (0.92 / 0.92) ** 1.56) == 6
    # 9.6 GB (converged, measured 116-132 s): 4.2 x (9.6 / 0.92)^1.56 = 162 s -> 9 + 5 min
    seconds = 4.2 * (9.6 / 0.92) ** 1.56
    assert 132 < seconds < 170
    assert resources.runtime_minutes(seconds, attempt=2) == 2 * (5 + math.ceil(3 * seconds / 60))
    assert resources.influence_mem_mb(geometry, BUILD) == \
        int(geometry.influence_cost(BUILD).peak_bytes / 1e6) + 200


def test_surfaces_runtime_and_memory():
    # IAAFT, 60 surfaces of 120 x 120: 60 x 0.01 s x 4^1.5 = 4.8 s -> 1 min, + 5 min
    exact = cell(120, method=Generator.EXACT)
    assert resources.surfaces_seconds(exact) == pytest.approx(4.8)
    assert resources.surfaces_runtime(exact, attempt=3) == 18
    assert resources.surfaces_mem_mb(exact) == int(300 + 160 * 60 * 14400 / 1e6)
    # the filter adds its calibration (15 s at most); the paper's filter has none
    assert resources.surfaces_seconds(cell(120)) == pytest.approx(15.0 + 60 * 0.001 * 4**1.5)
    assert resources.surfaces_seconds(cell(120, method=Generator.PAPER)) == \
        pytest.approx(60 * 0.001 * 4**1.5)


def test_convergence_and_summaries():
    geometry = dense_job().geometry
    report = ConvergenceSettings(presets=("a",) * 4, surfaces=3, sigma=24.5e-6,
                                 corr_length=1e-3, pressures=(1e6,))
    # 4 presets + half-space, 3 surfaces: 30 + 15 x 4 s = 90 s -> 5 + 5 min
    assert resources.convergence_runtime(geometry, ["a"] * 4, report) == 10
    # 60 x 60: 5 matrices of 104 MB, below the 2 GB floor; 120 x 120: 8.3 GB
    assert resources.convergence_mem_mb(geometry, ["a"] * 4) == 2000
    assert resources.convergence_mem_mb(dense_job(120).geometry, ["a"] * 4) == \
        int(1000 + 5 * 8 * 14400**2 / 1e6)
    assert resources.summary_runtime(attempt=2) == 2 * (5 + 2)


def test_loader_names_the_file_and_the_missing_key(tmp_path):
    data = yaml.safe_load(resources.COST_MODEL_FILE.read_text())
    del data["contact"]["dense_solve_seconds"]
    path = tmp_path / "cost_model.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError, match=r"cost_model\.yaml.*contact\.dense_solve_seconds"):
        resources.load_cost_model(path)
    with pytest.raises(FileNotFoundError, match="missing.yaml"):
        resources.load_cost_model(tmp_path / "missing.yaml")


HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def test_compare_prints_predictions_against_benchmarks(tmp_path, capsys):
    quick = resources.SCHEMA_FILE.parent / "quick.yaml"
    config = yaml.safe_load(quick.read_text())
    validate(config, str(resources.SCHEMA_FILE))
    key, geometry = sorted(study_plan(Study.from_config(config)).geometries.items())[0]
    build = BuildSettings.from_section(config["body"])
    seconds = resources.influence_seconds(geometry, build)
    mem_mb = resources.influence_mem_mb(geometry, build)
    folder = tmp_path / "influence"
    folder.mkdir()
    (folder / f"{key}.tsv").write_text(HEADER + "2.00\t0:00:02\t100.0\t1\t1\t1\t0\t0\t50\t1\n")
    (folder / "not_a_job.tsv").write_text(HEADER + "1\t0\t1\t1\t1\t1\t0\t0\t1\t1\n")
    code = cost_drift.main(["--compare", str(tmp_path), "--configfile", str(quick)])
    assert code == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if key in line]
    assert len(lines) == 1
    fields = lines[0].split()
    assert fields[0] == "influence"
    assert float(fields[1]) == pytest.approx(seconds, abs=0.01)
    assert float(fields[3]) == pytest.approx(seconds / 2.0, abs=0.01)
    assert int(fields[4]) == mem_mb and float(fields[6]) == pytest.approx(mem_mb / 100, abs=0.01)


def test_jobs_planned_beyond_the_machine_are_named_with_the_keys_to_change():
    quick = resources.SCHEMA_FILE.parent / "quick.yaml"
    config = yaml.safe_load(quick.read_text())
    validate(config, str(resources.SCHEMA_FILE))
    plan = study_plan(Study.from_config(config))
    planned = machine.planned_memory(plan)
    # the study's jobs and, beside them, the configured report and the audit
    assert {"contact", "influence", "surfaces", "influence_convergence", "audit"} <= set(planned)
    largest = max(mem for jobs in planned.values() for mem in jobs.values())
    assert machine.machine_problems(plan, total_mb=largest) == []
    contact = max(cost_drift.predictions(plan)["contact"].values())[1]
    problems = machine.machine_problems(plan, total_mb=contact - 1)
    by_kind = {p.split(" job ")[0]: p for p in problems}
    assert "contact" in by_kind and "body.operator: auto" in by_kind["contact"]
    assert "more than the limit of" in by_kind["contact"]
    assert "reports.influence_convergence" in by_kind["influence_convergence"]
    assert all("set job_memory_gb to their memory" in p for p in problems)


def plan_of(config: dict):
    """The plan of a validated configuration."""
    return study_plan(Study.from_config(config))


def huge_grid_config(**extra):
    """The issue's case: a 4096 x 4096 grid with operator: auto and the mesh report."""
    config = yaml.safe_load((resources.SCHEMA_FILE.parent / "quick.yaml").read_text())
    config["surfaces"]["grid"] = [4096, 4096]
    config["body"]["operator"] = "auto"
    config |= {"figures": {}, "sweeps": {}, **extra}
    return config


def test_a_report_beyond_the_machine_is_refused_before_any_job():
    config = validated(huge_grid_config(job_memory_gb=64))
    with pytest.raises(ConfigProblems) as err:
        machine.check_machine(plan_of(config))
    (problem,) = err.value.problems
    assert problem.startswith("influence_convergence job influence_convergence: planned "
                              "6.76 PB of memory, more than job_memory_gb = 64. Remove "
                              "reports.influence_convergence")
    # the advice, followed: without the report the plan fits
    del config["reports"]["influence_convergence"]
    machine.check_machine(plan_of(config))
    assert "influence_convergence" not in machine.planned_memory(plan_of(config))


def test_a_report_made_on_demand_is_refused_only_when_asked_for():
    config = validated(huge_grid_config(job_memory_gb=64))
    del config["reports"]["influence_convergence"]
    plan = plan_of(config)
    machine.check_machine(plan)  # the default target fits
    with pytest.raises(ConfigProblems, match=r"speed_vs_error job speed_vs_error: planned "
                                             r"[\d.]+ PB .* reports.speed_vs_error.grids"):
        machine.check_machine(plan, kinds=("speed_vs_error",))


def test_the_memory_a_job_may_use_is_this_machines_unless_configured():
    config = validated(huge_grid_config())
    assert config["job_memory_gb"] is None
    limit, source = machine.memory_limit_mb(Study.from_config(config))
    assert limit == machine.machine_memory_mb() and source.startswith("this machine's ")
    config["job_memory_gb"] = 2.5
    assert machine.memory_limit_mb(Study.from_config(config)) == (2500.0,
                                                                    "job_memory_gb = 2.5")
