"""The configuration reference, generated from ``config/schema.yaml`` (the one source).

``.. schema-reference:: ../config/schema.yaml`` (a path relative to the page) renders
every key of the schema, with its type, default, unit and description, one section per
top-level key and one for each shared definition that has properties of its own (a
study, a measured surface, a spectrum). Nothing is written by hand: a key added to the
schema appears here at the next build, and one without a description fails the docs
test (``tests/docs/test_site.py``).

Units follow the schema's convention: a number's unit is in its key name (``_mm``,
``_um``, ``_MPa``, ``_gb``); a number without such a suffix is dimensionless (a count,
a ratio, a tolerance, a seed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import yaml

#: Unit suffixes of key names (the schema's convention) and the unit each stands for.
UNIT_SUFFIXES = {"_mm": "mm", "_um": "µm", "_MPa": "MPa", "_gb": "GB"}

#: Shared definitions documented once, in a section of their own, as (definition name,
#: section title, where the definition is used). Every other definition is inlined.
SHARED = {
    "study": ("A study", "``figures.fig07`` ... ``figures.table_Eu``, ``figures.hardness``, "
              "``figures.measured``, ``figures.fig11_resolved`` and every ``sweeps.<name>``"),
    "measured_surface": ("A measured surface", "the ``surface`` of a study"),
    "spectrum": ("A spectrum", "``surfaces.spectrum``, the ``spectrum`` of a study and "
                 "``reports.speed_vs_error.spectrum``"),
}


@dataclass
class Row:
    """One key: its dotted path and the four columns of the reference."""

    path: str
    type: str
    default: str
    unit: str
    description: str
    case: str = ""


@dataclass
class Group:
    """One section of the reference: a top-level key or a shared definition."""

    title: str
    label: str
    intro: str
    rows: list[Row] = field(default_factory=list)


def load_schema(path: str | Path) -> dict:
    """The schema as a mapping (YAML, as Snakemake reads it)."""
    with open(path, encoding="utf-8") as f:
        return yaml.safe_load(f)


def resolve(schema: dict, node: dict) -> dict:
    """``node`` with its ``$ref`` followed (keys written beside the ``$ref`` win)."""
    seen = 0
    while isinstance(node, dict) and "$ref" in node and seen < 20:
        target = schema
        for part in node["$ref"].removeprefix("#/").split("/"):
            target = target[part]
        node = {**target, **{k: v for k, v in node.items() if k != "$ref"}}
        seen += 1
    return node


def shared_name(node: dict) -> str | None:
    """The shared definition ``node`` refers to, if any."""
    ref = node.get("$ref", "") if isinstance(node, dict) else ""
    name = ref.removeprefix("#/definitions/")
    return name if name in SHARED else None


def flow(value) -> str:
    """A default value as it is written in a YAML config (flow style)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(flow(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {flow(v)}" for k, v in value.items()) + "}"
    return str(value)


def _bounds(node: dict) -> str:
    """``in [a, b]``, ``> a``, ``<= b`` ... of a number's limits ('' without any)."""
    low = ("[", node["minimum"]) if "minimum" in node else (
        ("(", node["exclusiveMinimum"]) if "exclusiveMinimum" in node else None)
    high = ("]", node["maximum"]) if "maximum" in node else (
        (")", node["exclusiveMaximum"]) if "exclusiveMaximum" in node else None)
    if low and high:
        text = f"in {low[0]}{flow(low[1])}, {flow(high[1])}{high[0]}"
    elif low:
        text = f"{'>=' if low[0] == '[' else '>'} {flow(low[1])}"
    elif high:
        text = f"{'<=' if high[0] == ']' else '<'} {flow(high[1])}"
    else:
        text = ""
    if "multipleOf" in node:
        text += f"{', ' if text else ''}multiple of {flow(node['multipleOf'])}"
    return text


def type_text(schema: dict, node: dict) -> str:
    """What a key accepts, in words (``number > 0``, ``[nx, ny]``, one of ...)."""
    name = shared_name(node)
    if name:
        return f":ref:`{SHARED[name][0].lower()} <config-{name}>`"
    node = resolve(schema, node)
    if "enum" in node:
        return "one of " + ", ".join(f"``{flow(v)}``" for v in node["enum"])
    for key in ("oneOf", "anyOf"):
        if key in node and "type" not in node:
            return " or ".join(type_text(schema, option) for option in node[key])
    kind = node.get("type")
    if isinstance(kind, list):
        base = " or ".join(kind)
    elif kind == "array":
        items = node.get("prefixItems") or node.get("items", {})
        if isinstance(items, list):
            inner = ", ".join(type_text(schema, i) for i in items)
            base = f"list of [{inner}]"
        else:
            inner = type_text(schema, items) if items else "values"
            size = node.get("minItems"), node.get("maxItems")
            if size[0] == 2 and size[1] == 2:
                base = f"pair of ({inner})"
            elif size[0] is not None and size[0] == size[1]:
                base = f"list of {size[0]} ({inner})"
            else:
                base = f"list of ({inner})"
                if size[0] and size[0] > 1:
                    base += f", at least {size[0]}"
    elif kind == "object" or "properties" in node:
        base = "mapping"
    elif kind:
        base = kind
    else:
        base = "any"
    bounds = _bounds(node)
    return f"{base} {bounds}" if bounds else base


def unit_text(key: str, node: dict) -> str:
    """The unit of a key: its name's suffix; '-' for another number; '' otherwise."""
    for suffix, unit in UNIT_SUFFIXES.items():
        if key.endswith(suffix):
            return unit
    kinds = node.get("type")
    kinds = kinds if isinstance(kinds, list) else [kinds]
    options = [o.get("type") for o in node.get("oneOf", []) if isinstance(o, dict)]
    if {"number", "integer"} & set(kinds + options):
        return "-"
    return ""


def description_of(schema: dict, node: dict) -> str:
    """A key's own description, else that of the definition it refers to."""
    if isinstance(node, dict) and node.get("description"):
        return " ".join(str(node["description"]).split())
    resolved = resolve(schema, node) if isinstance(node, dict) else {}
    return " ".join(str(resolved.get("description", "")).split())


def _branch_defaults(node: dict) -> dict[str, str]:
    """Defaults that a definition sets only in some cases (``allOf`` ``if``/``then``/
    ``else`` branches), as ``{key: 'value (when)'}``."""
    out: dict[str, list[str]] = {}
    for branch in node.get("allOf", []):
        condition = branch.get("if", {})
        alternatives = condition.get("anyOf", [condition])
        required = [r for alt in alternatives for r in alt.get("required", [])]
        consts = [f"{k}: {flow(v['const'])}" for k, v in condition.get("properties", {}).items()
                  if isinstance(v, dict) and "const" in v]
        cases = ((("then", " or ".join(consts)), ("else", "not " + " or ".join(consts)))
                 if consts else (("then", "with " + " or ".join(required)),
                                 ("else", "without " + " or ".join(required))))
        for part, when in cases:
            for key, sub in branch.get(part, {}).get("properties", {}).items():
                if isinstance(sub, dict) and "default" in sub:
                    out.setdefault(key, []).append(f"``{flow(sub['default'])}`` ({when})")
    return {k: "; ".join(v) for k, v in out.items()}


def _properties(schema: dict, node: dict) -> list[tuple[str, dict, str]]:
    """The properties of an object as ``(key, node, case)``, with those that only an
    ``allOf`` branch declares (a spectrum's kinds) after them, ``case`` naming the
    branch (``kind: table``); a branch's placeholder ``{}`` is left out."""
    node = resolve(schema, node)
    out = [(key, sub, "") for key, sub in node.get("properties", {}).items()]
    for branch in node.get("allOf", []):
        consts = {k: v["const"] for k, v in branch.get("if", {}).get("properties", {}).items()
                  if isinstance(v, dict) and "const" in v}
        case = ", ".join(f"{k}: {flow(v)}" for k, v in consts.items())
        for key, sub in branch.get("then", {}).get("properties", {}).items():
            if sub and case:
                out.append((key, sub, case))
    return out


def rows_of(schema: dict, node: dict, prefix: str) -> list[Row]:
    """Rows for every key under ``node``, nested objects expanded, shared definitions
    linked to their own section."""
    node = resolve(schema, node)
    required = set(node.get("required", [])).union(
        *(branch.get("then", {}).get("required", []) for branch in node.get("allOf", [])))
    branch_defaults = _branch_defaults(node)
    rows = []
    for key, sub, case in _properties(schema, node):
        path = f"{prefix}{key}"
        full = resolve(schema, sub)
        if "default" in sub or "default" in full:
            default = f"``{flow(sub.get('default', full.get('default')))}``"
        elif key in required:
            default = "required"
        else:
            default = branch_defaults.get(key, "")
        rows.append(Row(path, type_text(schema, sub), default, unit_text(key, full),
                        description_of(schema, sub), case))
        if not shared_name(sub) and "properties" in full:
            rows += rows_of(schema, full, f"{path}.")
    if isinstance(node.get("additionalProperties"), dict):
        sub = node["additionalProperties"]
        rows.append(Row(f"{prefix}<name>", type_text(schema, sub), "", "",
                        description_of(schema, sub)))
    return rows


def groups(schema: dict) -> list[Group]:
    """The sections of the reference, in the schema's order, shared definitions last."""
    out = [Group("Top-level keys", "config-top", "Keys of the configuration file itself.")]
    for key, sub in schema["properties"].items():
        full = resolve(schema, sub)
        if "properties" in full or isinstance(full.get("additionalProperties"), dict):
            group = Group(f"``{key}``", f"config-{key}", description_of(schema, sub))
            group.rows = rows_of(schema, full, f"{key}.")
            out.append(group)
        else:
            out[0].rows += rows_of(schema, {"properties": {key: sub}}, "")
    for name, (title, where) in SHARED.items():
        node = schema["definitions"][name]
        group = Group(title, f"config-{name}",
                      f"{description_of(schema, node)} Used as {where}.")
        group.rows = rows_of(schema, node, f"<{name}>.")
        out.append(group)
    return out


_CODE = re.compile(r"`([^`]+)`")
_SPECIAL = re.compile(r"([^\w\s])")


def rst_text(text: str) -> str:
    """Plain text for reStructuredText: `code` spans as literals, every other
    punctuation character escaped, so a description reads exactly as written."""
    parts = _CODE.split(text)
    out = []
    for i, part in enumerate(parts):
        out.append(f"``{part}``" if i % 2 else _SPECIAL.sub(r"\\\1", part))
    return "".join(out)


def render(schema: dict) -> list[str]:
    """The reference as reStructuredText lines."""
    lines = []
    for group in groups(schema):
        title = group.title
        lines += [f".. _{group.label}:", "", title, "-" * max(len(title), 8), ""]
        if group.intro:
            lines += [rst_text(group.intro), ""]
        lines += [".. list-table::", "   :header-rows: 1", "   :widths: 22 18 12 6 42",
                  "   :class: config-reference", ""]
        lines += ["   * - key", "     - type", "     - default", "     - unit",
                  "     - description"]
        for row in group.rows:
            key = f"``{row.path}``" + (f" (``{row.case}``)" if row.case else "")
            cells = [key, row.type, row.default, rst_text(row.unit),
                     rst_text(row.description)]
            lines.append(f"   * - {cells[0]}")
            lines += [f"     - {cell}" if cell else "     -" for cell in cells[1:]]
        lines.append("")
    return lines


def setup(app):
    """Register ``.. schema-reference::`` (Sphinx is imported only here, so the rendering
    above runs without it, in the tests)."""
    from docutils import nodes
    from docutils.statemachine import StringList
    from sphinx.util.docutils import SphinxDirective
    from sphinx.util.nodes import nested_parse_with_titles

    class SchemaReference(SphinxDirective):
        """``.. schema-reference:: <path of schema.yaml relative to this page>``"""

        required_arguments = 1

        def run(self):
            rel, path = self.env.relfn2path(self.arguments[0])
            self.env.note_dependency(rel)
            container = nodes.section()
            content = StringList(render(load_schema(path)), source=str(path))
            nested_parse_with_titles(self.state, content, container)
            return container.children

    app.add_directive("schema-reference", SchemaReference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
