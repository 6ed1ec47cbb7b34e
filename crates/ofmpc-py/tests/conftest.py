"""Shared paths and helpers of the Python tests (run by `.ci/python`)."""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]
IRB140_DIR = REPO / "crates" / "ofmpc" / "robots" / "irb140"
IRB140_URDF = IRB140_DIR / "irb140.urdf"
IRB140_DRIVES = IRB140_DIR / "drives.toml"
EXAMPLES = REPO / "examples" / "python"

# The examples are modules of the tests (and of the Dask workers, which are new
# processes: hence PYTHONPATH too).
sys.path.insert(0, str(EXAMPLES))
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(EXAMPLES), os.environ.get("PYTHONPATH")]))


def ofmpc_binary() -> pathlib.Path:
    """The `ofmpc` CLI: $OFMPC_BIN, else target/release/ofmpc (built if missing)."""
    env = os.environ.get("OFMPC_BIN")
    if env:
        return pathlib.Path(env)
    path = REPO / "target" / "release" / "ofmpc"
    if not path.exists():
        cargo = shutil.which("cargo")
        if cargo is None:
            pytest.skip("no ofmpc binary and no cargo to build it")
        subprocess.run([cargo, "build", "--release", "-p", "ofmpc-cli"], cwd=REPO, check=True)
    return path


def rel_err(a, b) -> float:
    """‖a − b‖ / ‖b‖ (Frobenius), with ‖b‖ floored at 1e-300."""
    import numpy as np

    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))
