"""The real Snakemake workflow on config/quick.yaml, in a temporary directory."""

import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml

from roughcontact.study.config import load_config
from roughcontact.study.jobs.storage import read_contact, read_influence
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.records import surface_cell_from_params
from roughcontact.study.settings import Study
from roughcontact.surfaces import johnson
from roughcontact.surfaces import synthetic as surface
from roughcontact.surfaces.statistics import height_stats

REPO = Path(__file__).resolve().parents[2]
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
    return load_config(REPO / "config" / "quick.yaml")


def test_surface_files_hold_seeded_surfaces_with_their_moments(quick_run):
    workdir, _ = quick_run
    config = quick_config()
    for cell in study_plan(Study.from_config(config)).figure_surfaces["fig04"]:
        path = workdir / "results" / "surfaces" / f"{cell.key}.h5"
        with h5py.File(path, "r") as f:
            heights = f["heights"][()]
            seeds = f["seeds"][()]
            attrs = dict(f.attrs)
            realised_kurt = f["stats/kurt"][()]
        assert heights.shape == (cell.count, *cell.grid[::-1])
        # the stored statistics are those of the stored heights
        assert np.allclose(realised_kurt, height_stats(heights)["kurt"])
        # every surface is reproducible from its stored seed and the stored spec
        spec = surface_cell_from_params(json.loads(attrs["params"])).spec()
        again = surface.generate(spec, int(seeds[1]))
        assert np.array_equal(again, heights[1])
        # the seeds derive from the study seed and the cell's statistics
        expected = surface.derive_seeds(config["study_seed"], cell.statistics_key, len(seeds))
        assert np.array_equal(seeds.astype(np.uint64), expected)
        # the recorded white-noise moments transfer to the calibrated process
        # moments (Eq 12-13), whose windows have the target sample moments
        s3, s4 = attrs["filter_S3"], attrs["filter_S4"]
        skew_p, kurt_p = attrs["calibration_skew"], attrs["calibration_kurt"]
        assert s3 * attrs["input_skew"] == pytest.approx(skew_p, abs=1e-12)
        assert 3 + s4 * (attrs["input_kurt"] - 3) == pytest.approx(kurt_p, abs=1e-12)
        assert attrs["calibration_converged"]
        assert attrs["calibration_expected_kurt"] == pytest.approx(cell.kurt, rel=1e-4)
        curve = johnson.fit(attrs["input_skew"], attrs["input_kurt"])
        assert curve.family == attrs["johnson_family"]
        for key in ("package_version", "git_commit", "config_hash", "created"):
            assert attrs[key], key


def test_influence_file_holds_unit_modulus_matrix_of_the_block(quick_run):
    workdir, _ = quick_run
    config = quick_config()
    geometry = Study.from_config(config).body.geometry
    path = workdir / "results" / "influence" / f"{geometry.key}.h5"
    unit, attrs = read_influence(path)
    nx, ny = geometry.grid
    assert unit.shape == (nx * ny, nx * ny)
    # nu = 0, bonded base: a uniform pressure P gives u = P L / E (Eq 37-38),
    # so every row of E * C sums to the thickness L
    assert geometry.nu == 0.0
    assert np.allclose(unit.sum(axis=1), geometry.thickness, rtol=1e-10)
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
        (lambda c: c["figures"]["fig07"].update(sigma_um=-30.0), "sigma_um"),
        (lambda c: c["contact"].update(method="newton"), "newton"),
        (lambda c: c["body"].update(nu=0.5), "nu"),
        (lambda c: c["figures"]["fig07"].update(pressure_MPa=[5.0, 0.1]), "pressure_MPa"),
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
    assert "sk1.5_ku3.3" in out and "not reachable in expectation" in out
    assert "Raise kurt to at least" in out


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


# ---------------------------------------------------------------------------
# The contact study on the quick config


def aggregates(workdir, name):
    base = workdir / "results" / "aggregates"
    return (pd.read_csv(base / f"{name}.csv"), pd.read_csv(base / f"{name}.moduli.csv"),
            json.loads((base / f"{name}.json").read_text()))


