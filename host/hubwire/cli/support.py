"""What the ``hubwire`` commands share: opening the board with errors that say what to do,
channel look-ups in words, and value formatting for text and ``--json`` output."""
from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Dict, Sequence, TextIO

from .. import diagnose
from ..client.protocol import jsonable
from ..device import Device, connect
from ..errors import HubwireError, NoDeviceFound, Timeout
from ..ports import PYTHON_ADVICE

__all__ = ["CliError", "columns", "jsonable", "fmt_value", "print_json", "progress_printer", "open_device", "channel",
           "channel_json", "goal_or_argument"]


def fmt_value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return "{" + ", ".join(f"{k}: {fmt_value(x)}" for k, x in v._asdict().items()) + "}"
    if isinstance(v, (tuple, list)):
        return "[" + ", ".join(fmt_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if v is None:
        return "-"
    return str(v)


def columns(rows: Sequence[Sequence[str]]) -> str:
    """``rows`` (the first one the headers) as text in aligned columns, one line each."""
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "".join("  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip() + "\n" for r in rows)


def print_json(obj: Any, out: TextIO = sys.stdout) -> None:
    out.write(json.dumps(obj, ensure_ascii=False) + "\n")
    out.flush()


def progress_printer() -> Any:
    if not sys.stderr.isatty():
        return None

    def progress(received: int, total: int) -> None:
        sys.stderr.write(f"\rdownloading descriptor: {received}/{total} bytes")
        if received >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()
    return progress


class CliError(Exception):
    """An error the command reports as is: ``kind`` is one of :data:`diagnose.ERROR_TYPES`."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


def open_device(args: argparse.Namespace) -> Device:
    url = None if args.url in (None, "auto") else args.url
    try:
        # a command does not answer the board's hub channels: it reads, writes and calls
        return connect(url, args.baud, timeout=args.timeout, progress=progress_printer(), hub_later=True,
                       cache_dir=False if args.no_cache else None)
    except Timeout as e:
        # someone else reading the port takes the answers: say who rather than "no answer"
        holders = diagnose.port_holders(url)
        if holders:
            raise CliError("PortBusy", diagnose.busy_message(str(url), holders)) from e
        raise CliError("ConnectTimeout", str(e)) from e
    except diagnose.PortOpenError:
        raise
    except NoDeviceFound as e:
        if url is None and str(e).endswith(PYTHON_ADVICE):
            raise CliError("NoDeviceFound", str(e)[:-len(PYTHON_ADVICE)] + _name_the_port(args)) from None
        raise
    except HubwireError as e:
        if url is not None and isinstance(e.__cause__, OSError):
            raise diagnose.open_error(url, e.__cause__) from e.__cause__
        raise


def _name_the_port(args: argparse.Namespace) -> str:
    """The command as typed with a port instead of ``auto``."""
    rest = [getattr(args, k, None) for k in ("channel", "value", "action", "arg")]
    example = " ".join(["hubwire", args.command, "/dev/ttyACM0", *(str(r) for r in rest if r is not None)])
    return f"Name the board's port instead of auto, e.g. `{example}` (`hubwire ports` lists the ports)."


def goal_or_argument(ch: Any, text: Any) -> Any:
    """The parsed argument of a call or goal of a mission (None for none); CliError when it is
    missing or there should be none."""
    what = "goal" if ch.mission else "argument"
    if ch.codec.kind == "void" and text is not None:
        raise CliError("InvalidValue", f"{ch.name} takes no {what}")
    if ch.codec.kind != "void" and text is None:
        raise CliError("InvalidValue", f"{ch.name} needs {'a' if ch.mission else 'an'} {what} ({ch.codec.name})")
    return None if text is None else ch.codec.parse_text(text)


def channel(dev: Device, name: str, need: str) -> Any:
    """The channel ``name`` if its access has the letter ``need``; a CliError in words otherwise."""
    try:
        ch = dev.channel(name)
    except KeyError as e:
        raise CliError("UnknownChannel", str(e.args[0] if e.args else e)) from None
    refused = diagnose.access_error(name, ch.access, need)
    if refused:
        raise CliError(*refused)
    return ch


def channel_json(c: Any) -> Dict[str, Any]:
    d: Dict[str, Any] = {"id": c.id, "name": c.name, "access": c.access, "type": c.type_name}
    for k, v in (("unit", c.unit), ("min", c.min), ("max", c.max), ("failsafe", jsonable(c.failsafe)),
                 ("progress_max", c.progress_max), ("description", c.description)):
        if v is not None:
            d[k] = v
    return d
