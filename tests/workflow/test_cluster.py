"""Cluster execution: the submission path on one machine (profiles/local-cluster)
and the resources every job of the paper's study asks Slurm for (profiles/slurm)."""

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from roughcontact.study.config import ConvergenceSettings, load_config, report_section
from roughcontact.study.plan import resources
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.settings import Study

REPO = Path(__file__).resolve().parents[2]
PROFILES = REPO / "profiles"
LOCAL_CLUSTER = PROFILES / "local-cluster"
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
QUICK = REPO / "config" / "quick.yaml"
PAPER = REPO / "config" / "config.yaml"


def run_snakemake(workdir, *args, config=QUICK, timeout=600):
    cmd = [
        *SNAKEMAKE,
        "--snakefile", str(REPO / "Snakefile"),
        "--directory", str(workdir),
        "--configfile", str(config),
        *args,
    ]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    env.pop("SNAKEMAKE_PROFILE", None)
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout,
                          cwd=workdir)


# ---------------------------------------------------------------------------
# The local cluster's scripts on their own


def write_jobscript(path, body, rule="demo"):
    """A jobscript as Snakemake writes it: shebang, properties line, command."""
    properties = json.dumps({"type": "single", "rule": rule, "threads": 1,
                             "resources": {"mem_mb": 100, "runtime": 6}, "output": ["out.txt"]})
    path.write_text(f"#!/bin/sh\n# properties = {properties}\n{body}\n")
    return path


def profile_script(name, *args, cwd):
    proc = subprocess.run([str(LOCAL_CLUSTER / name), *args], capture_output=True, text=True,
                          cwd=cwd, timeout=30)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def wait_for_end(jobid, cwd, timeout=20):
    deadline = time.monotonic() + timeout
    while (state := profile_script("status.py", jobid, cwd=cwd)) == "running":
        assert time.monotonic() < deadline, f"{jobid} still running after {timeout} s"
        time.sleep(0.1)
    return state


def test_submit_runs_the_jobscript_detached_and_status_reports_its_exit(tmp_path):
    ok = profile_script("submit.py", str(write_jobscript(tmp_path / "ok.sh",
                                                         "echo done > out.txt")), cwd=tmp_path)
    bad = profile_script("submit.py", str(write_jobscript(tmp_path / "bad.sh", "exit 3")),
                         cwd=tmp_path)
    assert ok != bad and ok.startswith("local-")
    assert wait_for_end(ok, tmp_path) == "success"
    assert (tmp_path / "out.txt").read_text() == "done\n"  # ran in the submitting directory
    assert wait_for_end(bad, tmp_path) == "failed"
    logdir = tmp_path / "results" / "logs" / "cluster"
    assert (logdir / f"{bad}.exit").read_text().strip() == "3"
    table = pd.read_csv(logdir / "submissions.tsv", sep="\t")
    assert list(table["jobid"]) == [ok, bad]
    assert list(table["name"]) == ["demo", "demo"]
    assert profile_script("status.py", "local-unknown", cwd=tmp_path) == "failed"


def test_cancel_stops_a_running_job(tmp_path):
    script = write_jobscript(tmp_path / "slow.sh", "sleep 60; echo late > out.txt")
    jobid = profile_script("submit.py", str(script), cwd=tmp_path)
    time.sleep(0.3)
    assert profile_script("status.py", jobid, cwd=tmp_path) == "running"
    profile_script("cancel.py", jobid, cwd=tmp_path)
    assert wait_for_end(jobid, tmp_path, timeout=10) == "failed"
    assert not (tmp_path / "out.txt").exists()


# ---------------------------------------------------------------------------
# Fig 14 of the quick config through the local cluster, against a plain run

FIG14 = "results/figures/fig14.png"