def test_mean_plane_modulus_is_E_for_nu0_and_deviates_for_nu03(quick_run):
    workdir, _ = quick_run
    _, moduli, meta = aggregates(workdir, "table_Eu")
    ratio = moduli["mean_plane_modulus"] / (moduli["E_MPa"] * 1e6)
    nu0 = moduli["nu"] == 0.0
    assert nu0.any() and (~nu0).any()
    # Eq 44: rows of C sum to L / E, so d_b = P L / E on every surface
    assert np.abs(ratio[nu0] - 1.0).max() < 1e-6
    # nu = 0.3: still linear in P, but E_u differs from E (the paper: about 5 %)
    summaries = [s for s in meta["mean_plane_modulus"] if s["nu"] == 0.3]
    assert summaries and all(abs(s["relative_deviation"]) > 1e-3 for s in summaries)
    assert all(s["max_linearity_residual"] < 1e-3 for s in summaries)


def test_stiffness_rises_towards_E_and_negative_skew_is_stiffer(quick_run):
    workdir, _ = quick_run
    table, _, _ = aggregates(workdir, "fig07")
    assert (table["unconverged_steps"] == 0).all()
    for _, cell in table.groupby("cell"):
        k = cell["normalized_stiffness_mean"].to_numpy() / (cell["E_MPa"].iloc[0] * 1e6)
        assert np.all(np.diff(k) > -0.05 * k[:-1]), k  # rises with P (within its noise)
        assert 0.85 < k[-1] <= 1.0 + 1e-9, k[-1]  # at 5 MPa, approaching E from below
    for _mesh, part in table.groupby("mesh"):
        gauss = part[part["skew"] == 0.0]["normalized_stiffness_mean"].to_numpy()
        negative = part[part["skew"] < 0.0]["normalized_stiffness_mean"].to_numpy()
        assert np.mean(negative > gauss) > 0.8  # Fig 7: negative skew stiffer


def test_aggregates_carry_the_interface_quantities(quick_run):
    """Spots, corrected area and mean gap beside the paper's quantities, and the
    audit's summary of them: the mean gap falls with the load, every level with contact
    has a spot, the corrected area lies below the element count (c_P > 0) and above half
    of it (a lone element keeps 1 - 4 c_P = 0.53), the mean spot area is the area over
    the count."""
    workdir, _ = quick_run
    table, _, meta = aggregates(workdir, "fig07")
    for _, cell in table.groupby("cell"):
        gap = cell["mean_gap_mean"].to_numpy()
        assert (gap > 0).all() and np.all(np.diff(gap) < 0), gap
        spots = cell["spot_count_mean"].to_numpy()
        assert (spots >= 1).all(), spots
        area = cell["real_area_fraction_mean"].to_numpy()
        corrected = cell["corrected_real_area_fraction_mean"].to_numpy()
        assert np.all(corrected < area) and np.all(corrected > 0.5 * area)
        assert np.all(cell["gap_p10_mean"] <= cell["gap_median_mean"])
        assert np.all(cell["gap_median_mean"] <= cell["gap_p90_mean"])
        assert np.all(cell["median_spot_area_mean"] <= cell["largest_spot_area_mean"])
    assert meta["units"]["mean_gap_mean"] == "m" and meta["units"]["spot_count_mean"] == "1"
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv")
    assert (audit["spots_at_P_max"] >= 1).all()
    assert (audit["mean_spot_elements_at_P_max"] >= 1).all()
    assert (audit["mean_gap_over_sigma_at_P_max"] > 0).all()


def test_two_nominal_areas_agree_within_their_bands_for_nu0(quick_run):
    workdir, _ = quick_run
    table, _, _ = aggregates(workdir, "fig14")
    (_, a), (_, b) = table.groupby("cell")
    assert a["size_mm"].iloc[0] != b["size_mm"].iloc[0]
    gap = np.abs(a["normalized_stiffness_mean"].to_numpy()
                 - b["normalized_stiffness_mean"].to_numpy())
    band = (a["normalized_stiffness_half_width"].to_numpy()
            + b["normalized_stiffness_half_width"].to_numpy())
    assert np.all(gap <= band)


