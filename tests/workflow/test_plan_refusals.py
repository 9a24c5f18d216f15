"""Input errors of a counter body stop `snakemake -n` before any job: the message names
the key and no traceback follows; a single-surface study plans with one warning."""

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
STEEL = {"kind": "block", "E_MPa": 210000.0, "nu": 0.3}
SWEEP = {"sigma_um": 2.0, "b_mm": 0.5, "pressure_MPa": [1.0, 30.0], "count": 3,
         "counterface": {"surface": {"sigma_um": 1.0}, "body": STEEL}}

pytestmark = pytest.mark.workflow


def dry_run(workdir: Path, config: dict) -> subprocess.CompletedProcess:
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump({"surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4]},
                                    "figures": {}, "reports": {}, **config}))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    env.pop("SNAKEMAKE_PROFILE", None)
    return subprocess.run([sys.executable, "-m", "snakemake", "--snakefile",
                           str(REPO / "Snakefile"), "--directory", str(workdir), "--dry-run",
                           "--configfile", str(path)],
                          capture_output=True, text=True, env=env, timeout=300, cwd=workdir)


@pytest.mark.parametrize(("counterface", "key"), [
    ({"body": {**STEEL, "E_MPa": 210}}, "sweeps.pad.counterface.body.E_MPa = 210"),
    ([{"body": "rigid"}, {"surface": {"measured": {"file": "disc.csv"}}}],
     "sweeps.pad.counterface[1].surface.measured.file: disc.csv: no such file"),
    ({"surface": {"sigma_um": "1.5"}}, "sweeps.pad.counterface.surface.sigma_um: \"1.5\""),
    ([{"body": "rigid"}, {"surface": "smooth", "body": "rigid"}],
     "sweeps.pad.counterface[1]: {\"body\": \"rigid\", \"surface\": \"smooth\"} repeats"),
])
def test_a_bad_counter_body_stops_the_plan_naming_its_key(tmp_path, counterface, key):
    proc = dry_run(tmp_path, {"sweeps": {"pad": {**SWEEP, "counterface": counterface}}})
    output = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert key in output, output[-3000:]
    # Snakemake's one line of where the plan stopped, not a traceback of the library
    assert "Traceback" not in output and "roughcontact/" not in output.split(key)[1].replace(
        "rules/common.smk", ""), output[-3000:]
    assert not (tmp_path / "results").exists()


def test_a_single_surface_study_plans_with_one_warning(tmp_path):
    proc = dry_run(tmp_path, {"surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4],
                                           "count": 1},
                              "sweeps": {"pad": {k: v for k, v in SWEEP.items() if k != "count"},
                                         "again": {"from": "pad"}}})
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output[-3000:]
    warned = [line for line in output.splitlines() if "one surface per cell" in line]
    assert warned == ["sweeps.pad: one surface per cell (surfaces.count = 1): a single-surface "
                      "cell has no confidence band (its 95 % band of the mean is NaN in the "
                      "aggregates); set surfaces.count to 2 or more for one"]
