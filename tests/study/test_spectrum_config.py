"""``surfaces.spectrum`` (and a study's ``spectrum``): plan, cell keys, surface files."""

from __future__ import annotations

import hashlib
import json
import logging
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from roughcontact.errors import MeasurementError
from roughcontact.study.config import ConfigError, validated
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.settings import Study
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.surfaces import spectra

REPO = Path(__file__).resolve().parents[2]
MEASURED = REPO / "data" / "example_plateau_honed.xyz"
#: Cut-off of the tables: within the 16 x 16 grid over 4.8 mm (Nyquist 0.6 mm).
CUTOFF_MM = 0.8


@pytest.fixture(autouse=True)
def _quiet(caplog):
    caplog.set_level(logging.ERROR)


def write_table(path: Path, rolloff_mm: float = 1.2) -> Path:
    """A self-affine PSD (H 0.8, cut-off 0.8 mm) as a q_per_mm,C table."""
    q = np.geomspace(0.5, 2 * math.pi / CUTOFF_MM, 30)
    c = spectra.self_affine_psd(q / 1e-3, 0.8, rolloff_mm * 1e-3, CUTOFF_MM * 1e-3)
    rows = "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(q, c, strict=True))
    path.write_text("q_per_mm,C\n" + rows)
    return path


def config(surface_spectrum=None, **sweep):
    """A small config: the ``plain`` sweep, and an ``own`` one with ``sweep``'s keys."""
    surfaces = {"grid": [16, 16], "size_mm": [4.8, 4.8], "count": 2, "method": "paper"}
    if surface_spectrum is not None:
        surfaces["spectrum"] = surface_spectrum
    return validated({"study_seed": 1, "figures": {}, "surfaces": surfaces,
                      "body": {"mesh": "paper"},
                      "sweeps": {"plain": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1.0]},
                                 **({"own": sweep} if sweep else {})}})


def plan_keys(cfg) -> list[str]:
    return sorted(study_plan(Study.from_config(cfg)).surfaces)


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_cells_without_a_spectrum_keep_their_keys_and_parameters():
    cfg = config()
    assert cfg["surfaces"]["spectrum"] == {"kind": "acf"}  # the schema's default
    # the key and the parameters of a cell as they were before spectra existed
    (cell,) = study_plan(Study.from_config(cfg)).surfaces.values()
    assert cell.key == "sk0_ku3_b1x1mm_L4.8x4.8mm_g16x16_exp_per_paper_n2"
    assert sorted(cell.params()) == ["acf", "b_mm", "count", "grid", "kurt", "method",
                                     "periodic", "size_mm", "skew"]


def test_a_table_spectrum_puts_the_file_hash_in_the_key_and_a_new_file_a_new_key(tmp_path):
    path = write_table(tmp_path / "psd.csv")
    cfg = config({"kind": "table", "file": str(path)})
    (key,) = plan_keys(cfg)
    assert key == (f"sk0_ku3_b1x1mm_L4.8x4.8mm_g16x16_psd_per_paper_tab-{sha256(path)[:12]}"
                   "_n2")
    cell = study_plan(Study.from_config(cfg)).surfaces[key]
    assert cell.params()["spectrum"] == {"kind": "table", "file": str(path),
                                         "file_sha256": sha256(path)}
    assert cell.input_files == (str(path),)
    spec = cell.spec()
    assert spec.acf == "psd" and spec.psd[0] == pytest.approx((500.0, 1.0))
    write_table(path, rolloff_mm=1.0)  # the same file name, another spectrum
    (changed,) = plan_keys(cfg)
    assert changed != key and sha256(path)[:12] in changed


def test_a_study_can_set_its_own_spectrum(tmp_path):
    spectrum = {"kind": "self-affine", "hurst": 0.7, "rolloff_mm": 1.2, "cutoff_mm": 0.6}
    cfg = config(sigma_um=1.0, pressure_MPa=[0.1, 1.0], spectrum=spectrum)
    plain = {"plain": contact_cells(Study.from_config(
            cfg), "plain"), "own": contact_cells(Study.from_config(cfg), "own")}
    assert plain["plain"][0].surface.spectrum is None
    assert "spectrum" not in plain["plain"][0].surface.params()
    own = plain["own"][0].surface
    assert own.acf == "self-affine" and own.spectrum.hurst == 0.7
    assert own.params()["spectrum"]["rolloff_mm"] == 1.2
    assert "_sel_per_paper_sa-" in own.key
    spec = own.spec()
    assert (spec.hurst, spec.rolloff_wavelength, spec.cutoff_wavelength) == \
        pytest.approx((0.7, 1.2e-3, 0.6e-3))
    assert spec.corr_length == pytest.approx((1.2e-3, 1.2e-3))  # b_mm is not used
    assert len(plan_keys(cfg)) == 2


def test_a_spectrum_on_padded_surfaces_stops_the_plan_in_one_line(tmp_path):
    path = write_table(tmp_path / "psd.csv")
    cfg = config({"kind": "table", "file": str(path)})
    cfg["surfaces"]["periodic"] = False
    with pytest.raises(ConfigProblems) as err:
        study_plan(Study.from_config(cfg))
    assert err.value.problems == ["surfaces.spectrum: kind table generates periodic surfaces "
                                  "only; set surfaces.periodic: true or remove the spectrum"]


