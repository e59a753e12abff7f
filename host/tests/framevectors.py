"""One golden frame vector (test/vectors/<folder>/frames.json) checked both ways: it encodes to the
pinned wire bytes and decodes back to the pinned header, payload and message."""
from __future__ import annotations

import json
import pathlib
from typing import Any

from hubwire.wire.frame import FrameDecoder, encode_frame

from hubwire.wire import messages as m

VECTORS = pathlib.Path(__file__).resolve().parents[2] / "test" / "vectors"


def load(folder: str) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """The vectors document of a folder and its vectors by name."""
    doc = json.loads((VECTORS / folder / "frames.json").read_text())
    return doc, {v["name"]: v for v in doc["vectors"]}


def check_frame(v: dict[str, Any], limit: int = 255, kind: str | None = None) -> None:
    """kind: the message kind describe() is told (None: it tells it from the frame)."""
    payload = bytes.fromhex(v["payload"])
    assert len(payload) <= limit
    wire = encode_frame(v["type"], v["seq"], v["id"], payload)
    assert wire.hex() == v["wire"]
    (f,) = FrameDecoder(limit).feed(wire)
    assert (f.type, f.seq, f.id, f.payload) == (v["type"], v["seq"], v["id"], payload)
    assert m.describe(f, kind) == v["message"]
