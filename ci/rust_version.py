#!/usr/bin/env python3
"""Checks the Rust versions we state against what the crates built for them declare.

Only one toolchain can be installed on the CI machine, so an old compiler cannot be tried; this
reads what the dependencies declare instead. For each case (a package, its features, whether its
tests' dev-dependencies count), `cargo tree` lists the crates built for this machine and
`cargo metadata` their `rust-version`; a crate needing more than the case's stated version is a
failure naming both. A case's stated version is the package's `rust-version`, or for an optional
feature or a package's tests the version its `Cargo.toml` comment gives (cargo has no
per-feature `rust-version`). The two workspaces of their own (`embedded/`, `python/`) are held
to their `rust-version` over every crate in their lock file. Run from the workspace root:
`python3 ci/rust_version.py`.
"""

import json
import subprocess
import sys

# (package, features, edges, stated): the default build of each crate a user depends on, its
# optional features, and the tests (dev-dependencies included). `stated` None: the package's
# `rust-version`; else the version the feature's or dev-dependency's comment in `Cargo.toml` gives.
CASES = [
    ("kiss-odom-core", "", "normal,build", None),
    ("kiss-odom-core", "defmt", "normal,build", None),
    ("kiss-odom-core", "", "normal,build,dev", "1.88"),
    ("kiss-odom-sensors", "", "normal,build", None),
    ("kiss-odom-sensors", "defmt", "normal,build", None),
    ("kiss-odom", "", "normal,build", None),
    ("kiss-odom", "ros2", "normal,build", "1.88"),
    ("kiss-odom", "rerun", "normal,build", "1.89"),
    ("kiss-odom-tests", "", "normal,build,dev", None),
]


def version(text):
    """A `rust-version` as a comparable tuple (`1.88` is `(1, 88, 0)`)."""
    parts = [int(p) for p in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


# Workspaces of their own, each held to its package's `rust-version` over its whole lock file.
OWN_WORKSPACES = [("embedded", "kiss-odom-embedded"), ("python", "kiss-odom-python")]


def cargo(*args, cwd=None):
    out = subprocess.run(["cargo", *args], check=True, capture_output=True, text=True, cwd=cwd)
    return out.stdout


def own_workspace(directory, package):
    """Failures of a workspace whose lock file holds only what its one package builds."""
    meta = json.loads(cargo("metadata", "--format-version", "1", "--locked", cwd=directory))
    own = next(p for p in meta["packages"] if p["name"] == package).get("rust_version")
    needs = [(version(p["rust_version"]), p) for p in meta["packages"] if p.get("rust_version")]
    worst, crate = max(needs, key=lambda n: n[0])
    print(
        f"{directory}/ ({package}): stated {own}; {len(meta['packages'])} crates locked, the most "
        f"demanding {crate['name']} {crate['version']} needs {crate['rust_version']}"
    )
    bad = [p for need, p in needs if own is None or need > version(own)]
    for p in bad:
        print(f"  FAIL: {p['name']} {p['version']} needs rust {p['rust_version']} > {own}")
    return len(bad) + (own is None)


def main():
    meta = json.loads(cargo("metadata", "--format-version", "1", "--locked"))
    declared = {(p["name"], p["version"]): p.get("rust_version") for p in meta["packages"]}
    members = {p["name"]: p for p in meta["packages"] if p["id"] in meta["workspace_members"]}
    failures = 0
    for package, features, edges, stated in CASES:
        own = stated or members[package].get("rust_version")
        if own is None:
            print(f"{package}: no rust-version declared")
            failures += 1
            continue
        args = ["tree", "--locked", "-p", package, "-e", edges, "--prefix", "none"]
        args += ["--format", "{p}"]
        if features:
            args += ["--features", features]
        built = set()
        for line in cargo(*args).splitlines():
            fields = line.split()
            if len(fields) >= 2 and fields[1].startswith("v"):
                built.add((fields[0], fields[1][1:]))
        needs = [(version(declared[c]), c) for c in built if declared.get(c)]
        worst, crate = max(needs)
        what = f"{package}" + (f" --features {features}" if features else "")
        what += " (with its tests)" if "dev" in edges else ""
        print(
            f"{what}: stated {own}; {len(built)} crates built, the most demanding "
            f"{crate[0]} {crate[1]} needs {declared[crate]}"
        )
        for need, c in sorted(needs, reverse=True):
            if need > version(own):
                print(f"  FAIL: {c[0]} {c[1]} needs rust {declared[c]} > {own}")
                failures += 1
    for directory, package in OWN_WORKSPACES:
        failures += own_workspace(directory, package)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
