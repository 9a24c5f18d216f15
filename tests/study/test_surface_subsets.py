"""A smaller surface cell takes its first surfaces from a larger cell of the same statistics."""

import dataclasses
from pathlib import Path

import h5py
import numpy as np
import pytest

from roughcontact.errors import StoredFileError
from roughcontact.study.config import load_config
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan.cells import study_plan, surfaces_from
from roughcontact.study.provenance import provenance
from roughcontact.study.records import GeneratedCell, Generator
from roughcontact.study.settings import Study

REPO = Path(__file__).resolve().parents[2]
#: Root attributes that differ between two builds of the same cell: provenance, the
#: calibration's wall time, and the file a cell's surfaces were taken from.
VARYING = {*provenance(), "calibration_seconds", "surfaces_from", "surfaces_from_sha256"}


def cell(method="filter", count=3, **change) -> GeneratedCell:
    """A small periodic cell (16 x 16 over 2.4 mm, b = 0.5 mm, Sk -0.5, Ku 4)."""
    fields = {"skew": -0.5, "kurt": 4.0, "corr_length": (0.5e-3, 0.5e-3), "grid": (16, 16),
              "size": (2.4e-3, 2.4e-3), "acf": "exponential", "periodic": True,
              "method": Generator(method), "count": count} | change
    return GeneratedCell(**fields)


def contents(path) -> tuple[dict, dict]:
    """``({dataset: (dtype, shape, bytes, attributes)}, root attributes)`` of a file."""
    datasets = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: datasets.__setitem__(
            name, (obj.dtype, obj.shape, obj[()].tobytes(), dict(obj.attrs)))
            if isinstance(obj, h5py.Dataset) else None)
        attrs = dict(f.attrs)
    return datasets, attrs


def test_the_plan_takes_each_smaller_cell_from_its_largest_twin():
    plan = study_plan(Study.from_config(load_config(REPO / "config" / "quick.yaml")))
    # Fig 3's one-surface cells and Fig 9's three-surface cells have four-surface twins
    assert plan.surfaces_from == {
        small.key: small.key.rsplit("_n", 1)[0] + "_n4"
        for small in plan.surfaces.values() if small.count < 4}
    assert len(plan.surfaces_from) == 4
    assert set(plan.surfaces_from.values()) <= set(plan.surfaces)
    cells = [cell(count=2), cell(count=3), cell(count=5), cell(method="exact", count=2),
             cell(count=2, skew=0.0)]
    assert surfaces_from({c.key: c for c in cells}) == {
        cells[0].key: cells[2].key, cells[1].key: cells[2].key}


@pytest.mark.parametrize("method", ["filter", "paper", "exact"])
def test_taken_surfaces_are_the_generated_ones_bit_for_bit(tmp_path, method):
    large = cell(method, count=3)
    source = tmp_path / "large.h5"
    build_surface_cell(large.params(), 11, source)
    for count in (1, 2):
        small = dataclasses.replace(large, count=count)
        made, taken = tmp_path / f"made{count}.h5", tmp_path / f"taken{count}.h5"
        build_surface_cell(small.params(), 11, made)
        build_surface_cell(small.params(), 11, taken, source=large.params(),
                           source_path=source)
        (made_sets, made_attrs), (taken_sets, taken_attrs) = contents(made), contents(taken)
        assert made_sets.keys() == taken_sets.keys() and made_sets["heights"][1][0] == count
        for name, (dtype, shape, data, attrs) in made_sets.items():
            assert taken_sets[name][:3] == (dtype, shape, data), name
            assert taken_sets[name][3].keys() == attrs.keys(), name
            assert all(np.array_equal(taken_sets[name][3][k], v) for k, v in attrs.items())
        assert set(taken_attrs) - set(made_attrs) == {"surfaces_from", "surfaces_from_sha256"}
        for name in set(made_attrs) - VARYING:  # also the content hash
            assert np.array_equal(made_attrs[name], taken_attrs[name]), name
        assert taken_attrs["surfaces_from"] == str(source)
        assert taken_attrs["cell"] == small.key


def test_a_source_that_does_not_fit_is_refused(tmp_path):
    large = cell("paper", count=3)
    small = dataclasses.replace(large, count=2)
    source = tmp_path / "large.h5"
    build_surface_cell(large.params(), 11, source)

    def take(source_cell, path=source, study_seed=11):
        build_surface_cell(small.params(), study_seed, tmp_path / "small.h5",
                           source=source_cell.params(), source_path=path)

    with pytest.raises(ValueError, match="its statistics differ"):
        take(dataclasses.replace(large, skew=-0.4))
    with pytest.raises(ValueError, match="made by method exact, not paper"):
        take(dataclasses.replace(large, method=Generator.EXACT))
    with pytest.raises(ValueError, match="it has 1 surfaces, fewer than the 2 asked for"):
        take(dataclasses.replace(large, count=1))
    # the file is checked as every stored file: its seed, its cell and its content
    with pytest.raises(StoredFileError, match="study_seed = 11 in the file, 12 expected"):
        take(large, study_seed=12)
    with pytest.raises(StoredFileError, match="count = 3 in the file, 4 expected"):
        take(dataclasses.replace(large, count=4))
    with h5py.File(source, "r+") as f:
        f["heights"][0, 0, 0] += 1e-12
    with pytest.raises(StoredFileError, match="no longer match"):
        take(large)
    assert not (tmp_path / "small.h5").exists()
