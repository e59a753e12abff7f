"""Serving the dashboard: the page, the token check, and the web server on the caller's event loop.

``await run_dashboard(fleet, port=8080)`` serves until cancelled. NiceGUI keeps one app per process,
so one dashboard per process."""
from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import socket
from typing import Any, Callable, Dict, Iterable, Iterator, Mapping, Optional, Set

from .auth import TOKEN_COOKIE, Gate, TokenGate, load_token, served_names
from .feed import Feeds
from .fleet import FleetLike

__all__ = ["run_dashboard", "DEFAULT_PORT", "is_loopback", "load_token", "TOKEN_COOKIE", "Gate", "TokenGate"]

log = logging.getLogger("hubwire.dashboard")

DEFAULT_PORT = 8080
#: how often values, health and events are pushed to a page, s
VALUE_REFRESH = 0.1
#: how often plots are redrawn, s
PLOT_REFRESH = 0.5

def is_loopback(host: str) -> bool:
    """True when ``host`` is reachable from this machine only (127.x, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        try:
            return all(ipaddress.ip_address(a[4][0]).is_loopback for a in socket.getaddrinfo(host, None))
        except (OSError, ValueError):
            return False


# Channels off screen are not redrawn: the page tells which channel cards are on screen (or nearly).
_VISIBILITY_JS = """<script>
document.addEventListener('DOMContentLoaded', () => {
  const send = d => {  // once the page is connected to the server
    if (window.did_handshake && getElement(0)) emitEvent('hw_visible', d); else setTimeout(() => send(d), 50);
  };
  const seen = new IntersectionObserver(entries => {
    for (const e of entries) send({key: e.target.dataset.hwChannel, on: e.isIntersecting});
  }, {rootMargin: '300px'});
  const watched = new WeakSet();
  const scan = () => document.querySelectorAll('[data-hw-channel]').forEach(el => {
    if (!watched.has(el)) { watched.add(el); seen.observe(el); } });
  new MutationObserver(scan).observe(document.body, {childList: true, subtree: true});
  scan();
});
</script>"""


def _page(feeds: Feeds) -> None:
    from nicegui import ui

    from .view_board import BoardView

    @ui.page("/", title="Hubwire dashboard")
    def index() -> None:
        ui.query("body").classes("bg-gray-100")
        ui.add_head_html(_VISIBILITY_JS)
        visible: Set[str] = set()

        def on_visible(e: Any) -> None:
            (visible.add if e.args.get("on") else visible.discard)(str(e.args.get("key")))

        ui.on("hw_visible", on_visible)
        with ui.header(fixed=False).classes("items-center"):
            ui.label("Hubwire").classes("text-2xl font-bold")
            count = ui.label("").props("data-hw-boards")
        column = ui.column().classes("w-full max-w-screen-2xl mx-auto")
        with column:
            empty = ui.label("no boards yet").classes("text-gray-600")
        views: Dict[str, BoardView] = {}

        def sync() -> None:
            boards = feeds.boards()
            keys = [b.key for b in boards]
            for key in [k for k in views if k not in keys]:
                column.remove(views.pop(key).card)
            for b in boards:
                feed = feeds.feeds.get(b.key)
                v = views.get(b.key)
                if v is None or v.generation != (feed.generation if feed is not None else 0):
                    if v is not None:
                        column.remove(v.card)
                    with column:
                        views[b.key] = BoardView(b, feed, feeds.fleet)
                    views[b.key].card.move(column, target_index=keys.index(b.key) + 1)
                views[b.key].refresh(b, visible)
            empty.set_visibility(not boards)
            count.set_text(f"{len(boards)} board{'s' if len(boards) != 1 else ''}: "
                           + ", ".join(f"{b.key} {b.state}" for b in boards))

        def plots() -> None:
            for v in views.values():
                v.refresh_plots(visible)

        sync()
        ui.timer(VALUE_REFRESH, sync)
        ui.timer(PLOT_REFRESH, plots)


class _Server:
    """uvicorn's server without its signal handlers: whoever runs the loop owns the signals."""

    def __init__(self, app: Any, host: str, port: int) -> None:
        import uvicorn

        class Quiet(uvicorn.Server):
            @contextlib.contextmanager
            def capture_signals(self) -> Iterator[None]:
                yield

        self.server = Quiet(uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="on"))

    async def serve(self, started: Optional[Callable[[], None]]) -> None:
        task = asyncio.ensure_future(self.server.serve())
        try:
            while not self.server.started:
                if task.done():
                    await task  # failed to start: raise its error
                    raise OSError("the dashboard's web server stopped at start")
                await asyncio.sleep(0.05)
            if started is not None:
                started()
            await asyncio.shield(task)
        finally:
            self.server.should_exit = True
            with contextlib.suppress(Exception, asyncio.CancelledError):
                await task


async def run_dashboard(fleet: FleetLike, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                        token: Optional[str] = None, *, stream_hz: float = 10.0,
                        rates: Optional[Mapping[str, float]] = None,
                        started: Optional[Callable[[], None]] = None, allow_hosts: Iterable[str] = ()) -> None:
    """Serve the dashboard of ``fleet``'s boards at ``http://host:port/`` until cancelled.

    ``token``: required from browsers (``http://host:port/?token=TOKEN``), on loopback too (any local
    user reaches a loopback port); None raises ValueError (:func:`load_token` finds or makes one).
    Requests must name the dashboard in ``Host`` (localhost, 127.0.0.1, [::1], ``host``, or one of
    ``allow_hosts``) and come from its own origin (:class:`hubwire.dashboard.auth.Gate`).
    ``stream_hz``: the rate streamable channels are subscribed at first (selectable on the page);
    ``rates``: other first rates by channel name (every board) or ``"key.name"`` (one board).
    ``started`` is called once the server listens.
    """
    if not token:
        raise ValueError("the dashboard needs a token, also on loopback: load_token() finds or makes one")
    from fastapi import FastAPI
    from nicegui import ui

    feeds = Feeds(fleet, stream_hz, rates)
    await feeds.start()
    _page(feeds)
    app = FastAPI()
    ui.run_with(app, title="Hubwire dashboard", favicon="🔌", show_welcome_message=False,
                reconnect_timeout=10.0)
    wildcard = host in ("", "0.0.0.0", "::")
    served = Gate(app, token, served_names(host, allow_hosts), any_ip=wildcard)
    try:
        await _Server(served, host, port).serve(started)
    finally:
        await feeds.stop()
