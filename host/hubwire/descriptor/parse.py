"""Parsing and validating descriptor JSON (PROTOCOL.md §7): :func:`parse_descriptor` builds a
:class:`hubwire.descriptor.Descriptor` or raises :class:`DescriptorError` naming the offending place."""
from __future__ import annotations

import json
import math
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

from .model import (ACCESS_LETTERS, CHANNEL_KEYS, FIELD_KEYS, MAX_DEPTH, MAX_DESCRIPTOR_SIZE, MAX_LIST, MAX_VALUE,
                         NAME_MAX, NAME_RE, TOP_KEYS, Channel, Descriptor)
from ..errors import DescriptorError, InvalidValue
from ..text import clip, clip_json, clip_list
from ..wire.frame import PROTOCOL_MAX_PAYLOAD
from ..wire.messages import PROTOCOL_VERSION, fnv1a32
from ..wire.scalars import INTEGER_TYPES, NUMERIC_TYPES
from ..wire.values import SCALARS, Codec, codec_for

__all__ = ["parse_descriptor"]


def _fail(where: str, msg: str) -> DescriptorError:
    return DescriptorError(f"descriptor {where}: {msg}" if where else f"descriptor: {msg}")


def _json_depth(text: str) -> int:
    """Deepest bracket nesting of a JSON text, ignoring brackets inside strings."""
    depth = best = 0
    in_str = esc = False
    for ch in text:
        if in_str:
            if esc:
                esc = False
            elif ch == "\\":
                esc = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            if depth > best:
                best = depth
        elif ch in "]}":
            depth -= 1
    return best


def _no_duplicates(pairs: List[Tuple[str, Any]]) -> Dict[str, Any]:
    d: Dict[str, Any] = {}
    for k, v in pairs:
        if k in d:
            raise _DuplicateKey(k)
        d[k] = v
    return d


class _DuplicateKey(ValueError):
    pass


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not valid JSON")


def _object(where: str, obj: Any, keys: Any, what: str, hint: str = "") -> None:
    """``obj`` must be a JSON object with no key outside ``keys``."""
    if not isinstance(obj, dict):
        raise _fail(where, f"a {what} must be an object, got {clip_json(obj)}")
    extra = set(obj) - keys
    if extra:
        raise _fail(where, f"unknown key(s) {clip_list(sorted(map(clip, extra)))}{hint}")


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool)) and math.isfinite(v)


def _name(where: str, obj: Mapping[str, Any], what: str) -> str:
    if "n" not in obj:
        raise _fail(where, f"{what} has no name (key 'n')")
    n = obj["n"]
    if not isinstance(n, str):
        raise _fail(where, f"{what} name must be a string, got {clip_json(n)}")
    if len(n) > NAME_MAX:
        raise _fail(where, f"{what} name {clip(n)} is longer than {NAME_MAX} characters")
    if not NAME_RE.match(n):
        raise _fail(where, f"{what} name {clip(n)} must match [A-Za-z_][A-Za-z0-9_]*")
    return n


def _count(where: str, obj: Mapping[str, Any], key: str, maximum: int, what: str) -> Optional[int]:
    if key not in obj:
        return None
    c = obj[key]
    if not _is_int(c) or not 1 <= c <= maximum:
        raise _fail(where, f"{what} '{key}' must be an integer 1..{maximum}, got {clip_json(c)}")
    return int(c)


def _type_obj(where: str, t: Any, c_obj: Mapping[str, Any], ckey: str, allow: Tuple[str, ...],
              vkey: str = "") -> Dict[str, Any]:
    """Validate a (t, c) pair, or (t, vc) where ``vkey`` names the variable-length count that is
    allowed here; ``allow`` lists the non-scalar type names allowed here."""
    if not isinstance(t, str):
        raise _fail(where, f"type must be a string, got {clip_json(t)}")
    if vkey and vkey in c_obj:
        if t not in SCALARS:
            raise _fail(where, f"a variable-length array '{vkey}' needs a scalar type, not {clip(t)}")
        if ckey in c_obj:
            raise _fail(where, f"'{ckey}' and '{vkey}' exclude each other (fixed or variable length)")
        return {"t": t, "vc": _count(where, c_obj, vkey, MAX_LIST, "variable-length array capacity")}
    if t in SCALARS:
        c = _count(where, c_obj, ckey, MAX_VALUE, "array count")
        out: Dict[str, Any] = {"t": t}
        if c is not None:
            if c * SCALARS[t][1] > MAX_VALUE:
                raise _fail(where, f"{t}[{c}] is {c * SCALARS[t][1]} bytes, more than the largest value, {MAX_VALUE}")
            out["c"] = c
        return out
    if t not in allow:
        known = ", ".join(list(SCALARS) + list(allow))
        if t in ("str", "struct", "void"):
            raise _fail(where, f"type {clip(t)} is not allowed here (allowed: {known})")
        raise _fail(where, f"unknown type {clip(t)} (known: {known})")
    if t == "str":
        if ckey not in c_obj:
            raise _fail(where, f"type 'str' needs a capacity '{ckey}'")
        c = _count(where, c_obj, ckey, PROTOCOL_MAX_PAYLOAD - 1, "string capacity")
        return {"t": "str", "c": c}
    if t == "void":
        if ckey in c_obj:
            raise _fail(where, f"type 'void' takes no count '{ckey}'")
        return {"t": "void"}
    raise _fail(where, f"type {clip(t)} is not allowed here")  # struct handled by caller


