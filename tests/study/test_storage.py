"""Stored files: every read checks the content hash written with the file and, given what
its job expects, the parameters the file was made for."""

import dataclasses
import errno
import os
from pathlib import Path

import h5py
import numpy as np
import pytest

from roughcontact.contact.curves import NondimSweep
from roughcontact.elasticity.operators import BlockOperator
from roughcontact.errors import DiskFullError, StoredFileError
from roughcontact.hashes import arrays_sha256
from roughcontact.study.jobs import storage
from roughcontact.study.jobs.storage import CONTACT_ARRAYS, CONTACT_FIELDS
from roughcontact.study.provenance import atomic_path, canonical_json
from roughcontact.study.records import Geometry, InfluenceModel


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


# ---------------------------------------------------------------------------
# File format versions: what older files lack is filled by the readers, in one place


def as_version_1(path, *lacking):
    """The file at ``path`` as version 1 wrote it: no ``format_version``, nor ``lacking``
    (attributes only: the content hash still holds)."""
    with h5py.File(path, "r+") as f:
        for name in ("format_version", *lacking):
            del f.attrs[name]


def test_new_files_carry_their_format_version_and_a_dense_file_its_operator(tmp_path):
    storage.write_influence(tmp_path / "g.h5", np.eye(4), {"geometry": "g"})
    storage.write_contact(tmp_path / "job.h5", sweep(), {"job": "{}"})
    surfaces_file(tmp_path / "cell.h5")
    _, attrs = storage.read_influence(tmp_path / "g.h5")
    version = storage.FORMAT_VERSION
    assert attrs["format_version"] == version and attrs["operator"] == "dense"
    assert storage.read_contact(tmp_path / "job.h5")[1]["format_version"] == version
    assert storage.read_surfaces(tmp_path / "cell.h5")["attrs"]["format_version"] == version


def test_a_version_1_file_reads_with_the_documented_values(tmp_path):
    assert storage.VERSION_1_LACKED == {"surfaces": {}, "influence": {"operator": "dense"},
                                        "contact": {"sweep_hardness": -1.0}}
    # a dense matrix from before the matrix-free operators: no operator attribute
    path = tmp_path / "g.h5"
    storage.write_influence(path, np.eye(4) * 2.0, {"geometry": "g"})
    as_version_1(path, "operator")
    unit, attrs = storage.read_influence(path)
    assert attrs["operator"] == "dense" and np.array_equal(unit, np.eye(4) * 2.0)
    # a version-1 operator file names its own operator: kept
    op = BlockOperator(grid=(4, 4), size=(2.4e-3, 2.4e-3), nu=0.0)
    storage.write_influence(path, op, {})
    as_version_1(path)
    assert storage.read_influence(path)[1]["operator"] == "halfspace"
    # a contact sweep from before the hardness cap: elastic
    path = tmp_path / "job.h5"
    storage.write_contact(path, sweep(), {"job": "{}"})
    as_version_1(path, "sweep_hardness")
    back, attrs = storage.read_contact(path)
    assert back.nondim_hardness is None and attrs["sweep_hardness"] == -1.0


def test_a_file_of_a_newer_format_version_is_refused(tmp_path):
    path = tmp_path / "job.h5"
    storage.write_contact(path, sweep(), {"job": "{}"})
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = storage.FORMAT_VERSION + 1
    newer = storage.FORMAT_VERSION + 1
    with pytest.raises(StoredFileError, match=rf"job\.h5: written in file format version "
                                              rf"{newer} by a newer roughcontact"):
        storage.read_contact(path)


# ---------------------------------------------------------------------------
# Parameters: a file is never trusted by its name


def geometry(mesh="refined", grid=(4, 4)):
    return Geometry(nu=0.0, size=(2.4e-3, 2.4e-3), thickness=10e-3, grid=grid,
                    base="clamped", mesh=mesh)


