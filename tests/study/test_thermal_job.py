"""A block's thermal influence is built once by its own job and read by its contact jobs,
each checked to have been made for the block; the plan names the file only where the
conductance crosses a block."""


import h5py
import numpy as np
import pytest
from study_sections import planned, with_sections

from roughcontact.contact.probes import SolvedFields
from roughcontact.errors import StoredFileError
from roughcontact.study import layout
from roughcontact.study.contact_records import ContactJob
from roughcontact.study.jobs.storage import check_parameters
from roughcontact.study.jobs.thermal import build_thermal, read_thermal
from roughcontact.study.plan import resources
from roughcontact.study.thermal_records import NO_THERMAL, ThermalBlock
from roughcontact.transport.conduction import ConductanceProbe
from roughcontact.transport.conduction.probe import BlockBody

BLOCK = ThermalBlock(size=(1.2e-3, 1.0e-3), thickness=0.6e-3, grid=(6, 5), mesh="paper")
STUDY = {"sigma_um": 1.0, "b_mm": 0.5, "pressure_MPa": [1.0, 20.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 210000.0, "nu": 0.3},
        "figures": {"fig07": STUDY}}


def plan(**sections):
    return planned(with_sections(BASE, **sections))


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    path = tmp_path_factory.mktemp("thermal") / "block.h5"
    attrs = build_thermal(BLOCK.params(), path)
    return path, attrs


def test_the_stored_influence_conducts_as_the_block(stored):
    path, attrs = stored
    unit = read_thermal(path, BLOCK)
    assert unit.shape == (30, 30) and attrs["params"] == BLOCK.params()
    # full contact: k A / L (1-D conduction through the block, not this code's number)
    probe = ConductanceProbe(BlockBody(BLOCK.block()), conductivity=20.0, tol=1e-12)
    full = np.ones((1, 5, 6))
    fields = SolvedFields(full, full, np.zeros(1), (0.2e-3, 0.2e-3), False)
    given = probe.with_unit_influence(unit).measure(fields)
    assert given["thermal_conductance"][0] == pytest.approx(20.0 * 1.2e-3 * 1.0e-3 / 0.6e-3,
                                                            rel=1e-9)
    # a spot: the stored influence gives what the probe's own build gives
    spot = np.zeros((1, 5, 6))
    spot[0, 1:3, 2:5] = 1.0
    fields = SolvedFields(spot, spot, np.zeros(1), (0.2e-3, 0.2e-3), False)
    np.testing.assert_allclose(probe.with_unit_influence(unit).measure(fields)
                               ["thermal_conductance"],
                               probe.measure(fields)["thermal_conductance"], rtol=1e-10)


def test_a_file_of_another_block_or_damaged_is_refused_naming_it(stored, tmp_path):
    path, _ = stored
    check_parameters(path, geometry=BLOCK.params())  # the audit's check of its attributes
    thicker = ThermalBlock(size=BLOCK.size, thickness=0.8e-3, grid=BLOCK.grid, mesh="paper")
    with pytest.raises(StoredFileError, match=r"thickness_mm = 0\.6 in the file, 0\.8 expected"):
        read_thermal(path, thicker)
    damaged = tmp_path / "damaged.h5"
    damaged.write_bytes(path.read_bytes())
    with h5py.File(damaged, "r+") as f:
        f["unit_conductivity_influence"][0, 0] *= 1.0001
    with pytest.raises(StoredFileError, match="no longer match the hash"):
        read_thermal(damaged, BLOCK)


def test_the_plan_names_the_file_where_the_heat_crosses_a_block_only():
    on = plan(conductance={"enabled": True, "conductivity_W_mK": 50.0})
    (job,) = on.jobs.values()
    assert isinstance(job.thermal, ThermalBlock) and job.thermal == ThermalBlock.of(job.geometry)
    assert job.paths()["thermal"] == layout.thermal(job.thermal.key)
    # what the audit checks of it, on the attributes alone, passes for its own file
    (made_for,) = [file.made_for for name, file in job.files().items() if name == "thermal"]
    assert made_for == {"geometry": job.thermal.params()}
    assert on.thermal == {job.thermal.key: job.thermal}
    assert ContactJob.from_params(job.params()) == job  # the job reads it from its params
    assert resources.job_memory_mb(on, "thermal", {"thermal": job.thermal.key}) > 0
    assert resources.job_runtime(on, "thermal", {"thermal": job.thermal.key}) >= 1
    for other in (plan(), plan(conductance={"enabled": True, "conductivity_W_mK": 50.0,
                                            "body": "halfspace"})):
        assert other.thermal == {}
        for job in other.jobs.values():
            assert job.thermal is NO_THERMAL and "thermal" not in job.paths()
            assert "thermal" not in job.params()


def test_beyond_the_dense_limit_the_file_holds_the_coarse_block_and_rebuilds_the_operator(
        tmp_path):
    from roughcontact.contact.checks import given_matrix

    large = ThermalBlock(size=(7.2e-3, 7.2e-3), thickness=3e-3, grid=(72, 72),
                         mesh="refined")
    path = tmp_path / "large.h5"
    attrs = build_thermal(large.params(), path)
    assert attrs["coarse"] == {"grid": [36, 36], "mesh": "refined"}
    with h5py.File(path) as f:
        assert list(f) == ["coarse_unit_conductivity_influence"]
        assert f["coarse_unit_conductivity_influence"].shape == (1296, 1296)
    operator = read_thermal(path, large)
    assert given_matrix(operator) is None and operator.shape == (5184, 5184)
    # full contact: k A / L, to the matrix-free block's accuracy (0.24 % measured at
    # 24 x 24; its bulk is its own full-contact solve, so the bulk share is 1)
    probe = ConductanceProbe(BlockBody(large.block()), conductivity=20.0, tol=1e-8)
    full = np.ones((1, 72, 72))
    measured = probe.with_unit_influence(operator).measure(
        SolvedFields(full, full, np.zeros(1), (1e-4, 1e-4), False))
    assert measured["thermal_conductance"][0] == pytest.approx(20.0 * 7.2e-3**2 / 3e-3,
                                                                rel=5e-3)
    assert measured["conduction_bulk_share"][0] == pytest.approx(1.0, rel=1e-6)
    with pytest.raises(StoredFileError, match='mesh = "refined" in the file, "converged"'):
        read_thermal(path, ThermalBlock(size=large.size, thickness=3e-3, grid=(72, 72),
                                        mesh="converged"))