def _fields(where: str, ch: Mapping[str, Any]) -> List[Dict[str, Any]]:
    if "f" not in ch:
        raise _fail(where, "a struct needs its fields 'f'")
    if "c" in ch or "vc" in ch:
        raise _fail(where, "a struct channel takes no count 'c'/'vc' (arrays of structs are not supported)")
    fs = ch["f"]
    if not isinstance(fs, list) or not fs:
        raise _fail(where, "struct fields 'f' must be a non-empty list")
    out = []
    names = set()
    size = 0
    for i, f in enumerate(fs):
        fw = f"{where}.f[{i}]"
        _object(fw, f, FIELD_KEYS, "field", " (allowed: n, t, c)")
        n = _name(fw, f, "field")
        fw = f"{where}.f[{i}] ({clip(n)})"
        if n in names:
            raise _fail(fw, f"duplicate field name {clip(n)}")
        names.add(n)
        if "t" not in f:
            raise _fail(fw, "field has no type 't'")
        to = _type_obj(fw, f["t"], f, "c", ())
        size += SCALARS[to["t"]][1] * to.get("c", 1)
        out.append({"n": n, **to})
    if size > MAX_VALUE:
        raise _fail(where, f"struct is {size} bytes, more than the largest value, {MAX_VALUE}")
    return out


def _access(where: str, ch: Mapping[str, Any]) -> str:
    a = ch.get("a")
    if not isinstance(a, str) or not a:
        raise _fail(where, f"access 'a' must be a non-empty string of {ACCESS_LETTERS}, got {clip_json(a)}")
    bad = [x for x in a if x not in ACCESS_LETTERS]
    if bad:
        raise _fail(where, f"unknown access letter(s) {clip(''.join(bad))} in {clip(a)} (r readable, w writable, c callable, e event, s streamable, m mission)")
    if len(set(a)) != len(a):
        raise _fail(where, f"repeated access letter in {clip(a)}")
    if "s" in a and "r" not in a:
        raise _fail(where, f"access {clip(a)}: streamable 's' requires readable 'r'")
    if "w" in a and "c" in a:
        raise _fail(where, f"access {clip(a)}: writable 'w' and callable 'c' exclude each other")
    if "e" in a and a != "e":
        raise _fail(where, f"access {clip(a)}: event 'e' stands alone")
    if "m" in a and a != "m":
        raise _fail(where, f"access {clip(a)}: mission 'm' stands alone")
    return a


def _channel_type(where: str, ch: Mapping[str, Any], name: str, a: str) -> Tuple[Dict[str, Any], Codec, Optional[Codec]]:
    """The type object, codec and (callables) return codec of a channel."""
    callable_ = "c" in a or "m" in a  # a mission's goal and result are typed as a call's
    if "t" not in ch:
        raise _fail(where, "channel has no type 't'")
    t = ch["t"]
    if t == "struct":
        type_obj: Dict[str, Any] = {"t": "struct", "f": _fields(where, ch)}  # a struct argument is fine
    else:
        if "f" in ch:
            raise _fail(where, "fields 'f' are only for type 'struct'")
        allow = ("str", "struct", "void") if callable_ else ("str", "struct")
        type_obj = _type_obj(where, t, ch, "c", allow, "vc")
    returns = None
    if "rt" in ch or "rc" in ch or "rvc" in ch:
        if not callable_:
            raise _fail(where, "return type 'rt'/'rc'/'rvc' is only for callable channels and missions")
        if "rt" not in ch:
            raise _fail(where, "'rc'/'rvc' given without a return type 'rt'")
        rto = _type_obj(where + " return", ch["rt"], ch, "rc", ("void",) if "m" in a else ("str", "void"), "rvc")
        returns = codec_for(rto, where=f"{name} return value", class_name=f"{name}_result")
    elif callable_:
        returns = codec_for({"t": "void"})
    codec = codec_for(type_obj, where=name, class_name=name)
    if "s" in a and codec.max_size + 2 > MAX_VALUE:
        raise _fail(where, f"a streamable value of {codec.max_size} bytes does not fit a sample frame")
    return type_obj, codec, returns