def test_hardness_study_caps_its_capped_cells_and_checks_its_elastic_ones(quick_run):
    workdir, _ = quick_run
    table, _, meta = aggregates(workdir, "hardness")
    validity = pd.read_csv(workdir / "results" / "aggregates" / "hardness.validity.csv")
    H = quick_config()["figures"]["hardness"]["hardness_MPa"]
    capped = table[table["cap_MPa"].notna()]
    elastic = table[table["cap_MPa"].isna()]
    # capped on the meshes of cap_meshes only, elastic (with the validity map) on all
    assert set(capped["mesh"]) == set(quick_config()["figures"]["hardness"]["cap_meshes"])
    assert len(capped) == (elastic["mesh"].isin(set(capped["mesh"]))).sum() > 0
    assert set(elastic["mesh"]) == {"paper", "refined"}
    assert (capped["max_pressure_mean"] <= H * 1e6 * (1 + 1e-9)).all()
    assert (elastic["max_pressure_mean"] > H * 1e6).any()  # the cap does matter here
    assert (capped["plastic_area_fraction_mean"] > 0).any()
    assert (elastic["plastic_area_fraction_mean"] == 0).all()
    # the elastic cells' shares above H, one row per elastic cell and level
    assert set(validity["cell"]) == set(elastic["cell"])
    assert len(validity) == len(elastic)
    assert validity["flagged"].any()
    assert validity[["area_above_mean", "load_above_mean"]].le(1.0).all().all()
    # load is concentrated on the high-pressure elements: its share is the larger
    assert (validity["load_above_mean"] >= validity["area_above_mean"] - 1e-9).all()
    flagged = meta["validity"]["flagged_cells"]
    assert flagged and set(flagged) <= set(elastic["cell"])
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv")
    assert audit["flags"].fillna("").str.contains("elastic beyond the hardness").any()
    # the other studies name no hardness: header-only validity tables, nothing flagged
    plain = pd.read_csv(workdir / "results" / "aggregates" / "fig07.validity.csv")
    assert plain.empty and "area_above_mean" in plain.columns


def test_study_figures_are_written(quick_run):
    workdir, start = quick_run
    for fig in ("fig07", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "table_Eu",
                "hardness", "gaps"):
        path = workdir / "results" / "figures" / f"{fig}.png"
        assert path.stat().st_size > 1000 and path.stat().st_mtime >= start - 1, fig


def test_contact_results_are_reproducible(quick_run, tmp_path):
    workdir = tmp_path / "run"  # a copy: the shared run stays up to date
    shutil.copytree(quick_run[0], workdir, symlinks=True)
    before = (workdir / "results" / "aggregates" / "fig14.csv").read_bytes()
    proc = run_snakemake(workdir, "--forcerun", "contact", "aggregate", "--",
                         "results/aggregates/fig14.csv")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "contact" in proc.stdout + proc.stderr  # the solves really ran again
    assert (workdir / "results" / "aggregates" / "fig14.csv").read_bytes() == before


def test_a_single_figure_builds_only_its_cells(tmp_path):
    proc = run_snakemake(tmp_path, "--dry-run", "--quiet", "rules", "--",
                         "results/figures/fig14.png")
    assert proc.returncode == 0, proc.stderr[-3000:]
    # two areas: two surface cells, two geometries, two contact jobs, one aggregate
    assert job_counts(proc.stdout) == {"surfaces": "2", "influence": "2", "contact": "2",
                                       "aggregate": "1", "figure": "1", "total": "8"}, proc.stdout


#: Loaded at the start of every Python process of the interrupted run (PYTHONPATH):
#: the contact job stops at its first progress line, touches the file
#: HOLD_STARTED names and waits there until it is interrupted, so the signal
#: always finds it running, however fast it or the machine is.
HOLD_AT_FIRST_PROGRESS_LINE = """
import logging, os, pathlib, time


class _Hold(logging.Handler):
    def emit(self, record):
        if "surfaces x" in record.getMessage():
            pathlib.Path(os.environ["HOLD_STARTED"]).touch()
            while True:
                time.sleep(0.05)


logging.getLogger("roughcontact.study.jobs.contact").addHandler(_Hold())
"""


