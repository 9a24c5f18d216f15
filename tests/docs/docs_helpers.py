"""Shared by the docs tests: the repository's folders and the docs' own modules."""

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
