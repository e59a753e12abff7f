#!/usr/bin/env python3
"""Check Hubwire's package manifests, offline.

  python3 tools/check_manifests.py [--root DIR] [--online]

1. library.json and library.properties must pass PlatformIO's own manifest parser and schema
   (ManifestParserFactory + ManifestSchema, from `pip install platformio`). The schema wants the
   SPDX licence list from the network; offline (the default) a short built-in list of common SPDX
   identifiers stands in for it. --online uses the real list.
2. Our own rules: names, architectures=*, category Communication, includes/headers = Hubwire.h
   (and the header exists), srcDir src, the same version in library.json, library.properties and
   host/pyproject.toml (if present).
3. platformio.ini: parsed with configparser (and PlatformIO's ProjectConfig when available); the
   required environments exist and are set up for this library.
4. What users install (tools/check_package.py): LICENSE, export.include, the tree packed as
   `pio pkg pack` packs it and the Arduino IDE zip (tools/dist.py) holding only library files,
   install instructions that name things that exist.

Exit status 0 when everything holds; 1 with one line per problem otherwise.
"""

import argparse
import configparser
import json
import os
import re
import sys

LIB_NAME = "Hubwire"
HEADER = "Hubwire.h"
CATEGORY = "Communication"
PROPERTIES_REQUIRED = (
    "name",
    "version",
    "author",
    "maintainer",
    "sentence",
    "paragraph",
    "category",
    "url",
    "architectures",
)
# env name -> (platform, board) requirements; board None = any
REQUIRED_ENVS = {
    "native": ("native", None),
    "uno": ("atmelavr", "uno"),
    "megaatmega2560": ("atmelavr", "megaatmega2560"),
    "leonardo": ("atmelavr", "leonardo"),
    "teensy41": ("teensy", "teensy41"),
    "esp32dev": ("espressif32", "esp32dev"),
}
# at least one env on each of these platforms (any name)
REQUIRED_PLATFORMS = {
    "ststm32": "an STM32 board (e.g. nucleo_f401re)",
    "raspberrypi": "a Raspberry Pi Pico (RP2040)",
}
# Offline stand-in for https://spdx.org/licenses/ (only used when not --online).
OFFLINE_SPDX = (
    "MIT", "Apache-2.0", "BSD-2-Clause", "BSD-3-Clause", "ISC", "Zlib", "Unlicense", "0BSD",
    "MPL-2.0", "GPL-2.0-only", "GPL-2.0-or-later", "GPL-3.0-only", "GPL-3.0-or-later",
    "LGPL-2.1-only", "LGPL-2.1-or-later", "LGPL-3.0-only", "LGPL-3.0-or-later", "CC0-1.0",
)

SEMVER_RE = re.compile(r"^\d+\.\d+\.\d+(?:-[0-9A-Za-z.-]+)?(?:\+[0-9A-Za-z.-]+)?$")


class Checker:
    def __init__(self, root):
        self.root = root
        self.errors = []
        self.notes = []

    def error(self, where, msg):
        self.errors.append(f"{where}: {msg}")

    def note(self, msg):
        self.notes.append(msg)

    def path(self, *parts):
        return os.path.join(self.root, *parts)


# ---- PlatformIO parsers ------------------------------------------------------------------------
def load_platformio(online):
    try:
        from platformio.package.manifest.parser import ManifestParserFactory
        from platformio.package.manifest.schema import ManifestSchema
    except ImportError:
        return None, None
    if not online:
        # staticmethod on the class: replaces the network fetch of the SPDX list
        ManifestSchema.load_spdx_licenses = staticmethod(
            lambda: {"licenses": [{"licenseId": i} for i in OFFLINE_SPDX]}
        )
    return ManifestParserFactory, ManifestSchema


def pio_validate(ck, fname, factory, schema):
    path = ck.path(fname)
    try:
        raw = factory.new_from_file(path).as_dict()
        return schema().load_manifest(raw)
    except Exception as exc:  # ManifestParserError, ManifestValidationError, OSError
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        ck.error(fname, f"PlatformIO rejects it: {type(exc).__name__}: {msg}")
        return None


# ---- library.properties ------------------------------------------------------------------------
def read_properties(ck):
    fname = "library.properties"
    props = {}
    try:
        with open(ck.path(fname), encoding="utf-8") as f:
            for n, line in enumerate(f, 1):
                line = line.rstrip("\r\n")
                if not line.strip() or line.lstrip().startswith("#"):
                    continue
                if "=" not in line:
                    ck.error(fname, f"line {n}: not key=value: {line!r}")
                    continue
                key, value = line.split("=", 1)
                key = key.strip()
                if key in props:
                    ck.error(fname, f"line {n}: duplicate key {key}")
                props[key] = value.strip()
    except OSError as exc:
        ck.error(fname, f"cannot read: {exc}")
        return None
    return props


