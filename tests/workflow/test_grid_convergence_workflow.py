"""The grid-convergence study through the real snakemake, on demand and on tiny grids."""

import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import pandas as pd
import pytest
import yaml

from roughcontact.study.config import validated
from roughcontact.study.provenance import config_hash

REPO = Path(__file__).resolve().parents[2]

#: config/gridconv.yaml shrunk to 32^2 .. 128^2 and two surfaces (a few seconds of solves).
CONFIG = {"study_seed": 5, "reports": {"grid_convergence": {
    "grids": [32, 64, 128], "surfaces": 2, "cutoff_mm": 0.125, "rolloff_mm": 0.5, "steps": 8}}}

pytestmark = pytest.mark.workflow


def run(workdir, config, *args):
    """``snakemake --cores 2 *args`` in ``workdir`` with ``config`` written beside it."""
    (workdir / "config.yaml").write_text(yaml.safe_dump(config))
    options = {"--snakefile": REPO / "Snakefile", "--directory": workdir,
               "--configfile": workdir / "config.yaml", "--cores": 2}
    command = [sys.executable, "-m", "snakemake"]
    for option, value in options.items():
        command += [option, str(value)]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    return subprocess.run([*command, *args], capture_output=True, text=True, timeout=600,
                          env=env)


def test_the_config_file_validates():
    section = validated(yaml.safe_load((REPO / "config" / "gridconv.yaml").read_text()))
    assert section["reports"]["grid_convergence"]["grids"] == [128, 256, 512, 1024]


def test_the_study_is_not_among_the_default_targets(tmp_path):
    quick = yaml.safe_load((REPO / "config" / "quick.yaml").read_text())
    proc = run(tmp_path, quick, "--dry-run", "--quiet", "rules")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "grid_convergence" not in proc.stdout + proc.stderr


def test_the_target_builds_table_and_figure_with_provenance(tmp_path):
    proc = run(tmp_path, CONFIG, "grid_convergence")
    assert proc.returncode == 0, proc.stderr[-4000:]
    table = pd.read_csv(tmp_path / "results" / "reports" / "grid_convergence.csv")
    assert sorted(table["grid"].unique()) == [32, 64, 128]
    assert (table["unconverged_solves"] == 0).all()
    assert table.loc[table["quantity"] == "kappa", "mean"].between(1.0, 4.0).all()
    assert (tmp_path / "results" / "reports" / "grid_convergence.png").stat().st_size > 10_000
    full = validated(CONFIG)
    with h5py.File(tmp_path / "results" / "grid_convergence" / "contact_64.h5") as f:
        attrs = dict(f.attrs)
        assert f["real_area_fraction"].shape == (2, 8)
    assert json.loads(attrs["params"]) == full["reports"]["grid_convergence"]
    assert len(json.loads(attrs["seeds"])) == 2
    assert attrs["config_hash"] == config_hash(full)
    assert attrs["git_commit"] and attrs["package_version"] and attrs["content_sha256"]
    with h5py.File(tmp_path / "results" / "grid_convergence" / "surfaces_64.h5") as f:
        assert f["heights"].shape == (2, 64, 64) and f["heights"].attrs["units"] == "m"
        assert attrs["surfaces_content_sha256"] == f.attrs["content_sha256"]
    rerun = run(tmp_path, CONFIG, "grid_convergence", "--dry-run")
    assert "Nothing to be done" in rerun.stdout + rerun.stderr
