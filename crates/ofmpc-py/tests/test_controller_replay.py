"""The Python `Controller` is the library's one controller: fed the states that `ofmpc run`
measured along the paper's path (controller second, 0.25 kg payload, ideal sensing, no torque
limits), it computes bit for bit the torques the closed loop applied (issue 34)."""

from __future__ import annotations

import csv
import subprocess

import numpy as np

import ofmpc
from conftest import ofmpc_binary


def test_python_controller_replays_the_paper_run_bit_for_bit(tmp_path):
    out = tmp_path / "run"
    subprocess.run(
        [str(ofmpc_binary()), "reproduce", "--controllers", "second", "--payload", "0.25",
         "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with open(out / "second_m0.25" / "timeseries.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    n, horizon = 6, 10
    col = lambda row, name: [float(row[f"{name}{i + 1}"]) for i in range(n)]  # noqa: E731
    x = np.array([col(r, "q") + col(r, "qd") for r in rows])
    w = np.array([col(r, "qref") for r in rows])
    tau = np.array([col(r, "tau") for r in rows])
    assert len(rows) > 1000 and np.abs(tau).max() > 1.0

    c = ofmpc.Controller("second", ofmpc.Robot.irb140(), ts=0.01, horizon=horizon,
                         q_yw=1.0, q_dy=0.5, q_du=1e-5, q_u=1e-4, solver="auto")
    c.reset(x[0])
    last = len(rows) - 1
    for k in range(len(rows)):
        preview = w[[min(k + j, last) for j in range(1, horizon + 1)]]
        got = c.step(x[k], w[k], preview)
        # Bit for bit: the same doubles (the CSV holds each one's shortest exact decimal).
        assert np.array_equal(got, tau[k]), f"sample {k}: {got} != {tau[k]}"