@pytest.fixture(scope="module")
def fig14_runs(tmp_path_factory):
    cluster = tmp_path_factory.mktemp("local_cluster")
    start = time.monotonic()
    proc = run_snakemake(cluster, "--profile", str(LOCAL_CLUSTER), FIG14)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    seconds = time.monotonic() - start
    plain = tmp_path_factory.mktemp("plain")
    local = run_snakemake(plain, "--cores", "2", FIG14)
    assert local.returncode == 0, local.stderr[-4000:]
    return cluster, plain, proc.stdout + proc.stderr, seconds


@pytest.mark.workflow
def test_every_job_went_through_the_submit_script(fig14_runs):
    workdir, _, log, seconds = fig14_runs
    config = load_config(QUICK)
    cells = contact_cells(Study.from_config(config), "fig14")
    logdir = workdir / "results" / "logs" / "cluster"
    table = pd.read_csv(logdir / "submissions.tsv", sep="\t")
    singles = table[table["type"] == "single"]
    groups = table[table["type"] == "group"]
    # one submission per influence matrix and per contact job ...
    assert sorted(singles["name"]) == sorted(
        ["influence"] * len({c.geometry.key for c in cells})
        + ["contact"] * len({c.contact_key for c in cells})
    )
    contact_outputs = set(singles.loc[singles["name"] == "contact", "output"])
    assert contact_outputs == {f"results/contact/{c.contact_key}.h5" for c in cells}
    # ... and the cheap jobs in two group submissions: the surface cells together,
    # the aggregate with its figure
    assert sorted(groups["name"]) == ["summaries", "surfaces"]
    surfaces = groups.loc[groups["name"] == "surfaces", "output"].item().split(",")
    assert sorted(surfaces) == sorted(
        {f"results/surfaces/{c.surface.key}.h5" for c in cells})
    summary = groups.loc[groups["name"] == "summaries", "output"].item().split(",")
    assert FIG14 in summary
    # the resources of rules/common.smk reach the submission
    assert (table["threads"] >= 1).all() and (table["mem_mb"] > 0).all()
    assert (table["runtime"] > 0).all()
    # every job ran in its own background process, which ended well and ran
    # the rules it was submitted for
    for row in table.itertuples():
        assert f"with external jobid '{row.jobid}'" in log
        assert (logdir / f"{row.jobid}.exit").read_text().strip() == "0"
        job_log = (logdir / f"{row.jobid}.log").read_text()
        rules = ["surfaces"] if row.name == "surfaces" else (
            ["aggregate", "figure"] if row.name == "summaries" else [row.name])
        for rule in rules:
            assert re.search(rf"^\s*localrule {rule}:", job_log, re.M), (row.jobid, rule)
    print(f"local cluster: {len(table)} submissions in {seconds:.1f} s")


@pytest.mark.workflow
def test_cluster_results_equal_a_plain_run(fig14_runs):
    cluster, plain, _, _ = fig14_runs
    for name in ("fig14.csv", "fig14.moduli.csv"):
        ours = pd.read_csv(cluster / "results" / "aggregates" / name)
        theirs = pd.read_csv(plain / "results" / "aggregates" / name)
        assert len(ours) > 0
        pd.testing.assert_frame_equal(ours, theirs, check_exact=True)
    table = pd.read_csv(cluster / "results" / "aggregates" / "fig14.csv")
    assert table.filter(like="k_P").notna().all().all()
    png = (cluster / FIG14).read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 1000


# ---------------------------------------------------------------------------
# The paper's study with the Slurm profile (dry run: no Slurm needed)


def dry_run_jobs(text):
    """Jobs of a dry run's listing: rule, job group (None if alone), input files,
    wildcards, threads and resources."""
    jobs, group = [], None
    for line in text.splitlines():
        if match := re.search(r"Group job (\S+) \(jobs", line):
            group = match.group(1)
        elif match := re.fullmatch(r"(\s*)(?:local)?rule (\w+):", line):
            if not match.group(1):  # not indented: a job outside any group
                group = None
            jobs.append({"rule": match.group(2), "group": group, "wildcards": "",
                         "input": [], "threads": 1, "resources": {}})
        elif match := re.fullmatch(r"\s+input: (.*)", line):
            jobs[-1]["input"] = match.group(1).split(", ")
        elif match := re.fullmatch(r"\s+wildcards: (.*)", line):
            jobs[-1]["wildcards"] = match.group(1)
        elif match := re.fullmatch(r"\s+threads: (\d+)", line):
            jobs[-1]["threads"] = int(match.group(1))
        elif match := re.fullmatch(r"\s+resources: (.*)", line):
            jobs[-1]["resources"] = dict(item.split("=", 1) for item in match.group(1).split(", "))
    return jobs


