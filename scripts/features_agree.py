#!/usr/bin/env python3
"""Check that `cargo run` (the `mrsim` package) and the Python build (maturin,
the `mrsim-python` package) compile every dependency with the features that
`cargo test --workspace` compiles it with, so neither builds rapier2d and its
dependencies a second time. Exit 1 naming each crate whose features differ
(add them to crates/workspace-hack/Cargo.toml).

Cargo resolves the features of a crate built for the host (a build script's
or a proc-macro's dependency) apart from those of the same crate built into
the program, so the two are compared apart: merged, a feature the host copy
has hides that the program's copy lacks it."""
import subprocess
import sys

def host_target():
    """This machine's platform, the one the builds compare on (`cargo tree`
    would otherwise list the dependencies of every platform)."""
    out = subprocess.run(
        ["rustc", "-vV"], check=True, capture_output=True, text=True
    ).stdout
    for line in out.splitlines():
        if line.startswith("host: "):
            return line.split(" ", 1)[1].strip()
    sys.exit("rustc -vV names no host platform")


def features(*args):
    """(name, version, built for the host) -> features, from `cargo tree`."""
    out = subprocess.run(
        ["cargo", "tree", *args, "-f", "{p}|{f}", "--prefix", "indent",
         "--no-dedupe", "--target", host_target()],
        check=True, capture_output=True, text=True,
    ).stdout
    found = {}
    # (indent, whether what is under this line is built for the host)
    stack = []
    for line in out.splitlines():
        body = line.lstrip("│├└─ \u00a0")
        indent = len(line) - len(body)
        while stack and stack[-1][0] >= indent:
            stack.pop()
        host = stack[-1][1] if stack else False
        if body.startswith("[build-dependencies]"):
            stack.append((indent, True))
            continue
        if body.startswith("[dev-dependencies]"):
            stack.append((indent, host))
            continue
        if "|" not in body:
            continue
        package, feats = body.split("|", 1)
        name, version = package.split(" ")[:2]
        host = host or "(proc-macro)" in package
        found.setdefault((name, version, host), set()).update(
            f for f in feats.split(",") if f
        )
        stack.append((indent, host))
    return found


def main():
    workspace = features("--workspace", "-e", "normal,build,dev")
    bad = 0
    for package in ("mrsim", "mrsim-python"):
        for key, feats in sorted(features("-p", package, "-e", "normal,build").items()):
            if key in workspace and workspace[key] != feats:
                bad += 1
                name, version, host = key
                where = "built for the host" if host else "built into the program"
                print(f"{package}: {name} {version} ({where}) lacks the workspace's features"
                      f" {sorted(workspace[key] - feats)} (and has {sorted(feats - workspace[key])} more)")
    if bad:
        print(f"{bad} dependencies built with other features than `cargo test --workspace`"
              " builds them with: add them to crates/workspace-hack/Cargo.toml", file=sys.stderr)
        return 1
    print("one build: `cargo run` and the Python build use the test build's dependency features")
    return 0


if __name__ == "__main__":
    sys.exit(main())