def _progress(where: str, ch: Mapping[str, Any], name: str, a: str) -> Tuple[Optional[Codec], Optional[float]]:
    """A mission's progress codec (void when ``pt`` is absent) and ``pmax``; None for other channels."""
    keys = [k for k in ("pt", "pc", "pmax") if k in ch]
    if "m" not in a:
        if keys:
            raise _fail(where, f"{clip_list(keys)}: progress keys are only for missions (access 'm')")
        return None, None
    if "pc" in ch and "pt" not in ch:
        raise _fail(where, "'pc' given without a progress type 'pt'")
    pto = _type_obj(where + " progress", ch["pt"], ch, "pc", ("void",)) if "pt" in ch else {"t": "void"}
    pmax = ch.get("pmax")
    if pmax is not None and not _is_num(pmax):
        raise _fail(where, f"'pmax' must be a number, got {clip_json(pmax)}")
    codec = codec_for(pto, where=f"{name} progress", class_name=f"{name}_progress")
    if codec.max_size + 2 > PROTOCOL_MAX_PAYLOAD:
        raise _fail(where, f"a progress value of {codec.max_size} bytes does not fit a mission update")
    return codec, pmax


def _text(where: str, ch: Mapping[str, Any], key: str, what: str) -> Optional[str]:
    v = ch.get(key)
    if v is not None and not isinstance(v, str):
        raise _fail(where, f"{what} '{key}' must be a string, got {clip_json(v)}")
    return v


def _range(where: str, ch: Mapping[str, Any], a: str, codec: Codec) -> Tuple[Any, Any]:
    lo, hi = ch.get("min"), ch.get("max")
    if lo is None and hi is None:
        return lo, hi
    if "e" in a or codec.scalar not in NUMERIC_TYPES or codec.kind not in ("scalar", "array", "list"):
        raise _fail(where, f"'min'/'max' are only for numeric types, not {codec.name}")
    for key, v in (("min", lo), ("max", hi)):
        if v is None:
            continue
        if not _is_num(v):
            raise _fail(where, f"'{key}' must be a number, got {clip_json(v)}")
        if codec.scalar in INTEGER_TYPES:
            _, _, tlo, thi = SCALARS[codec.scalar]
            if not tlo <= v <= thi:
                raise _fail(where, f"'{key}' {v} is outside the {codec.scalar} range {tlo}..{thi}")
    if lo is not None and hi is not None and lo > hi:
        raise _fail(where, f"'min' {lo} is greater than 'max' {hi}")
    return lo, hi


def _failsafe(where: str, ch: Mapping[str, Any], a: str, codec: Codec, type_obj: Mapping[str, Any]) -> Any:
    if "fs" not in ch:
        return None
    if "e" in a or "c" in a or "m" in a:
        raise _fail(where, "a failsafe value 'fs' is only for readable/writable channels")
    raw_fs = ch["fs"]
    try:
        value: Any = raw_fs
        if _is_num(value) or isinstance(value, bool):
            # a single number for an array or struct sets every element (as a device may write it)
            if codec.kind == "array":
                value = [value] * codec.count  # type: ignore[attr-defined]
            elif codec.kind == "struct":
                value = {f["n"]: ([value] * f["c"] if "c" in f else value) for f in type_obj["f"]}
        return codec.check(codec.from_json(value))
    except (InvalidValue, TypeError) as e:
        raise _fail(where, f"failsafe 'fs' {clip_json(raw_fs)} does not fit {codec.name}: {e}") from None


def _parse_channel(i: int, ch: Any, key: str = "ch") -> Channel:
    where = f"{key}[{i}]"
    _object(where, ch, CHANNEL_KEYS, "channel")
    name = _name(where, ch, "channel")
    where = f"{key}[{i}] ({clip(name)})"
    if "id" not in ch:
        raise _fail(where, "channel has no 'id'")
    cid = ch["id"]
    if not _is_int(cid) or not 1 <= cid <= 255:
        raise _fail(where, f"'id' must be an integer 1..255, got {clip_json(cid)}")
    a = _access(where, ch)
    if key == "hub" and ("s" in a or "m" in a):
        raise _fail(where, f"access {clip(a)}: a hub channel is not {'streamable' if 's' in a else 'a mission'}")
    type_obj, codec, returns = _channel_type(where, ch, name, a)
    unit = _text(where, ch, "u", "unit")
    desc = _text(where, ch, "d", "description")
    lo, hi = _range(where, ch, a, codec)
    fs = _failsafe(where, ch, a, codec, type_obj)
    progress, pmax = _progress(where, ch, name, a)
    if "m" in a and returns is not None and returns.max_size + 2 > PROTOCOL_MAX_PAYLOAD:
        raise _fail(where, f"a result of {returns.max_size} bytes does not fit a mission update")
    if "m" in a and codec.max_size + 1 > PROTOCOL_MAX_PAYLOAD:
        raise _fail(where, f"a goal of {codec.max_size} bytes does not fit a start (op byte + goal)")
    return Channel(id=cid, name=name, access=a, codec=codec, type=type_obj, unit=unit, min=lo, max=hi, failsafe=fs,
                   description=desc, returns=returns, progress=progress, progress_max=pmax)


