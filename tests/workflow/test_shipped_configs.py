"""Every configuration shipped in config/ plans: `snakemake -n` of the command its header
documents (the default target where it names none) ends without an error.

A dry run plans every job and prints its resources, which a run evaluates only when
the job is about to start: the configurations with ``operator: auto`` crashed here
(a resource read a checkpoint still to be made) while their real runs worked. The
files that are data, not configurations, are named, so that a new configuration is
dry-run without being listed here.
"""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: Files of config/ that are data read by the workflow, not configurations to run.
DATA_FILES = {"schema.yaml", "accuracy_presets.yaml", "cost_model.yaml"}
CONFIGS = sorted(p.name for p in (REPO / "config").glob("*.yaml") if p.name not in DATA_FILES)

pytestmark = pytest.mark.workflow


def documented_targets(path: Path) -> list[str]:
    """The targets of the ``snakemake ... --configfile`` command in a config's header
    comment (none: the default target)."""
    for line in path.read_text().splitlines():
        if not line.startswith("#"):
            break
        if "snakemake" in line and "--configfile" in line:
            words = shlex.split(line.lstrip("#"))
            words = words[[i for i, w in enumerate(words) if w.endswith("snakemake")][0] + 1:
                          words.index("--configfile")]
            values = {i + 1 for i, w in enumerate(words) if w in ("--cores", "-c")}
            return [w for i, w in enumerate(words) if not w.startswith("-") and i not in values]
    return []


def test_the_documented_targets_are_read_from_the_header():
    assert documented_targets(REPO / "config" / "gridconv.yaml") == ["grid_convergence"]
    assert documented_targets(REPO / "config" / "fig11_resolved.yaml") == [
        "results/figures/fig11_resolved.png"]
    assert documented_targets(REPO / "config" / "large.yaml") == []
    assert {"config.yaml", "quick.yaml", "large.yaml", "measured.yaml", "two_bodies.yaml",
            "fig11_resolved.yaml", "gridconv.yaml", "seal.yaml"} <= set(CONFIGS)
    assert documented_targets(REPO / "config" / "seal.yaml") == []


@pytest.mark.parametrize("name", CONFIGS)
def test_every_shipped_config_dry_runs(tmp_path, name):
    """The dry run of each shipped configuration in an empty working directory (the
    repository's data/ beside it, as the configurations name their files), without
    --quiet: every job's resources are evaluated and printed."""
    (tmp_path / "data").symlink_to(REPO / "data")
    path = REPO / "config" / name
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(tmp_path), "--dry-run", *documented_targets(path),
           "--configfile", str(path)]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    env.pop("SNAKEMAKE_PROFILE", None)
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600,
                          cwd=tmp_path)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output[-4000:]
    assert "Traceback" not in output, output[-4000:]
    assert "This was a dry-run" in output
    assert re.search(r"^total\s+\d+$", output, re.MULTILINE), output[-2000:]
    assert not (tmp_path / "results").exists()