def wildcard_values(job):
    """A dry-run job's wildcards, name -> value."""
    return dict(item.split("=", 1) for item in job["wildcards"].split(", ") if item)


def _influence(plan, config, job):
    geometry = plan.geometries[wildcard_values(job)["geometry"]]
    return (resources.influence_mem_mb(geometry, plan.build),
            resources.influence_runtime(geometry, plan.build))


def _influence_choice(plan, config, job):
    planned = plan.choices[wildcard_values(job)["auto"]].candidates(plan.build.max_bytes)[0]
    return (resources.choice_mem_mb(planned, plan.build),
            resources.choice_runtime(planned, plan.build))


def _pair_influence(plan, config, job):
    pair = plan.pairs[wildcard_values(job)["pair"]]
    return resources.pair_mem_mb(pair), resources.pair_runtime(pair)


def _surfaces(plan, config, job):
    cell = plan.surfaces[wildcard_values(job)["cell"]]
    return resources.surfaces_mem_mb(cell), resources.surfaces_runtime(cell)


def _contact(plan, config, job):
    contact = plan.jobs[wildcard_values(job)["job"]]
    return (resources.contact_mem_mb(contact, plan.contact, plan.build),
            resources.contact_runtime(contact, plan.contact, plan.build))


def _influence_convergence(plan, config, job):
    presets = Study.from_config(config).reports.convergence_presets
    section = ConvergenceSettings.from_section(
        report_section(config["reports"], "influence_convergence"))
    return (resources.convergence_mem_mb(plan.body, presets),
            resources.convergence_runtime(plan.body, presets, section))


def _audit(plan, config, job):  # it reads and hashes its input files
    return (resources.audit_mem_mb(plan.geometries.values(), plan.build),
            resources.audit_runtime(len(job["input"])))


def _summary(plan, config, job):  # its memory is the rule's own number
    return None, resources.summary_runtime()


#: Rule -> (plan, config, dry-run job) -> (memory [MB], wall time [min]) of a first attempt
#: from the cost model (roughcontact.study.plan.resources on config/cost_model.yaml), from the
#: records rules/common.smk passes it; None where the model does not give the number.
MODEL_REQUESTS = {
    "influence": _influence,
    "influence_choice": _influence_choice,
    "pair_influence": _pair_influence,
    "surfaces": _surfaces,
    "contact": _contact,
    "influence_convergence": _influence_convergence,
    "audit": _audit,
    "aggregate": _summary,
    "figure": _summary,
    "table": _summary,
    "config_snapshot": _summary,
}


def model_request(plan, config, job):
    """``{"mem_mb": MB, "runtime": min}`` the cost model gives a dry-run ``job`` of the
    validated ``config`` (its ``plan``), the entries it gives (:data:`MODEL_REQUESTS`; a
    rule not listed there fails, so that a new rule's resources are checked too)."""
    mem_mb, runtime = MODEL_REQUESTS[job["rule"]](plan, config, job)
    return {name: value for name, value in (("mem_mb", mem_mb), ("runtime", runtime))
            if value is not None}


def slurm_dry_run(workdir, *args):
    # A dry run caps threads at --cores (1 unless given); a Slurm run does not.
    proc = run_snakemake(workdir, "--dry-run", "--profile", str(PROFILES / "slurm"),
                         "--cores", "64", *args, config=PAPER)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    return proc.stdout + proc.stderr


