#!/usr/bin/env python3
"""Print, as shell `export` lines, the two variables maturin sets for PyO3's
build scripts when it builds the Python package with this interpreter:
PYO3_PYTHON (the interpreter) and PYO3_ENVIRONMENT_SIGNATURE. Cargo runs
those build scripts again whenever either differs from the last build, so a
`cargo test` or `cargo clippy` given them leaves PyO3 as the Python build
wants it. Run it with the virtualenv's python:

    eval "$(python/.venv/bin/python3 scripts/pyo3_env.py)"
"""
import os
import shlex
import struct
import sys

# maturin passes the interpreter pip runs it with; a virtualenv's
# bin/python3 is a link to the base interpreter, so the venv path is kept
# as it is, not resolved.
executable = os.path.abspath(sys.executable)
signature = "{}-{}.{}-{}bit".format(
    sys.implementation.name, sys.version_info.major, sys.version_info.minor,
    struct.calcsize("P") * 8,
)
print(f"export PYO3_PYTHON={shlex.quote(executable)}")
print(f"export PYO3_ENVIRONMENT_SIGNATURE={shlex.quote(signature)}")
