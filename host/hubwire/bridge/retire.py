"""Retained topics of a key a board no longer has.

The bridge sees every retained descriptor on the broker (it subscribes to them to find the boards
of other services). One that this service published, for a board that is now served under another
key (same name and board id: the key was retired, e.g. by the change to keys derived from identity
alone), is stale, and so is everything retained under that key: its descriptor, link state, channel
states and Home Assistant configs (left there, Home Assistant keeps a ghost device). A key whose
board is merely unplugged, or that another service publishes, is never touched.
"""
from __future__ import annotations

import json
from collections import OrderedDict
from typing import Any, Iterable, List, Optional, Tuple

from ..descriptor import parse_descriptor
from . import ha
from .topics import Topics, level, safe_id

__all__ = ["Retired", "MAX_REMEMBERED"]

#: retained descriptors of unknown keys remembered until their board shows up (the oldest are
#: forgotten beyond it: their topics then stay until cleared by hand)
MAX_REMEMBERED = 1000

Identity = Tuple[str, Optional[str]]


class Retired:
    def __init__(self, topics: Topics, service_id: str) -> None:
        self.topics = topics
        self.service_id = service_id
        #: key -> (identity, retained descriptor body) of keys this service published, not served now
        self._waiting: "OrderedDict[str, Tuple[Identity, Any]]" = OrderedDict()

    def note(self, key: str, payload: Any, boards: Iterable[Tuple[str, Identity]]) -> List[str]:
        """A retained descriptor of ``key`` (not one of ours now): the topics to clear at once when
        its board is served under another key (``boards``: ``(key, (name, board id))`` of ours)."""
        try:
            body = json.loads(bytes(payload)) if payload else None
        except (ValueError, TypeError, RecursionError):  # RecursionError: nested too deep
            return []
        if not isinstance(body, dict) or body.get("service") != self.service_id:
            self._waiting.pop(key, None)
            return []
        name, board_id = body.get("name"), body.get("board_id")
        if not isinstance(name, str) or not (board_id is None or isinstance(board_id, str)):
            return []
        ident = (name, board_id)
        if any(k != key and i == ident for k, i in boards):
            return self._topics(key, ident, body)
        self._waiting[key] = (ident, body)
        self._waiting.move_to_end(key)
        while len(self._waiting) > MAX_REMEMBERED:
            self._waiting.popitem(last=False)
        return []

    def seen(self, key: str, ident: Identity) -> List[str]:
        """A board of ours is served under ``key``: the topics to clear of its former keys."""
        self._waiting.pop(key, None)
        out: List[str] = []
        for old in [k for k, (i, _) in self._waiting.items() if i == ident]:
            out += self._topics(old, ident, self._waiting.pop(old)[1])
        return out

    def _topics(self, key: str, ident: Identity, body: Any) -> List[str]:
        # the key as it was written (an older key need not be a level of today's rules)
        p = self.topics.prefix
        out = [f"{p}/{key}/descriptor", f"{p}/{key}/status"]
        try:
            desc = parse_descriptor(json.dumps(body.get("descriptor")).encode())
        except Exception:  # noqa: BLE001 - no descriptor: the channel topics are unknown
            return out
        for ch in desc.channels:
            out += sorted({f"{p}/{key}/state/{ch.name}", f"{p}/{key}/state/{level(ch.name)}"})
            if ch.callable:
                out.append(self.topics.result(key, ch.name))
        if self.topics.discovery_prefix:
            for ch in desc.channels:
                kinds = ha.entity_kinds(ch) + [k for k in [ha.legacy_kind(ch)] if k is not None]
                for kind in sorted(set(kinds)):
                    # today's config topic, and the one of earlier versions
                    out += sorted({ha.config_topic(self.topics, kind, key, ch.name),
                                   f"{self.topics.discovery_prefix}/{kind}/{safe_id(key)}/{safe_id(ch.name)}/config"})
        return out
