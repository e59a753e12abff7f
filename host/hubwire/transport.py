"""Transports: how the hub's bytes reach one device.

A :class:`Transport` is a byte pipe the session opens on its event loop, writes frames to and gets
received bytes from through two callbacks. It may be opened again after it failed (the session
re-opens it with backoff when a USB cable comes back). :class:`SerialTransport` covers every URL
``serial.serial_for_url`` accepts; ``hubwire.testing`` wraps transports to inject faults.

Serial ports and ptys are watched with ``loop.add_reader`` on their file descriptor: the loop sleeps
until bytes arrive, with no thread and no polling per port. A URL handler without a file
descriptor (``loop://``, ...) gets one reader thread blocking in ``read()`` instead.
"""
from __future__ import annotations

import abc
import asyncio
import errno
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Dict, Optional

import serial

from .diagnose import open_error

__all__ = ["Transport", "SerialTransport", "DataCallback", "LostCallback"]

DataCallback = Callable[[bytes], None]
LostCallback = Callable[[BaseException], None]

#: bytes waiting to be written before further writes are dropped (a device that stopped reading)
MAX_WRITE_BACKLOG = 64 * 1024
READ_SIZE = 65536


class Transport(abc.ABC):
    """One device's byte pipe. :meth:`open` and :meth:`close` are called on the session's event loop
    thread, :meth:`write` from any thread (the synchronous API writes from the calling thread); the
    callbacks are made on the loop thread."""

    #: what this transport reaches (for messages)
    url: str = ""

    @abc.abstractmethod
    def open(self, loop: asyncio.AbstractEventLoop, on_data: DataCallback, on_lost: LostCallback) -> None:
        """Open the pipe; from now on call ``on_data(bytes)`` on ``loop`` for received bytes and
        ``on_lost(exc)`` once if the pipe fails. Raise ``OSError`` if it cannot be opened."""

    @abc.abstractmethod
    def write(self, data: bytes) -> None:
        """Queue ``data`` for sending without blocking (silently dropped when the pipe is closed)."""

    @abc.abstractmethod
    def close(self) -> None:
        """Close the pipe (idempotent); no callback is made after it returns."""


    @property
    def is_open(self) -> bool:
        return False


