"""Every link of the README (and host/README.md) to a file of the repository must name a file that
exists: the README is read on GitHub, outside the documentation site's strict build. Anchors into
docs pages are checked against their headings as MkDocs spells them. Exit 1 naming each broken link."""
from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import List, Set

ROOT = Path(__file__).resolve().parents[2]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def anchors(md: Path) -> Set[str]:
    """Heading ids as MkDocs' toc extension makes them (lower case, words joined by '-')."""
    ids: Set[str] = set()
    fenced = False
    for line in md.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        m = None if fenced else re.match(r"#{1,6}\s+(.*?)\s*#*$", line)
        if m:
            text = re.sub(r"[^\w\s-]", "", m.group(1).replace("`", "")).strip().lower()
            ids.add(re.sub(r"[-\s]+", "-", text))
    return ids


def broken(readme: Path) -> List[str]:
    bad = []
    fenced = False
    for n, line in enumerate(readme.read_text(encoding="utf-8").splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        for target in ([] if fenced else LINK.findall(re.sub(r"`[^`]*`", "", line))):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                continue
            path, _, anchor = target.partition("#")
            file = (readme.parent / path).resolve()
            where = f"{os.path.relpath(readme, ROOT)}:{n}: {target}"
            if not file.exists():
                bad.append(f"{where}: no such file")
            elif anchor and file.suffix == ".md" and anchor not in anchors(file):
                bad.append(f"{where}: no heading #{anchor} in {path}")
    return bad


def main() -> int:
    bad = [b for f in ("README.md", "host/README.md") for b in broken(ROOT / f)]
    for b in bad:
        print(b, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
