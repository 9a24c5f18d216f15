"""Fig 11 on a resolving grid (config/fig11_resolved.yaml): on demand, planned as configured."""

from pathlib import Path

import pytest
import yaml

from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.settings import Study

REPO = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.workflow


def config(name: str) -> dict:
    return validated(yaml.safe_load((REPO / "config" / name).read_text()))


def test_the_config_asks_for_the_papers_fig11_cells_on_256_elements():
    """The cells as configured (the full plan calibrates the filter of each cell near
    the kurtosis bound, about a minute at 256 x 256: not run here)."""
    resolved = config("fig11_resolved.yaml")
    assert list(resolved["figures"]) == ["fig11_resolved"] and not resolved["sweeps"]
    cells = contact_cells(Study.from_config(resolved), "fig11_resolved")
    assert [cell.surface.corr_length for cell in cells] == [
        pytest.approx((b, b)) for b in (0.5e-3, 1e-3, 2e-3)]
    assert {(cell.surface.grid, cell.surface.count, cell.surface.skew, cell.surface.kurt)
            for cell in cells} == {((256, 256), 60, 0.0, 3.0)}
    for cell in cells:
        assert (cell.sigma, cell.E) == (pytest.approx(24.5e-6), pytest.approx(511e6))
        assert cell.pressure_range == pytest.approx((1e5, 5e6))
    assert {cell.geometry for cell in cells} == {Study.from_config(resolved).body.geometry}
    assert Study.from_config(resolved).body.geometry.grid == (256, 256)
    assert resolved["body"]["operator"] == "auto"  # the hybrid model above 64 x 64


@pytest.mark.parametrize("name", ["config.yaml", "quick.yaml"])
def test_the_study_is_not_among_the_default_targets(name):
    assert "fig11_resolved" not in study_plan(Study.from_config(config(name))).figures