def parse_descriptor(data: Union[bytes, bytearray, str]) -> Descriptor:
    """Parse and validate a descriptor; raise :class:`DescriptorError` on any defect."""
    if isinstance(data, str):
        raw = data.encode("utf-8")
        text = data
    elif isinstance(data, (bytes, bytearray, memoryview)):
        raw = bytes(data)
        if len(raw) > MAX_DESCRIPTOR_SIZE:
            raise _fail("", f"{len(raw)} bytes exceeds the hub's limit of {MAX_DESCRIPTOR_SIZE} bytes")
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as e:
            raise _fail("", f"is not valid UTF-8 ({e.reason} at byte {e.start})") from None
    else:
        raise TypeError("descriptor must be bytes or str")
    if len(raw) > MAX_DESCRIPTOR_SIZE:
        raise _fail("", f"{len(raw)} bytes exceeds the hub's limit of {MAX_DESCRIPTOR_SIZE} bytes")
    depth = _json_depth(text)
    if depth > MAX_DEPTH:
        raise _fail("", f"nests {depth} levels deep; the format allows at most {MAX_DEPTH}")
    try:
        doc = json.loads(text, object_pairs_hook=_no_duplicates, parse_constant=_reject_constant)
    except _DuplicateKey as e:
        raise _fail("", f"duplicate key {clip(e.args[0])} in an object") from None
    except (ValueError, RecursionError) as e:
        raise _fail("", f"is not valid JSON ({e})") from None
    if not isinstance(doc, dict):
        raise _fail("", f"must be a JSON object, got {type(doc).__name__}")
    extra = set(doc) - TOP_KEYS
    if extra:
        raise _fail("", f"unknown top-level key(s) {clip_list(sorted(map(clip, extra)))} (allowed: p, n, fw, ch, hub)")
    p = doc.get("p")
    if not _is_int(p):
        raise _fail("", f"protocol version 'p' must be an integer, got {clip_json(p)}")
    if p != PROTOCOL_VERSION:
        raise _fail("", f"protocol version 'p' is {p}, this hub reads version {PROTOCOL_VERSION}")
    name = doc.get("n")
    if not isinstance(name, str):
        raise _fail("", f"device name 'n' must be a string, got {clip_json(name)}")
    fw = doc.get("fw")
    if fw is not None and not isinstance(fw, str):
        raise _fail("", f"firmware version 'fw' must be a string, got {clip_json(fw)}")
    channels = _channel_list(doc, "ch")
    hub = _channel_list(doc, "hub") if "hub" in doc else ()
    return Descriptor(protocol=p, name=name, firmware=fw, channels=channels, raw=raw, hash=fnv1a32(raw), hub=hub)


def _channel_list(doc: Mapping[str, Any], key: str) -> Tuple[Channel, ...]:
    """The channels under ``key``: "ch" (ids unique), or "hub" (hub ids 1..N in order)."""
    chs = doc.get(key)
    if not isinstance(chs, list):
        raise _fail("", f"channels '{key}' must be a list, got {clip_json(chs)}")
    channels: List[Channel] = []
    ids: Dict[int, str] = {}
    names: Dict[str, int] = {}
    for i, ch in enumerate(chs):
        c = _parse_channel(i, ch, key)
        if key == "hub" and c.id != i + 1:
            raise _fail(f"hub[{i}] ({clip(c.name)})", f"hub id must be {i + 1} (1..N in order), got {c.id}")
        if c.id in ids:
            raise _fail(f"{key}[{i}] ({clip(c.name)})", f"duplicate channel id {c.id} (also used by {clip(ids[c.id])})")
        if c.name in names:
            raise _fail(f"{key}[{i}]", f"duplicate channel name {clip(c.name)} (ids {names[c.name]} and {c.id})")
        ids[c.id] = c.name
        names[c.name] = c.id
        channels.append(c)
    return tuple(channels)