def influence_file(path, geom):
    n = geom.grid[0] * geom.grid[1]
    unit = np.eye(n) * 2.0 + 0.1
    storage.write_influence(path, unit, {"geometry": geom.key,
                                         "params": canonical_json(geom.params())})
    return unit


def test_an_influence_file_of_another_mesh_is_refused_naming_the_field(tmp_path):
    paper, refined = geometry("paper"), geometry("refined")
    path = tmp_path / f"{refined.key}.h5"
    influence_file(path, paper)  # the paper mesh's file under the refined mesh's name
    storage.read_influence(path)  # valid and hashed: nothing else tells it apart
    with pytest.raises(StoredFileError) as err:
        storage.read_influence(path, geometry=refined.params())
    message = str(err.value)
    assert str(path) in message and err.value.path == str(path)
    assert 'mesh = "paper" in the file, "refined" expected' in message
    assert f"rm {path}" in message
    # the same check on the attributes alone (the re-verification's)
    with pytest.raises(StoredFileError, match='mesh = "paper" in the file'):
        storage.check_parameters(path, geometry=refined.params())
    assert storage.check_parameters(path, geometry=paper.params())["geometry"] == paper.key
    unit, _ = storage.read_influence(path, geometry=paper.params())
    assert unit.shape == (16, 16)


def test_an_influence_file_of_another_grid_is_refused_before_its_matrix_is_used(tmp_path):
    g16, g32 = geometry(grid=(4, 4)), geometry(grid=(8, 8))
    path = tmp_path / f"{g32.key}.h5"
    influence_file(path, g16)
    with pytest.raises(StoredFileError, match=r"grid = \[4, 4\] in the file, \[8, 8\] expected"):
        storage.read_influence(path, geometry=g32.params())
    # parameters edited to claim the other grid: the matrix's shape still tells
    with h5py.File(path, "r+") as f:
        f.attrs["params"] = canonical_json(g32.params())
    with pytest.raises(StoredFileError, match=r"shape of unit_influence .* = \[16, 16\] in "
                                              r"the file, \[64, 64\] expected"):
        storage.read_influence(path, geometry=g32.params())


def test_an_operator_file_of_another_model_is_refused(tmp_path):
    dense, hybrid = geometry(), dataclasses.replace(geometry(), operator=InfluenceModel.HYBRID)
    op = BlockOperator(grid=(4, 4), size=(2.4e-3, 2.4e-3), nu=0.0)
    path = tmp_path / "g.h5"
    storage.write_influence(path, op, {"params": canonical_json(hybrid.params())})
    assert storage.read_influence(path, geometry=hybrid.params())[0].kind == "halfspace"
    with pytest.raises(StoredFileError, match=r'operator = "hybrid" in the file, \(not set\) '
                                              r"expected"):
        storage.read_influence(path, geometry=dense.params())


def test_an_operator_that_cannot_be_made_from_its_file_names_the_file(tmp_path):
    path = tmp_path / "op.h5"
    storage.write_h5(path, {"correction": np.ones((3, 3))},
                     {"operator": "hybrid", "operator_grid": [4, 4],
                      "operator_size_m": [1e-3, 1e-3], "operator_nu": 0.0,
                      "coarse_grid": [2, 2]})
    with pytest.raises(StoredFileError, match=r"op\.h5: its hybrid operator cannot be made.*"
                                              r"shape \(4, 4\).*rm "):
        storage.read_influence(path)


def cell_params(count=3, grid=(5, 6), skew=0.0):
    return {"skew": skew, "kurt": 3.0, "b_mm": [0.5, 0.5], "grid": list(grid),
            "size_mm": [2.4, 2.4], "acf": "exponential", "periodic": True,
            "method": "filter", "count": count}


