"""On-disk descriptor cache, keyed by the descriptor's FNV-1a hash and length."""
from __future__ import annotations

import os
import tempfile
from typing import Optional, Union

from .wire.messages import fnv1a32

__all__ = ["DescriptorCache", "default_cache_dir"]


def default_cache_dir() -> str:
    """``$HUBWIRE_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/hubwire`` or ``~/.cache/hubwire``."""
    env = os.environ.get("HUBWIRE_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "hubwire")


class DescriptorCache:
    """Descriptor bytes stored as ``<hash>-<length>.json``; entries are verified on read.

    ``directory=None`` uses :func:`default_cache_dir`; ``directory=False`` disables caching.
    A cache that cannot be written (read-only home, ...) is silently skipped.
    """

    def __init__(self, directory: Union[str, None, bool] = None) -> None:
        if directory is False:
            self.directory: Optional[str] = None
        elif directory is None or directory is True:
            self.directory = default_cache_dir()
        else:
            self.directory = str(directory)

    def _path(self, hash: int, length: int) -> Optional[str]:
        if not self.directory:
            return None
        return os.path.join(self.directory, f"{hash:08x}-{length}.json")

    def get(self, hash: int, length: int) -> Optional[bytes]:
        """Cached descriptor with this hash and length, or None (missing or corrupt)."""
        path = self._path(hash, length)
        if path is None:
            return None
        try:
            with open(path, "rb") as fh:
                data = fh.read(length + 1)
        except OSError:
            return None
        if len(data) != length or fnv1a32(data) != hash:
            return None
        return data

    def put(self, data: bytes) -> None:
        """Store a descriptor (atomically; errors are ignored)."""
        path = self._path(fnv1a32(data), len(data))
        if path is None:
            return
        try:
            os.makedirs(self.directory, exist_ok=True)  # type: ignore[arg-type]
            fd, tmp = tempfile.mkstemp(dir=self.directory, suffix=".tmp")
            try:
                with os.fdopen(fd, "wb") as fh:
                    fh.write(data)
                os.replace(tmp, path)
            except BaseException:
                os.unlink(tmp)
                raise
        except OSError:
            pass
