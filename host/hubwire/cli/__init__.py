"""The ``hubwire`` command: ``command`` (the parser and every subcommand), ``support`` (opening a
board, formatting values), ``watch`` (the live view), ``mission`` (``hubwire call`` on a mission)
and ``serve`` (``hubwire serve``: the daemon, with the MQTT bridge and the dashboard it may run)."""
from __future__ import annotations

from .command import build_parser, main

__all__ = ["build_parser", "main"]