def check_properties(ck, props):
    fname = "library.properties"
    for key in PROPERTIES_REQUIRED:
        if not props.get(key):
            ck.error(fname, f"missing required field {key}=")
    if props.get("name") != LIB_NAME:
        ck.error(fname, f"name must be {LIB_NAME}, not {props.get('name')!r}")
    if props.get("architectures") != "*":
        ck.error(fname, f"architectures must be *, not {props.get('architectures')!r}")
    if props.get("category") != CATEGORY:
        ck.error(fname, f"category must be {CATEGORY}, not {props.get('category')!r}")
    if props.get("includes") != HEADER:
        ck.error(fname, f"includes must be {HEADER}, not {props.get('includes')!r}")
    version = props.get("version", "")
    if version and not SEMVER_RE.match(version):
        ck.error(fname, f"version {version!r} is not semver (MAJOR.MINOR.PATCH)")
    url = props.get("url", "")
    if url and not url.startswith(("http://", "https://")):
        ck.error(fname, f"url must be http(s): {url!r}")
    # 1.5 layout: sources under src/, not also in the root or utility/
    if os.path.isdir(ck.path("utility")):
        ck.error(fname, "1.5 layout: utility/ must not exist next to src/")


# ---- library.json ------------------------------------------------------------------------------
def as_list(value):
    if value is None:
        return []
    if isinstance(value, str):
        return [v.strip() for v in value.split(",") if v.strip()]
    return list(value)


