"""One of each at the edges of the package: one known-USB-id port filter, one board record and one
fleet, one error-to-type mapping that the command line, the service and its clients share."""
from __future__ import annotations

import argparse
import ast
import json
from pathlib import Path
from typing import Any, Dict, Iterator, List, Tuple

import pytest

from hubwire.cli import command
from hubwire.client import protocol
from hubwire.errors import InvalidValue, LinkLost, NakError, Timeout, UnknownBoard, error_from

PACKAGE = Path(__file__).resolve().parents[1] / "hubwire"


def trees() -> Iterator[Tuple[str, ast.Module]]:
    for f in sorted(PACKAGE.rglob("*.py")):
        yield ".".join(f.relative_to(PACKAGE.parent).with_suffix("").parts), ast.parse(f.read_text(), str(f))


def test_one_port_filter() -> None:
    """Only hubwire.ports lists the serial ports or looks a vendor id up among the known ones."""
    users = set()
    for mod, tree in trees():
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and node.attr == "comports") or (
                    isinstance(node, ast.Name) and node.id == "KNOWN_USB_VIDS"):
                users.add(mod)
    assert users == {"hubwire.ports"}


def test_one_board_record_and_one_fleet() -> None:
    boards, fleets = [], []
    for mod, tree in trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and node.name == "Board":
                boards.append(mod)
            if isinstance(node, ast.ClassDef) and node.name.endswith("Fleet"):
                bases = {b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in node.bases}
                fleets.append(node.name if node.name == "Fleet" or "Fleet" in bases else f"{mod}.{node.name}")
    assert boards == ["hubwire.daemon.fleet"]
    assert sorted(fleets) == ["DeviceFleet", "Fleet"]  # DeviceFleet is a Fleet


ERRORS = [NakError(3, "left"), InvalidValue("bad", 2), Timeout("slow"), LinkLost("gone"),
          UnknownBoard("no board 'x'"), KeyError("no channel 'x'"), ValueError("other")]


@pytest.mark.parametrize("exc", ERRORS, ids=lambda e: type(e).__name__)
def test_an_error_reads_the_same_on_the_command_line_and_the_socket(exc: BaseException, monkeypatch: Any) -> None:
    printed: List[Dict[str, Any]] = []
    monkeypatch.setattr(command, "print_json", printed.append)  # what `hubwire ... --json` prints
    command._error(argparse.Namespace(json=True), exc)
    sent = protocol.error_json(exc)
    assert sent.pop("ok") is False and printed == [sent]
    assert json.loads(json.dumps(sent)) == sent


@pytest.mark.parametrize("exc", [e for e in ERRORS if not isinstance(e, (KeyError, ValueError))] + [UnknownBoard("u")],
                         ids=lambda e: type(e).__name__)
def test_a_client_raises_the_error_the_service_reported(exc: BaseException) -> None:
    again = error_from(protocol.error_json(exc))
    assert type(again) is type(exc) and str(again) == str(exc)
    assert getattr(again, "code", None) == getattr(exc, "code", None)
    assert getattr(again, "channel", None) == getattr(exc, "channel", None)
