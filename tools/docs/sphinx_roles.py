"""MkDocs hook: the hub's docstrings use Sphinx roles (:class:`Device`) and ``::`` before a code
block, as they read in an editor; on the site the role becomes plain code and ``::`` one colon."""
from __future__ import annotations

import re
from typing import Any

_ROLE = re.compile(r":(?:class|func|meth|mod|attr|exc|data|obj|const):(<code>)~?")
_LITERAL = re.compile(r"::(</p>)")


def on_page_content(html: str, page: Any, config: Any, files: Any) -> str:
    return _LITERAL.sub(r":\1", _ROLE.sub(r"\1", html))
