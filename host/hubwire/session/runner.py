"""Threads of the synchronous API: the one shared event loop, and each session's callback thread.

Every session a process opens through the synchronous API runs on one asyncio event loop, in one
daemon thread (``hubwire-loop``) that exists while at least one such session is open. Application
callbacks never run on that loop: each session hands them to its own dispatcher thread
(``hubwire-dispatch``), so a callback may itself make calls on the device.
"""
from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import queue
import threading
from typing import Any, Awaitable, Callable, Optional, Set, Tuple, TypeVar

__all__ = ["acquire_loop", "release_loop", "run_sync", "on_loop_thread", "running_loop", "run_handler",
           "ThreadDispatcher", "LoopDispatcher"]

log = logging.getLogger("hubwire")
T = TypeVar("T")

_lock = threading.Lock()
_loop: Optional[asyncio.AbstractEventLoop] = None
_thread: Optional[threading.Thread] = None
_users = 0


def acquire_loop() -> asyncio.AbstractEventLoop:
    """The shared loop (started on first use); pair every call with :func:`release_loop`."""
    global _loop, _thread, _users
    with _lock:
        if _loop is None:
            loop = asyncio.new_event_loop()
            started = threading.Event()

            def run() -> None:
                asyncio.set_event_loop(loop)
                loop.call_soon(started.set)
                loop.run_forever()

            _thread = threading.Thread(target=run, name="hubwire-loop", daemon=True)
            _thread.start()
            started.wait()
            _loop = loop
        _users += 1
        return _loop


def release_loop() -> None:
    """One user fewer; the loop and its thread stop with the last one."""
    global _loop, _thread, _users
    with _lock:
        _users -= 1
        if _users > 0 or _loop is None:
            return
        loop, thread, _loop, _thread = _loop, _thread, None, None
    loop.call_soon_threadsafe(loop.stop)
    if thread is not None and thread is not threading.current_thread():
        thread.join(5)
        loop.close()


def on_loop_thread() -> bool:
    """True on the shared loop's thread."""
    return _thread is threading.current_thread()


def run_sync(loop: asyncio.AbstractEventLoop, aw: Awaitable[T]) -> T:
    """Run a coroutine on ``loop`` from another thread and return its result (or raise)."""
    if on_loop_thread():
        raise RuntimeError("hubwire: a synchronous call cannot be made on the hub's event loop thread")
    fut: "concurrent.futures.Future[T]" = asyncio.run_coroutine_threadsafe(aw, loop)  # type: ignore[arg-type]
    try:
        return fut.result()
    except BaseException:
        fut.cancel()
        raise


def running_loop() -> Optional[asyncio.AbstractEventLoop]:
    """The loop running in this thread, or None."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def run_handler(loop: asyncio.AbstractEventLoop, dispatch: Callable[[Callable[[], None]], None],
                fn: Callable[..., Any], args: Tuple[Any, ...], finish: Callable[[bool, Any], None]) -> None:
    """Run application handler ``fn(*args)`` through ``dispatch`` (where callbacks run; a coroutine
    it returns is awaited on ``loop``), then ``finish(True, result)`` or ``finish(False, exception)``
    on ``loop``: the hub's answer to a board's request waits for the handler, never in it."""

    def settle(fut: Any) -> None:
        exc = fut.exception()
        loop.call_soon_threadsafe(finish, exc is None, exc if exc is not None else fut.result())

    def call() -> None:
        try:
            res = fn(*args)
        except Exception as e:  # noqa: BLE001 - the handler's failure is the board's answer
            loop.call_soon_threadsafe(finish, False, e)
            return
        if asyncio.iscoroutine(res):
            task: Any = loop.create_task(res) if running_loop() is loop else asyncio.run_coroutine_threadsafe(res, loop)
            task.add_done_callback(settle)
            return
        loop.call_soon_threadsafe(finish, True, res)
    dispatch(call)


class ThreadDispatcher:
    """Runs callbacks in order on a thread of their own (``hubwire-dispatch``)."""

    def __init__(self) -> None:
        self._q: "queue.Queue[Optional[Tuple[Callable[..., Any], Tuple[Any, ...]]]]" = queue.Queue()
        self._thread = threading.Thread(target=self._run, name="hubwire-dispatch", daemon=True)
        self._thread.start()

    def __call__(self, fn: Callable[..., Any], *args: Any) -> None:
        self._q.put((fn, args))

    def pending(self) -> int:
        return self._q.qsize()

    def _run(self) -> None:
        while True:
            item = self._q.get()
            if item is None:
                return
            fn, args = item
            try:
                fn(*args)
            except Exception:  # noqa: BLE001 - an application callback must not kill the hub
                log.exception("hubwire: callback %r raised", fn)

    def stop(self) -> None:
        self._q.put(None)
        if self._thread is not threading.current_thread():
            self._thread.join(2.0)


class LoopDispatcher:
    """Runs callbacks on the session's own loop (the asyncio API); coroutine results become tasks."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._waiting = 0
        self._tasks: "Set[asyncio.Task[Any]]" = set()

    def __call__(self, fn: Callable[..., Any], *args: Any) -> None:
        self._waiting += 1
        self._loop.call_soon(self._run, fn, args)

    def pending(self) -> int:
        return self._waiting

    def _run(self, fn: Callable[..., Any], args: Tuple[Any, ...]) -> None:
        self._waiting -= 1
        try:
            res = fn(*args)
        except Exception:  # noqa: BLE001
            log.exception("hubwire: callback %r raised", fn)
            return
        if asyncio.iscoroutine(res):
            task = self._loop.create_task(res)
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    def stop(self) -> None:
        pass
