"""The workflow with each influence model (`body.operator`), end to end, on a tiny study."""

import copy
import hashlib
import json
import shutil

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml
from test_workflow import run_snakemake

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.operators import BlockOperator
from roughcontact.study.jobs.storage import read_influence

pytestmark = pytest.mark.workflow

CONFIG = {
    "study_seed": 11,
    "blas_threads": 1,
    "surfaces": {"grid": [24, 24], "size_mm": [4.8, 4.8], "acf": "exponential",
                 "periodic": True, "method": "filter", "count": 3},
    "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0, "base": "clamped",
             "mesh": "refined", "solver": "auto", "max_memory_gb": 8},
    "contact": {"method": "cg", "tol": 1.0e-10, "precision": "double", "steps": 12,
                "pressure_levels": 6},
    "figures": {},
    "sweeps": {"models": {"sigma_um": 24.5, "b_mm": 0.8, "pressure_MPa": [0.2, 3.0]}},
}


def _run(tmp_path, name, **body):
    config = copy.deepcopy(CONFIG)
    config["body"].update(body)
    workdir = tmp_path / name
    workdir.mkdir()
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(workdir, config=path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    table = pd.read_csv(workdir / "results" / "aggregates" / "models.csv")
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv", dtype={"flags": str})
    (used,) = set(audit["geometry"])  # the influence file the cells were solved on
    return workdir / "results" / "influence" / f"{used}.h5", table, audit


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("operators")
    return {
        "dense": _run(tmp_path, "dense"),
        # at 24 x 24 the coarse model is the grid itself: the hybrid is the
        # finite-element matrix applied matrix-free (Love in, Love out)
        "hybrid": _run(tmp_path, "hybrid", operator="hybrid"),
        "auto": _run(tmp_path, "auto", operator="auto",
                     halfspace_tolerance={"k_P": None, "real_area": 0.5,
                                          "max_pressure": 0.5}),
    }


COLUMNS = ["normalized_stiffness_mean", "real_area_fraction_mean", "max_pressure_mean",
           "mean_plane_deflection_mean"]


def test_hybrid_operator_reproduces_the_dense_study(runs):
    path, hybrid, audit = runs["hybrid"]
    unit, attrs = read_influence(path)
    assert isinstance(unit, BlockOperator) and attrs["operator"] == "hybrid"
    assert unit.coarse_grid == (24, 24)
    _, dense, _ = runs["dense"]
    np.testing.assert_allclose(hybrid[COLUMNS], dense[COLUMNS], rtol=1e-6)
    assert (audit["operator"] == "hybrid").all()
    assert audit["flags"].isna().all() or (audit["flags"].fillna("") == "").all()


def test_auto_takes_the_halfspace_when_the_tolerance_allows_it(runs):
    path, table, audit = runs["auto"]
    unit, attrs = read_influence(path)
    assert attrs["operator"] == "halfspace" and unit.correction is None
    assert path.name == "nu0_L4.8x4.8mm_t10mm_g24x24_clamped_refined_halfspace.h5"
    love = halfspace_influence((24, 24), (4.8e-3, 4.8e-3), 1.0, 0.0)
    assert np.abs(unit.to_dense() - love).max() <= 1e-13 * love.max()
    with h5py.File(path, "r") as f:
        assert "unit_influence" not in f and f.attrs["dofs"] == 0  # no finite elements
    # the choice, measured on the planned dense model (built under its own name)
    folder = path.parent
    (choice_file,) = (folder / "choices").glob("*.json")
    choice = json.loads(choice_file.read_text())
    assert choice["operator"] == "halfspace" and choice["resolved_key"] == path.stem
    assert choice["measured_on"].endswith("nu0_L4.8x4.8mm_t10mm_g24x24_clamped_refined.h5")
    assert set(choice["halfspace_errors"]) == {"k_P", "real_area", "max_pressure"}
    assert choice["halfspace_errors"]["real_area"] <= 0.5
    assert (audit["operator"] == "halfspace").all()
    _, dense, _ = runs["dense"]
    # the half-space has no bulk compliance L/E: its mean-plane deflection is
    # smaller (mean Love displacement over the square is about 0.5 L here)
    ratio = table["mean_plane_deflection_mean"] / dense["mean_plane_deflection_mean"]
    assert (ratio < 0.8).all()


def state(folder):
    """File -> (mtime_ns, sha256) of every file under ``folder``."""
    return {p.relative_to(folder): (p.stat().st_mtime_ns,
                                    hashlib.sha256(p.read_bytes()).hexdigest())
            for p in sorted(folder.rglob("*.h5")) if p.is_file()}


def test_auto_keeps_the_files_of_a_geometry_it_resolves_to_the_same_model(runs, tmp_path):
    dense_file, _, _ = runs["dense"]
    workdir = tmp_path / "dense_then_auto"
    shutil.copytree(dense_file.parents[2], workdir, symlinks=True)
    results = workdir / "results"
    before = state(results / "influence") | state(results / "contact")
    table = (results / "aggregates" / "models.csv").read_bytes()
    config = copy.deepcopy(CONFIG)
    config["body"]["operator"] = "auto"  # the default tolerance: 2 % in k_P
    path = workdir / "auto.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(workdir, config=path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    choice = json.loads(next((results / "influence" / "choices").glob("*.json")).read_text())
    assert choice["operator"] == "dense" and choice["halfspace_errors"]["k_P"] > 0.02
    assert choice["resolved_key"] == dense_file.stem  # the dense geometry's own name
    # nothing rebuilt, re-solved or re-aggregated: the same files, bytes and times
    assert state(results / "influence") | state(results / "contact") == before
    assert (results / "aggregates" / "models.csv").read_bytes() == table
    assert "rule contact:" not in proc.stderr and "rule influence:" not in proc.stderr
