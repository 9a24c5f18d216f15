"""The half-space criterion (roughcontact.contact.halfspace_criterion), measured by solving."""

from __future__ import annotations

import pytest

from roughcontact.contact.halfspace_criterion import halfspace_errors, halfspace_meets
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence


def test_halfspace_errors_depend_on_the_quantity_and_the_bulk():
    """The half-space lacks the block's bulk compliance L/E: on the paper's block
    (L = 10 mm under 9 mm) k_P is off by about 20 %, while real area is within a
    few percent; a block whose bulk compliance happens to match the half-space's
    mean (L = 8 mm under 9 mm) gives a small k_P error too."""
    errors = {}
    for thickness in (10e-3, 8e-3):
        geom = BlockGeometry(grid=(30, 30), thickness=thickness, mesh="refined")
        fe = unit_modulus_influence(geom)
        errors[thickness] = halfspace_errors(
            fe, geom.grid, geom.size, geom.nu, geom.thickness)
    paper = errors[10e-3]
    assert paper["k_P"] > 0.1
    assert paper["real_area"] < 0.1
    assert errors[8e-3]["k_P"] < 0.05
    assert not halfspace_meets(paper, {"k_P": 0.02, "real_area": 0.05})
    assert halfspace_meets(paper, {"k_P": None, "real_area": 0.1,
                                             "max_pressure": None})
    with pytest.raises(ValueError, match="unknown quantities"):
        halfspace_meets(paper, {"area": 0.1})