def check_library_json(ck):
    fname = "library.json"
    try:
        with open(ck.path(fname), encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as exc:
        ck.error(fname, f"cannot read JSON: {exc}")
        return None
    if data.get("name") != LIB_NAME:
        ck.error(fname, f"name must be {LIB_NAME}, not {data.get('name')!r}")
    version = str(data.get("version", ""))
    if not SEMVER_RE.match(version):
        ck.error(fname, f"version {version!r} is not semver")
    if "arduino" not in as_list(data.get("frameworks")):
        ck.error(fname, "frameworks must include arduino")
    if as_list(data.get("platforms")) != ["*"]:
        ck.error(fname, f"platforms must be \"*\", not {data.get('platforms')!r}")
    if HEADER not in as_list(data.get("headers")):
        ck.error(fname, f"headers must include {HEADER}")
    if not as_list(data.get("keywords")):
        ck.error(fname, "keywords missing")
    repo = data.get("repository") or {}
    if not isinstance(repo, dict) or not repo.get("url") or not repo.get("type"):
        ck.error(fname, "repository {type, url} missing")
    build = data.get("build") or {}
    if build.get("srcDir") != "src":
        ck.error(fname, f"build.srcDir must be src, not {build.get('srcDir')!r}")
    return data


# ---- cross-file rules --------------------------------------------------------------------------
def pyproject_version(ck):
    path = ck.path("host", "pyproject.toml")
    if not os.path.exists(path):
        return None
    try:
        import tomllib  # Python 3.11+

        with open(path, "rb") as f:
            return str(tomllib.load(f).get("project", {}).get("version"))
    except ImportError:
        pass
    except Exception as exc:
        ck.error("host/pyproject.toml", f"cannot parse: {exc}")
        return None
    # Python < 3.11: the [project] table's version line
    section = None
    with open(path, encoding="utf-8") as f:
        for line in f:
            s = line.strip()
            if s.startswith("["):
                section = s
            elif section == "[project]":
                m = re.match(r'version\s*=\s*["\']([^"\']+)["\']', s)
                if m:
                    return m.group(1)
    return None


def check_cross(ck, props, data):
    versions = {}
    if props and props.get("version"):
        versions["library.properties"] = props["version"]
    if data and data.get("version"):
        versions["library.json"] = str(data["version"])
    pv = pyproject_version(ck)
    if pv is not None:
        versions["host/pyproject.toml"] = pv
    if len(set(versions.values())) > 1:
        ck.error("versions", "differ: " + ", ".join(f"{k}={v}" for k, v in versions.items()))
    if not os.path.isfile(ck.path("src", HEADER)):
        ck.error("src", f"src/{HEADER} (named by includes= and headers) does not exist")
    ck.note("version " + ", ".join(f"{k}={v}" for k, v in versions.items()))


# ---- platformio.ini ----------------------------------------------------------------------------
def resolve(cp, section, option, seen=None):
    """Value of option in section, following PlatformIO's [env] defaults and extends=."""
    seen = seen or set()
    if section in seen:
        return None
    seen.add(section)
    if cp.has_option(section, option):
        return cp.get(section, option)
    if cp.has_option(section, "extends"):
        for parent in re.split(r"[,\s]+", cp.get(section, "extends").strip()):
            if parent:
                value = resolve(cp, parent, option, seen)
                if value is not None:
                    return value
    if section.startswith("env:") and cp.has_section("env") and cp.has_option("env", option):
        return cp.get("env", option)
    return None


def check_platformio_ini(ck):
    fname = "platformio.ini"
    path = ck.path(fname)
    if not os.path.exists(path):
        ck.error(fname, "missing")
        return
    cp = configparser.ConfigParser(
        interpolation=None, inline_comment_prefixes=(";", "#"), strict=True
    )
    try:
        cp.read(path, encoding="utf-8")
    except configparser.Error as exc:
        ck.error(fname, f"cannot parse: {exc}".splitlines()[0])
        return
    envs = [s[4:] for s in cp.sections() if s.startswith("env:")]
    for env, (platform, board) in REQUIRED_ENVS.items():
        sec = "env:" + env
        if env not in envs:
            ck.error(fname, f"[{sec}] missing")
            continue
        got = resolve(cp, sec, "platform")
        if got is None or got.split("@")[0].strip() != platform:
            ck.error(fname, f"[{sec}] platform must be {platform}, not {got!r}")
        if board and resolve(cp, sec, "board") != board:
            ck.error(fname, f"[{sec}] board must be {board}, not {resolve(cp, sec, 'board')!r}")
    for platform, what in REQUIRED_PLATFORMS.items():
        if not any(
            (resolve(cp, "env:" + e, "platform") or "").split("@")[0].strip().endswith(platform)
            for e in envs
        ):
            ck.error(fname, f"no env with platform {platform} ({what})")
    for e in envs:
        sec = "env:" + e
        platform = (resolve(cp, sec, "platform") or "").strip()
        if platform == "native":
            if resolve(cp, sec, "test_framework") != "googletest":
                ck.error(fname, f"[{sec}] test_framework must be googletest")
            if "arduino" in (resolve(cp, sec, "framework") or ""):
                ck.error(fname, f"[{sec}] must not use the arduino framework")
            continue
        if (resolve(cp, sec, "framework") or "").strip() != "arduino":
            ck.error(fname, f"[{sec}] framework must be arduino")
        deps = resolve(cp, sec, "lib_deps") or ""
        extra = resolve(cp, sec, "lib_extra_dirs") or ""
        if LIB_NAME not in deps and not extra:
            ck.error(fname, f"[{sec}] does not use this library (lib_deps {LIB_NAME}=symlink://.)")
    if cp.has_option("platformio", "src_dir"):
        src_dir = cp.get("platformio", "src_dir").strip()
        if not os.path.isdir(ck.path(src_dir)):
            ck.error(fname, f"src_dir {src_dir} does not exist")
    if cp.has_option("platformio", "default_envs"):
        for e in re.split(r"[,\s]+", cp.get("platformio", "default_envs").strip()):
            if e and e not in envs:
                ck.error(fname, f"default_envs names unknown env {e}")

    # PlatformIO's own reader: unknown options, bad values (offline, no install needed)
    try:
        from platformio.project.config import ProjectConfig
    except ImportError:
        return
    try:
        pc = ProjectConfig(path, parse_extra=False, expand_interpolations=True)
        pc.validate(silent=True)
        for w in pc.warnings:
            ck.error(fname, f"PlatformIO: {w}")
    except Exception as exc:
        ck.error(fname, f"PlatformIO rejects it: {type(exc).__name__}: {exc}".splitlines()[0])
    ck.note(f"platformio.ini envs: {', '.join(envs)}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--root", default=os.path.dirname(here), help="repository root")
    ap.add_argument("--online", action="store_true", help="fetch the real SPDX licence list")
    ap.add_argument("-q", "--quiet", action="store_true")
    args = ap.parse_args(argv)
    ck = Checker(os.path.abspath(args.root))

    factory, schema = load_platformio(args.online)
    if factory is None:
        ck.error("platformio", "not importable: pip install platformio (its parsers work offline)")
    props = read_properties(ck)
    if props is not None:
        check_properties(ck, props)
    data = check_library_json(ck)
    if factory is not None:
        for fname in ("library.json", "library.properties"):
            if os.path.exists(ck.path(fname)):
                m = pio_validate(ck, fname, factory, schema)
                if m is not None:
                    ck.note(f"{fname}: PlatformIO schema OK ({m.get('name')} {m.get('version')})")
    check_cross(ck, props, data)
    check_platformio_ini(ck)
    if factory is not None:
        import check_package  # imports tools/dist.py, which needs PlatformIO's packer

        check_package.check_all(ck, data)

    if ck.errors:
        for e in ck.errors:
            print("check_manifests: ERROR " + e, file=sys.stderr)
        print(f"check_manifests: {len(ck.errors)} problem(s)", file=sys.stderr)
        return 1
    if not args.quiet:
        for n in ck.notes:
            print("check_manifests: " + n)
        print("check_manifests: OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
