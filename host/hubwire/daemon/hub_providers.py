"""Who answers a board's hub channels inside ``hubwire serve`` (docs/SERVICE.md "Hub channels").

A board served by the service may read, write and call channels of the hub (PROTOCOL.md 10). The
service answers them for a **provider**: a client of its socket (``connect(name, hub=...)``) or the
MQTT bridge (``--mqtt-hub``, bridge/hub_topics.py). :class:`HubProviders` keeps, per board key and
hub channel name, the one provider that holds it: a second one is refused with an error naming
both. For a held channel the service declares a stand-in on the board's session (the board's own
type, the provider's unit and range) whose handlers ask the provider; a channel nobody holds is not
declared, so the bind report says ``UNKNOWN_CHANNEL`` and the board takes its unbound path (the
sketch's failure function, its failsafe). Hub events (access ``e``) are not held: every client and
the bridge may send them (``notify``), in the order they reach the service.
"""
from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Tuple

from ..descriptor import Channel
from ..errors import HubChannelError, HubwireError
from ..hub import HubChannel, HubChannels, bind_status
from ..session.hub_channels import mismatch
from ..text import clip
from ..wire.messages import nak_name

__all__ = ["HubProviders", "Provider", "HubConflict", "entry_of", "ANSWER_TIMEOUT_S"]

log = logging.getLogger("hubwire.service")

#: how long the service waits for a provider's answer before the board is told REJECTED (the board
#: itself gives up after HUBWIRE_HUB_TRIES x HUBWIRE_HUB_RETRY_MS, 0.5 s by default)
ANSWER_TIMEOUT_S = 2.0


class HubConflict(HubwireError):
    """A hub channel is already provided by another client or by the MQTT bridge."""

    kind = "Conflict"


class Provider:
    """One provider of hub channels: ``label`` names it in errors and in the bind status; ``kind``
    is ``"client"`` or ``"mqtt"``. Subclasses answer the board's requests (values as the board's
    codec decodes them); raising (or returning False from ``write``) answers the board REJECTED."""

    kind = "client"

    def __init__(self, label: str) -> None:
        self.label = label

    def ready(self, key: str, name: str) -> bool:
        """Whether the channel is declared to the board yet (MQTT: once it has a value)."""
        return True

    async def read(self, key: str, name: str) -> Any:
        raise HubwireError("not readable")

    async def write(self, key: str, name: str, value: Any) -> Any:
        raise HubwireError("not writable")

    async def call(self, key: str, name: str, arg: Any) -> Any:
        raise HubwireError("not callable")


@dataclass
class _Claim:
    provider: Provider
    entry: Dict[str, Any]  # the provider's declaration (descriptor entry: type, unit, range)


def entry_of(exp: Channel) -> Dict[str, Any]:
    """A hub-side declaration matching what the board expects (for providers that declare nothing
    of their own, such as the MQTT bridge)."""
    e: Dict[str, Any] = {"n": exp.name, "a": exp.access, **exp.codec.type_obj}
    if exp.returns is not None and exp.returns.type_obj.get("t") != "void":
        e["rt"] = exp.returns.type_obj["t"]
        if "c" in exp.returns.type_obj:
            e["rc"] = exp.returns.type_obj["c"]
    for k, v in (("u", exp.unit), ("min", exp.min), ("max", exp.max)):
        if v is not None:
            e[k] = v
    return e


