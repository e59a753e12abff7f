"""The import graph docs/ARCHITECTURE.md promises ("The layers of host/hubwire"): every module of the
package belongs to one layer, a layer imports only the layers listed for it, and no two modules
import each other, directly or around a loop (imports inside functions count: a late import hides a
cycle, it does not remove it; imports under ``if TYPE_CHECKING:`` count for the layers only)."""
from __future__ import annotations

import ast
from pathlib import Path
from typing import Dict, Iterator, List, Set, Tuple

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "hubwire"

#: module prefix -> layer (the longest prefix wins)
LAYER_OF: Dict[str, str] = {
    "hubwire.wire": "wire", "hubwire.errors": "wire", "hubwire.text": "wire",
    "hubwire.descriptor": "descriptor", "hubwire.hub": "descriptor",
    "hubwire.transport": "transport", "hubwire.ports": "transport", "hubwire.diagnose": "transport",
    "hubwire.session": "session",
    "hubwire.device": "face", "hubwire.aio": "face", "hubwire.job": "face", "hubwire.ops": "face",
    "hubwire.iterators": "face", "hubwire.hub_face": "face", "hubwire.roads": "face", "hubwire.board": "face",
    "hubwire": "package",
    "hubwire.client": "client",
    "hubwire.daemon": "daemon",
    "hubwire.bridge": "bridge",
    "hubwire.dashboard": "dashboard",
    "hubwire.cli": "cli", "hubwire.__main__": "cli",
    "hubwire.testing": "testing",
}

_BELOW_FACE = {"wire", "descriptor", "transport", "session"}
#: layer -> the layers it may import (its own always)
ALLOWED: Dict[str, Set[str]] = {
    "wire": set(),
    "descriptor": {"wire"},
    "transport": {"wire"},
    "session": {"wire", "descriptor", "transport"},
    "face": _BELOW_FACE,
    "client": _BELOW_FACE | {"face"},
    "package": _BELOW_FACE | {"face", "client"},  # hubwire/__init__: the public names, and the road choice
    "daemon": _BELOW_FACE | {"face", "client", "package"},
    "bridge": _BELOW_FACE | {"face", "package", "daemon"},
    "dashboard": _BELOW_FACE | {"face", "package", "daemon"},
    "cli": _BELOW_FACE | {"face", "package", "client", "daemon", "bridge", "dashboard"},
    "testing": _BELOW_FACE | {"face", "package"},
}


def layer(module: str) -> str:
    best = max((p for p in LAYER_OF if module == p or module.startswith(p + ".")), key=len)
    return LAYER_OF[best]


def modules() -> Dict[str, Tuple[Path, bool]]:
    out = {}
    for f in PACKAGE.rglob("*.py"):
        parts = list(f.relative_to(PACKAGE.parent).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts.pop()
        out[".".join(parts)] = (f, is_pkg)
    return out


def _type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST, typing_only: bool = False) -> Iterator[Tuple[ast.stmt, bool]]:
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node, typing_only
        elif isinstance(node, ast.If) and _type_checking(node):
            for child in node.body:
                yield from _imports(ast.Module(body=[child], type_ignores=[]), True)
            for child in node.orelse:
                yield from _imports(ast.Module(body=[child], type_ignores=[]), typing_only)
        else:
            yield from _imports(node, typing_only)


def edges() -> Dict[str, Dict[str, bool]]:
    """module -> {imported module of the package: True when only for type checking}."""
    mods = modules()
    graph: Dict[str, Dict[str, bool]] = {}
    for mod, (path, is_pkg) in mods.items():
        out: Dict[str, bool] = {}
        for node, typing_only in _imports(ast.parse(path.read_text(), str(path))):
            targets: List[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                assert isinstance(node, ast.ImportFrom)
                if node.level:
                    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                    base = base[:len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                # ``from . import ops`` imports the module hubwire.ops; ``from .. import __version__`` the package
                subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in mods]
                targets = subs if len(subs) == len(node.names) else subs + [target]
            for t in targets:
                while t and t not in mods:
                    t = t.rpartition(".")[0]
                if t.startswith("hubwire") and t != mod:
                    out[t] = out.get(t, True) and typing_only
        graph[mod] = out
    return graph


def test_every_module_has_a_layer() -> None:
    for mod in modules():
        assert layer(mod) in ALLOWED, mod


def test_layers_import_only_downward() -> None:
    wrong = []
    for mod, targets in sorted(edges().items()):
        for t in sorted(targets):
            if layer(t) != layer(mod) and layer(t) not in ALLOWED[layer(mod)]:
                wrong.append(f"{mod} ({layer(mod)}) imports {t} ({layer(t)})")
    assert not wrong, "imports against the layers:\n" + "\n".join(wrong)


def _cycles(graph: Dict[str, Set[str]]) -> List[List[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: Dict[str, int] = {}
    low: Dict[str, int] = {}
    stack: List[str] = []
    on: Set[str] = set()
    found: List[List[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


#: the one cycle left: messages.describe() decodes every message, the missions' layouts included,
#: while wire/missions.py builds on the message constants and checks of messages.py. To be ended
#: (the constants and checks in a module of their own), never added to.
KNOWN_CYCLES = [["hubwire.wire.messages", "hubwire.wire.missions"]]


def test_no_import_cycles() -> None:
    graph = {m: {t for t, typing_only in ts.items() if not typing_only} for m, ts in edges().items()}
    cycles = _cycles(graph)
    assert cycles == KNOWN_CYCLES, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_the_checks_can_fail() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert layer("hubwire.daemon.fleet") == "daemon" and layer("hubwire") == "package"
    assert layer("hubwire.descriptor_x") == "package"


@pytest.mark.parametrize("face", ["hubwire.device", "hubwire.aio"])
def test_the_face_imports_no_service(face: str) -> None:
    # hubwire.service: where the daemon, the client and the bridge lived before they had folders
    above = ("hubwire.service", "hubwire.client", "hubwire.daemon", "hubwire.bridge", "hubwire.dashboard",
             "hubwire.cli")
    assert not {t for t in edges()[face] if t.startswith(above)}
