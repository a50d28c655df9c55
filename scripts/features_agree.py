#!/usr/bin/env python3
"""Check that `cargo run` (the `mrsim` package) and the Python build (maturin,
the `mrsim-python` package) compile every dependency with the features that
`cargo test --workspace` compiles it with, so neither builds rapier2d and its
dependencies a second time. Exit 1 naming each crate whose features differ
(add them to crates/workspace-hack/Cargo.toml)."""
import subprocess
import sys


def features(*args):
    out = subprocess.run(
        ["cargo", "tree", *args, "-f", "{p}|{f}", "--prefix", "none", "--no-dedupe"],
        check=True, capture_output=True, text=True,
    ).stdout
    found = {}
    for line in out.splitlines():
        if "|" not in line:
            continue
        package, feats = line.split("|", 1)
        name, version = package.split(" ")[:2]
        found.setdefault((name, version), set()).update(f for f in feats.split(",") if f)
    return found


def main():
    workspace = features("--workspace", "-e", "normal,build,dev")
    bad = 0
    for package in ("mrsim", "mrsim-python"):
        for key, feats in sorted(features("-p", package, "-e", "normal,build").items()):
            if key in workspace and workspace[key] != feats:
                bad += 1
                more = sorted(workspace[key] - feats)
                print(f"{package}: {key[0]} {key[1]} lacks the workspace's features {more}"
                      f" (and has {sorted(feats - workspace[key])} more)")
    if bad:
        print(f"{bad} dependencies built with other features than `cargo test --workspace`"
              " builds them with: add them to crates/workspace-hack/Cargo.toml", file=sys.stderr)
        return 1
    print("one build: `cargo run` and the Python build use the test build's dependency features")
    return 0


if __name__ == "__main__":
    sys.exit(main())