class SerialTransport(Transport):
    """Any ``serial.serial_for_url`` URL: a port (``/dev/ttyACM0``, ``COM3``), a pty, ``socket://``..."""

    def __init__(self, url: str, baudrate: int = 115200, **serial_kwargs: Any) -> None:
        self.url = url
        self.baudrate = baudrate
        self.serial_kwargs: Dict[str, Any] = serial_kwargs
        self._port: Optional[Any] = None
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._fd: Optional[int] = None
        self._raw_fd = False
        self._wbuf = bytearray()
        self._on_data: Optional[DataCallback] = None
        self._on_lost: Optional[LostCallback] = None
        self._reader: Optional[ThreadPoolExecutor] = None
        self._wlock = threading.Lock()
        self._loop_thread = 0

    @property
    def is_open(self) -> bool:
        return self._port is not None

    def open(self, loop: asyncio.AbstractEventLoop, on_data: DataCallback, on_lost: LostCallback) -> None:
        # exclusive: a second program gets a clear "in use by pid N" instead of resetting the board
        # under the first (pyserial's flock on POSIX; URL handlers ignore it)
        kw: Dict[str, Any] = {"timeout": 0, "write_timeout": 0, "exclusive": True}
        kw.update(self.serial_kwargs)
        try:
            port = serial.serial_for_url(self.url, baudrate=self.baudrate, **kw)
        except (serial.SerialException, OSError, ValueError) as e:
            raise open_error(self.url, e) from e
        try:
            port.reset_input_buffer()
        except Exception:  # noqa: BLE001 - not every URL handler supports it
            pass
        with self._wlock:
            self._port, self._loop, self._on_data, self._on_lost = port, loop, on_data, on_lost
            self._wbuf.clear()
        self._loop_thread = threading.get_ident()
        fd = _fileno(port)
        if fd is None:
            self._start_thread_reader(port)
            return
        self._fd = fd
        # the plain serial class reads with one os.read; URL handlers that filter bytes (spy://,
        # socket://) keep their own read()
        self._raw_fd = type(port).read is serial.Serial.read
        if self._raw_fd:
            os.set_blocking(fd, False)
        loop.add_reader(fd, self._readable)

    def _readable(self) -> None:
        try:
            if self._raw_fd:
                data = os.read(self._fd, READ_SIZE)  # type: ignore[arg-type]
            else:
                port = self._port
                data = port.read(max(1, port.in_waiting)) if port is not None else b""
        except BlockingIOError:
            return
        except (OSError, serial.SerialException, TypeError, AttributeError) as e:
            self._failed(e)
            return
        if not data:
            self._failed(OSError(errno.EIO, "end of file: the device went away"))
            return
        self._on_data(data)  # type: ignore[misc]

    def write(self, data: bytes) -> None:
        with self._wlock:
            port, fd = self._port, self._fd
            if port is None:
                return
            if fd is None or not self._raw_fd:
                try:
                    port.write(data)
                except (OSError, serial.SerialException) as e:
                    self._fail_soon(port, e)
                return
            if self._wbuf:
                if len(self._wbuf) < MAX_WRITE_BACKLOG:
                    self._wbuf += data
                return
            try:
                n = os.write(fd, data)
            except BlockingIOError:
                n = 0
            except OSError as e:
                self._fail_soon(port, e)
                return
            if n < len(data):
                # the rest goes when the port can take it (the loop watches for that)
                self._wbuf += data[n:]
                self._loop.call_soon_threadsafe(self._watch_writable, port)  # type: ignore[union-attr]

    def _watch_writable(self, port: Any) -> None:
        if self._port is port and self._fd is not None and self._wbuf:
            self._loop.add_writer(self._fd, self._writable)  # type: ignore[union-attr]

    def _fail_soon(self, port: Any, exc: BaseException) -> None:
        """A write failed (any thread, the write lock held): report it from the loop."""
        try:
            self._loop.call_soon_threadsafe(self._fail_if_current, port, exc)  # type: ignore[union-attr]
        except RuntimeError:  # the loop is closed: nobody to tell
            pass

    def _fail_if_current(self, port: Any, exc: BaseException) -> None:
        if self._port is port:
            self._failed(exc)

    def _writable(self) -> None:
        with self._wlock:
            try:
                n = os.write(self._fd, self._wbuf)  # type: ignore[arg-type]
            except BlockingIOError:
                return
            except OSError as e:
                self._fail_soon(self._port, e)
                return
            del self._wbuf[:n]
            if not self._wbuf:
                self._loop.remove_writer(self._fd)  # type: ignore[union-attr, arg-type]

    def _failed(self, exc: BaseException) -> None:
        cb = self._on_lost
        self.close()
        if cb is not None:
            cb(exc)

    def close(self) -> None:
        with self._wlock:
            port, self._port = self._port, None
            self._on_data = self._on_lost = None
            if self._fd is not None and self._loop is not None and not self._loop.is_closed():
                self._loop.remove_reader(self._fd)
                self._loop.remove_writer(self._fd)
            self._fd = None
            self._wbuf.clear()
        if port is not None:
            try:
                port.close()
            except Exception:  # noqa: BLE001
                pass
        if self._reader is not None:
            self._reader.shutdown(wait=False)
            self._reader = None

    # ------------------------------------------------------------ URL handlers without a descriptor

    def _start_thread_reader(self, port: Any) -> None:
        port.timeout = 0.05  # a blocking read that still notices close() promptly
        self._reader = ThreadPoolExecutor(1, thread_name_prefix="hubwire-rx")
        self._reader.submit(self._thread_read, port)

    def _thread_read(self, port: Any) -> None:
        loop = self._loop
        serial_port: Any = port  # (``port`` itself is narrowed to Optional by the loop's test)
        while self._port is port:
            try:
                data = serial_port.read(max(1, serial_port.in_waiting))
            except Exception as e:  # noqa: BLE001 - reported as a lost port
                if self._port is port:
                    loop.call_soon_threadsafe(self._thread_failed, port, e)  # type: ignore[union-attr]
                return
            if data:
                loop.call_soon_threadsafe(self._thread_data, port, data)  # type: ignore[union-attr]

    def _thread_data(self, port: Any, data: bytes) -> None:
        if self._port is port and self._on_data is not None:
            self._on_data(data)

    def _thread_failed(self, port: Any, exc: BaseException) -> None:
        if self._port is port:
            self._failed(exc)


def _fileno(port: Any) -> Optional[int]:
    try:
        fd = port.fileno()
    except Exception:  # noqa: BLE001 - AttributeError, NotImplementedError, closed ports...
        return None
    return fd if isinstance(fd, int) and fd >= 0 else None
