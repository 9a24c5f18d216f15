"""A study with counter bodies (Eq 17-18), end to end on a tiny grid.

One sweep presses its surfaces against a rough, compliant block identical to the
first, against an identical smooth block, against a far stiffer half-space (treated
as rigid) and against the rigid smooth flat; a second sweep is the one-body study of
modulus E/2. Checked: the identical smooth block doubles the compliance, so its
cell equals the one-body cell of E/2 and each block takes half of the mean-plane
deflection; the stiff half-space, treated as rigid (as its file and sidecar say),
gives the one-body numbers bit for bit; the rough counter surface is reported with
its composite sigma; the audit re-solves pairs and finds them identical; the
two-bodies figure draws both sweeps, and the report's caption names their counter bodies.
"""

import json

import numpy as np
import pandas as pd
import pytest
import yaml
from test_workflow import run_snakemake

pytestmark = pytest.mark.workflow

SWEEP = {"sigma_um": 24.5, "b_mm": 0.5, "pressure_MPa": [0.2, 2.0], "count": 3}
CONFIG = {
    "study_seed": 5,
    "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4]},
    "body": {"E_MPa": 511.0, "nu": 0.0, "mesh": "paper"},
    "contact": {"steps": 12, "pressure_levels": 6},
    "figures": {"two_bodies": {"studies": ["pair", "half"]}},
    "reports": {},
    "audit": {"verify": True, "verify_sample": 8},
    "sweeps": {
        "pair": {**SWEEP, "counterface": [
            {"surface": {"sigma_um": 12.0}, "body": {"kind": "block", "E_MPa": 511.0}},
            {"body": {"kind": "block", "E_MPa": 511.0}},
            {"body": {"kind": "halfspace", "E_MPa": 511.0e4, "nu": 0.3}},
            {"body": "rigid"},
        ]},
        "half": {**SWEEP, "E_MPa": 255.5},
    },
}
COLUMNS = ["normalized_stiffness_mean", "real_area_fraction_mean", "max_pressure_mean",
           "approach_mean", "mean_plane_deflection_mean", "spot_count_mean", "mean_gap_mean"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("counterface")
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump(CONFIG))
    proc = run_snakemake(workdir, config=path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    results = workdir / "results"
    table = pd.read_csv(results / "aggregates" / "pair.csv")
    half = pd.read_csv(results / "aggregates" / "half.csv")
    meta = json.loads((results / "aggregates" / "pair.json").read_text())
    cells = [table[table["cell"] == i].reset_index(drop=True) for i in range(4)]
    return cells, half, meta, results, proc


def test_two_identical_blocks_are_one_block_of_half_the_modulus(run):
    cells, half, _, _, _ = run
    twin = cells[1]
    np.testing.assert_allclose(twin[COLUMNS], half[COLUMNS], rtol=1e-6)
    np.testing.assert_allclose(twin["counter_share_mean"], 0.5, rtol=1e-9)
    np.testing.assert_allclose(twin["body_deflection_mean"], twin["counter_deflection_mean"],
                               rtol=1e-9)
    np.testing.assert_allclose(twin["body_deflection_mean"] + twin["counter_deflection_mean"],
                               twin["mean_plane_deflection_mean"], rtol=1e-12)


def test_a_far_stiffer_counter_body_is_treated_as_rigid_and_logged(run):
    cells, _, meta, results, _ = run
    stiff, flat = cells[2], cells[3]
    summary = meta["mean_plane_modulus"][2]
    assert summary["counter_treated_as_rigid"] is True
    assert summary["counter_compliance_share"] < 0.001
    assert stiff["counter_share_mean"].isna().all()  # not modelled: not reported
    pd.testing.assert_frame_equal(stiff[COLUMNS], flat[COLUMNS])
    logs = "".join(p.read_text() for p in (results / "logs" / "contact").glob("*cf*.log"))
    assert "treated as rigid" in logs


def test_a_rough_counter_surface_is_reported_with_the_composite_surface(run):
    cells, _, meta, _, _ = run
    rough, smooth = cells[0], cells[1]
    assert rough["equivalent_sigma_um"].iloc[0] == pytest.approx(np.hypot(24.5, 12.0))
    assert rough["counter_sigma_um"].iloc[0] == 12.0
    summary = meta["mean_plane_modulus"][0]
    assert summary["equivalent_sample_sigma_um"] == pytest.approx(np.hypot(24.5, 12.0),
                                                                   rel=0.15)
    assert abs(summary["equivalent_skew"]) < 1.0
    assert rough["contact_key"].iloc[0] != smooth["contact_key"].iloc[0]


def test_the_audit_re_solves_pairs_bit_for_bit(run):
    _, _, _, results, _ = run
    verify = pd.read_csv(results / "audit" / "verify.csv")
    assert verify["contact_job"].str.contains("__cf").any()
    assert verify["identical"].all()


def test_each_pair_of_bodies_is_summed_once_and_checked_on_read(run):
    from roughcontact.errors import StoredFileError
    from roughcontact.study.jobs.storage import read_contact, read_pair

    _, _, _, results, _ = run
    pairs = sorted((results / "influence" / "pairs").glob("*.h5"))
    # the rough and the smooth counter block share one pair; the stiff half-space has its own
    assert len(pairs) == 2
    recorded = set()
    for path in (results / "contact").glob("*__cf*.h5"):
        _, attrs = read_contact(path)
        recorded.add(attrs["pair_content_sha256"])
    assert recorded == {read_pair(p)[2]["content_sha256"] for p in pairs}
    block = next(p for p in pairs if "halfspace" not in p.name)
    matrix, weights, attrs = read_pair(block)
    assert matrix.shape == (256, 256) and weights.shape == (256,)
    other = json.loads(attrs["params"]) | {"modulus_ratio": 2.0}
    with pytest.raises(StoredFileError, match="modulus_ratio"):
        read_pair(block, pair=other)


def test_the_two_bodies_figure_and_its_caption_name_each_counter_body(run):
    import nbformat

    _, _, _, results, _ = run
    for ext in ("png", "pdf", "ipynb"):
        assert (results / "figures" / f"two_bodies.{ext}").stat().st_size > 1000, ext
    notebook = nbformat.read(results / "figures" / "two_bodies.ipynb", as_version=4)
    printed = "".join(o.get("text", "") for c in notebook.cells if c.cell_type == "code"
                      for o in c.outputs)
    assert "half-space E 5.11e+06 MPa nu 0.3 (smooth) (treated as rigid)" in printed
    assert "rigid smooth flat" in printed and "half:" in printed
    proc = run_snakemake(results.parent, "--report", "report.html",
                         config=results.parent / "config.yaml")
    assert proc.returncode == 0, proc.stderr[-4000:]
    report = (results.parent / "report.html").read_text()
    assert ("pair (first body: sigma 24.5 um, E 511 MPa, nu 0, a 10 mm block on the paper's "
            "mesh (5 uniform trilinear layers)) against the block E 511 MPa nu 0 10 mm paper "
            "(sigma 12 um), the block E 511 MPa nu 0 10 mm paper (smooth), the half-space "
            "E 5.11e+06 MPa nu 0.3 (smooth) and the rigid smooth flat; half") in report
