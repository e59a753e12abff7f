"""Checks on what a user installs, run by tools/check_manifests.py (offline).

- LICENSE: present at the root (Arduino's linter, rule LD002), MIT, the same licence that
  library.json and host/pyproject.toml declare; host/LICENSE (the Python package's) the same text.
- No tracked symlinks (the Library Manager's indexer and arduino-lint reject them), and no
  `sys.path.insert` in tracked Python (scripts and tests import the installed package).
- library.json's export.include lists exactly the library (tools/dist.py LIBRARY_PATHS); the tree
  packed as `pio pkg pack` packs it and the Arduino IDE zip hold nothing else (offending paths named).
- The README's install instructions name things that exist: no `pip install hubwire` from a
  registry (the package is not published), and the example "With a real board" uploads is the one
  platformio.ini builds.
"""

import json
import os
import re
import subprocess
import tempfile

import dist

LICENSE_ID = "MIT"
LICENSE_FIRST_LINE = "MIT License"
UNPUBLISHED = re.compile(r"pip install (-U )?['\"]?hubwire\b")
PATH_EDIT = re.compile(r"\bsys\.path\.insert\(")
SAYS_INSTALL = ("README.md", "library.properties", "host/README.md")


def check_license(ck):
    path = ck.path("LICENSE")
    if not os.path.isfile(path):
        ck.error("LICENSE", "no licence file at the repository root (arduino-lint LD002)")
        return
    with open(path, encoding="utf-8") as f:
        text = f.read()
    if not text.startswith(LICENSE_FIRST_LINE) or "The Hubwire authors" not in text:
        ck.error("LICENSE", f"must be the {LICENSE_ID} licence of The Hubwire authors")
    with open(ck.path("library.json"), encoding="utf-8") as f:
        if json.load(f).get("license") != LICENSE_ID:
            ck.error("library.json", f"license must be {LICENSE_ID}")
    host_license = ck.path("host", "LICENSE")
    if os.path.lexists(host_license):
        if not os.path.isfile(host_license):
            ck.error("host/LICENSE", "must be a file with the same text as LICENSE")
        else:
            with open(host_license, encoding="utf-8") as f:
                if f.read() != text:
                    ck.error("host/LICENSE", "must be the same text as LICENSE")
    pyproject = ck.path("host", "pyproject.toml")
    if os.path.exists(pyproject):
        with open(pyproject, encoding="utf-8") as f:
            if not re.search(rf'^license = "{LICENSE_ID}"$', f.read(), re.M):
                ck.error("host/pyproject.toml", f'license must read license = "{LICENSE_ID}" (SPDX)')


def check_export(ck, data):
    include = (data.get("export") or {}).get("include") or []
    include = {p.strip("/") for p in ([include] if isinstance(include, str) else include)}
    want = {p.strip("/") for p in dist.LIBRARY_PATHS}
    if include != want:
        ck.error("library.json", f"export.include must be {sorted(want)}, not {sorted(include)}")


def check_archives(ck):
    with tempfile.TemporaryDirectory() as out:
        try:
            paths, problems = dist.build_and_check(ck.root, out)
        except Exception as exc:  # PlatformIO's packer refusing the tree
            ck.error("pack", f"{type(exc).__name__}: {exc}".splitlines()[0])
            return
        for p in problems:
            ck.error("pack", p)
        sizes = ", ".join(f"{os.path.basename(p)} {os.path.getsize(p):,} B" for p in paths)
    ck.note(f"packed: {sizes}")


def read(ck, rel):
    with open(ck.path(rel), encoding="utf-8") as f:
        return f.read()


def check_readme(ck):
    for rel in SAYS_INSTALL:
        if os.path.exists(ck.path(rel)) and UNPUBLISHED.search(read(ck, rel)):
            ck.error(rel, "says `pip install hubwire`, which is not published: `pip install ./host`")
    readme = read(ck, "README.md")
    m = re.search(r"^## With a real board\n(.*?)(?=^## )", readme, re.M | re.S)
    src_dir = re.search(r"^src_dir\s*=\s*(\S+)", read(ck, "platformio.ini"), re.M)
    if not m or not src_dir:
        ck.error("README.md", "no 'With a real board' section, or platformio.ini has no src_dir")
        return
    named = re.search(r"examples/(\w+)/", m.group(1))  # the first example the section names
    built = os.path.basename(src_dir.group(1).rstrip("/"))
    if not named or named.group(1) != built:
        ck.error("README.md", f"'With a real board' uploads {named and named.group(1)}; `pio run -e uno "
                              f"-t upload` uploads {built} (platformio.ini src_dir)")


def check_tree(ck):
    try:
        listing = subprocess.run(["git", "-C", ck.root, "ls-files", "-s"], capture_output=True, text=True,
                                 check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        ck.note("not a git checkout: tracked symlinks and sys.path edits not checked")
        return
    for line in listing.splitlines():
        info, rel = line.split("\t", 1)
        if info.startswith("120000 "):
            ck.error(rel, "is a symlink: the Library Manager's indexer and arduino-lint reject them")
        elif rel.endswith(".py") and os.path.isfile(ck.path(rel)) and PATH_EDIT.search(read(ck, rel)):
            ck.error(rel, "edits sys.path: import the installed package (make setup) or pass PYTHONPATH")


def check_all(ck, data):
    check_license(ck)
    check_tree(ck)
    if data is not None:
        check_export(ck, data)
    check_readme(ck)
    check_archives(ck)