#: Run the command after it with SIGINT's default action: a test run in the background of
#: a shell (``make test &``) inherits SIGINT ignored, and Python started so never raises
#: KeyboardInterrupt (Snakemake and its job would outlive the interrupt).
WITH_SIGINT = [sys.executable, "-c", "import os, signal, sys; "
               "signal.signal(signal.SIGINT, signal.SIG_DFL); os.execvp(sys.argv[1], sys.argv[1:])"]


def test_interrupted_contact_job_resumes_without_redoing_finished_work(tmp_path):
    config = quick_config()
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(config))
    cell = contact_cells(Study.from_config(config), "fig14")[0]
    key = cell.contact_key
    target = f"results/contact/{key}.h5"
    first = run_snakemake(tmp_path, f"results/surfaces/{cell.surface.key}.h5",
                          f"results/influence/{cell.geometry.key}.h5", config=path)
    assert first.returncode == 0, first.stderr[-3000:]
    done = {p: p.stat().st_mtime_ns for p in (tmp_path / "results").rglob("*.h5")}
    hold = tmp_path / "hold"
    hold.mkdir()
    (hold / "sitecustomize.py").write_text(HOLD_AT_FIRST_PROGRESS_LINE)
    started = tmp_path / "started"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", HOLD_STARTED=str(started),
               PYTHONPATH=os.pathsep.join(filter(None, [str(hold),
                                                        os.environ.get("PYTHONPATH")])))
    proc = subprocess.Popen(
        [*WITH_SIGINT, *SNAKEMAKE, "--snakefile", str(REPO / "Snakefile"), "--directory",
         str(tmp_path), "--configfile", str(path), "--cores", "2", target],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True, env=env,
    )
    deadline = time.time() + 300
    while not started.exists():
        assert time.time() < deadline and proc.poll() is None, "contact job did not start"
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=300) != 0  # interrupted while the contact job runs
    assert not (tmp_path / target).exists()  # no partial result under the final name
    again = run_snakemake(tmp_path, target, config=path)
    assert again.returncode == 0, again.stderr[-3000:]
    nd, attrs = read_contact(tmp_path / target)
    assert nd.converged.all() and attrs["unconverged_steps"] == 0
    for p, mtime in done.items():  # the finished surfaces and influence files were kept
        assert p.stat().st_mtime_ns == mtime, p


# ---------------------------------------------------------------------------
# Audit


def job_counts(text):
    block = text[text.index("Job stats:"):]
    return dict(re.findall(r"^(\w+)\s+(\d+)\s*$", block.split("\n\n")[0], re.MULTILINE))


def planned_jobs(workdir, tmp_path, config) -> dict:
    """The jobs a dry run of ``config`` (written to ``tmp_path``) plans in ``workdir``."""
    path = tmp_path / "edited.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(workdir, "--dry-run", "--quiet", "rules", config=path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return job_counts(proc.stdout)


def test_editing_one_cell_reruns_exactly_its_jobs(quick_run, tmp_path):
    workdir, _ = quick_run
    config = quick_config()
    config["figures"]["fig14"]["size_mm"] = [4.8, 3.0]
    # the new area: its surfaces, geometry and contact job; the fig14 aggregate
    # and figure; the audit and configuration snapshot; nothing else
    assert planned_jobs(workdir, tmp_path, config) == {
        "surfaces": "1", "influence": "1", "contact": "1", "aggregate": "1", "figure": "1",
        "audit": "1", "config_snapshot": "1", "all": "1", "total": "8"}


def test_a_smaller_cell_takes_its_surfaces_from_its_twin_and_reruns_alone(quick_run, tmp_path):
    workdir, _ = quick_run
    plan = study_plan(Study.from_config(quick_config()))
    for small, large in plan.surfaces_from.items():  # Fig 3's n1 and Fig 9's n3 cells
        log = (workdir / "results" / "logs" / "surfaces" / f"{small}.log").read_text()
        assert f"taken from results/surfaces/{large}.h5" in log
        with h5py.File(workdir / "results" / "surfaces" / f"{small}.h5", "r") as f, \
                h5py.File(workdir / "results" / "surfaces" / f"{large}.h5", "r") as g:
            count = f["heights"].shape[0]
            assert np.array_equal(f["heights"][()], g["heights"][:count])
    config = quick_config()
    config["figures"]["fig09"]["count"] = 2
    # Fig 9's two new cells (taken from their twins, which stay), their contact jobs,
    # the fig09 aggregate and Figs 9 and 10, the audit and configuration snapshot
    assert planned_jobs(workdir, tmp_path, config) == {
        "surfaces": "2", "contact": "2", "aggregate": "1", "figure": "2", "audit": "1",
        "config_snapshot": "1", "all": "1", "total": "10"}


