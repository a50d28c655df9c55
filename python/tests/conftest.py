import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture
def repo():
    """The repository's root (scenarios/, README.md, target/)."""
    return REPO


def built_mrsim(repo):
    """The `mrsim` executable the tests run: MRSIM_BIN, or the release build."""
    import os

    exe = os.environ.get("MRSIM_BIN") or str(repo / "target" / "release" / "mrsim")
    if not os.path.exists(exe):
        pytest.fail(f"{exe} not found: build it first (cargo build --release)")
    return exe
