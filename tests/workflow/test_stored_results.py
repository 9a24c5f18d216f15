"""Stored results and inputs that cannot be wrong silently (a small sweeps-only study).

Each test damages a copy of one finished run the way a user or a disk might,
and checks that the workflow names the file and what to do instead of using
it, that the audit notices, and that no study rewrites another's results.
"""

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]

#: A config that states only what differs from the defaults: one sweep, no figures.
SWEEP = {"sweeps": {"small": {"sigma_um": 24.5, "pressure_MPa": [0.5, 2.0], "count": 3,
                              "size_mm": 2.4}},
         "contact": {"steps": 8, "pressure_levels": 5}}


def run(workdir, *targets, config=None):
    path = workdir / "config.yaml"
    if config is not None or not path.exists():
        path.write_text(yaml.safe_dump(config or SWEEP))
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(workdir), "--configfile", str(path), "--cores", "2", *targets]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))


def finish(tmp_path_factory, name: str, config=None) -> Path:
    """A finished run of ``config`` (default: the sweep) in a new folder."""
    workdir = tmp_path_factory.mktemp(name)
    proc = run(workdir, config=config)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return workdir


def copy_of(workdir: Path, tmp_path: Path) -> Path:
    """A copy of a finished run, to damage."""
    target = tmp_path / "run"
    shutil.copytree(workdir, target, symlinks=True)
    return target


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    return finish(tmp_path_factory, "sweep")


@pytest.fixture
def copy(finished, tmp_path):
    return copy_of(finished, tmp_path)


