"""The seal's answers on the leakage figure: the sealing pressures (from the sidecar) with
their bands, the levels at which the faces would open, legends that tell every study and
cell apart, and every mark explained."""

import json
import re

import matplotlib
import numpy as np
import pandas as pd

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.hashes import file_sha256  # noqa: E402
from roughcontact.reports.study_figures import (  # noqa: E402
    cell_labels,
    leakage_answers,
    load_percolation,
    load_pressure_drops,
    open_levels_sentence,
    plot_leakage,
    sealing_sentence,
)

LEVELS_PA = (1e5, 3e5, 1e6, 3e6, 1e7)


def seal_table(moments=((0.0, 3.0), (-0.8, 4.0)), **columns) -> pd.DataFrame:
    """A leakage study's table along x: one cell per (Sk, Ku) of ``moments``, five levels,
    every level on 4 surfaces but the first (on 3: a hollow marker); ``columns``: a
    column per name, one value per cell. The faces open below a 0.5 MPa drop."""
    rows = []
    for cell, (skew, kurt) in enumerate(moments):
        for level, P in enumerate(LEVELS_PA):
            leak = 1e-6 / 10 ** (2 * level) if level < 4 else 0.0
            count = 3 if level == 0 else 4
            rows.append({"cell": cell, "skew": skew, "kurt": kurt, "nominal_pressure": P,
                         "nominal_pressure_MPa": P / 1e6, "surfaces": 4, "sigma_um": 5.0,
                         "b_mm": 0.5, "E_MPa": 511.0, "coverage": "all surfaces",
                         "label": f"Sk {skew:g}, Ku {kurt:g}",
                         "real_area_fraction_mean": 0.1 * (level + 1),
                         "real_area_fraction_half_width": 0.01,
                         "real_area_fraction_count": count,
                         "leak_rate_x_mean": leak, "leak_rate_x_half_width": 0.1 * leak,
                         "leak_rate_x_count": count, "flow_factor_x_mean": leak * 1e5,
                         "flow_factor_x_half_width": leak * 1e4, "flow_factor_x_count": count,
                         "flow_connected_x_mean": float(leak > 0),
                         "flow_connected_x_half_width": 0.0, "flow_connected_x_count": count,
                         "faces_open": 0.5e6 > P,
                         **{name: values[cell] for name, values in columns.items()}})
    return pd.DataFrame(rows)


#: Two cells' percolation thresholds as a sidecar holds them: the first sealed inside the
#: range with a band, the second's band open above (null).
PERCOLATION = [
    {"cell": 0, "label": "a", "contact_key": "k0", "direction": "x", "area": 0.41,
     "area_low": 0.39, "area_high": 0.43, "pressure_MPa": 4.5712, "pressure_low_MPa": 3.8815,
     "pressure_high_MPa": 4.7234},
    {"cell": 1, "label": "b", "contact_key": "k1", "direction": "x", "area": 0.43,
     "area_low": 0.40, "area_high": None, "pressure_MPa": 6.6502, "pressure_low_MPa": 5.5,
     "pressure_high_MPa": None},
]


def write_study(tmp_path, name: str, table: pd.DataFrame, drop_Pa: float = 0.5e6) -> list:
    """The four aggregate files of a study (table, moduli, sidecar, validity) with the
    sidecar's flow entry: the pressure drop and :data:`PERCOLATION`."""
    path, moduli = tmp_path / f"{name}.csv", tmp_path / f"{name}.moduli.csv"
    table.to_csv(path, index=False)
    moduli.write_text("cell\n0\n")
    meta = {"table_sha256": file_sha256(path), "moduli_sha256": file_sha256(moduli),
            "flow": {"pressure_drop_Pa": drop_Pa, "percolation": PERCOLATION}}
    sidecar = tmp_path / f"{name}.json"
    sidecar.write_text(json.dumps(meta))
    return [path, moduli, sidecar, tmp_path / f"{name}.validity.csv"]


def test_two_studies_of_equal_moments_get_distinct_labels():
    """The legend labels a cell by its study and (Sk, Ku), and by what tells a study's
    cells of equal moments apart (a counter body; a measured map and its twin)."""
    table = seal_table(((0.0, 3.0),))
    first, second = cell_labels(table, "seal"), cell_labels(table, "seal_cap")
    assert first[0] != second[0]
    assert first[0].startswith("seal: ") and "Sk = 0, Ku = 3" in first[0]
    countered = seal_table(((0.0, 3.0), (0.0, 3.0)),
                           counter=["rigid smooth flat", "steel block"])
    labels = cell_labels(countered, "pair")
    assert len(set(labels.values())) == 2
    assert "steel block" in labels[1] and "rigid smooth flat" in labels[0]
    measured = seal_table(((0.5, 3.5), (0.5, 3.5)),
                          label=["measured scan.csv: Sk 0.5, Ku 3.5", "Sk 0.5, Ku 3.5"])
    labels = cell_labels(measured, "scan")
    assert labels[0].startswith("scan: measured scan.csv") and len(set(labels.values())) == 2
    # cells nothing tells apart keep apart by their index
    twins = cell_labels(seal_table(((0.0, 3.0), (0.0, 3.0))), "same")
    assert len(set(twins.values())) == 2