@pytest.mark.workflow
def test_slurm_profile_gives_every_job_of_the_study_its_resources(tmp_path):
    text = slurm_dry_run(tmp_path)
    total = int(re.search(r"^total\s+(\d+)$", text, re.M).group(1))
    jobs = [job for job in dry_run_jobs(text) if job["rule"] != "all"]
    assert len(jobs) == total - 1 > 50
    for job in jobs:
        res = job["resources"]
        assert int(res["mem_mb"]) > 0, job
        assert int(res["runtime"]) > 0, job
        assert job["threads"] >= 1, job
        assert res["slurm_account"] == "CHANGE_ME" and res["slurm_partition"] == "CHANGE_ME"
    # each job asks for what the cost model gives it, through rules/common.smk
    config = load_config(PAPER)
    plan = study_plan(Study.from_config(config))
    for job in jobs:
        model = model_request(plan, config, job)
        asked = {name: int(job["resources"][name]) for name in model}
        assert asked == model, (job["rule"], job["wildcards"])
    by_rule = {}
    for job in jobs:
        by_rule.setdefault(job["rule"], []).append(job)
    # one core per build: the sparse factorization is the only multithreaded part
    # of a build (rules/influence.smk), and a second reserved core would idle
    assert {job["threads"] for job in by_rule["influence"]} == {1}
    # cheap jobs are grouped, the long ones are submitted alone
    groups = {rule: {job["group"] for job in js} for rule, js in by_rule.items()}
    assert groups["surfaces"] == {"surfaces"}
    for rule in ("aggregate", "figure", "audit", "config_snapshot"):
        assert groups[rule] == {"summaries"}, rule
    for rule in ("influence", "contact", "influence_convergence"):
        assert groups[rule] == {None}, rule

    # the estimates cover what was measured on the reference machine (2 cores):
    # converged influence 132 s and, condensed by mirror-symmetry class, 2.4 GB (7.8 GB
    # in one factorization); contact on 60 x 60, 60 surfaces up to 186 s / 0.42 GB
    def resources(rule, key_part):
        (job,) = [j for j in by_rule[rule]
                  if key_part in j["wildcards"] and "__cap" not in j["wildcards"]]
        return int(job["resources"]["runtime"]), int(job["resources"]["mem_mb"])

    runtime, mem_mb = resources("influence", "g60x60_clamped_converged")
    assert runtime * 60 >= 132 and mem_mb >= 2400
    runtime, mem_mb = resources("contact", "sk0_ku4.5_b1x1mm_L9x9mm_g60x60_exp_per_filter_n60"
                                           "__nu0_L9x9mm_t10mm_g60x60_clamped_paper")
    assert runtime * 60 >= 186 and mem_mb >= 415
    small, _ = resources("contact", "_g30x30_clamped_paper")
    assert small < runtime  # a quarter of the elements: less time


@pytest.mark.workflow
def test_slurm_resources_of_the_on_demand_speed_report(tmp_path):
    """Measured with the paper's config (2 cores, 2026-11-24): 401 s, peak 1.4 GB.
    The request covers that and fits the 24 GB machine it was measured on (its
    grid study reaches 240 x 240 matrix-free, with no dense matrix of that grid)."""
    text = slurm_dry_run(tmp_path, "results/reports/speed_vs_error.md")
    (job,) = [j for j in dry_run_jobs(text) if j["rule"] == "speed_vs_error"]
    runtime, mem_mb = int(job["resources"]["runtime"]), int(job["resources"]["mem_mb"])
    assert runtime * 60 >= 401 and 1400 <= mem_mb <= 24000


@pytest.mark.workflow
def test_slurm_account_and_partition_from_the_command_line(tmp_path):
    text = slurm_dry_run(tmp_path, "results/config.yaml", "--default-resources",
                         "slurm_account=proj42", "slurm_partition=short")
    jobs = dry_run_jobs(text)
    assert [job["rule"] for job in jobs] == ["config_snapshot"]
    assert jobs[0]["resources"]["slurm_account"] == "proj42"
    assert jobs[0]["resources"]["slurm_partition"] == "short"
    assert int(jobs[0]["resources"]["runtime"]) > 0
