"""MkDocs hooks of the user guide (mkdocs.yml, ``hooks:``).

The docstrings cross-reference in Sphinx's style (``:func:`name```); mkdocstrings renders the
name as code but leaves the role in front of it. ``on_page_content`` drops the role, so the
reference pages read ``name`` instead of ``:func:name``.
"""
from __future__ import annotations

import re

_ROLE = re.compile(r":(?:py:)?(?:class|func|mod|data|meth|attr|exc|obj|const):(?=<code)")


def on_page_content(html: str, **kwargs) -> str:
    """The page's HTML with Sphinx roles before code spans removed."""
    return _ROLE.sub("", html)