def test_missing_or_bad_spectrum_files_stop_the_plan(tmp_path):
    with pytest.raises(ConfigProblems, match=r"surfaces.spectrum: .*missing.csv: no such file"):
        study_plan(Study.from_config(
                config({"kind": "table", "file": str(tmp_path / "missing.csv")})))
    bad = tmp_path / "bad.csv"
    bad.write_text("q_per_mm,C\n1,1\n0.5,2\n")
    with pytest.raises(ConfigProblems, match="q must increase strictly"):
        study_plan(Study.from_config(config({"kind": "table", "file": str(bad)})))
    with pytest.raises(ConfigError, match=r"surfaces.spectrum: .file. is missing"):
        config({"kind": "table"})
    # the cut-off finer than the grid can carry: the plan names the cell
    with pytest.raises(ConfigProblems, match="cutoff_wavelength .* two grid spacings"):
        study_plan(Study.from_config(config({"kind": "self-affine", "hurst": 0.5, "rolloff_mm": 1.0,
                           "cutoff_mm": 0.1})))


def test_the_surfaces_job_writes_the_table_hash_and_refuses_a_changed_file(tmp_path):
    path = write_table(tmp_path / "psd.csv")
    (cell,) = study_plan(Study.from_config(
            config({"kind": "table", "file": str(path)}))).surfaces.values()
    out = tmp_path / "cell.h5"
    build_surface_cell(cell.params(), 1, out)
    with h5py.File(out, "r") as f:
        attrs = dict(f.attrs)
        heights = f["heights"][()]
    assert attrs["spectrum_file_sha256"] == sha256(path)
    assert attrs["spectrum_kind"] == "table"
    assert json.loads(attrs["spec_psd"])[0] == pytest.approx([500.0, 1.0])
    # the stored surfaces carry the table's spectrum: no power above its last q
    q_last = 2 * math.pi / (CUTOFF_MM * 1e-3)
    n, size = 16, 4.8e-3
    q = 2 * math.pi * np.fft.fftfreq(n, size / n)
    above = np.hypot(q[None, :], q[:, None]) > q_last * (1 + 1e-9)
    power = np.abs(np.fft.fft2(heights)) ** 2
    assert above.any() and power[:, above].sum() < 1e-24 * power.sum()
    write_table(path, rolloff_mm=1.0)
    with pytest.raises(MeasurementError, match="changed after the workflow was planned"):
        build_surface_cell(cell.params(), 1, tmp_path / "again.h5")


def test_a_measured_spectrum_is_keyed_by_the_file_and_its_options():
    entry = {"kind": "measured", "file": str(MEASURED), "format": "xyz", "height_unit": "um",
             "fill_holes": 0.01}
    cfg = config(entry)
    (key,) = plan_keys(cfg)
    digest = sha256(MEASURED)
    assert f"_psd_per_paper_mpsd-{digest[:12]}-" in key
    (other,) = plan_keys(config({**entry, "form_degree": 2}))
    assert other != key and digest[:12] in other
    cell = study_plan(Study.from_config(cfg)).surfaces[key]
    assert cell.spectrum.file == str(MEASURED) and cell.input_files == (str(MEASURED),)
    assert cell.spec().acf == "psd"


def test_the_speed_report_takes_a_spectrum_from_its_section():
    cfg = validated({"reports": {"speed_vs_error": {"spectrum": {
        "kind": "self-affine", "hurst": 0.8, "rolloff_mm": 3.0, "cutoff_mm": 0.6}}}})
    section = cfg["reports"]["speed_vs_error"]
    fields = spectrum_from_entry(section["spectrum"]).spec_fields()
    assert fields == pytest.approx({"acf": "self-affine", "hurst": 0.8,
                                    "rolloff_wavelength": 3e-3, "cutoff_wavelength": 0.6e-3})
    assert "spectrum" not in validated({})["reports"]["speed_vs_error"]


def test_a_measured_study_gives_its_spectrum_to_the_twin_only(tmp_path):
    path = write_table(tmp_path / "psd.csv")
    surface = {"file": str(MEASURED), "format": "xyz", "height_unit": "um", "fill_holes": 0.01}
    spectrum = {"kind": "table", "file": str(path)}
    cfg = config(surface=surface, compare_synthetic=True, count=2, spectrum=spectrum,
                 pressure_MPa=[1.0, 50.0])
    measured_cell, twin = (c.surface for c in contact_cells(Study.from_config(cfg), "own"))
    assert measured_cell.spectrum is None and "spectrum" not in measured_cell.params()
    assert twin.spectrum.file_sha256 == sha256(path) and twin.grid == (64, 64)
    lone = config(surface=surface, spectrum=spectrum, pressure_MPa=[1.0, 50.0])
    with pytest.raises(ConfigProblems, match="own: 'spectrum' applies to the generated twin"):
        study_plan(Study.from_config(lone))
