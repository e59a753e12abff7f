"""A device's channels as the hub knows them: ``model`` (:class:`Channel`, :class:`Descriptor`),
``parse`` (:func:`parse_descriptor`, which checks every field) and ``cache`` (descriptors on disk,
keyed by their SHA-256 digest)."""
from __future__ import annotations

from .model import MAX_DEPTH, MAX_DESCRIPTOR_SIZE, MAX_VALUE, Channel, Descriptor
from .parse import parse_descriptor

__all__ = ["MAX_DESCRIPTOR_SIZE", "MAX_DEPTH", "MAX_VALUE", "Channel", "Descriptor", "parse_descriptor"]
