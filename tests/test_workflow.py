"""The real Snakemake workflow on config/quick.yaml, in a temporary directory."""

import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

from roughcontact import johnson, surface
from roughcontact.storage import read_influence
from roughcontact.study import (
    cell_key,
    figure_cells,
    geometry_key,
    geometry_params,
    spec_from_params,
    statistics_key,
)

REPO = Path(__file__).resolve().parent.parent
SNAKEMAKE = [sys.executable, "-m", "snakemake"]

pytestmark = pytest.mark.workflow


def run_snakemake(workdir, *args, config=REPO / "config" / "quick.yaml"):
    cmd = [
        *SNAKEMAKE,
        "--snakefile", str(REPO / "Snakefile"),
        "--directory", str(workdir),
        "--configfile", str(config),
        "--cores", "2",
        *args,
    ]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("quick")
    start = time.time()
    proc = run_snakemake(workdir)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return workdir, start


def quick_config():
    return yaml.safe_load((REPO / "config" / "quick.yaml").read_text())


def test_surface_files_hold_seeded_surfaces_with_their_moments(quick_run):
    workdir, _ = quick_run
    config = quick_config()
    for params in figure_cells(config, "fig04"):
        path = workdir / "results" / "surfaces" / f"{cell_key(params)}.h5"
        with h5py.File(path, "r") as f:
            heights = f["heights"][()]
            seeds = f["seeds"][()]
            attrs = dict(f.attrs)
            realised_kurt = f["stats/kurt"][()]
        assert heights.shape == (params["count"], *params["grid"][::-1])
        # the stored statistics are those of the stored heights
        assert np.allclose(realised_kurt, surface.height_stats(heights)["kurt"])
        # every surface is reproducible from its stored seed and the stored spec
        spec = spec_from_params(json.loads(attrs["params"]))
        again = surface.generate(spec, int(seeds[1]))
        assert np.array_equal(again, heights[1])
        # the seeds derive from the study seed and the cell's statistics
        expected = surface.derive_seeds(config["study_seed"], statistics_key(params), len(seeds))
        assert np.array_equal(seeds.astype(np.uint64), expected)
        # the recorded white-noise moments transfer to the target (Eq 12-13)
        s3, s4 = attrs["filter_S3"], attrs["filter_S4"]
        assert s3 * attrs["input_skew"] == pytest.approx(params["skew"], abs=1e-12)
        assert 3 + s4 * (attrs["input_kurt"] - 3) == pytest.approx(params["kurt"], abs=1e-12)
        curve = johnson.fit(attrs["input_skew"], attrs["input_kurt"])
        assert curve.family == attrs["johnson_family"]
        for key in ("package_version", "git_commit", "config_hash", "created"):
            assert attrs[key], key


def test_influence_file_holds_unit_modulus_matrix_of_the_block(quick_run):
    workdir, _ = quick_run
    config = quick_config()
    params = geometry_params(config["body"], config["surfaces"])
    path = workdir / "results" / "influence" / f"{geometry_key(params)}.h5"
    unit, attrs = read_influence(path)
    nx, ny = params["grid"]
    assert unit.shape == (nx * ny, nx * ny)
    # nu = 0, bonded base: a uniform pressure P gives u = P L / E (Eq 37-38),
    # so every row of E * C sums to the thickness L
    assert params["nu"] == 0.0
    assert np.allclose(unit.sum(axis=1), params["thickness_mm"] * 1e-3, rtol=1e-10)
    assert np.abs(unit - unit.T).max() <= 1e-10 * np.abs(unit).max()
    assert attrs["content_sha256"] == hashlib.sha256(unit.tobytes()).hexdigest()
    for key in ("package_version", "git_commit", "config_hash", "dofs", "build_seconds"):
        assert attrs[key], key


def test_figures_are_written_by_this_run(quick_run):
    workdir, start = quick_run
    for fig in ("fig01", "fig02", "fig03", "fig04", "fig05"):
        for ext in ("png", "pdf", "ipynb"):
            path = workdir / "results" / "figures" / f"{fig}.{ext}"
            assert path.stat().st_size > 1000, path
            assert path.stat().st_mtime >= start - 1, path
        png = (workdir / "results" / "figures" / f"{fig}.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        nb = json.loads((workdir / "results" / "figures" / f"{fig}.ipynb").read_text())
        injected = [
            c for c in nb["cells"] if "injected-parameters" in c["metadata"].get("tags", [])
        ]
        assert injected, f"{fig}: papermill did not inject parameters"


def test_second_run_has_nothing_to_do(quick_run):
    workdir, _ = quick_run
    proc = run_snakemake(workdir, "--dry-run")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "Nothing to be done" in proc.stdout + proc.stderr


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda c: c["surfaces"].update(count=-1), "count"),
        (lambda c: c.update(studyseed=3), "studyseed"),
        (lambda c: c["surfaces"].update(acf="fractal"), "fractal"),
        (lambda c: c["figures"]["fig04"].update(moments=[[1.0, 1.5]]), "Eq 14"),
    ],
)
def test_bad_config_fails_before_any_job(tmp_path, edit, message):
    config = quick_config()
    edit(config)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(tmp_path, "--dry-run", config=path)
    assert proc.returncode != 0
    assert message in proc.stdout + proc.stderr
    assert not (tmp_path / "results").exists()


def test_infeasible_cell_is_listed_with_its_bound(tmp_path):
    config = quick_config()
    config["figures"]["fig04"]["moments"] = [[0.0, 3.0], [1.5, 3.3]]
    config["figures"]["fig04"]["b_mm"] = 1.0
    path = tmp_path / "infeasible.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(tmp_path, "--dry-run", config=path)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert "sk1.5_ku3.3" in out and "minimum kurtosis" in out


def test_lint_is_clean():
    proc = subprocess.run(
        [*SNAKEMAKE, "--lint", "--snakefile", str(REPO / "Snakefile"), "--directory", str(REPO),
         "--configfile", str(REPO / "config" / "quick.yaml")],
        capture_output=True, text=True, timeout=300,
    )
    # The only lint allowed: rules name no conda environment or container; the
    # project's environment is the pinned .venv that `make` builds.
    text = proc.stdout + proc.stderr
    lints = [line for line in text.splitlines() if line.strip().startswith("* ")]
    allowed = "Specify a conda environment or container for each rule"
    assert lints, text[-2000:]  # the linter ran and reported per rule
    assert all(allowed in line for line in lints), text[-3000:]


def test_config_files_validate():
    from snakemake.utils import validate

    for name in ("config.yaml", "quick.yaml"):
        config = yaml.safe_load((REPO / "config" / name).read_text())
        validate(config, str(REPO / "config" / "schema.yaml"))
