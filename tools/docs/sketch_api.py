"""The sketch reference: every ``///`` comment of the library's public headers with the declaration
that follows it, and the compile-time settings of config.h, as one Markdown page.

Run by MkDocs as a hook (mkdocs.yml ``hooks:``): the page is generated into the build, never
committed. ``python tools/docs/sketch_api.py`` prints it. A ``///`` block with no declaration after
it, or a header list that finds nothing, stops the build: the page must not silently lose entries.
"""
from __future__ import annotations

import logging
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional, Tuple

ROOT = Path(__file__).resolve().parents[2]
PAGE = "reference/sketch.md"
REPO_URL = "https://github.com/hubwire/hubwire"
log = logging.getLogger("mkdocs.hooks.sketch_api")

# The headers a sketch uses, in reading order: the Arduino face, the declarations, the session
# (hub.update(), emit(), request() ... are Session's), the feature constants.
FIRST = ["src/Hubwire.h", "src/hubwire/channels/declare.h", "src/hubwire/channels/dsl.h",
         "src/hubwire/channels/decl.h", "src/hubwire/channels/list_dsl.h", "src/hubwire/channels/list.h",
         "src/hubwire/channels/remote.h", "src/hubwire/channels/mission.h"]
LAST = ["src/hubwire/session/session.h", "src/hubwire/features.h"]
_SCOPE = re.compile(r"^(?:template\s*<.*>\s*)?(?:class|struct)\s+(\w+)[^;]*\{")


@dataclass
class Entry:
    scope: Optional[str]
    text: List[str] = field(default_factory=list)
    example: List[str] = field(default_factory=list)
    declaration: str = ""
    line: int = 0

    @property
    def name(self) -> str:
        d = self.declaration
        if d.startswith("#define"):
            return d.split()[1].split("(")[0]
        m = re.match(r"(?:template\s*<.*?>\s*)?(?:class|struct)\s+(\w+)", d)
        if m:
            return m.group(1)
        word = _callee(re.sub(r"^template\s*<.*?>\s+(?=\S+\s)", "", d, count=1)) or d
        return f"{self.scope}::{word}" if self.scope and not word.startswith(self.scope) else word


def _callee(decl: str) -> str:
    """The name before the parameter list: the first '(' outside template arguments."""
    depth = 0
    for k, ch in enumerate(decl):
        if ch == "<":
            depth += 1
        elif ch == ">" and depth:
            depth -= 1
        elif ch == "(" and depth == 0:
            m = re.search(r"([~\w]+)\s*$", decl[:k])
            return m.group(1) if m else ""
    return ""


def headers() -> List[str]:
    found = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "src/hubwire/channels").glob("*.h"))
    rest = [p for p in found if p not in FIRST]
    return [p for p in FIRST + rest + LAST if (ROOT / p).exists()]


def _declaration(lines: List[str], i: int) -> Tuple[str, int]:
    """The declaration starting at lines[i]: up to its body or ';', one line; and the next index."""
    parts: List[str] = []
    while i < len(lines):
        line = lines[i].split("//")[0].rstrip()
        i += 1
        if not line.strip():
            if parts:
                break
            continue
        if line.lstrip().startswith("#define"):
            return line.strip().rstrip("\\").strip(), i
        parts.append(line.strip())
        text = " ".join(parts)
        if re.match(r"^template\s*<.*>$", text):
            continue
        if "{" in text or text.endswith(";"):
            break
    text = " ".join(parts)
    text = re.sub(r"\)\s*:\s*[\w:]+\(.*$", ")", text)      # a constructor's initialiser list
    text = text.split("{")[0].rstrip(" ;")
    return re.sub(r"\s+", " ", text), i


def extract(path: str) -> List[Entry]:
    lines = (ROOT / path).read_text(encoding="utf-8").splitlines()
    entries: List[Entry] = []
    scope: Optional[str] = None
    i = 0
    while i < len(lines):
        raw = lines[i]
        m = _SCOPE.match(raw)
        if m:
            scope = m.group(1)
        elif raw.startswith("};"):
            scope = None
        if not raw.lstrip().startswith("///"):
            i += 1
            continue
        entry = Entry(scope=scope if raw.startswith(" ") else None, line=i + 1)
        while i < len(lines) and lines[i].lstrip().startswith("///"):
            body = lines[i].lstrip()[3:]
            (entry.example if body.startswith("   ") else entry.text).append(body.strip() if not body.startswith("   ") else body[3:])
            i += 1
        entry.declaration, i = _declaration(lines, i)
        if not entry.declaration:
            raise ValueError(f"{path}:{entry.line}: a /// comment with no declaration after it")
        m = _SCOPE.match(entry.declaration + " {")
        if m and not raw.startswith(" "):
            scope = m.group(1)
        entries.append(entry)
    return entries


_SETTING = re.compile(r"^#ifndef (HUBWIRE_\w+)$")


def settings() -> List[Tuple[str, str, str]]:
    """config.h's overridable settings: (name, default, the comment above it)."""
    lines = (ROOT / "src/hubwire/config.h").read_text(encoding="utf-8").splitlines()
    rows, comment, block = [], "", []
    for n, line in enumerate(lines):
        if line.startswith("//"):
            block.append(line[2:].strip())
            continue
        if block:
            comment, block = " ".join(block), []
        m = _SETTING.match(line)
        if m and n + 1 < len(lines) and lines[n + 1].startswith(f"#define {m.group(1)} "):
            rows.append((m.group(1), lines[n + 1].split(None, 2)[2].strip(), comment))
    return rows


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def render() -> str:
    out = ["# Sketch API reference", "",
           "Generated when the site is built from the `///` comments of the library's headers, each with "
           "the declaration it documents. The guide is [The sketch](../SKETCH.md).", ""]
    total = 0
    for path in headers():
        entries = extract(path)
        if not entries:
            continue
        total += len(entries)
        out += [f"## {path}", "", f"[Source]({REPO_URL}/blob/main/{path})", ""]
        for e in entries:
            out += [f"### `{e.name}`", "", "```cpp", e.declaration, "```", ""]
            if e.text:
                out += [" ".join(e.text), ""]
            if e.example:
                out += ["```cpp", *e.example, "```", ""]
    if total == 0:
        raise ValueError("no /// comments found in the library's headers")
    rows = settings()
    if not rows:
        raise ValueError("no settings found in src/hubwire/config.h")
    out += ["## Compile-time settings", "",
            f"From [src/hubwire/config.h]({REPO_URL}/blob/main/src/hubwire/config.h): override each with a "
            "`-D` flag (PlatformIO `build_flags = -DHUBWIRE_MAX_STREAMS=2`). The range of each is "
            "checked when the sketch compiles.", "",
            "| setting | default | what |", "| --- | --- | --- |"]
    out += [f"| `{n}` | `{_cell(v)}` | {_cell(c)} |" for n, v, c in rows]
    return "\n".join(out) + "\n"


def on_files(files: Any, config: Any) -> Any:
    """MkDocs hook: add the generated page to the site."""
    from mkdocs.structure.files import File
    files.append(File.generated(config, PAGE, content=render()))
    return files


if __name__ == "__main__":
    sys.stdout.write(render())
