"""Sphinx configuration of the roughcontact documentation (``make docs``).

The pages are Markdown (MyST); the configuration reference is generated from
``config/schema.yaml`` by the local extension ``_ext/schema_reference.py``, the
API reference from the docstrings (autodoc, autosummary, napoleon for the
NumPy-style sections).
"""

import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))

project = "roughcontact"
author = "roughcontact contributors"
copyright = "2026, roughcontact contributors"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "schema_reference",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_templates", "README.md"]
templates_path = ["_templates"]
# Keep quotes, dashes and `--options` as typed: code and key names are quoted verbatim.
smartquotes = False

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

autosummary_generate = True
autosummary_ignore_module_all = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

html_theme = "furo"
html_title = "roughcontact"
html_static_path = []
html_show_sourcelink = False

# Ambiguous cross-references guessed from the words of a type ("shape" in
# "ndarray, shape (n,)") are not links anyone wrote: keep them out of the warnings.
suppress_warnings = ["ref.python"]

# Docstrings write |x| for an absolute value, never a reStructuredText substitution:
# escape the bars outside literals and roles (a literal may span lines).
_LITERAL = re.compile(r"(``.+?``|:[\w:]+:`[^`]*`)", re.DOTALL)


def _plain_bars(app, what, name, obj, options, lines):
    parts = _LITERAL.split("\n".join(lines))
    text = "".join(p if i % 2 else p.replace("|", "\\|") for i, p in enumerate(parts))
    lines[:] = text.split("\n")


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars)
