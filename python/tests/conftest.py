"""Shared fixtures: the repository root and the `cablevib` command-line binary the bindings
are compared with (CABLEVIB_BIN, set by python/run-tests.sh; default target/release)."""

import json
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENES = REPO / "scenes"


@pytest.fixture(scope="session")
def cli_bin() -> pathlib.Path:
    path = pathlib.Path(
        os.environ.get("CABLEVIB_BIN", REPO / "target" / "release" / "cablevib")
    )
    if not path.is_file():
        pytest.fail(f"{path}: no cablevib binary (cargo build --release, or set CABLEVIB_BIN)")
    return path


@pytest.fixture(scope="session")
def run_cli(cli_bin):
    """Run `cablevib ARGS...`; returns the CompletedProcess (text mode)."""

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [str(cli_bin), *args], capture_output=True, text=True, timeout=600, check=False
        )

    return run


@pytest.fixture(scope="session")
def cli_json(run_cli):
    """`cablevib ARGS... --json` parsed; the command must succeed."""

    def run(*args: str) -> dict:
        p = run_cli(*args, "--json")
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    return run


def cli_error(proc: subprocess.CompletedProcess) -> str:
    """The one-line message of a failed command: stderr without the `cablevib: ` prefix."""
    assert proc.returncode != 0, proc.stdout
    line = proc.stderr.strip()
    assert line.startswith("cablevib: "), line
    return line[len("cablevib: "):]
