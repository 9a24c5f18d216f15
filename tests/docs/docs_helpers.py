"""Shared by the docs tests: the repository's folders, the docs' own modules, and a walk
over config/schema.yaml written independently of the reference's generator."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
SCHEMA = ROOT / "config" / "schema.yaml"


def docs_module(relative: str):
    """A module of docs/ (not a package) imported by its path."""
    path = DOCS / relative
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


#: Parts of a schema that state conditions on keys declared elsewhere, not keys.
CONDITIONS = {"if", "not"}


def schema_properties(node, where=""):
    """(where, name, node) of every entry of every ``properties`` mapping, conditions left
    out: walked here independently of the reference's generator."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key in CONDITIONS:
                continue
            if key == "properties" and isinstance(value, dict):
                for name, sub in value.items():
                    yield where, name, sub
                    yield from schema_properties(sub, f"{where}.{name}")
            else:
                yield from schema_properties(value, f"{where}/{key}")
    elif isinstance(node, list):
        for item in node:
            yield from schema_properties(item, where)


def target(schema, ref):
    node = schema
    for part in ref.removeprefix("#/").split("/"):
        node = node[part]
    return node


def description(schema, node):
    """A property's description: its own, or that of the definition it refers to."""
    if node.get("description"):
        return node["description"]
    return target(schema, node["$ref"]).get("description") if "$ref" in node else None


def is_overlay(node):
    """``{}`` or ``{default: ...}`` in a branch: a key declared (and described) elsewhere."""
    return set(node) <= {"default"}