def test_the_caption_gives_each_sealing_pressure_of_the_sidecar(tmp_path):
    """The sentence the caption gives (``sealing_sentence``) holds each cell's sealing
    pressure and band as the sidecar has them (read here with json), in MPa, to 3
    significant digits; a band open above says so."""
    paths = write_study(tmp_path, "seal", seal_table())
    tables = {"seal": pd.read_csv(paths[0])}
    sentence = sealing_sentence(tables, load_percolation(paths, ["seal"]))
    stored = json.loads(paths[2].read_text())["flow"]["percolation"]
    for row, part in zip(stored, sentence.split(": ", 1)[1].split("; "), strict=True):
        found = re.search(r"([\d.]+) MPa \(95 %: (?:([\d.]+)-([\d.]+)|above ([\d.]+))\) "
                          r"along x", part)
        assert found, part
        value, low, high, low_only = found.groups()
        assert abs(float(value) - row["pressure_MPa"]) <= 5e-3 * row["pressure_MPa"]
        if row["pressure_high_MPa"] is None:  # open above
            assert high is None
            assert abs(float(low_only) - row["pressure_low_MPa"]) <= 5e-3 * row["pressure_low_MPa"]
        else:
            assert abs(float(low) - row["pressure_low_MPa"]) <= 5e-3 * row["pressure_low_MPa"]
            assert abs(float(high) - row["pressure_high_MPa"]) <= 5e-3 * row["pressure_high_MPa"]
    assert "seal: Sk = 0, Ku = 3: 4.57 MPa (95 %: 3.88-4.72) along x" in sentence
    assert load_pressure_drops(paths, ["seal"]) == {"seal": 0.5}


def test_the_figure_marks_the_open_faces_and_the_sealing_pressures(tmp_path):
    """Against P: the levels below the drop shaded and hatched from the first level to the
    drop; each cell's sealing pressure a dash-dot line in its colour on the leak rate and
    the share still leaking, its band shaded on the latter, its numbers in that panel's
    legend; the legend of the flow factor explains the hollow markers, the shading and the
    sealing lines."""
    paths = write_study(tmp_path, "seal", seal_table())
    fig = plot_leakage({"seal": pd.read_csv(paths[0])}, load_percolation(paths, ["seal"]),
                       load_pressure_drops(paths, ["seal"]))
    leak, factor, _, connected = fig.axes
    for ax in (leak, factor, connected):
        (shade,) = [p for p in ax.patches if p.get_hatch() == "//"]
        corners = shade.get_xy() if hasattr(shade, "get_xy") else None
        xs = np.asarray(corners)[:, 0] if corners is not None and np.ndim(corners) == 2 \
            else [shade.get_x(), shade.get_x() + shade.get_width()]
        np.testing.assert_allclose([min(xs), max(xs)], [0.1, 0.5])
    for ax in (leak, connected):
        sealing = [line for line in ax.lines if line.get_linestyle() == "-."]
        np.testing.assert_allclose([line.get_xdata()[0] for line in sealing], [4.5712, 6.6502])
    band = [p for p in connected.patches if p.get_hatch() != "//"]
    assert len(band) == 1  # the first cell's band; the second's is open above
    legend = [t.get_text() for t in connected.get_legend().get_texts()]
    assert legend == ["seal: Sk = 0, Ku = 3: 4.57 MPa (95 %: 3.88-4.72)",
                      "seal: Sk = -0.8, Ku = 4: 6.65 MPa (95 %: above 5.5)"]
    marks = " ".join(t.get_text() for t in factor.get_legend().get_texts())
    assert "hollow" in marks and "faces would open: pressure drop 0.5 MPa > P" in marks
    assert "sealing pressure (x)" in marks
    hollow = [line for line in leak.lines if line.get_marker() == "o"]
    assert hollow and all(line.get_markerfacecolor() == "none" for line in hollow)
    plt.close(fig)


def test_the_open_levels_sentence_lists_the_levels_below_the_drop(tmp_path):
    """``open_levels_sentence``: the levels whose nominal pressure lies below the drop, in
    MPa (computed here from the pressures, not from the table's ``faces_open``)."""
    table = seal_table()
    pressures = sorted(set(table["nominal_pressure_MPa"]))
    drop = pressures[1] * 1.01  # the two lowest levels lie below it
    table["faces_open"] = table["nominal_pressure_MPa"] < drop
    sentence = open_levels_sentence({"seal": table}, {"seal": drop})
    listed = [float(x) for x in re.findall(r"([\d.e+-]+)(?:,| MPa \(faces open\))",
                                            sentence.split(" at ", 1)[1])]
    np.testing.assert_allclose(listed, pressures[:2], rtol=5e-3)
    closed = open_levels_sentence({"seal": table.assign(faces_open=False)}, {"seal": 0.1})
    assert closed == "seal: pressure drop 0.1 MPa above P at no level."
    # the caption's answers hold only what the plan cannot know (the open levels it gives
    # itself): no thresholds, no sentence
    assert leakage_answers({"seal": table}, {}) == "\n"
