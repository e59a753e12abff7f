"""What the page says, in plain words: why a write, call or stream was refused, and a board's link.

The protocol's names (``BUSY``, ``REJECTED``, ...) stay available to tests and to whoever looks for
them, on the element (``data-hw-code``) and in the hover text; the page's text says what happened."""
from __future__ import annotations

import asyncio
from typing import Optional, Tuple

from ..errors import HubwireError, InvalidValue, NakError

__all__ = ["NAK_WORDS", "outcome", "outcome_text", "STATE_WORDS"]

#: each NAK name (docs/PROTOCOL.md, section 5) as a user would say it
NAK_WORDS = {
    "UNKNOWN_TYPE": "the board does not understand this request",
    "UNKNOWN_CHANNEL": "the board has no such channel",
    "BAD_LENGTH": "the value has the wrong size for this channel",
    "OUT_OF_RANGE": "the value is outside the channel's range",
    "NOT_WRITABLE": "this channel cannot be set",
    "NOT_READABLE": "this channel cannot be read",
    "NOT_STREAMABLE": "this channel cannot be streamed",
    "BUSY": "the board is busy",
    "BAD_OFFSET": "the board could not send its description",
    "NOT_LINKED": "the board is not connected yet",
    "BAD_VALUE": "the value is not valid for this channel",
    "REJECTED": "the board's sketch turned the value down",
    "UNSUPPORTED_VERSION": "the board speaks another protocol version",
}

#: a board's link state as the page names it
STATE_WORDS = {"ready": "ready", "connecting": "connecting", "lost": "lost", "unplugged": "unplugged"}


def outcome(exc: BaseException) -> Tuple[str, Optional[str]]:
    """``(what the page says, the protocol's name of the reason or None)`` for a failed write or call."""
    if isinstance(exc, NakError):
        return "refused by the board: " + NAK_WORDS.get(exc.error, "for a reason it did not name"), exc.error
    if isinstance(exc, InvalidValue):  # the hub's own checks, which say what is wrong: never sent
        return f"not sent: {exc}", exc.error
    if isinstance(exc, (asyncio.TimeoutError, TimeoutError)):
        return "the board did not answer in time", None
    if isinstance(exc, HubwireError):
        return str(exc), None
    return f"not a valid value: {exc}", None  # ValueError, TypeError from the hub's checks


def outcome_text(exc: BaseException) -> str:
    """What the page says of a failed write or call (:func:`outcome` without the name)."""
    return outcome(exc)[0]