def test_audit_lists_every_cell_and_flags_a_corrupted_result(quick_run, tmp_path):
    workdir, _ = quick_run
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv", dtype={"flags": str})
    config = quick_config()
    studies = [n for n in config["figures"] if n in ("fig07", "fig09", "fig10", "fig11",
                                                       "fig12", "fig13", "fig14", "table_Eu",
                                                       "hardness")]
    sources = sorted({Study.from_config(config).source_name(n) for n in studies})  # fig12: fig07
    assert len(audit) == sum(len(contact_cells(Study.from_config(config), n)) for n in sources)
    # a study "from:" another is not listed again (its cells are the same)
    assert set(audit["study"]) == set(sources) and "fig12" not in sources
    assert not audit.duplicated(subset=["study", "cell"]).any()
    assert not audit["flags"].fillna("").str.contains("unusable|unconverged|another").any()
    assert (audit["worst_residual"] <= audit["tol"]).all()
    # corrupt one value of one stored result in a copy of the run
    copy = tmp_path / "run"
    shutil.copytree(workdir, copy, symlinks=True)
    victim = copy / "results" / "contact" / f"{audit['contact_job'].iloc[0]}.h5"
    with h5py.File(victim, "r+") as f:
        f["nominal_pressure"][0, 5] *= 1.0 + 1e-9
    proc = run_snakemake(copy, "audit")
    assert proc.returncode == 0, proc.stderr[-3000:]
    audit = pd.read_csv(copy / "results" / "audit" / "audit.csv", dtype={"flags": str})
    hit = audit["contact_job"] == victim.stem
    assert audit.loc[hit, "flags"].str.contains("no longer match").all()
    assert not audit.loc[~hit, "flags"].fillna("").str.contains("no longer match").any()
    md = (copy / "results" / "audit" / "audit.md").read_text()
    flagged_part = md.split("## All cells")[0]
    assert victim.stem in flagged_part


def test_audit_verify_resolves_a_sample_bit_identically(quick_run):
    workdir, _ = quick_run
    proc = run_snakemake(workdir, "audit_verify")
    assert proc.returncode == 0, proc.stderr[-3000:]
    table = pd.read_csv(workdir / "results" / "audit" / "verify.csv")
    assert len(table) == 3
    # same code, same machine: the re-solved batches equal the stored ones bit for bit
    assert table["identical"].all() and table["ok"].all()


def test_speed_vs_error_report_is_built_on_demand(quick_run):
    workdir, _ = quick_run
    proc = run_snakemake(workdir, "results/reports/speed_vs_error.md")
    assert proc.returncode == 0, proc.stderr[-3000:]
    md = (workdir / "results" / "reports" / "speed_vs_error.md").read_text()
    assert "## Recommendation" in md and "## How it was measured" in md
    table = pd.read_csv(workdir / "results" / "reports" / "speed_vs_error.csv")
    assert {"solver", "mesh", "grid", "surfaces", "recommendation"} <= set(table["table"])
    solver = table[table["table"] == "solver"]
    assert {"cg", "steepest", "exact"} <= set(solver["method"])


def test_speed_report_plans_without_a_convergence_section(tmp_path):
    """The speed report reads the mesh-convergence table; without a configured
    `reports: influence_convergence` that report runs with the schema's defaults
    (it used to fail with KeyError: 'surfaces' while planning)."""
    config = yaml.safe_load((REPO / "config" / "quick.yaml").read_text())
    config.get("reports", {}).pop("influence_convergence", None)
    path = tmp_path / "no_convergence.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(tmp_path, "--dry-run", "results/reports/speed_vs_error.md", config=path)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "influence_convergence" in out and "KeyError" not in out
