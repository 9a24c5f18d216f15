"""The leakage figure end to end on a tiny grid: a seal study with the flow on.

Two cells, (Sk, Ku) = (0, 3) and (0.8, 4), three surfaces each on the refined
mesh (on the paper's, far too stiff, they had not sealed at 20 MPa), pressed past
sealing. Checked: the figure and its notebook are made, the notebook prints each
cell's leak rate at three pressures (the leak rate equal to the seal's formula on
the conductance column) and the percolation thresholds of the sidecar, and the
report's caption names the configured fluid and seal.
"""

import json

import numpy as np
import pandas as pd
import pytest
import yaml
from test_workflow import run_snakemake

pytestmark = pytest.mark.workflow

FLOW = {"enabled": True, "directions": ["x", "y"], "viscosity_Pa_s": 0.002,
        "pressure_drop_MPa": 0.5, "seal_width_mm": 50.0, "seal_length_mm": 3.0}
CONFIG = {
    "study_seed": 7,
    "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4], "count": 3},
    "body": {"E_MPa": 511.0, "nu": 0.0, "mesh": "refined"},
    "contact": {"steps": 12, "pressure_levels": 6},
    "flow": FLOW,
    "figures": {"leakage": {"studies": ["seal"]}},
    "reports": {},
    "sweeps": {"seal": {"sigma_um": 5.0, "b_mm": 0.5, "moments": [[0.0, 3.0], [0.8, 4.0]],
                        "pressure_MPa": [0.2, 20.0]}},
}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("leakage")
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump(CONFIG))
    proc = run_snakemake(workdir, config=path)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return workdir / "results"


def test_the_leakage_notebook_prints_the_leak_rates_and_the_thresholds(run):
    import nbformat

    results = run
    for ext in ("png", "pdf", "ipynb"):
        assert (results / "figures" / f"leakage.{ext}").stat().st_size > 1000, ext
    table = pd.read_csv(results / "aggregates" / "seal.csv")
    seal = FLOW["seal_width_mm"] * 1e-3 * FLOW["pressure_drop_MPa"] * 1e6 / (
        12 * FLOW["viscosity_Pa_s"] * FLOW["seal_length_mm"] * 1e-3)
    np.testing.assert_allclose(table["leak_rate_x_mean"], seal * table["flow_conductance_x_mean"],
                               rtol=1e-12)
    notebook = nbformat.read(results / "figures" / "leakage.ipynb", as_version=4)
    printed = [o.get("text", "") for c in notebook.cells if c.cell_type == "code"
               for o in c.outputs]
    rates, thresholds = printed[-2], printed[-1]
    assert rates.startswith("seal:") and "leak_rate_x_mean" in rates and "leak_rate_y_mean" in rates
    assert len(rates.splitlines()) == 2 + 2 * 3  # the study, the header, 2 cells x 3 levels
    found = json.loads((results / "aggregates" / "seal.json").read_text())["flow"]["percolation"]
    assert len(found) == 4 and {row["direction"] for row in found} == {"x", "y"}
    assert thresholds.startswith("seal:") and "area_low" in thresholds
    assert len(thresholds.splitlines()) == 2 + len(found)
    assert all(row["sealed_inside"] == 3 for row in found)  # pressed past sealing
    assert f"{found[0]['area']:.4g}" in thresholds and f"{found[-1]['pressure_MPa']:.4g}" in \
        thresholds


def test_the_report_shows_the_leakage_figure_with_the_seals_caption(run):
    workdir = run.parent
    proc = run_snakemake(workdir, "--report", "report.html", config=workdir / "config.yaml")
    assert proc.returncode == 0, proc.stderr[-4000:]
    report = (workdir / "report.html").read_text()
    assert "leakage.png" in report
    assert ("a fluid of viscosity 0.002 Pa s through a seal 50 mm wide and 3 mm long with "
            "0.5 MPa across it") in report
