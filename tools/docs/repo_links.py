"""MkDocs hook: a docs page may link to any file of the repository (``../bench/RESULTS.md``,
``../examples/Rover/Rover.ino``), as it reads on GitHub. Such a link leaves the site, so it becomes
the file's address in the repository; a link to a file that does not exist is a warning, which
``strict: true`` turns into a failed build. Links inside docs/ are left to MkDocs, which checks them.
"""
from __future__ import annotations

import logging
import posixpath
import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
log = logging.getLogger("mkdocs.hooks.repo_links")
_LINK = re.compile(r"(\]\()([^)\s#]+)(#[^)\s]*)?(\))")
_FENCE = re.compile(r"^\s*(```|~~~)")


def _rewrite(line: str, page_dir: str, docs: Path, repo_url: str, where: str) -> str:
    def one(m: "re.Match[str]") -> str:
        target = m.group(2)
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("/"):
            return m.group(0)
        path = (ROOT / docs.relative_to(ROOT) / page_dir / target).resolve()
        if path == docs or docs in path.parents:
            return m.group(0)                    # inside the site: MkDocs checks it
        if ROOT not in path.parents:
            log.warning("%s: link %s leaves the repository", where, target)
            return m.group(0)
        if not path.exists():
            log.warning("%s: link %s names a file the repository does not have", where, target)
            return m.group(0)
        kind = "tree" if path.is_dir() else "blob"
        rel = posixpath.join(*path.relative_to(ROOT).parts)
        return f"{m.group(1)}{repo_url}/{kind}/main/{rel}{m.group(3) or ''}{m.group(4)}"
    return _LINK.sub(one, line)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    docs = Path(config["docs_dir"]).resolve()
    repo_url = str(config.get("repo_url") or "").rstrip("/")
    page_dir = posixpath.dirname(page.file.src_uri)
    out, fenced = [], False
    for line in markdown.split("\n"):
        if _FENCE.match(line):
            fenced = not fenced
        out.append(line if fenced else _rewrite(line, page_dir, docs, repo_url, page.file.src_uri))
    return "\n".join(out)