def test_a_surface_file_of_another_cell_or_seed_is_refused(tmp_path):
    path = tmp_path / "cell.h5"
    rng = np.random.default_rng(1)
    storage.write_surfaces(path, {"heights": rng.standard_normal((3, 6, 5)),
                                  "seeds": np.arange(3, dtype=np.int64)},
                           {"spec": "{}", "study_seed": 7,
                            "params": canonical_json(cell_params())})
    assert storage.read_surfaces(path, cell=cell_params(), study_seed=7)["heights"].shape \
        == (3, 6, 5)
    with pytest.raises(StoredFileError, match=r"skew = 0 in the file, -0.8 expected"):
        storage.read_surfaces(path, cell=cell_params(skew=-0.8), study_seed=7)
    with pytest.raises(StoredFileError, match=r"study_seed = 7 in the file, 8 expected"):
        storage.read_surfaces(path, cell=cell_params(), study_seed=8)
    with pytest.raises(StoredFileError, match=r"count = 3 in the file, 4 expected"):
        storage.read_surfaces(path, cell=cell_params(count=4), study_seed=7)


def test_a_file_without_parameters_is_refused_when_they_are_expected(tmp_path):
    path = tmp_path / "cell.h5"
    surfaces_file(path)  # no params attribute
    with pytest.raises(StoredFileError, match=r"params = \(not set\) in the file"):
        storage.read_surfaces(path, cell=cell_params())


def test_a_contact_file_of_another_job_is_refused_and_labels_do_not_count(tmp_path):
    job = {"surface": cell_params(count=2), "geometry": geometry().params(),
           "surface_key": "s", "geometry_key": "g", "pressure_end": 4.0,
           "accuracy": "as configured", "expected_error": {}}
    path = tmp_path / "job.h5"
    storage.write_contact(path, sweep(), {"job": canonical_json(job)})
    # the accuracy preset's name only labels a job
    storage.read_contact(path, job=job | {"accuracy": "fast", "expected_error": {"k_P": 0.1}})
    with pytest.raises(StoredFileError, match=r"pressure_end = 4 in the file, 8 expected"):
        storage.read_contact(path, job=job | {"pressure_end": 8.0})
    with pytest.raises(StoredFileError, match=r"hardness = \(not set\) in the file, 0.5 "):
        storage.read_contact(path, job=job | {"hardness": 0.5})
    with pytest.raises(StoredFileError, match=r"geometry.mesh = \"refined\" in the file, "
                                              r"\"paper\" expected"):
        storage.read_contact(path, job=job | {"geometry": geometry("paper").params()})


# ---------------------------------------------------------------------------
# A full disk


