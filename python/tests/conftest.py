"""Shared fixtures: the repository, the CLI binary built by `cargo test --release` / `cargo build --release`."""

import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The `mislab` binary of this checkout (MISLAB_BIN overrides); a test that needs it fails without it."""
    path = pathlib.Path(os.environ.get("MISLAB_BIN", REPO / "target" / "release" / "mislab"))
    if not path.is_file():
        pytest.fail(f"{path}: no mislab binary; build it first with `cargo build --release`")
    return path
