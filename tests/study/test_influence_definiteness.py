"""The study certifies its influence models positive definite where it builds and loads them.

A stored influence model that is not positive definite (written by hand or by
an older version) is refused by the contact job, naming the file, with its
eigenvalues; its advice (delete the file, so that the workflow rebuilds it)
works. A build whose model is not positive definite is refused before the
file is written, naming the geometry and the config keys to change, and that
advice works too.
"""

from pathlib import Path

import numpy as np
import pytest

from roughcontact.elasticity import influence
from roughcontact.errors import IndefiniteOperator
from roughcontact.study.config import load_config
from roughcontact.study.jobs import influence as jobs
from roughcontact.study.jobs.contact import solve_contact_job
from roughcontact.study.jobs.influence import build_influence
from roughcontact.study.jobs.storage import read_contact, read_influence, write_influence
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.settings import Study

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def small_study():
    """The quick study on 8 x 8 grids (2.4 mm: twice its longest b): its config and first
    contact job."""
    config = load_config(REPO / "config" / "quick.yaml")
    config["surfaces"]["grid"] = [8, 8]
    config["surfaces"]["size_mm"] = [2.4, 2.4]
    job = next(iter(study_plan(Study.from_config(config)).jobs.values()))
    return config, job


def _build(config, geometry, path):
    body = config["body"]
    return build_influence(geometry.params(), path, solver=body["solver"],
                           max_memory_gb=body["max_memory_gb"])


def test_an_indefinite_influence_file_is_refused_naming_it_and_its_advice_works(
        small_study, tmp_path):
    config, job = small_study
    surfaces = tmp_path / "surfaces.h5"
    build_surface_cell(job.surface.params(), config["study_seed"], surfaces)
    stored = tmp_path / f"{job.geometry.key}.h5"
    _build(config, job.geometry, stored)
    unit, attrs = read_influence(stored)
    # the same file with two far elements coupled beyond their self-compliance
    unit[0, -1] = unit[-1, 0] = 2.0 * unit[0, 0]
    smallest = np.linalg.eigvalsh(unit)[0]
    assert smallest < 0
    stored.unlink()
    write_influence(stored, unit, {k: v for k, v in attrs.items() if k != "content_sha256"})
    settings = Study.from_config(config).contact.params()
    out = tmp_path / "contact.h5"
    with pytest.raises(IndefiniteOperator) as info:
        solve_contact_job(job.params(), {"surfaces": surfaces, "influence": stored}, out,
                          settings)
    message = str(info.value)
    assert str(stored) in message and f"smallest about {smallest:.4g} m" in message
    assert "Delete the file" in message and not out.exists()
    # the advice, followed: delete it, and the workflow's build writes it again
    stored.unlink()
    _build(config, job.geometry, stored)
    solve_contact_job(job.params(), {"surfaces": surfaces, "influence": stored}, out,
                          settings)
    sweep, _ = read_contact(out)
    assert sweep.converged.all()


def test_a_build_that_is_not_positive_definite_is_refused_and_its_advice_works(
        small_study, tmp_path, monkeypatch):
    config, job = small_study
    real = influence.unit_modulus_influence

    def unresolved(model, **options):
        """The finite-element matrix, made indefinite for the paper's mesh (as a mesh
        that does not resolve the block could make it)."""
        unit = real(model, **options)
        if model.mesh == "paper":
            unit[0, -1] = unit[-1, 0] = 2.0 * unit[0, 0]
        return unit

    monkeypatch.setattr(jobs.influence, "unit_modulus_influence", unresolved)
    geometry = Study.from_config(config).body.geometry
    assert geometry.mesh == "paper"
    path = tmp_path / "g.h5"
    with pytest.raises(IndefiniteOperator) as info:
        _build(config, geometry, path)
    message = str(info.value)
    assert f"geometry {geometry.key}" in message and "smallest about -" in message
    assert "set body.mesh to refined or converged" in message
    assert not path.exists()
    # the advice, followed: body.mesh: refined
    refined = Study.from_config(
            {**config, "body": {**config["body"], "mesh": "refined"}}).body.geometry
    assert refined.mesh == "refined"
    attrs = _build(config, refined, path)
    assert attrs["check_positive_definite"] == "cholesky"


def test_a_failed_factorization_names_the_geometry_and_its_mesh(small_study, tmp_path,
                                                                 monkeypatch):
    from roughcontact.elasticity import sparse_solve
    from roughcontact.errors import FactorizationError

    config, _ = small_study

    def failing(model, **options):
        raise sparse_solve._pardiso_error(-2)

    monkeypatch.setattr(jobs.influence, "unit_modulus_influence", failing)
    geometry = Study.from_config(config).body.geometry
    path = tmp_path / "g.h5"
    with pytest.raises(FactorizationError) as info:
        _build(config, geometry, path)
    message = str(info.value)
    assert message.startswith(f"geometry {geometry.key} (body.mesh paper")
    assert "not enough memory" in message and info.value.code == -2
    assert not path.exists()
