"""The documentation site's build tools (tools/docs/): the sketch reference taken from the headers'
/// comments, links out of docs/ turned into repository addresses, and the README link check."""
from __future__ import annotations

import importlib.util
import logging
import os
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"docs_{name}", ROOT / "tools" / "docs" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


sketch_api = _load("sketch_api")
repo_links = _load("repo_links")
readme_links = _load("check_readme_links")

HEADER = """\
namespace hubwire {
/// A free function.
///   int n = twice(2);
template <typename T>
constexpr Decl<T, kControl, void (*)(T)> twice(const char* name,
                                               void (*fn)(T)) {
  return 0;
}
class Thing {
 public:
  /// Reads it; never blocks.
  ///   thing.read();
  bool read() const { return ok_; }
};
/// The macro.
#define THING(var, ...) \\
  something
}
"""


def test_each_comment_comes_with_the_declaration_after_it(tmp_path: Path) -> None:
    header = tmp_path / "thing.h"
    header.write_text(HEADER)
    entries = sketch_api.extract(str(header))
    assert [e.name for e in entries] == ["twice", "Thing::read", "THING"]
    assert entries[0].declaration == ("template <typename T> constexpr Decl<T, kControl, void (*)(T)> "
                                      "twice(const char* name, void (*fn)(T))")
    assert entries[0].text == ["A free function."] and entries[0].example == ["int n = twice(2);"]
    assert entries[1].declaration == "bool read() const"
    assert entries[2].declaration == "#define THING(var, ...)"


def test_a_comment_without_a_declaration_stops_the_build(tmp_path: Path) -> None:
    header = tmp_path / "orphan.h"
    header.write_text("int a;\n/// Nothing follows.\n")
    with pytest.raises(ValueError, match="no declaration"):
        sketch_api.extract(str(header))


def test_the_reference_covers_the_declarations_the_session_and_the_settings() -> None:
    page = sketch_api.render()
    for heading in ("### `HUBWIRE_CHANNELS`", "### `Decl::failsafe`", "### `Session::emit`", "### `remote`",
                    "### `mission`", "### `Hubwire::begin`"):
        assert heading in page
    assert "| `HUBWIRE_MAX_STREAMS` | `4` |" in page


def test_a_link_out_of_docs_becomes_the_repository_address(caplog: pytest.LogCaptureFixture) -> None:
    docs, url = ROOT / "docs", "https://github.com/hubwire/hubwire"
    line = "[r](../bench/RESULTS.md#row-8) [p](PROTOCOL.md) [x](../no/such/file.md)"
    with caplog.at_level(logging.WARNING):
        out = repo_links._rewrite(line, "", docs, url, "page.md")
    assert f"[r]({url}/blob/main/bench/RESULTS.md#row-8)" in out
    assert "[p](PROTOCOL.md)" in out and "[x](../no/such/file.md)" in out
    assert [r.getMessage() for r in caplog.records] == [
        "page.md: link ../no/such/file.md names a file the repository does not have"]


def test_the_readme_check_names_a_missing_file_and_a_missing_heading(tmp_path: Path) -> None:
    (tmp_path / "guide.md").write_text("# Guide\n\n## Over WiFi\n")
    readme = tmp_path / "README.md"
    readme.write_text("[a](guide.md#over-wifi) [b](gone.md)\n`[c](not-a-link.md)`\n"
                      "[d](guide.md#over-usb) [e](https://example.org/x.md)\n")
    bad = readme_links.broken(readme)
    rel = os.path.relpath(readme, ROOT)
    assert bad == [f"{rel}:1: gone.md: no such file", f"{rel}:3: guide.md#over-usb: no heading #over-usb in guide.md"]


def test_the_repository_readmes_have_no_broken_link() -> None:
    assert readme_links.main() == 0
