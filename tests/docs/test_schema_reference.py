"""Every key of config/schema.yaml has a description, and the generated configuration
reference shows it (the schema is the one place where keys are described)."""

import re

import pytest
import yaml
from docs_helpers import SCHEMA, description, docs_module, is_overlay, schema_properties


@pytest.fixture(scope="module")
def schema():
    return yaml.safe_load(SCHEMA.read_text())


def test_every_property_has_a_description(schema):
    declared = [(w, n, s) for w, n, s in schema_properties(schema) if not is_overlay(s)]
    assert len({n for _, n, _ in declared}) > 90  # the walk sees the whole schema
    missing = [f"{where.lstrip('.') or '(top level)'}: {name}" for where, name, sub in declared
               if not description(schema, sub)]
    assert not missing, ("keys of config/schema.yaml without a description (add a "
                         "`description:` with the unit to each):\n" + "\n".join(missing))


def test_overlays_name_declared_keys(schema):
    """A branch's ``{}`` or ``{default: ...}`` must stand for a key that the same
    definition declares with a description (else it would be a key without one)."""
    declared = {(w.split(".")[0].split("/allOf")[0], n) for w, n, s in schema_properties(schema)
                if not is_overlay(s) and description(schema, s)}
    loose = [(w, n) for w, n, s in schema_properties(schema) if is_overlay(s)
             and (w.split(".")[0].split("/allOf")[0], n) not in declared]
    assert not loose


def _plain(rst: str) -> str:
    """Rendered reStructuredText as a reader sees it: literals and escapes removed."""
    text = rst.replace("``", "")
    text = re.sub(r"\\(.)", r"\1", text)
    return " ".join(text.split())


def test_reference_shows_every_key_with_its_description(schema):
    reference = docs_module("_ext/schema_reference.py")
    text = _plain("\n".join(reference.render(schema)))
    missing = []
    for _, name, sub in schema_properties(schema):
        if is_overlay(sub):
            continue
        if not re.search(rf"(^|[.\s]){re.escape(name)}(\s|\()", text):
            missing.append(f"key {name}")
        wanted = " ".join((description(schema, sub) or "").replace("`", "").split())
        if wanted and wanted not in text:
            missing.append(f"description of {name}: {wanted[:60]}")
    assert not missing, "\n".join(missing)


def test_reference_columns_of_known_keys(schema):
    """Type, default and unit of a few keys, as the schema states them."""
    reference = docs_module("_ext/schema_reference.py")
    rows = {(row.path, row.case): row for group in reference.groups(schema)
            for row in group.rows}
    grid = rows[("surfaces.grid", "")]
    assert (grid.default, grid.unit) == ("``[60, 60]``", "-")
    assert "4, 4096" in grid.type
    size = rows[("surfaces.size_mm", "")]
    assert (size.default, size.unit) == ("``[9.0, 9.0]``", "mm")
    assert rows[("body.max_memory_gb", "")].unit == "GB"
    assert rows[("<study>.sigma_um", "")].unit == "µm"
    assert rows[("<study>.pressure_MPa", "")].unit == "MPa"
    assert rows[("<measured_surface>.file", "")].default == "required"
    assert rows[("<study>.b_mm", "")].default == "``1.0`` (without from or surface)"
    assert rows[("<spectrum>.hurst", "kind: self-affine")].default == "required"
    assert rows[("<spectrum>.hurst", "kind: self-affine")].unit == "-"
    assert rows[("contact.method", "")].type.startswith("one of ``auto``")
    assert "a study" in rows[("figures.fig07", "")].type
