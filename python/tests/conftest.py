"""Shared fixtures: the committed sample, and the `afford` command line of the same wheel
(the console script beside this interpreter; AFFORD_CLI overrides it, e.g. with
target/release/afford)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "data" / "sample" / "room.ply"


def cli_path() -> str:
    given = os.environ.get("AFFORD_CLI")
    if given:
        return given
    bindir = Path(sys.executable).parent
    for name in ("afford", "afford.exe"):
        if (bindir / name).exists():
            return str(bindir / name)
    raise RuntimeError(f"no afford script in {bindir}: is the wheel installed in this environment?")


def run_cli(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([cli_path(), *args], capture_output=True, text=True, cwd=cwd)


@pytest.fixture(scope="session")
def sample() -> Path:
    return SAMPLE


@pytest.fixture(scope="session")
def cli():
    return run_cli


@pytest.fixture(scope="session")
def sample_cli_json(tmp_path_factory) -> dict:
    """The CLI's --json document of the committed sample (run from the repository root,
    so the file is named data/sample/room.ply)."""
    out = tmp_path_factory.mktemp("cli") / "sample.json"
    p = run_cli("detect", "data/sample/room.ply", "--json", str(out), cwd=ROOT)
    assert p.returncode == 0, p.stderr
    return json.loads(out.read_text())


def write_ply(path: Path, points: np.ndarray) -> None:
    """A binary little-endian PLY of float32 x, y, z (NaN rows kept)."""
    pts = np.ascontiguousarray(points, dtype="<f4")
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(pts)}\n"
        "property float x\nproperty float y\nproperty float z\nend_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(pts.tobytes())
