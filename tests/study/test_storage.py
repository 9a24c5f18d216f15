"""Stored files: every read checks the content hash written with the file."""

import os

import h5py
import numpy as np
import pytest

from roughcontact.contact.curves import NondimSweep
from roughcontact.errors import StoredFileError
from roughcontact.hashes import arrays_sha256
from roughcontact.study import storage
from roughcontact.study.storage import CONTACT_ARRAYS, CONTACT_FIELDS


def surfaces_file(path):
    rng = np.random.default_rng(5)
    heights = rng.standard_normal((3, 6, 5))
    datasets = {"heights": heights, "seeds": np.arange(3, dtype=np.int64),
                "stats/skew": heights.reshape(3, -1).mean(axis=1)}
    storage.write_surfaces(path, datasets, {"spec": "{}"})
    return datasets


def sweep():
    shape = (2, 4)
    arrays = {CONTACT_FIELDS.get(name, name): np.linspace(0.1, 1.0, 8).reshape(shape)
              for name in CONTACT_ARRAYS}
    arrays["iterations"] = np.ones(shape, dtype=np.int64)
    arrays["matvecs"] = np.ones(shape, dtype=np.int64)
    arrays["converged"] = np.ones(shape, dtype=bool)
    arrays["stiffness_converged"] = np.ones(shape, dtype=bool)
    return NondimSweep(**arrays, thickness=0.01, element_area=1e-8, n_elements=30,
                       method="cg", tol=1e-8, stiffness_tol=1e-6, precision="mixed",
                       max_iter=None)


def test_surfaces_carry_the_hash_of_their_datasets_and_reads_check_it(tmp_path):
    path = tmp_path / "cell.h5"
    datasets = surfaces_file(path)
    cell = storage.read_surfaces(path)
    # the hash is that of the arrays as given, computed independently here
    assert cell["content_sha256"] == arrays_sha256(datasets)
    assert np.array_equal(storage.read_surfaces(path, count=2)["heights"], datasets["heights"][:2])
    with h5py.File(path, "r+") as f:
        f["heights"][0, 1, 1] += 2.0
    with pytest.raises(StoredFileError, match=r"cell\.h5.*no longer match.*delete it"):
        storage.read_surfaces(path)


def test_a_file_without_a_hash_is_refused_not_used(tmp_path):
    path = tmp_path / "old.h5"
    with h5py.File(path, "w") as f:
        f["heights"] = np.zeros((1, 4, 4))
        f["seeds"] = np.zeros(1, dtype=np.int64)
        f.attrs["spec"] = "{}"
    with pytest.raises(StoredFileError, match=r"old\.h5: no content hash"):
        storage.read_surfaces(path)


def test_a_changed_influence_matrix_is_named_before_any_symmetry_check(tmp_path):
    path = tmp_path / "g.h5"
    unit = np.array([[2.0, 0.5], [0.5, 2.0]])
    storage.write_influence(path, unit, {"geometry": "g"})
    assert np.array_equal(storage.read_influence(path)[0], unit)
    with h5py.File(path, "r+") as f:
        f["unit_influence"][0, 1] = 0.6  # no longer symmetric
    with pytest.raises(StoredFileError, match=r"g\.h5: its datasets no longer match"):
        storage.read_influence(path)


def test_contact_files_round_trip_and_refuse_edits_and_truncation(tmp_path):
    path = tmp_path / "job.h5"
    stored = sweep()
    storage.write_contact(path, stored, {"job": "{}"})
    back, attrs = storage.read_contact(path)
    assert np.array_equal(back.nominal_pressure, stored.nominal_pressure)
    with h5py.File(path, "r+") as f:
        f["nominal_pressure"][0, 0] *= 1.0 + 1e-12
    with pytest.raises(StoredFileError, match="no longer match"):
        storage.read_contact(path)
    storage.write_contact(path, stored, {"job": "{}"})
    os.truncate(path, os.path.getsize(path) // 2)
    with pytest.raises(StoredFileError, match=r"job\.h5: not a readable HDF5 file"):
        storage.read_contact(path)
