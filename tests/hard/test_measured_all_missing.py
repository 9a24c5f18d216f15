"""A height map that can never be filled says so, instead of suggesting an impossible fill_holes.

An all-NaN map used to be told to "raise fill_holes to at least 1", while the
config schema caps fill_holes at 0.5 (and no interpolation starts from no
data). With no known point, or more than half the points missing, the message
must say that the data cannot be filled and that the file must be repaired or
re-exported, naming the file.
"""

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from roughcontact.errors import MeasurementError
from roughcontact.surfaces import measured, preparation
from roughcontact.surfaces.measured import ImportOptions

SCHEMA = Path(__file__).resolve().parents[2] / "config" / "schema.yaml"


def _fill_holes_maximum():
    """The largest fill_holes the config schema accepts, read from the schema itself."""
    found = []

    def walk(node):
        if isinstance(node, dict):
            if isinstance(node.get("fill_holes"), dict) and "maximum" in node["fill_holes"]:
                found.append(float(node["fill_holes"]["maximum"]))
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(yaml.safe_load(SCHEMA.read_text()))
    assert found, "fill_holes has no maximum in config/schema.yaml"
    return max(found)


def _suggested_fill_holes(message):
    """Every fill_holes value the message asks for ("... fill_holes to at least X")."""
    return [float(v) for v in re.findall(r"fill_holes to at least ([0-9.eE+-]+)", message)]


def _assert_cannot_be_filled(message, source):
    assert "cannot be filled" in message
    assert source in message
    assert "repair" in message and "re-export" in message
    assert not _suggested_fill_holes(message), message


@pytest.mark.parametrize("fill_holes", [0.0, 0.3, 0.5, 0.9])
def test_all_missing_map_cannot_be_filled(fill_holes):
    heights = np.full((8, 6), np.nan)
    with pytest.raises(MeasurementError) as info:
        preparation.fill_missing(heights, fill_holes, source="scans/plate_07.xyz")
    _assert_cannot_be_filled(str(info.value), "scans/plate_07.xyz")
    assert "48 of 48 points" in str(info.value)
    assert info.value.path == "scans/plate_07.xyz"


def test_all_missing_file_names_the_file(tmp_path):
    path = tmp_path / "all_nan_scan.npy"
    np.save(path, np.full((16, 16), np.nan))
    with pytest.raises(MeasurementError) as info:
        measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-6, 1e-6), fill_holes=0.5))
    _assert_cannot_be_filled(str(info.value), str(path))


@pytest.mark.parametrize("missing", [0.6, 0.95])
def test_more_missing_than_the_schema_allows_cannot_be_filled(missing):
    maximum = _fill_holes_maximum()
    assert maximum == 0.5
    heights = np.arange(400.0).reshape(20, 20)
    heights.ravel()[: int(missing * heights.size)] = np.nan
    with pytest.raises(MeasurementError) as info:
        preparation.fill_missing(heights, maximum, source="scan.txt")
    _assert_cannot_be_filled(str(info.value), "scan.txt")


def test_fillable_map_still_gets_a_possible_fill_holes():
    # 20 % missing with fill_holes = 0.1: raising fill_holes (within the schema) helps
    heights = np.arange(100.0).reshape(10, 10)
    heights.ravel()[:20] = np.nan
    with pytest.raises(MeasurementError) as info:
        preparation.fill_missing(heights, 0.1, source="scan.txt")
    suggested = _suggested_fill_holes(str(info.value))
    assert suggested == [pytest.approx(0.2)]
    assert suggested[0] <= _fill_holes_maximum()
    filled, count = preparation.fill_missing(heights, suggested[0], source="scan.txt")
    assert count == 20
    # a linear ramp is filled exactly (Laplace interpolation reproduces planes)
    np.testing.assert_allclose(filled, np.arange(100.0).reshape(10, 10), atol=1e-9)