def state(folder: Path) -> dict:
    """File -> (mtime_ns, sha256 of its bytes) of every file under ``folder``."""
    return {p.name: (p.stat().st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
            for p in sorted(folder.glob("*.h5"))}


def only(folder: Path) -> Path:
    (path,) = folder.glob("*.h5")
    return path


@pytest.mark.workflow
def test_a_sweeps_only_config_runs_just_its_sweep_on_the_defaults(finished):
    results = finished / "results"
    table = pd.read_csv(results / "aggregates" / "small.csv")
    assert len(table) == 5 and (table["surfaces"] == 3).all()
    # the default body (Table 1: 10 mm, nu 0, the paper's mesh) at 16 x 16 over 2.4 mm
    assert only(results / "influence").name == "nu0_L2.4x2.4mm_t10mm_g16x16_clamped_paper.h5"
    assert not (results / "figures").exists()


@pytest.mark.workflow
def test_an_edited_surfaces_file_stops_the_contact_job_naming_it(copy):
    surfaces = only(copy / "results" / "surfaces")
    with h5py.File(surfaces, "r+") as f:
        f["heights"][0, 3, 3] = f["heights"][0].max() + 2.0
    before = state(copy / "results" / "contact")
    proc = run(copy)
    assert proc.returncode != 0
    log = (proc.stderr + "".join(p.read_text() for p in (copy / "results" / "logs")
                                 .rglob("*.log")))
    assert surfaces.name in log and "no longer match" in log and "delete it" in log
    # nothing downstream was rewritten from it
    assert state(copy / "results" / "contact").keys() <= before.keys()


@pytest.mark.workflow
def test_a_damaged_influence_matrix_is_named_not_used(copy):
    influence = only(copy / "results" / "influence")
    with h5py.File(influence, "r+") as f:
        f["unit_influence"][5, 5] *= 1.01  # stays symmetric
    proc = run(copy)
    assert proc.returncode != 0
    log = proc.stderr + "".join(p.read_text() for p in (copy / "results" / "logs")
                                .rglob("contact/*.log"))
    assert influence.name in log and "no longer match" in log
    assert "symmetrize" not in log


@pytest.mark.workflow
def test_a_truncated_contact_file_is_flagged_by_the_audit_and_named_by_the_aggregate(copy):
    contact = only(copy / "results" / "contact")
    os.truncate(contact, 8000)
    old_audit = (copy / "results" / "audit" / "audit.csv").read_text()
    proc = run(copy, "audit")
    assert proc.returncode == 0, proc.stderr[-3000:]
    audit = pd.read_csv(copy / "results" / "audit" / "audit.csv", dtype={"flags": str})
    assert audit["flags"].str.contains("unusable file").all()
    assert audit["flags"].str.contains(contact.name).all()
    assert old_audit != (copy / "results" / "audit" / "audit.csv").read_text()
    proc = run(copy, "results/aggregates/small.csv", "--forcerun", "aggregate")
    assert proc.returncode != 0
    log = proc.stderr + (copy / "results" / "logs" / "aggregates" / "small.log").read_text()
    assert contact.name in log and "delete it" in log


@pytest.mark.workflow
def test_the_audit_sees_an_edit_that_keeps_the_mtime_and_strict_fails(copy):
    contact = only(copy / "results" / "contact")
    stat = contact.stat()
    with h5py.File(contact, "r+") as f:
        f["nominal_pressure"][0, 2] *= 1.0 + 1e-9
    os.utime(contact, ns=(stat.st_atime_ns, stat.st_mtime_ns))  # touch -r
    proc = run(copy, "audit")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Nothing to be done" not in proc.stdout + proc.stderr
    audit = pd.read_csv(copy / "results" / "audit" / "audit.csv", dtype={"flags": str})
    assert audit["flags"].str.contains("no longer match").all()
    proc = run(copy, "audit_strict")
    assert proc.returncode != 0
    assert "1 of 1 cells flagged" in proc.stderr + (
        copy / "results" / "logs" / "audit" / "strict.log").read_text()
    assert (copy / "results" / "audit" / "audit.csv").exists()  # kept for the user to read


@pytest.mark.workflow
def test_adding_a_sigma_rewrites_no_existing_result(copy):
    before = state(copy / "results" / "contact")
    config = yaml.safe_load(yaml.safe_dump(SWEEP))
    config["sweeps"]["small"]["sigma_um"] = [24.5, 2.0]  # needs a sweep 16 times longer
    proc = run(copy, config=config)
    assert proc.returncode == 0, proc.stderr[-3000:]
    after = state(copy / "results" / "contact")
    assert {k: after[k] for k in before} == before  # bytes and mtime unchanged
    assert len(after) == len(before) + 1
    table = pd.read_csv(copy / "results" / "aggregates" / "small.csv")
    assert sorted(set(table["sigma_um"])) == [2.0, 24.5]


@pytest.mark.workflow
def test_a_value_in_the_wrong_unit_stops_before_any_job(copy):
    before = state(copy / "results" / "contact")
    config = yaml.safe_load(yaml.safe_dump(SWEEP))
    config["sweeps"]["small"]["sigma_um"] = 2.45e-5  # metres typed into a micrometre key
    proc = run(copy, config=config)
    assert proc.returncode != 0
    assert "sweeps.small.sigma_um = 2.45e-05" in proc.stderr
    assert "typed in m? then write sweeps.small.sigma_um: 24.5" in proc.stderr
    assert "plausibility_check: false" in proc.stderr
    assert state(copy / "results" / "contact") == before


def test_a_constant_height_map_is_refused_alone_before_any_job(tmp_path):
    np.save(tmp_path / "flat.npy", np.full((32, 32), 3.0))  # 3 um everywhere
    surface = {"file": "flat.npy", "height_unit": "um", "spacing_mm": [0.01, 0.01]}
    config = {"sweeps": {"flat": {"surface": surface, "compare_synthetic": True,
                                  "pressure_MPa": [0.1, 1.0]}}}
    proc = run(tmp_path, "-n", config=config)
    assert proc.returncode != 0
    output = proc.stdout + proc.stderr
    assert "flat.surface: flat.npy: the heights are flat (a constant or a plane)" in output
    # nothing of the statistics of its rounding noise, before or after
    assert not any(word in output for word in ("NaN", "form_degree", "autocorrelation"))


def test_a_bad_key_is_named_in_one_line(tmp_path):
    config = yaml.safe_load(yaml.safe_dump(SWEEP))
    config["sweeps"]["small"]["sigma_um"] = -1
    proc = run(tmp_path, "-n", config=config)
    assert proc.returncode != 0
    output = proc.stdout + proc.stderr
    assert "sweeps.small.sigma_um: -1 is out of range: it must be above 0" in output
    assert len(output.splitlines()) < 30  # not the schema's text
