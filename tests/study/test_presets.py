"""Tests of the stored accuracy presets and their drift command (roughcontact.study.presets)."""

import copy
import math
import subprocess
import sys

import pytest
import yaml

from roughcontact.study import presets

STORED = {
    "accuracy_presets": {
        "paper": {"mesh": "paper", "tol": 1e-8, "k_P_error": 0.09, "sampling_k_P": 0.02},
        "fast": {"mesh": "refined", "tol": 1e-6, "k_P_error": 0.0046, "sampling_k_P": 0.04},
    },
    "fallback_mesh_errors": {"paper": {"build_s": 5.6, "k_P_error": 0.09}},
}


def write(path, data):
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.fixture
def stored_path(tmp_path):
    return write(tmp_path / "stored.yaml", STORED)


def test_relative_drift():
    assert presets.relative_drift(0.1, 0.15) == pytest.approx(0.5)
    assert presets.relative_drift(0.1, 0.05) == pytest.approx(0.5)
    assert presets.relative_drift(0.0, 0.0) == 0.0
    assert presets.relative_drift(0.0, 1e-9) == math.inf


def test_one_changed_number_is_flagged_and_exits_0(tmp_path, stored_path, capsys):
    fresh = copy.deepcopy(STORED)
    fresh["accuracy_presets"]["fast"]["sampling_k_P"] = 0.06  # +50 %
    fresh_path = write(tmp_path / "fresh.yaml", fresh)
    assert presets.main(["--stored", str(stored_path), "--compare", str(fresh_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    [line] = [line for line in lines if "fast" in line and "sampling_k_P" in line]
    assert line.split()[3:7] == ["0.04", "0.06", "50.0%", "<--"]
    assert "DRIFT" in line
    unchanged = [line for line in lines if "paper" in line and "k_P_error" in line]
    assert unchanged and all("0.0%" in line and "DRIFT" not in line for line in unchanged)
    assert "1 of 10 values drift above 0.25" in lines
    assert not any("structure differs" in line for line in lines)
    # a looser tolerance flags nothing
    assert presets.main(["--stored", str(stored_path), "--compare", str(fresh_path),
                         "--rtol", "0.6"]) == 0
    assert "0 of 10 values drift above 0.6" in capsys.readouterr().out


def test_a_missing_or_extra_key_exits_1(tmp_path, stored_path, capsys):
    fresh = copy.deepcopy(STORED)
    del fresh["accuracy_presets"]["paper"]["sampling_k_P"]
    fresh["fallback_mesh_errors"]["paper"]["peak_memory_GB"] = 0.8
    fresh_path = write(tmp_path / "fresh.yaml", fresh)
    assert presets.main(["--stored", str(stored_path), "--compare", str(fresh_path)]) == 1
    out = capsys.readouterr().out
    assert ("structure differs: accuracy_presets/paper: key sampling_k_P: only in the stored "
            "file") in out
    assert ("structure differs: fallback_mesh_errors/paper: key peak_memory_GB: only in the "
            "fresh file") in out
    assert presets.structure_differences(STORED, STORED) == []


def test_module_command_line(tmp_path, stored_path):
    """``python -m roughcontact.study.presets --compare``: the stored file against itself."""
    proc = subprocess.run([sys.executable, "-m", "roughcontact.study.presets", "--compare",
                           str(presets.PRESETS_FILE)], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 0, proc.stderr
    assert "\n0 of " in proc.stdout and "k_P_error" in proc.stdout
    other = write(tmp_path / "other.yaml", STORED)
    proc = subprocess.run([sys.executable, "-m", "roughcontact.study.presets", "--compare",
                           str(other)], capture_output=True, text=True, check=False)
    assert proc.returncode == 1  # the stored file has other presets and keys
    assert "structure differs" in proc.stdout


def test_stored_presets_are_read_only_constants():
    assert set(presets.ACCURACY_PRESETS) == {"paper", "fast", "converged"}
    assert dict(presets.load_presets()["accuracy_presets"]["paper"]) == dict(
        presets.ACCURACY_PRESETS["paper"])
    with pytest.raises(TypeError):
        presets.ACCURACY_PRESETS["paper"]["tol"] = 1.0
