"""A stored file is never trusted by its name (a small sweep on two meshes).

The case of the issue: the influence file of the ``paper`` mesh copied over the
``refined`` mesh's file of the same grid. Both are valid and hashed, so only
the parameters recorded inside the file tell them apart; the contact job, the
audit and the re-verification each compare them with what the file's name and
the configuration ask for, and the advice they give rebuilds the study.
"""

import shutil

import pandas as pd
import pytest
from test_stored_results import copy_of, finish, run

pytestmark = pytest.mark.workflow

SWEEP = {"sweeps": {"meshes": {"sigma_um": 24.5, "pressure_MPa": [0.5, 2.0], "count": 3,
                               "size_mm": 2.4, "meshes": ["paper", "refined"]}},
         "contact": {"steps": 8, "pressure_levels": 5}}
AGGREGATE = ("results", "aggregates", "meshes.csv")


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    return finish(tmp_path_factory, "meshes", config=SWEEP)


@pytest.fixture
def swapped(finished, tmp_path):
    """A copy of the run and its paper and refined meshes' influence files."""
    target = copy_of(finished, tmp_path)
    folder = target / "results" / "influence"
    paper, = folder.glob("*_paper.h5")
    refined, = folder.glob("*_refined.h5")
    return target, paper, refined


def logs(workdir, proc, part="*.log"):
    return proc.stdout + proc.stderr + "".join(
        p.read_text() for p in (workdir / "results" / "logs").rglob(part))


def test_the_contact_job_refuses_the_paper_matrix_under_the_refined_name(finished, swapped):
    workdir, paper, refined = swapped
    table = workdir.joinpath(*AGGREGATE).read_bytes()
    shutil.copyfile(paper, refined)  # new mtime: the refined cells' contact jobs rerun
    proc = run(workdir)
    assert proc.returncode != 0
    text = logs(workdir, proc, "contact/*.log")
    assert refined.name in text
    assert 'mesh = "paper" in the file, "refined" expected' in text
    assert f"rm results/influence/{refined.name}" in text
    assert workdir.joinpath(*AGGREGATE).read_bytes() == table  # nothing made from it
    # the advice, followed literally: remove the file, run the same command again
    refined.unlink()
    proc = run(workdir)
    assert proc.returncode == 0, proc.stderr[-4000:]
    again = pd.read_csv(workdir.joinpath(*AGGREGATE))
    pd.testing.assert_frame_equal(again, pd.read_csv(finished.joinpath(*AGGREGATE)))


def test_the_audit_and_the_reverification_refuse_a_copy_that_keeps_the_mtime(swapped):
    workdir, paper, refined = swapped
    shutil.copy2(paper, refined)  # cp -p: the mtime too, so nothing is rerun from it
    proc = run(workdir, "audit")
    assert proc.returncode == 0, proc.stderr[-4000:]
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv", dtype={"flags": str})
    on_refined = audit["mesh"] == "refined"
    assert on_refined.any() and (~on_refined).any()
    flags = audit["flags"].fillna("")
    assert flags[on_refined].str.contains(
        f'{refined.name}: made for other parameters.*mesh = "paper" in the file').all()
    # the paper cells are sound (this tiny study's plausibility flags aside)
    assert not flags[~on_refined].str.contains("made for other parameters").any()
    # the cells solved on the swapped name get no mesh error of the refined mesh
    assert audit.loc[on_refined, "mesh_diagonal_error"].isna().all()
    proc = run(workdir, "audit_verify", "--forcerun", "audit_verify")
    assert proc.returncode != 0
    text = logs(workdir, proc, "audit/verify.log")
    assert "were not made for the jobs that read them" in text
    assert f'{refined.name}: made for other parameters' in text
    assert 'mesh = "paper" in the file, "refined" expected' in text
    # the advice, followed literally
    refined.unlink()
    proc = run(workdir, "all", "audit_verify")
    assert proc.returncode == 0, proc.stderr[-4000:]
    verify = pd.read_csv(workdir / "results" / "audit" / "verify.csv")
    assert verify["ok"].all()
    audit = pd.read_csv(workdir / "results" / "audit" / "audit.csv", dtype={"flags": str})
    assert not audit["flags"].fillna("").str.contains("made for other parameters").any()
