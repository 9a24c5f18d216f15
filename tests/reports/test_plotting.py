"""Figure helpers of the notebooks: tables as CSV and as figures, 3-D surface panels."""

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.reports.plotting import draw_surfaces, draw_table, save_table  # noqa: E402
from roughcontact.study import storage  # noqa: E402


def test_save_table_writes_the_csv_and_clears_stale_temporaries(tmp_path):
    frame = pd.DataFrame({"nu": [0.0, 0.3], "E_u_mean_MPa": [511.0, 523.2095484676289]})
    stale = tmp_path / ".table_Eu.tmp999999999.csv"  # no such process
    stale.write_text("half")
    save_table(frame, tmp_path / "table_Eu.csv")
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "table_Eu.csv"), frame)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table_Eu.csv"]


def test_draw_table_holds_every_cell_under_its_header():
    frame = pd.DataFrame({r"$\nu$": ["0", "0.3"], "$E_u$ [MPa]": ["511.00 ± 0.00",
                                                                  "523.21 ± 0.01"]})
    fig = draw_table(frame, title="$E_u$")
    (table,) = fig.axes[0].tables
    cells = table.get_celld()
    assert [cells[0, j].get_text().get_text() for j in range(2)] == list(frame.columns)
    assert cells[2, 1].get_text().get_text() == "523.21 ± 0.01"
    fig.canvas.draw()  # the mathtext headers render
    renderer = fig.canvas.get_renderer()
    for j in range(2):  # each column as wide as its widest entry
        width = cells[0, j].get_window_extent(renderer).width
        assert all(cells[i, j].get_text().get_window_extent(renderer).width < width
                   for i in range(3))
    plt.close(fig)


@pytest.mark.parametrize("panels", [2, 5])
def test_surface_panel_titles_are_legible(monkeypatch, panels):
    """Fig 3 and 4: two-line titles neither overlap each other or another panel nor
    leave the figure, and stay legible (5 pt or more) on a page 7 in wide, whatever
    the number of panels (a row of five panels shrank them to 3 pt)."""
    rng = np.random.default_rng(0)

    def fake_read(path, count=None):
        return {"spec": {"size": [4.8e-3, 4.8e-3]}, "heights": rng.standard_normal((1, 16, 16))}

    monkeypatch.setattr(storage, "read_surfaces", fake_read)
    titles = [f"target Sk = -0.8, Ku = {k}\nrealised Sk = -0.75, Ku = 3.53" for k in range(panels)]
    fig = draw_surfaces([f"s{k}.h5" for k in range(panels)], 40.0, titles)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    boxes = [ax.title.get_window_extent(renderer) for ax in fig.axes]
    assert [ax.get_title() for ax in fig.axes] == titles
    shrink = min(1.0, 7.0 / fig.get_figwidth())
    assert all(ax.title.get_fontsize() * shrink >= 5.0 for ax in fig.axes)
    for k, box in enumerate(boxes):
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
        for j, other in enumerate(boxes):
            assert j == k or not box.overlaps(other), (k, j)
        for j, ax in enumerate(fig.axes):  # nor the panel above (its axis labels)
            below = ax.get_tightbbox(renderer)
            assert j == k or not box.overlaps(below), (k, j)
    plt.close(fig)
