"""Where the tests find real instrument files (SurfaceTopography's test collection).

They are read in place: the folder ``ROUGHCONTACT_TOPOGRAPHIES`` names, else
``shared/data/topographies`` beside the checkout (see its README.md).
"""

import os
from pathlib import Path

import pytest

DATA = Path(os.environ.get("ROUGHCONTACT_TOPOGRAPHIES")  # unset or empty: beside the checkout
            or Path(__file__).resolve().parents[3] / "shared" / "data" / "topographies")
needs_data = pytest.mark.skipif(
    not DATA.is_dir(), reason=f"shared instrument files not found at {DATA}"
)
