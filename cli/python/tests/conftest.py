"""What the tests share: the repository, and the `flatray` command to
compare the binding against (built with cargo when it is not there)."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    return REPO


@pytest.fixture(scope="session")
def cli() -> str:
    """The path of the `flatray` command: FLATRAY_BIN, or the release
    build of this checkout."""
    named = os.environ.get("FLATRAY_BIN")
    if named:
        return named
    binary = REPO / "target" / "release" / "flatray"
    if not binary.exists():
        subprocess.run(
            ["cargo", "build", "--release", "-p", "flatray-cli"], cwd=REPO, check=True
        )
    return str(binary)
