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
from .attrs import tag
from .feed import Feeds
from .model import LinkRecord
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


# Channels off screen are not redrawn: the page tells which channel rows are on screen (or nearly).
# A click on a board's tile brings its card into view.
_PAGE_JS = """<script>
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
  document.addEventListener('click', ev => {
    const tile = ev.target.closest && ev.target.closest('[data-hw-tile]');
    const card = tile && document.querySelector('[data-hw-board="' + CSS.escape(tile.dataset.hwTile) + '"]');
    if (card) card.scrollIntoView({behavior: 'smooth', block: 'start'});
  });
});
</script>"""

# Wide screens: boards on the left, the plot and the event log on the right, kept in view while the
# boards scroll; narrow ones: one column.
_PAGE_CSS = """
.hw-main { display: grid; grid-template-columns: minmax(0, 1fr); gap: 12px; width: 100%; }
@media (min-width: 1024px) {
  .hw-main { grid-template-columns: minmax(400px, 480px) minmax(0, 1fr); }
  .hw-side { position: sticky; top: 8px; align-self: start; }
}
@media (min-width: 1800px) { .hw-main { grid-template-columns: minmax(480px, 600px) minmax(0, 1fr); } }
.nicegui-content { padding: 8px; }
"""


def _page(feeds: Feeds) -> None:
    from nicegui import ui

    from .view_board import BoardView
    from .view_overview import EventLog, Tile
    from .view_plot import PlotPanel

    def lookup(key: str) -> Any:
        board, _, name = key.partition(".")
        feed = feeds.feeds.get(board)
        return feed.records.get(name) if feed is not None else None

    def set_rate(key: str, hz: float) -> None:
        board, _, name = key.partition(".")
        feed = feeds.feeds.get(board)
        if feed is not None and name in feed.records:
            feed.set_rate(name, hz)

    @ui.page("/", title="Hubwire dashboard")
    def index() -> None:
        ui.query("body").classes("bg-gray-100")
        ui.add_head_html(_PAGE_JS)
        ui.add_css(_PAGE_CSS)
        visible: Set[str] = set()

        def on_visible(e: Any) -> None:
            (visible.add if e.args.get("on") else visible.discard)(str(e.args.get("key")))

        ui.on("hw_visible", on_visible)
        with ui.row().classes("w-full items-center gap-x-3 gap-y-0"):
            ui.label("Hubwire").classes("text-xl font-bold")
            count = ui.label("").classes("text-sm text-gray-600").props("data-hw-boards")
        tiles_row = tag(ui.row().classes("w-full gap-2"), overview="all")
        with ui.element("div").classes("hw-main"):
            column = ui.column().classes("w-full gap-3 min-w-0")
            with column:
                empty = ui.label("no boards yet").classes("text-gray-600")
            with ui.column().classes("hw-side w-full gap-3 min-w-0"):
                plot = PlotPanel(lookup, set_rate)
                log_view = EventLog()
        views: Dict[str, BoardView] = {}
        tiles: Dict[str, Tile] = {}

        def sync() -> None:
            boards = feeds.boards()
            keys = [b.key for b in boards]
            for key in [k for k in views if k not in keys]:
                column.remove(views.pop(key).card)
                tiles_row.remove(tiles.pop(key).card)
            built = False
            for b in boards:
                feed = feeds.feeds.get(b.key)
                v = views.get(b.key)
                if v is None or v.generation != (feed.generation if feed is not None else 0):
                    if built:  # one card per refresh: the boards' sessions share this loop
                        continue
                    built = True
                    if v is not None:
                        column.remove(v.card)
                        tiles_row.remove(tiles[b.key].card)
                    link = feeds.links.setdefault(b.key, LinkRecord())
                    with column:
                        views[b.key] = BoardView(b, feed, link, plot, feeds.fleet)
                    with tiles_row:
                        tiles[b.key] = Tile(b, feed)
                    views[b.key].card.move(column, target_index=keys.index(b.key) + 1)
                    tiles[b.key].card.move(tiles_row, target_index=keys.index(b.key))
                if b.key in views:
                    views[b.key].refresh(b, visible)
                    tiles[b.key].refresh(b)
            log_view.refresh([f for f in (feeds.feeds.get(k) for k in keys) if f is not None])
            empty.set_visibility(not boards)
            count.set_text(f"{len(boards)} board{'s' if len(boards) != 1 else ''}")

        sync()
        ui.timer(VALUE_REFRESH, sync)
        ui.timer(PLOT_REFRESH, plot.refresh)


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