def test_a_full_disk_names_the_file_and_what_to_free(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    old = tmp_path / "results" / "contact" / "old.h5"
    old.parent.mkdir(parents=True)
    old.write_bytes(b"x" * 5000)
    real_file = h5py.File

    def full_disk(name, mode="r", **kwargs):
        if mode == "w":  # a write that fills the disk part way
            Path(name).write_bytes(b"y" * 3000)
            raise OSError(errno.ENOSPC, "Can't synchronously write data (file write failed: "
                                        "errno = 28, error message = 'No space left on device')")
        return real_file(name, mode, **kwargs)

    monkeypatch.setattr(storage.h5py, "File", full_disk)
    target = Path("results", "surfaces", "cell.h5")
    with pytest.raises(DiskFullError) as err:
        surfaces_file(target)
    message = str(err.value)
    assert isinstance(err.value, OSError) and err.value.errno == errno.ENOSPC
    assert message.startswith(f"{target}: cannot be written, the disk holding it is full")
    assert "3 kB of it had been written" in message
    assert f"{old.relative_to(tmp_path)} (5 kB)" in message  # what there is to free
    assert "find results -name '.*.tmp*' -delete" in message
    assert "Errno" not in message
    assert not list(target.parent.iterdir())  # nothing half-written left
    # space freed: the same write goes through
    monkeypatch.setattr(storage.h5py, "File", real_file)
    surfaces_file(target)
    assert storage.read_surfaces(target)["heights"].shape == (3, 6, 5)


def test_a_full_disk_under_any_atomic_write_is_named(tmp_path):
    path = tmp_path / "table.csv"
    with pytest.raises(DiskFullError, match=r"table\.csv: cannot be written.*full"):
        with atomic_path(path) as tmp:
            Path(tmp).write_text("a,b\n")
            raise OSError(errno.EDQUOT, "Disk quota exceeded")
    assert not list(tmp_path.iterdir())
    with pytest.raises(PermissionError):  # other errors stay what they are
        with atomic_path(path):
            raise PermissionError(errno.EACCES, "Permission denied")


def test_contact_files_store_every_interface_quantity():
    """The storage module names the interface datasets itself (it imports no solver);
    they are the fields of the records it reads them into."""
    from roughcontact.contact.result import INTERFACE

    assert storage.INTERFACE_ARRAYS == INTERFACE


class _Touching:
    """A probe of one yes/no column and one length cubed (the storage needs only its
    kind, settings and columns)."""

    kind = "touching"

    def __init__(self, threshold=0.5):
        self.threshold = threshold

    def __eq__(self, other):
        return isinstance(other, _Touching) and other.threshold == self.threshold

    @property
    def columns(self):
        from roughcontact.contact.probes import Column

        return (Column("touching", "1", "share touching", dtype=bool),
                Column("gap_cubed", "m^3", "mean gap cubed", length_power=3))

    def params(self):
        return {"threshold": self.threshold}


def probed_sweep():
    from roughcontact.contact.probes import ProbeColumns

    values = {"touching": np.array([[True, False, True, False]] * 2),
              "gap_cubed": np.linspace(1.0, 2.0, 8).reshape(2, 4)}
    return dataclasses.replace(sweep(), probe_columns=ProbeColumns((_Touching(0.25),), values))


def test_a_probes_columns_and_settings_are_stored_and_its_kind_makes_it_again(
        tmp_path, monkeypatch):
    from roughcontact.study import probes

    path = tmp_path / "job.h5"
    stored = probed_sweep()
    storage.write_contact(path, stored, {"job": "{}"})
    with h5py.File(path, "r") as f:  # the datasets under the columns' names, the settings
        assert f.attrs["touching"] == '{"threshold":0.25}'  # under the probe's kind
        assert f["touching"].dtype == bool and np.array_equal(f["gap_cubed"][()],
                                                              np.linspace(1.0, 2.0, 8)
                                                              .reshape(2, 4))
    # a probe kind the registry does not know: refused, naming its datasets
    with pytest.raises(StoredFileError, match="datasets gap_cubed, touching of no probe"):
        storage.read_contact(path)
    monkeypatch.setattr(probes, "PROBE_KINDS", {**probes.PROBE_KINDS,
                                                "touching": lambda p: _Touching(**p)})
    back, _ = storage.read_contact(path)
    assert back.probe_columns.probes == (_Touching(0.25),)
    for name in ("touching", "gap_cubed"):
        np.testing.assert_array_equal(back.probe_columns[name], stored.probe_columns[name])
        assert back.probe_columns[name].dtype == stored.probe_columns[name].dtype
    # a file that names the probe but lacks one of its columns (its hash made without
    # it) is refused, naming it
    with h5py.File(path, "r+") as f:
        del f["gap_cubed"]
        f.attrs["content_sha256"] = arrays_sha256({name: f[name][()] for name in f})
    with pytest.raises(StoredFileError, match="no gap_cubed of the probes it names"):
        storage.read_contact(path)


def test_a_sweep_without_probes_stores_no_probe_dataset_or_attribute(tmp_path):
    path = tmp_path / "job.h5"
    storage.write_contact(path, sweep(), {"job": "{}"})
    with h5py.File(path, "r") as f:
        assert set(f) == set(CONTACT_ARRAYS) and "flow" not in f.attrs
    back, _ = storage.read_contact(path)
    assert len(back.probe_columns) == 0
