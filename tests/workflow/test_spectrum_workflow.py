"""A study whose surfaces take their spectrum from a PSD table: the real snakemake."""

import hashlib
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]

#: One sweep on small surfaces whose spectrum is the table ``psd.csv`` of the
#: working directory (a relative path, as a user would write it).
CONFIG = {"surfaces": {"grid": [16, 16], "size_mm": [4.8, 4.8], "count": 2, "method": "paper",
                       "spectrum": {"kind": "table", "file": "psd.csv"}},
          "sweeps": {"small": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1.0]}},
          "contact": {"steps": 5, "pressure_levels": 4}}

pytestmark = pytest.mark.workflow


def run(workdir, *args):
    path = workdir / "config.yaml"
    path.write_text(yaml.safe_dump(CONFIG))
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(workdir), "--configfile", str(path), "--cores", "1", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))


def write_table(path: Path, slope: float) -> str:
    """A power-law PSD from 0.5 to 6 1/mm; returns the file's SHA-256."""
    q = np.geomspace(0.5, 6.0, 12)
    path.write_text("q_per_mm,C\n" + "".join(f"{a:.12g},{a ** slope:.12g}\n" for a in q))
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_table_spectrum_is_an_input_of_its_surfaces_job_and_keys_it(tmp_path):
    digest = write_table(tmp_path / "psd.csv", -3.0)
    proc = run(tmp_path, "--dry-run")
    assert proc.returncode == 0, proc.stderr[-3000:]
    key = f"sk0_ku3_b1x1mm_L4.8x4.8mm_g16x16_psd_per_paper_tab-{digest[:12]}_n2"
    job = rf"rule surfaces:\n\s+input: psd\.csv\n\s+output: results/surfaces/{key}\.h5\n"
    assert re.search(job, proc.stdout), proc.stdout[-3000:]
    # the job itself: the file's hash is stored with the surfaces, which have no
    # power above the table's last wavenumber
    target = f"results/surfaces/{key}.h5"
    proc = run(tmp_path, target)
    assert proc.returncode == 0, proc.stderr[-3000:]
    with h5py.File(tmp_path / target, "r") as f:
        assert f.attrs["spectrum_file_sha256"] == digest
        heights = f["heights"][()]
    q = 2 * math.pi * np.fft.fftfreq(16, 0.3e-3)
    above = np.hypot(q[None, :], q[:, None]) > 6.0e3 * (1 + 1e-9)
    power = np.abs(np.fft.fft2(heights)) ** 2
    assert above.any() and power[:, above].sum() < 1e-24 * power.sum()
    # another table under the same name: a new cell
    changed = write_table(tmp_path / "psd.csv", -2.0)
    proc = run(tmp_path, "--dry-run")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert f"tab-{changed[:12]}_n2.h5" in proc.stdout and key not in proc.stdout