class HubProviders:
    """The service's table of hub channel providers, per board key (``fleet`` gives ``resolve``,
    ``get`` and ``descriptor``). At most one provider per (board, channel): one board has at most
    255 hub channels, so the table is bounded by the boards the fleet knows."""

    def __init__(self, fleet: Any) -> None:
        self.fleet = fleet
        self._claims: Dict[str, Dict[str, _Claim]] = {}
        self._reads: Dict[Tuple[str, str], "asyncio.Future[Any]"] = {}
        self._watchers: List[Callable[[str], None]] = []

    # ------------------------------------------------------------------------------- claims

    def claim(self, key: str, provider: Provider, entries: List[Dict[str, Any]]) -> None:
        """Hold ``entries`` (hub channel declarations) of board ``key`` for ``provider``, all or none:
        HubConflict naming both providers when another holds one, HubChannelError when one does not
        match what the board expects (as ``connect(..., hub=...)`` raises directly)."""
        desc = self.fleet.descriptor(key)
        held = self._claims.setdefault(key, {})
        checked: Dict[str, Dict[str, Any]] = {}
        for entry in entries:
            name = str(entry.get("n"))
            exp = next((c for c in desc.hub if c.name == name), None)
            if exp is None or "e" in exp.access:
                continue  # not a channel the board reads, writes or calls: nothing to hold
            other = held.get(name)
            if other is not None and other.provider is not provider:
                raise HubConflict(f"hub channel {name!r} of {key} is provided by {other.provider.label}; "
                                  f"{provider.label} cannot provide it too")
            hc = _declared(entry)
            code = bind_status(exp, hc)
            if code:
                raise HubChannelError(mismatch(exp, hc, code, desc.name))
            checked[name] = entry
        for name, entry in checked.items():
            held[name] = _Claim(provider, entry)
        self.refresh(key)

    def release(self, provider: Provider, key: Optional[str] = None, keep: Tuple[str, ...] = ()) -> None:
        """Let go of what ``provider`` holds (on board ``key`` only, except the names in ``keep``)."""
        for k, held in list(self._claims.items()):
            if key is not None and k != key:
                continue
            gone = [n for n, c in held.items() if c.provider is provider and n not in keep]
            for n in gone:
                del held[n]
            if gone:
                log.info("hubwire serve: %s no longer provides %s of %s", provider.label, ", ".join(gone), k)
                self.refresh(k)

    def holder(self, key: str, name: str) -> Optional[Provider]:
        c = self._claims.get(key, {}).get(name)
        return None if c is None else c.provider

    # ------------------------------------------------------------------ the board's session

    def refresh(self, key: str) -> None:
        """Declare on the board's session what is held and ready, withdraw the rest (each change
        sends the board a new bind report), then tell the watchers."""
        try:
            board = self.fleet.get(key)
        except KeyError:
            return
        if board.device is not None:
            self._apply(key, board.device)
        for w in list(self._watchers):
            w(key)

    def attach(self, key: str, dev: Any) -> None:
        """A new session of board ``key`` (plugged in again): declare what is held."""
        self._apply(key, dev)

    def _apply(self, key: str, dev: Any) -> None:
        channels: HubChannels = dev.core.hub.channels
        desc = dev.descriptor
        held = self._claims.get(key, {})
        for exp in desc.hub:
            if "e" in exp.access:
                continue
            claim = held.get(exp.name)
            current = channels.get(exp.name)
            want = claim is not None and claim.provider.ready(key, exp.name)
            if want and (current is None or getattr(current, "provider", None) is not claim):
                try:
                    self._declare(channels, key, exp, claim)  # type: ignore[arg-type]
                except HubwireError as e:
                    log.warning("hubwire serve: hub channel %s of %s not declared: %s", exp.name, key, clip(str(e), 200))
            elif not want and current is not None:
                channels.remove(exp.name)

    def _declare(self, channels: HubChannels, key: str, exp: Channel, claim: _Claim) -> None:
        e, p, name = claim.entry, claim.provider, exp.name
        kw: Dict[str, Any] = {"unit": e.get("u"), "min": e.get("min"), "max": e.get("max")}
        t = exp.codec.type_obj

        async def write(value: Any) -> Any:
            return await _answer(p.write(key, name, value))

        if "c" in exp.access:
            async def call(*arg: Any) -> Any:
                return await _answer(p.call(key, name, arg[0] if arg else None))
            rt = exp.returns.type_obj if exp.returns is not None else {"t": "void"}
            hc: HubChannel = channels.action(name, call, type=t, returns=rt)
        elif "r" in exp.access:
            async def read() -> Any:
                return await self._read(key, name, p)
            hc = channels.provide(name, read, type=t, writable="w" in exp.access,
                                  on_write=write if "w" in exp.access else None, **kw)
        else:
            hc = channels.accept(name, write, type=t, **kw)
        setattr(hc, "provider", claim)

    async def _read(self, key: str, name: str, p: Provider) -> Any:
        """One read at a time per channel: the board's retries of a read share its answer."""
        fut = self._reads.get((key, name))
        if fut is None:
            fut = asyncio.ensure_future(_answer(p.read(key, name)))
            self._reads[(key, name)] = fut
            fut.add_done_callback(lambda _f: self._reads.pop((key, name), None))
        return await asyncio.shield(fut)

    # ------------------------------------------------------------------------------ status

    def watch(self, cb: Callable[[str], None]) -> Callable[[], None]:
        """``cb(key)`` after every change of a board's providers; returns its remover."""
        self._watchers.append(cb)
        return lambda: self._watchers.remove(cb) if cb in self._watchers else None

    def status(self, key: str) -> List[Dict[str, Any]]:
        """Per hub channel the board uses: name, access, type, who provides it (``by``: a label,
        ``kind``: client / mqtt / service, None when unbound) and ``status`` (``ok``, ``unbound``,
        ``waiting`` for the provider's first value, or the bind report's code for the last session)."""
        try:
            desc = self.fleet.descriptor(key)
        except KeyError:
            return []
        board = self.fleet.get(key)
        side = board.device.core.hub if board.device is not None else None
        out: List[Dict[str, Any]] = []
        for exp in desc.hub:
            claim = self._claims.get(key, {}).get(exp.name)
            row: Dict[str, Any] = {"channel": exp.name, "access": exp.access, "type": exp.type_name}
            if "e" in exp.access:
                row.update(by="the service (notify)", kind="service")
            elif claim is not None:
                row.update(by=claim.provider.label, kind=claim.provider.kind)
            else:
                row.update(by=None, kind=None)
            if side is not None:
                code = bind_status(exp, side.channels.get(exp.name))
                row["bind"] = "ok" if code == 0 else nak_name(code)
                if claim is not None and not claim.provider.ready(key, exp.name):
                    row["status"] = "waiting"
                else:
                    row["status"] = "ok" if code == 0 else "unbound" if row["kind"] is None else nak_name(code)
            else:
                row.update(status="unplugged", bind="unplugged")
            out.append(row)
        return out


def _declared(entry: Dict[str, Any]) -> HubChannel:
    """The provider's declaration as a hub channel (checked by the descriptor parser)."""
    e = {k: v for k, v in entry.items() if k in ("n", "a", "t", "c", "vc", "f", "rt", "rc", "u", "min", "max", "d")}
    return HubChannel(dict(e, id=1))


async def _answer(aw: Any) -> Any:
    """A provider's answer within ANSWER_TIMEOUT_S (else the board is told REJECTED)."""
    try:
        return await asyncio.wait_for(aw, ANSWER_TIMEOUT_S)
    except asyncio.TimeoutError:
        raise HubwireError(f"no answer from the provider within {ANSWER_TIMEOUT_S} s") from None
