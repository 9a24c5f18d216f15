"""A study with the flow through the gap, end to end on a tiny grid.

One sweep of two (Sk, Ku) cells with the flow on, from first touch to past sealing,
beside the same study with the flow off. Checked: the flow off and on give the same
contact numbers (the flow changes no other column); the leak rate is the conductance
times W dp / (12 eta L) of the configured seal, by hand; each cell's percolation
threshold lies inside its sweep and is written to the sidecar; the contact files
carry the flow columns and the probe they were solved with, and the audit re-solves
them bit for bit; a change of the seal alone re-runs the aggregation, not the
contact jobs, and a change of the probe re-solves them; the leakage figure and its
notebook are made, the notebook prints each cell's leak rate at three pressures
and the sidecar's thresholds, and the report's caption names the fluid and seal.
"""

import copy
import json

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml
from test_workflow import run_snakemake

pytestmark = pytest.mark.workflow

SEAL = {"viscosity_Pa_s": 0.002, "pressure_drop_MPa": 0.5, "seal_width_mm": 50.0,
        "seal_length_mm": 3.0}
CONFIG = {
    "study_seed": 11,
    "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4], "count": 6},
    "body": {"E_MPa": 511.0, "nu": 0.0, "mesh": "paper"},
    "contact": {"steps": 14, "pressure_levels": 8},
    "flow": {"enabled": True, **SEAL},
    "figures": {"leakage": {"studies": ["seal"]}},
    "reports": {},
    "audit": {"verify": True, "verify_sample": 4},
    "sweeps": {"seal": {"sigma_um": 1.5, "b_mm": 0.5, "pressure_MPa": [2.0, 45.0],
                        "moments": [[0.0, 3.0], [-0.8, 4.0]]}},
}
CONTACT = ["normalized_stiffness_mean", "real_area_fraction_mean", "max_pressure_mean",
           "mean_gap_mean", "spot_count_mean", "approach_mean"]


def _write(workdir, config):
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = {}
    for name, enabled in (("on", True), ("off", False)):
        workdir = tmp_path_factory.mktemp(f"flow_{name}")
        config = copy.deepcopy(CONFIG)
        config["flow"]["enabled"] = enabled
        config["audit"]["verify"] = enabled  # the audit's re-solve only where there is flow
        if not enabled:
            config["figures"] = {}  # the leakage figure needs the flow
        proc = run_snakemake(workdir, config=_write(workdir, config))
        assert proc.returncode == 0, proc.stderr[-4000:]
        out[name] = workdir
    return out


def _table(workdir):
    return pd.read_csv(workdir / "results" / "aggregates" / "seal.csv")


def test_the_flow_changes_no_contact_number(runs):
    on, off = _table(runs["on"]), _table(runs["off"])
    pd.testing.assert_frame_equal(on[CONTACT], off[CONTACT])
    assert not [c for c in off.columns if "flow" in c or "leak" in c]
    assert {f"{q}_{d}_mean" for q in ("flow_conductance", "flow_factor", "leak_rate",
                                       "flow_connected", "flow_balance") for d in "xy"
            } <= set(on.columns)
    for d in "xy":  # every step's flow balanced: rounding-size, none flagged
        assert (on[f"flow_balance_{d}_mean"].dropna() < 1e-6).all()


def test_the_leak_rate_is_the_seals(runs):
    table = _table(runs["on"])
    factor = (SEAL["seal_width_mm"] * 1e-3 * SEAL["pressure_drop_MPa"] * 1e6
              / (12.0 * SEAL["viscosity_Pa_s"] * SEAL["seal_length_mm"] * 1e-3))
    for d in "xy":
        np.testing.assert_allclose(table[f"leak_rate_{d}_mean"],
                                   factor * table[f"flow_conductance_{d}_mean"], rtol=1e-12)
        leaking = table.groupby("cell")[f"flow_connected_{d}_mean"]
        # every surface leaks at the lightest load; most have sealed at the heaviest
        assert (leaking.first() == 1.0).all() and (leaking.last() < 0.5).all()


def test_the_tables_mark_the_open_faces_and_give_the_pressure_in_mpa(runs):
    """``faces_open`` where the 0.5 MPa drop exceeds the level (none of 2-45 MPa: by hand),
    with the flow on only; ``nominal_pressure_MPa`` beside the Pa column in both (to 12
    significant digits, as the tables write values for people)."""
    on, off = _table(runs["on"]), _table(runs["off"])
    np.testing.assert_array_equal(on["faces_open"].to_numpy(),
                                  SEAL["pressure_drop_MPa"] * 1e6 > on["nominal_pressure"])
    assert not on["faces_open"].any() and "faces_open" not in off
    for table in (on, off):
        np.testing.assert_allclose(table["nominal_pressure_MPa"],
                                   table["nominal_pressure"] / 1e6, rtol=1e-11)
        columns = list(table.columns)
        assert columns.index("nominal_pressure_MPa") == columns.index("nominal_pressure") + 1


