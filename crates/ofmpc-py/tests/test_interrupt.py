"""Issue #22 item 16: Ctrl-C during `ofmpc.run()` raises KeyboardInterrupt promptly (the run
checks a cancel flag before every sample; the waiting thread checks for signals), not when
the run ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

# The child: calibrates the cost of one sample on this machine (a short run's median step
# time), then starts one run long enough to last about TARGET_S, and reports how it ended.
CHILD = textwrap.dedent(
    """
    import json, signal, sys, time
    import ofmpc

    # A runner started in the background may ignore SIGINT: the default Python handler.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    program, target_s = sys.argv[1], float(sys.argv[2])
    base = {
        "controllers": ["second"],
        "payload": {"masses_kg": [0.0]},
        # A long horizon: costly steps, so that the run needs fewer samples (a smaller record).
        "mpc": {"horizon": 30},
        "program": {"file": program},
        "simulation": {"hold_s": 0.5, "steady_window_s": 0.1},
    }
    step_us = ofmpc.run(base)["runs"][0]["step_time_us"]["median"]
    ts = 0.01
    # Every sample steps the controller: the run lasts at least samples × median step.
    hold_s = max(10.0, target_s / (step_us * 1e-6) * ts)
    base["simulation"]["hold_s"] = hold_s
    expected_s = hold_s / ts * step_us * 1e-6
    print(json.dumps({"expected_s": expected_s}), flush=True)
    t0 = time.monotonic()
    try:
        ofmpc.run(base)
        print(json.dumps({"ended": "completed", "after_s": time.monotonic() - t0}), flush=True)
    except KeyboardInterrupt:
        print(json.dumps({"ended": "interrupted", "after_s": time.monotonic() - t0}), flush=True)
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child is POSIX")
def test_ctrl_c_interrupts_a_run_well_before_its_end(tmp_path):
    import json

    program = tmp_path / "p.gcode"
    program.write_text("G0 X500 Y0 Z600\nG1 X510 F600\n")
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(program), "10"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )
    try:
        line = child.stdout.readline()
        assert line, child.stderr.read()
        expected_s = json.loads(line)["expected_s"]
        time.sleep(1.0)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=max(120.0, 4 * expected_s))
        latency = time.monotonic() - sent
    finally:
        if child.poll() is None:
            child.kill()
    ended = json.loads(out.strip().splitlines()[-1])
    assert ended["ended"] == "interrupted", (ended, err)
    # Well before the run's end: a quarter of its shortest possible length (the machine may
    # be loaded: relative, not an absolute 0.2 s); unloaded it is about 20 ms plus a sample.
    assert latency < 0.25 * expected_s, (latency, expected_s)
    print(f"interrupted {latency:.3f} s after SIGINT; the run would have lasted >= {expected_s:.1f} s")
