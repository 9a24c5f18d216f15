"""The one codec of the study's records: each field's key and unit declared once.

A record's params are its fields' declarations written out in field order (Snakemake
compares a rule's params by their repr, so the order is part of them), and a record
comes back from its params. Checked on a record of every kind of declaration against
params written out by hand, and on the study's own records against the params (and
the job keys hashed from them) of the records before the codec.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import pytest

from roughcontact.study import codec
from roughcontact.study.codec import DEFAULT, Record
from roughcontact.study.config import BuildSettings, ContactSettings, validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.records import Geometry, InfluenceModel
from roughcontact.study.settings import Study, load_study
from roughcontact.transport.probe import NO_FLOW
from roughcontact.units import MM, MPA, UM

REPO = Path(__file__).resolve().parents[2]


class Shape(Enum):
    ROUND = "round"
    SQUARE = "square"


@dataclass(frozen=True)
class Part(Record):
    name: str
    width: float = codec.si(MM, "width_mm")

    @property
    def key(self) -> str:
        return f"part-{self.name}"


class _NoPart:
    """The null part: written as None."""


NO_PART = _NoPart()


@dataclass(frozen=True)
class Toy(Record):
    count: int
    sigma: float = codec.si(UM, "sigma_um")
    size: tuple[float, float] = codec.si_pair(MM, "size_mm")
    levels: tuple[float, ...] = codec.si_tuple(MPA, "levels_MPa")
    grid: tuple[int, int] = codec.grid()
    shape: Shape = codec.enum(Shape)
    part: Part = codec.record(Part)
    part_key: str = codec.key_of("part")
    kind: str = codec.constant("toy")
    spare: Part = codec.record(Part, null=NO_PART, flatten=True, default=NO_PART)
    errors: tuple = codec.pairs(float, sort=True, when=lambda t: t.shape is Shape.ROUND,
                                default=())
    cap: float | None = codec.si(MPA, "cap_MPa", omit=DEFAULT, default=None)
    note: str = codec.field(group="extra", default="")
    depth: float = codec.si(MM, "depth_mm", group="extra", default=0.0)
    scratch: object = codec.unwritten(default=None, compare=False)


TOY = Toy(count=3, sigma=24.5e-6, size=(1.2e-3, 2.4e-3), levels=(0.1e6, 5e6), grid=(8, 10),
          shape=Shape.ROUND, part=Part("a", 0.5e-3), errors=(("b", 0.2), ("a", None)),
          note="n", depth=2e-3, scratch="not a parameter")
#: Its params, written out by hand: every key in field order, in the declared units.
TOY_PARAMS = {"count": 3, "sigma_um": 24.5, "size_mm": [1.2, 2.4], "levels_MPa": [0.1, 5.0],
              "grid": [8, 10], "shape": "round", "part": {"name": "a", "width_mm": 0.5},
              "part_key": "part-a", "kind": "toy", "name": None, "width_mm": None,
              "errors": {"b": 0.2, "a": None}, "extra": {"note": "n", "depth_mm": 2.0}}


def test_a_record_is_written_as_its_fields_declare_in_their_order():
    params = TOY.params()
    assert params == TOY_PARAMS
    assert list(params) == list(TOY_PARAMS) and list(params["extra"]) == ["note", "depth_mm"]


def test_a_record_comes_back_from_its_params():
    again = Toy.from_params(TOY_PARAMS)
    assert again.errors == (("a", None), ("b", 0.2))  # sorted by name, as declared
    assert again == Toy(count=3, sigma=24.5 * UM, size=(1.2 * MM, 2.4 * MM),
                        levels=(0.1 * MPA, 5.0 * MPA), grid=(8, 10), shape=Shape.ROUND,
                        part=Part("a", 0.5 * MM), errors=(("a", None), ("b", 0.2)),
                        note="n", depth=2.0 * MM)
    assert again.sigma == 24.5 * UM and again.size == (1.2 * MM, 2.4 * MM)
    assert again.levels == (0.1 * MPA, 5.0 * MPA) and again.grid == (8, 10)
    assert again.shape is Shape.ROUND and again.part == Part("a", 0.5 * MM)
    assert again.spare is NO_PART and again.cap is None and again.scratch is None
    assert (again.note, again.depth) == ("n", 2.0 * MM)
    assert again.params() == TOY_PARAMS


def test_a_value_at_its_default_is_left_out_and_an_absent_key_reads_the_default():
    square = Toy.from_params({**TOY_PARAMS, "shape": "square", "cap_MPa": 100.0,
                              "name": "s", "width_mm": 1.0, "unknown": 1})
    assert square.cap == 100 * MPA and square.spare == Part("s", 1.0 * MM)
    assert square.errors == ()  # only with shape round, when read as when written
    written = square.params()
    assert "errors" not in written and written["cap_MPa"] == 100.0
    assert (written["name"], written["width_mm"]) == ("s", 1.0) and "unknown" not in written
    bare = {k: v for k, v in TOY_PARAMS.items() if k not in ("name", "width_mm", "errors")}
    with pytest.raises(KeyError, match="name"):  # a null record's first key is required
        Toy.from_params(bare)
    with pytest.raises(KeyError, match="sigma_um"):  # a key without a default is required
        Toy.from_params({k: v for k, v in TOY_PARAMS.items() if k != "sigma_um"})


def test_plain_fields_are_read_with_the_cast_of_their_annotation():
    settings = ContactSettings.from_section({"method": "cg", "tol": "1e-6", "precision": "double",
                                             "steps": 10.0, "pressure_levels": "8"})
    assert (settings.tol, settings.steps, settings.pressure_levels) == (1e-6, 10, 8)
    assert type(settings.steps) is int and settings.flow is NO_FLOW
    assert settings.params() == {"method": "cg", "tol": 1e-6, "precision": "double",
                                 "steps": 10, "pressure_levels": 8}  # no flow: no key
    build = BuildSettings.from_section({"solver": "auto", "max_memory_gb": 2})
    assert build.max_bytes == 2e9 and build.params() == {"solver": "auto",
                                                          "max_memory_gb": 2.0}


def test_a_geometry_reads_the_half_space_tolerance_of_operator_auto_only():
    section = {"nu": 0, "size_mm": 1.2, "thickness_mm": 2, "grid": 8, "base": "clamped",
               "mesh": "paper", "halfspace_tolerance": {"k_P": 0.02, "area": None}}
    dense = Geometry.from_params(section)
    assert dense.halfspace_tolerance == () and dense.nu == 0.0 and dense.grid == (8, 8)
    assert dense.params() == {"nu": 0.0, "size_mm": [1.2, 1.2], "thickness_mm": 2.0,
                              "grid": [8, 8], "base": "clamped", "mesh": "paper"}
    auto = Geometry.from_params({**section, "operator": "auto"})
    assert auto.operator is InfluenceModel.AUTO
    assert auto.halfspace_tolerance == (("area", None), ("k_P", 0.02))
    assert auto.params()["halfspace_tolerance"] == {"area": None, "k_P": 0.02}


def test_the_two_bodies_records_keep_the_params_and_keys_of_before_the_codec():
    """Written out from the hand-written params() the records had before."""
    plan = study_plan(load_study(REPO / "config" / "two_bodies.yaml"))
    cell = plan.cells["pad_on_disc"][0]
    params = cell.params()
    assert list(params) == ["surface", "geometry", "sigma_um", "E_MPa", "pressure_MPa",
                            "surface_key", "geometry_key", "accuracy", "counterface"]
    counter = params["counterface"]
    assert list(counter) == ["surface", "surface_key", "sigma_um", "geometry", "geometry_key",
                             "E_MPa", "rigid_share"]
    assert (counter["sigma_um"], counter["E_MPa"], counter["rigid_share"]) == (1.5, 110000.0,
                                                                                 0.001)
    assert counter["geometry"] == {"nu": 0.26, "size_mm": [9.0, 9.0], "thickness_mm": 10.0,
                                   "grid": [60, 60], "base": "clamped", "mesh": "paper",
                                   "operator": "halfspace"}
    assert counter["surface"]["stream"] == "counter"
    job = cell.job.params()
    assert list(job) == ["surface", "geometry", "surface_key", "geometry_key", "pressure_end",
                         "accuracy", "expected_error", "counter"]
    assert job["expected_error"] == {} and job["accuracy"] == "as configured"
    assert list(job["counter"]) == ["surface", "surface_key", "sigma_ratio", "geometry",
                                    "geometry_key", "modulus_ratio", "rigid_share"]
    assert cell.contact_key == ("sk0_ku3_b1x1mm_L9x9mm_g60x60_exp_per_filter_n20__nu0.25_L9x9mm"
                                "_t10mm_g60x60_clamped_refined__end8__cf5417aee425")
    flat = plan.cells["pad_on_disc"][1]
    assert "counterface" not in flat.params() and "counter" not in flat.job.params()
    (pair, _) = sorted(plan.pairs.values(), key=lambda p: p.key)
    assert list(pair.params()) == ["first", "second", "first_key", "second_key",
                                   "modulus_ratio", "rigid_share"]


def test_a_studys_settings_read_their_sections_as_the_configuration_writes_them():
    study = Study.from_config(validated({"study_seed": 0, "figures": {}, "reports": {
        "grid_convergence": {"grids": [64, 16, 32], "reduced_pressures": [0.1, 0.01]}}}))
    grid = study.reports.grid_convergence
    assert grid.grids == (16, 32, 64) and grid.reduced_pressures == (0.01, 0.1)
    assert all(type(g) is int for g in grid.grids)
