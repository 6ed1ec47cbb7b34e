"""MuJoCo as the plant (examples/python/mujoco_closed_loop.py): its model equals
ofmpc's, and closing the loop with ofmpc.Controller gives the paper's result: the
incremental controllers drive the steady error to zero under an unknown payload,
the usual MPC keeps an offset."""

from __future__ import annotations

import numpy as np
import pytest

import ofmpc
from conftest import IRB140_DRIVES, IRB140_URDF, rel_err

mujoco = pytest.importorskip("mujoco")


import mujoco_closed_loop as ex  # noqa: E402  (examples/python, on sys.path by conftest)

PAYLOAD = 0.25


@pytest.mark.parametrize("payload", [0.0, 1.3])
def test_the_mjcf_model_equals_ofmpc_s(payload):
    """Mass matrix (armature included), bias forces C q̇ + g and flange pose of the
    generated MJCF equal ofmpc's at random states: the plant is the model plus the
    payload, nothing else."""
    com = (0.01, -0.02, 0.05)
    model = mujoco.MjModel.from_xml_string(ex.mjcf_from_urdf(IRB140_URDF, IRB140_DRIVES, payload, com))
    data = mujoco.MjData(model)
    robot = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)
    robot.set_payload(payload, com)
    assert model.nv == robot.dof
    assert model.opt.gravity[2] == -ofmpc.STANDARD_GRAVITY
    site = model.site("flange").id
    rng = np.random.default_rng(1)
    worst = {"H": 0.0, "bias": 0.0, "pose": 0.0}
    for _ in range(20):
        q, v = rng.uniform(-2, 2, 6), rng.normal(0, 1, 6)
        data.qpos[:], data.qvel[:] = q, v
        mujoco.mj_forward(model, data)
        h = np.zeros((6, 6))
        try:
            mujoco.mj_fullM(model, data, h)  # MuJoCo >= 4
        except TypeError:
            mujoco.mj_fullM(model, h, data.qM)  # MuJoCo 2.x, 3.x
        pose = np.eye(4)
        pose[:3, :3] = data.site_xmat[site].reshape(3, 3)
        pose[:3, 3] = data.site_xpos[site]
        worst["H"] = max(worst["H"], rel_err(h, robot.mass_matrix(q)))
        worst["bias"] = max(worst["bias"], rel_err(data.qfrc_bias, robot.rnea(q, v, np.zeros(6))))
        worst["pose"] = max(worst["pose"], rel_err(pose, robot.flange_pose(q)))
    print(f"payload {payload} kg: MuJoCo vs ofmpc worst relative errors {worst}")
    # 1e-9: MuJoCo's point payload carries a 1e-12 kg·m² inertia (it needs one > 0).
    assert all(e < 1e-9 for e in worst.values()), worst


@pytest.fixture(scope="module")
def runs():
    robot = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)
    ref = ofmpc.plan("paper", robot)
    # The whole paper path (11.6 s) and a 1.5 s hold: ~0.2 s of wall time per controller.
    return {
        kind: ex.closed_loop(kind, PAYLOAD, hold_s=1.5, reference=ref)
        for kind in ("usual", "first", "second")
    }


@pytest.mark.parametrize("kind", ["first", "second"])
def test_incremental_controllers_have_no_steady_error_on_mujoco(runs, kind):
    m = runs[kind].metrics
    print(f"MuJoCo, {PAYLOAD} kg unknown, {kind}: {m}")
    assert m["steady_joint_error_max_rad"] < 1e-9
    assert m["steady_cartesian_error_mm"] < 1e-6


def test_usual_mpc_keeps_an_offset_on_mujoco(runs):
    """The contrast that makes the test above mean something: same plant, same
    payload, the positional MPC keeps a steady error orders of magnitude larger."""
    usual = runs["usual"].metrics
    print(f"MuJoCo, {PAYLOAD} kg unknown, usual: {usual}")
    assert usual["steady_cartesian_error_mm"] > 0.01
    assert usual["steady_joint_error_max_rad"] > 1e-5


def test_mujoco_and_ofmpc_s_own_plant_agree(runs):
    """Two independent plants (MuJoCo's RK4 on its model, ofmpc's RK4 on its own)
    under the same controller give the same RMS tracking error to 1e-4 relative."""
    metrics = ofmpc.run(
        {"controllers": ["usual", "first", "second"], "payload": {"masses_kg": [PAYLOAD]}, "simulation": {"hold_s": 1.5}}
    )
    for r in metrics["runs"]:
        mj = runs[r["controller"]].metrics["cartesian_error_rms_mm"]
        print(f"{r['controller']}: RMS Cartesian error ofmpc plant {r['cartesian_error_rms_mm']:.6g} mm, MuJoCo {mj:.6g} mm")
        assert abs(mj - r["cartesian_error_rms_mm"]) < 1e-4 * r["cartesian_error_rms_mm"]


def test_the_example_script_prints_its_table():
    """The script as a user runs it (short hold): one row per controller, the first
    algorithm's steady error at round-off."""
    import subprocess
    import sys

    from conftest import EXAMPLES

    out = subprocess.run(
        [sys.executable, str(EXAMPLES / "mujoco_closed_loop.py"), "--payload", "0.5", "--controllers", "usual,first", "--hold", "1"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    print(out)
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()[2:]}
    assert set(rows) == {"usual", "first"}
    assert float(rows["first"][1]) < 1e-6  # steady Cartesian error (mm)
    assert float(rows["usual"][1]) > 0.1  # 0.5 kg: the usual MPC's offset (about 0.17 mm)