def test_each_cells_threshold_lies_inside_its_sweep(runs):
    meta = json.loads((runs["on"] / "results" / "aggregates" / "seal.json").read_text())
    rows = meta["flow"]["percolation"]
    assert sorted((r["cell"], r["direction"]) for r in rows) == [
        (0, "x"), (0, "y"), (1, "x"), (1, "y")]
    table = _table(runs["on"])
    for row in rows:
        assert row["surfaces"] == 6 and row["sealed_inside"] == 6
        assert 0.2 < row["area"] < 0.7
        cell = table[table["cell"] == row["cell"]]
        assert cell["nominal_pressure"].min() / 1e6 <= row["pressure_MPa"] <= 45.0
    assert meta["flow"]["pressure_drop_Pa"] == 0.5e6


def test_the_contact_files_carry_the_flow_and_the_audit_re_solves_it(runs):
    files = sorted((runs["on"] / "results" / "contact").glob("*.h5"))
    assert len(files) == 2
    for path in files:
        with h5py.File(path) as f:
            assert json.loads(f.attrs["flow"])["directions"] == ["x", "y"]
            assert f["flow_connected_x"].dtype == bool
            assert f["flow_conductance_y"].shape == f["approach"].shape
    for path in sorted((runs["off"] / "results" / "contact").glob("*.h5")):
        with h5py.File(path) as f:
            assert "flow" not in f.attrs and "flow_conductance_x" not in f
    verify = pd.read_csv(runs["on"] / "results" / "audit" / "verify.csv")
    assert len(verify) >= 2 and verify["identical"].all() and verify["ok"].all()


def test_a_seal_change_re_aggregates_and_a_probe_change_re_solves(runs):
    workdir = runs["on"]
    for change, contact_jobs in (({"seal_length_mm": 6.0}, 0), ({"sides": "periodic"}, 2)):
        config = copy.deepcopy(CONFIG)
        config["flow"].update(change)
        proc = run_snakemake(workdir, "-n", "--quiet", "rules",
                             config=_write(workdir, config))
        assert proc.returncode == 0, proc.stderr[-3000:]
        planned = proc.stdout + proc.stderr
        counts = dict(line.split()[:2] for line in planned.splitlines()
                      if line.strip().startswith(("contact ", "aggregate ")))
        assert counts.get("aggregate") == "1", planned[-2000:]
        assert int(counts.get("contact", 0)) == contact_jobs, planned[-2000:]


def test_the_leakage_notebook_prints_the_leak_rates_and_the_thresholds(runs):
    import nbformat

    results = runs["on"] / "results"
    for ext in ("png", "pdf", "ipynb"):
        assert (results / "figures" / f"leakage.{ext}").stat().st_size > 1000, ext
    notebook = nbformat.read(results / "figures" / "leakage.ipynb", as_version=4)
    printed = [o.get("text", "") for c in notebook.cells if c.cell_type == "code"
               for o in c.outputs]
    rates, thresholds = printed[-2], printed[-1]
    assert rates.startswith("seal:") and "leak_rate_x_mean" in rates and "leak_rate_y_mean" in rates
    assert len(rates.splitlines()) == 2 + 2 * 3  # the study, the header, 2 cells x 3 levels
    found = json.loads((results / "aggregates" / "seal.json").read_text())["flow"]["percolation"]
    assert thresholds.startswith("seal:") and "area_low" in thresholds
    assert len(thresholds.splitlines()) == 2 + len(found)
    assert f"{found[0]['area']:.4g}" in thresholds and f"{found[-1]['pressure_MPa']:.4g}" in \
        thresholds


def test_the_report_shows_the_leakage_figure_with_the_seals_caption(runs):
    workdir = runs["on"]
    proc = run_snakemake(workdir, "--report", "report.html", config=_write(workdir, CONFIG))
    assert proc.returncode == 0, proc.stderr[-4000:]
    report = (workdir / "report.html").read_text()
    assert "leakage.png" in report
    assert ("a fluid of viscosity 0.002 Pa s through a seal 50 mm wide and 3 mm long with "
            "0.5 MPa across it") in report
    # the numbers after the plan's text: each cell's sealing pressure from the sidecar
    found = json.loads((workdir / "results" / "aggregates" / "seal.json").read_text())
    answers = (workdir / "results" / "figures" / "leakage.answers.rst").read_text()
    assert answers.startswith("Sealing pressure")
    assert "Sealing pressure (the nominal pressure at which half the surfaces" in report
    for row in found["flow"]["percolation"]:
        if row["pressure_MPa"] is not None:
            assert f"{row['pressure_MPa']:.3g} MPa" in report
