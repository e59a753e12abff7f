"""On-disk descriptor cache, keyed and checked by the descriptor digest the device announces.

The digest is the first 16 bytes of the descriptor's SHA-256 (PROTOCOL.md 3.1 and 7.1). The 32-bit
FNV-1a hash the hello also carries is no key here: a second descriptor with the same length and
FNV-1a hash is found in under a second, so a board could otherwise plant a tampered descriptor
that a genuine board with that hash would then be served. A file is stored only when its SHA-256
matches the digest it is filed under, and checked again on every read.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from typing import Optional, Union

__all__ = ["DescriptorCache", "default_cache_dir", "descriptor_digest", "DIGEST_SIZE"]

#: bytes of the descriptor's SHA-256 a device announces in its hello
DIGEST_SIZE = 16


def descriptor_digest(data: bytes) -> bytes:
    """The digest a device announces for the descriptor ``data``."""
    return hashlib.sha256(data).digest()[:DIGEST_SIZE]


def default_cache_dir() -> str:
    """``$HUBWIRE_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/hubwire`` or ``~/.cache/hubwire``."""
    env = os.environ.get("HUBWIRE_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "hubwire")


class DescriptorCache:
    """Descriptor bytes stored as ``sha256-<digest hex>.json``; entries are verified on read.

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

    def _path(self, digest: bytes) -> Optional[str]:
        if not self.directory:
            return None
        return os.path.join(self.directory, f"sha256-{digest.hex()}.json")

    def get(self, digest: bytes, length: int) -> Optional[bytes]:
        """The cached descriptor of this digest and length, or None (missing or not matching)."""
        path = self._path(digest)
        if path is None:
            return None
        try:
            with open(path, "rb") as fh:
                data = fh.read(length + 1)
        except OSError:
            return None
        if len(data) != length or descriptor_digest(data) != digest:
            return None
        return data

    def put(self, digest: bytes, data: bytes) -> bool:
        """Store ``data`` under ``digest`` (atomically) when it is the descriptor of that digest;
        returns whether it was stored (False also when the cache cannot be written)."""
        path = self._path(digest)
        if path is None or descriptor_digest(data) != digest:
            return False
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
            return False
        return True
