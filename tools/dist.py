#!/usr/bin/env python3
"""Build the Arduino library's release files, offline.

  python3 tools/dist.py [--root DIR] [--out DIR]     (make dist)

- build/dist/Hubwire-<version>.zip: one top-level folder Hubwire/ (the library's name) holding
  only the library (LIBRARY_PATHS), what the Arduino IDE's *Sketch > Include Library > Add .ZIP
  Library* takes: it copies that folder into the sketchbook's libraries/.
- build/dist/Hubwire-<version>.tar.gz: what `pio pkg pack` makes of the tree (library.json's
  export.include), for a PlatformIO `lib_deps = file://...` line or the registry. The SPDX licence
  list PlatformIO wants from the network is stubbed as in tools/check_manifests.py.

Both are checked after they are written (library_problems): a path outside the library fails.
"""

import argparse
import os
import sys
import tarfile
import zipfile

# The library, and nothing else: what the zip and the PlatformIO tarball may hold. extras/ stays
# out: the sketches there are benchmarks, nothing a user's build needs.
LIBRARY_PATHS = (
    "src/",
    "examples/",
    "library.json",
    "library.properties",
    "keywords.txt",
    "README.md",
    "LICENSE",
)
REQUIRED = ("src/Hubwire.h", "library.properties", "LICENSE", "README.md", "keywords.txt")
JUNK = ("__pycache__", ".pyc", ".DS_Store")


def is_library_path(rel):
    return any(rel == p or (p.endswith("/") and rel.startswith(p)) for p in LIBRARY_PATHS)


def library_problems(names, what):
    """Problems with a list of archive paths (relative to the library's folder)."""
    outside = {}  # top-level entry -> its files, so that a packed .venv/ is one line, not 4,000
    for n in sorted(names):
        if not is_library_path(n) or any(j in n for j in JUNK):
            outside.setdefault(n.split("/", 1)[0] + ("/" if "/" in n else ""), []).append(n)
    problems = [f"{what}: not part of the library: {top} ({len(files)} file(s): "
                f"{', '.join(files[:3])}{', ...' if len(files) > 3 else ''})"
                for top, files in outside.items()]
    problems += [f"{what}: missing {r}" for r in REQUIRED if r not in names]
    if not any(n.startswith("examples/") and n.endswith(".ino") for n in names):
        problems.append(f"{what}: no example sketch")
    return problems


def version_of(root):
    with open(os.path.join(root, "library.properties"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("version="):
                return line.split("=", 1)[1].strip()
    raise SystemExit("dist: library.properties has no version=")


def library_files(root):
    for p in LIBRARY_PATHS:
        full = os.path.join(root, p)
        if not p.endswith("/"):
            if os.path.isfile(full):
                yield p
            continue
        for d, dirs, files in os.walk(full):
            dirs[:] = sorted(x for x in dirs if x not in JUNK)
            for f in sorted(files):
                if not f.endswith(JUNK):
                    yield os.path.relpath(os.path.join(d, f), root).replace(os.sep, "/")


def build_zip(root, out, version):
    """The Arduino IDE zip: every entry under one folder; fixed timestamps, sorted entries."""
    top = "Hubwire"
    path = os.path.join(out, f"{top}-{version}.zip")
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for rel in library_files(root):
            info = zipfile.ZipInfo(f"{top}/{rel}", date_time=(2020, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            with open(os.path.join(root, rel), "rb") as f:
                z.writestr(info, f.read())
    return path


def zip_problems(path):
    with zipfile.ZipFile(path) as z:
        names = [n for n in z.namelist() if not n.endswith("/")]
    tops = {n.split("/", 1)[0] for n in names}
    if len(tops) != 1 or any("/" not in n for n in names):
        return [f"{path}: entries must sit under one top-level folder, found {sorted(tops)}"]
    return library_problems([n.split("/", 1)[1] for n in names], os.path.basename(path))


def pio_pack(root, out):
    """`pio pkg pack` of the tree, offline; returns the tarball's path."""
    from check_manifests import load_platformio  # stubs the SPDX list

    if load_platformio(online=False)[0] is None:
        raise SystemExit("dist: platformio is not importable (make setup installs it)")
    from platformio.package.pack import PackagePacker

    return PackagePacker(root).pack(out)


def tarball_problems(path):
    with tarfile.open(path) as t:
        names = [m.name for m in t.getmembers() if not m.isdir()]
    return library_problems(names, os.path.basename(path))


def build_and_check(root, out):
    """Writes both files into out; returns (paths, problems)."""
    zip_path = build_zip(root, out, version_of(root))
    tar_path = pio_pack(root, out)
    return (zip_path, tar_path), zip_problems(zip_path) + tarball_problems(tar_path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--root", default=os.path.dirname(here), help="repository root")
    ap.add_argument("--out", help="output folder (default ROOT/build/dist)")
    args = ap.parse_args(argv)
    root = os.path.abspath(args.root)
    out = os.path.abspath(args.out or os.path.join(root, "build", "dist"))
    os.makedirs(out, exist_ok=True)
    paths, problems = build_and_check(root, out)
    for p in problems:
        print("dist: ERROR " + p, file=sys.stderr)
    if problems:
        return 1
    for p in paths:
        print(f"dist: {os.path.relpath(p, root)} ({os.path.getsize(p):,} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
