"""Sphinx configuration: the API reference from the docstrings, with the ``docs/*.md`` pages.

Build (CI runs it, warnings as errors, so a broken reference or markup fails):

    python -m sphinx -W --keep-going -q -b html docs build/docs

``docs/api/`` holds the API pages (``docs/api/index.rst`` states what is public); the two local
extensions in ``docs/_ext/`` document each public object once (``public_api``), link or refuse
the docstrings' Python references (``references``) and show the pages' links to repository files
outside ``docs/`` as those files' paths (``repo_links``). No warning class is suppressed.
"""

from __future__ import annotations

import sys
from pathlib import Path

from pygments.lexers.special import TextLexer

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # the packages from this checkout, installed or not
sys.path.insert(0, str(DOCS / "_ext"))

project = "tumbling-testbed"
author = "tumbling-testbed contributors"
copyright = "the tumbling-testbed contributors, MIT licence"

extensions = [
    "myst_parser",  # the pages are GitHub Markdown (docs/*.md)
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # the docstrings' Google sections (Args:, Returns:, Attributes:)
    "public_api",
    "references",
    "repo_links",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "demo.ipynb",  # the notebook runs under the [notebook] extra (nbclient); not a page here
    "images",  # docs/images/make_images.py is a script, not a page; its pictures are linked
]

# The Markdown pages link each other as files (`[cli](cli.md#batched-runs)`), as GitHub renders
# them: headings get GitHub's anchors (slugs) up to level 4, the deepest any page links.
myst_heading_anchors = 4

autodoc_member_order = "bysource"
autodoc_typehints = "signature"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
# the plant contract's own section (analytic.plant.Plant), laid out as Args: are
napoleon_custom_sections = [("Class attributes a subclass sets", "params_style")]

html_theme = "alabaster"
html_title = "tumbling-testbed"
html_static_path = ["_static"]
html_css_files = ["site.css"]


def setup(app):
    # ```csv blocks (docs/trajectory-format.md) are shown as they are: Pygments has no CSV lexer
    app.add_lexer("csv", TextLexer)
