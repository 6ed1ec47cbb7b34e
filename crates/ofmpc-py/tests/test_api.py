"""The Python API: shapes, physical identities across the bindings, the reference
and its preview, the controller's contract, `run`, and errors with the library's
messages."""

from __future__ import annotations

import os
import pathlib

import numpy as np
import pytest

import ofmpc
from conftest import IRB140_DRIVES, IRB140_URDF, REPO, rel_err

N_JOINTS = 6
rng = np.random.default_rng(42)


@pytest.fixture(scope="module")
def robot():
    return ofmpc.Robot.irb140()


@pytest.fixture(scope="module")
def ref(robot):
    return ofmpc.plan("paper", robot)


def test_builtin_robot_equals_the_urdf_with_its_drives(robot):
    other = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)
    bare = ofmpc.Robot.from_urdf(str(IRB140_URDF))
    q = rng.uniform(-1, 1, N_JOINTS)
    assert robot.dof == other.dof == N_JOINTS
    np.testing.assert_array_equal(robot.mass_matrix(q), other.mass_matrix(q))
    # Without drives.toml there is no armature: H differs by exactly diag(armature).
    np.testing.assert_allclose(robot.mass_matrix(q) - bare.mass_matrix(q), np.diag(robot.armature), atol=1e-12)


def test_the_terms_compose_to_rnea_and_forward_dynamics_inverts_it(robot):
    for _ in range(10):
        q, qd, qdd = rng.uniform(-2, 2, 6), rng.normal(0, 1, 6), rng.normal(0, 2, 6)
        h, c, g = robot.mass_matrix(q), robot.coriolis_matrix(q, qd), robot.gravity(q)
        assert h.shape == c.shape == (6, 6) and g.shape == (6,)
        tau = robot.rnea(q, qd, qdd)
        assert rel_err(h @ qdd + c @ qd + g, tau) < 1e-12
        assert rel_err(robot.forward_dynamics(q, qd, tau), qdd) < 1e-10
        assert rel_err(robot.rnea(q, np.zeros(6), np.zeros(6)), g) < 1e-13
        assert np.allclose(h, h.T) and np.all(np.linalg.eigvalsh(h) > 0)


def test_a_point_payload_adds_its_weight_through_the_jacobian_transpose():
    """g_with − g_without = J_v(q)ᵀ · m · (0, 0, 9.80665) for a point mass at the flange."""
    bare, loaded = ofmpc.Robot.irb140(), ofmpc.Robot.irb140()
    loaded.set_payload(2.0)
    assert loaded.payload[0] == 2.0 and bare.payload is None
    for _ in range(5):
        q = rng.uniform(-1.5, 1.5, 6)
        jv = bare.flange_jacobian(q)[:3]
        expected = jv.T @ (2.0 * np.array([0.0, 0.0, ofmpc.STANDARD_GRAVITY]))
        assert rel_err(loaded.gravity(q) - bare.gravity(q), expected) < 1e-12
    loaded.set_payload(0.0)
    assert loaded.payload is None


def test_flange_pose_is_homogeneous_and_matches_the_documented_home(robot):
    pose = robot.flange_pose(np.zeros(6))
    # irb140.urdf: flange origin at q = 0 is (0.515, 0, 0.712) m, flange z along base +x.
    np.testing.assert_allclose(pose[:3, 3], [0.515, 0.0, 0.712], atol=1e-12)
    np.testing.assert_allclose(pose[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_array_equal(pose[3], [0, 0, 0, 1])
    r = robot.flange_pose(rng.uniform(-1, 1, 6))[:3, :3]
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)


def test_plan_shapes_times_and_ik_consistency(robot, ref):
    k = len(ref)
    assert ref.t.shape == (k,) and ref.q.shape == ref.qd.shape == ref.qdd.shape == (k, 6)
    assert ref.cartesian.shape == (k, 3)
    np.testing.assert_allclose(np.diff(ref.t), ref.ts, rtol=1e-12)
    assert abs(ref.duration - ref.t[-1]) < 1e-9
    # Every joint sample puts the flange on the Cartesian reference (the IK is exact).
    for i in range(0, k, 97):
        np.testing.assert_allclose(robot.flange_pose(ref.q[i])[:3, 3], ref.cartesian[i], atol=1e-9)
    # The velocity is the derivative of the position (central difference, O(ts²)).
    mid = (ref.q[2:] - ref.q[:-2]) / (2 * ref.ts)
    assert np.abs(mid - ref.qd[1:-1]).max() < 1e-2 * np.abs(ref.qd).max()


def test_preview_is_the_next_n_samples_with_the_last_held(ref):
    k = 100
    np.testing.assert_array_equal(ref.preview(k, 10), ref.q[k + 1 : k + 11])
    end = len(ref) - 3
    p = ref.preview(end, 5)
    np.testing.assert_array_equal(p[:2], ref.q[end + 1 :])
    np.testing.assert_array_equal(p[2:], np.repeat(ref.q[-1:], 3, axis=0))


def test_program_text_file_and_builtin_plan_the_same(robot, ref, tmp_path):
    text = (REPO / "examples" / "paper-table1.gcode").read_text()
    f = tmp_path / "p.gcode"
    f.write_text(text)
    for program in (text, str(f), f):
        np.testing.assert_array_equal(ofmpc.plan(program, robot).q, ref.q)
    # A work offset moves the path: origin in mm.
    moved = ofmpc.plan("G0 X0 Y0 Z0\nG1 X10 F1000\n", robot, origin=(450, 0, 400))
    np.testing.assert_allclose(moved.cartesian[0], [0.45, 0.0, 0.40], atol=1e-12)
    np.testing.assert_allclose(moved.cartesian[-1], [0.46, 0.0, 0.40], atol=1e-12)


def test_controller_holds_a_rest_state_and_validates_its_inputs(robot, ref):
    """At rest on the reference with a constant preview, the incremental controllers'
    first torque holds the robot: τ = g(q) (u = Δu small, H u + g)."""
    w = ref.q[0]
    x = np.concatenate([w, np.zeros(6)])
    for kind in ("usual", "first", "second"):
        c = ofmpc.Controller(kind, robot, ts=0.01, horizon=8, q_yw=[1.0] * 6, q_dy=0.5)
        assert (c.kind, c.dof, c.horizon, c.ts) == (kind, 6, 8, 0.01)
        c.reset(x)
        np.testing.assert_array_equal(c.input, np.zeros(6))
        tau = c.step(x, w, np.tile(w, (8, 1)))
        assert rel_err(tau, robot.gravity(w)) < 1e-9, kind
        assert c.last_info["cost"] >= 0.0
        t = c.last_telemetry
        assert 0.0 <= t["model_time_us"] <= t["solve_time_us"] <= t["total_time_us"], t
        assert (t["qp_iterations"], t["active_constraints"], t["budget_slack_us"]) == (0, 0, None)
        assert (t["fallback"], t["budget_hit"]) == ("none", False)
        # (N, n) and flat previews are the same input.
        c.reset(x)
        np.testing.assert_array_equal(c.step(x, w, np.tile(w, 8)), tau)
    c = ofmpc.Controller("second", robot)
    with pytest.raises(ofmpc.OfmpcError, match="x has 3 values"):
        c.step(x[:3], w, ref.preview(0, 10))
    with pytest.raises(ofmpc.OfmpcError, match="preview"):
        c.step(x, w, ref.preview(0, 9))
    c.reset(x)  # a step needs a state to start from (issue #22 item 6)
    with pytest.raises(ofmpc.OfmpcError, match="not finite"):
        c.step(np.full(12, np.nan), w, ref.preview(0, 10))


def test_baselines_step_from_python(robot, ref):
    """The baselines (issue #21) behind the same class: at rest on the reference the
    first torque holds the robot (τ = g(q)); their bandwidths are keyword arguments."""
    w = ref.q[0]
    x = np.concatenate([w, np.zeros(6)])
    # Each kind takes its own bandwidth only (issue #36: the others were ignored).
    bandwidths = {
        "pid": {"pid_bandwidth": 50.0},
        "ctc": {"ctc_bandwidth": [120.0] * 6},
        "ctc-adaptive": {"ctc_bandwidth": [120.0] * 6},
        "dob-mpc": {"dob_observer_bandwidth": 40.0},
    }
    for kind, kw in bandwidths.items():
        c = ofmpc.Controller(kind, robot, **kw)
        assert c.kind == kind
        c.reset(x)
        tau = c.step(x, w, np.tile(w, (10, 1)))
        assert rel_err(tau, robot.gravity(w)) < 1e-9, kind
    with pytest.raises(ofmpc.OfmpcError, match=r"ctc_bandwidth\[0\] = -1"):
        ofmpc.Controller("ctc", robot, ctc_bandwidth=-1.0)


def test_errors_carry_the_library_s_messages(robot):
    with pytest.raises(ofmpc.OfmpcError, match='unknown controller "third"'):
        ofmpc.Controller("third", robot)
    with pytest.raises(ofmpc.OfmpcError, match="unknown weight"):
        ofmpc.Controller("first", robot, q_xx=1.0)
    with pytest.raises(ofmpc.OfmpcError, match="horizon 0"):
        ofmpc.Controller("first", robot, horizon=0)
    with pytest.raises(ofmpc.OfmpcError, match=r"q_du\[0\] = -1"):
        ofmpc.Controller("first", robot, q_du=-1.0)
    with pytest.raises(ofmpc.OfmpcError, match="line 2, column"):
        ofmpc.plan("G0 X0 Y0 Z0\nG1 X Q\n", robot)
    with pytest.raises(FileNotFoundError):
        ofmpc.plan("no-such-file.gcode", robot)
    with pytest.raises(ofmpc.OfmpcError, match="no-such.urdf"):
        ofmpc.Robot.from_urdf("no-such.urdf")
    with pytest.raises(ofmpc.OfmpcError, match="q has 5 values"):
        robot.rnea(np.zeros(5), np.zeros(6), np.zeros(6))
    with pytest.raises(ofmpc.OfmpcError, match="invalid payload"):
        ofmpc.Robot.irb140().set_payload(-1.0)
    with pytest.raises(ofmpc.OfmpcError, match="unknown field `mpcx`"):
        ofmpc.run({"mpcx": {}})
    with pytest.raises(ofmpc.OfmpcError, match=r"\[mpc\] prediction horizon 0"):
        ofmpc.run({"mpc": {"horizon": 0}})
    assert issubclass(ofmpc.OfmpcError, ValueError)


def test_run_from_a_dict_and_from_a_file_agree(tmp_path):
    scenario = {
        "controllers": ["first"],
        "payload": {"masses_kg": [0.0, 0.5]},
        "mpc": {"q_dy": [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]},
        "simulation": {"hold_s": 1.0},
    }
    f = tmp_path / "s.toml"
    f.write_text(
        'controllers = ["first"]\n[payload]\nmasses_kg = [0.0, 0.5]\n'
        "[mpc]\nq_dy = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5]\n[simulation]\nhold_s = 1.0\n"
    )
    a, b = ofmpc.run(scenario), ofmpc.run(f)
    assert [r["name"] for r in a["runs"]] == ["first_m0", "first_m0.5"]
    for ra, rb in zip(a["runs"], b["runs"]):
        for key in ("wall_s", "step_time_us"):
            ra.pop(key), rb.pop(key)
        # The telemetry's times are the machine's; its counts are the run's.
        ta, tb = ra.pop("telemetry"), rb.pop("telemetry")
        for key in ("qp_iterations", "fallback_steps", "budget_hits"):
            assert ta[key] == tb[key], key
        assert ta["fallback_steps"]["none"] > 0
        assert ra == rb
        assert ra["steady_cartesian_error_mm"] < 1e-6 and not ra["diverged"]


def test_read_program_returns_the_moves_events_and_messages():
    p = ofmpc.read_program("G0 Z5 S100 M3\n(MSG, hi)\nG1 X10 F600\nG2 X20 Y0 I5 J0\n")
    assert p["units"] == "mm" and p["start"] == [0.0, 0.0, 0.0]
    assert [m["kind"] for m in p["moves"]] == ["rapid", "feed", "arc"]
    assert p["moves"][1]["end"] == [10.0, 0.0, 5.0]
    assert abs(p["moves"][1]["feed_mm_s"] - 10.0) < 1e-12
    assert abs(p["moves"][2]["turns"] + 0.5) < 1e-12
    assert [e["code"] for e in p["events"]] == ["S", "M3"]
    assert p["messages"] == [{"line": 2, "kind": "MSG", "text": "hi"}]


def test_read_program_takes_a_tool_table_for_g43_h(tmp_path):
    table = tmp_path / "tools.tbl"
    table.write_text("T2 P2 Z+12.5 D3 ;drill\n")
    text = "G0 X0 Y0 Z0\nG43 H2\nG1 Z1 F600\n"
    assert ofmpc.read_program(text, tool_table=table)["tool_length_mm"] == 12.5
    with pytest.raises(ofmpc.OfmpcError, match="no tool table was given"):
        ofmpc.read_program(text)


def test_hostile_arguments_raise_ofmpc_error_naming_them(robot, ref):
    """Issue #22 items 1, 6, 7: no abort or panic from a size, no step before reset, no array
    of the right count but the wrong shape or dtype read by position."""
    # Item 1: a huge preview is refused by the controllers' limit, never allocated.
    for h in (2**40, 2**62, 1001):
        with pytest.raises(ofmpc.OfmpcError, match="at most 1000"):
            ref.preview(0, h)
    assert ref.preview(2**63, 3).shape == (3, 6)
    np.testing.assert_array_equal(ref.preview(2**63, 2), ref.preview(len(ref), 2))
    w = ref.q[0]
    x = np.concatenate([w, np.zeros(6)])
    c = ofmpc.Controller("second", robot)
    # Item 6: step before reset.
    with pytest.raises(ofmpc.OfmpcError, match="step before reset"):
        c.step(x, w, ref.preview(0, 10))
    c.reset(x)
    good = c.step(x, w, ref.preview(0, 10))
    assert np.all(np.abs(good) < 1e3)
    # Item 7: shapes, with the argument's name.
    bad = [
        ((x, w, ref.preview(0, 10).T), r"preview must be \(horizon, dof\) = \(10, 6\).*got \(6, 10\)"),
        ((x.reshape(6, 2), w, ref.preview(0, 10)), r"x must be \(2·dof,\) = \(12,\), got \(6, 2\)"),
        ((x, w.reshape(6, 1), ref.preview(0, 10)), r"w_k must be \(dof,\) = \(6,\), got \(6, 1\)"),
        ((x, w, ref.preview(0, 10).reshape(10, 6, 1)), r"preview must be .*got \(10, 6, 1\)"),
        ((x.astype(complex), w, ref.preview(0, 10)), r"x has dtype .*complex"),
        ((x, np.zeros(6, dtype="datetime64[s]"), ref.preview(0, 10)), r"w_k has dtype .*datetime64"),
        ((x, w, np.zeros((10, 6), dtype="timedelta64[s]")), r"preview has dtype .*timedelta64"),
        ((x.astype(str), w, ref.preview(0, 10)), r"x has dtype .*string"),
    ]
    for args, msg in bad:
        with pytest.raises(ofmpc.OfmpcError, match=msg):
            c.step(*args)
    with pytest.raises(ofmpc.OfmpcError, match=r"x0 must be"):
        c.reset(x.reshape(2, 6))


def test_sections_as_lists_and_robot_files_named_like_built_ins(tmp_path, monkeypatch):
    """Issue #22 items 11, 12: a section given as a list is an error naming it; a file named
    like the built-in robot in the working directory does not shadow it."""
    with pytest.raises(ofmpc.OfmpcError, match=r"mpc is written as an array"):
        ofmpc.run({"mpc": [0.01, 10], "controllers": ["usual"]})
    monkeypatch.chdir(tmp_path)
    (tmp_path / "irb140").write_text("not a URDF")
    m = ofmpc.run(
        {
            "controllers": ["usual"],
            "payload": {"masses_kg": [0.0]},
            "simulation": {"hold_s": 0.2, "steady_window_s": 0.1},
        }
    )
    assert m["runs"][0]["status"] == "ok"


def test_program_files_are_read_with_a_limit_and_named(robot, tmp_path):
    """Issue #22 items 15, 17: /dev/zero is not read whole; a Latin-1 file names the byte and
    the encoding; a missing file is said to be missing, not parsed as G-code."""
    if os.path.exists("/dev/zero"):
        # Issue #36: a device is refused as what it is, never read.
        with pytest.raises(ofmpc.OfmpcError, match="it is a character device"):
            ofmpc.plan(pathlib.Path("/dev/zero"), robot)
    latin = tmp_path / "p.gcode"
    latin.write_bytes("G0 X500 Y0 Z600 ; caf\xe9\n".encode("latin-1"))
    with pytest.raises(ofmpc.OfmpcError, match=r"not UTF-8 text: byte 21 \(line 1, column 22\)"):
        ofmpc.plan(str(latin), robot)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        ofmpc.plan("prog.gcode2", robot)


def test_first_stage_gains_reproduce_the_next_torque(robot, ref):
    """gains=True: last_gains holds K (n, 2n), tau_ff = τ_k and x_lin = x_k; a second controller
    stepped at x_k + δx gives τ ≈ tau_ff + K δx (to a few 1e-4 of |K δx|, issue 37 item 5)."""
    w = ref.q[0]
    x = np.concatenate([w + 1e-3, np.full(6, 0.05)])
    dx = 1e-5 * np.arange(1.0, 13.0)
    taus = []
    for xi in (x, x + dx):
        c = ofmpc.Controller("second", robot, horizon=20, gains=True)
        assert c.last_gains is None
        c.reset(np.concatenate([w, np.zeros(6)]))
        taus.append(c.step(xi, w, ref.preview(0, 20)))
        if xi is x:
            g = c.last_gains
    assert g["gain"].shape == (6, 12)
    np.testing.assert_array_equal(g["tau_ff"], taus[0])
    np.testing.assert_array_equal(g["x_lin"], x)
    lin = g["gain"] @ dx
    assert np.max(np.abs(taus[1] - taus[0] - lin)) <= 1e-3 * np.max(np.abs(lin))
    assert ofmpc.Controller("second", robot).last_gains is None
    with pytest.raises(ofmpc.OfmpcError, match="first-stage gains"):
        ofmpc.Controller("pid", robot, gains=True)


def test_the_predicted_command_of_a_position_velocity_output(robot, ref):
    """output="position_velocity": last_command holds the predicted q, q̇, q̈ one lead time
    ahead (issue 37), None with a torque output; an unknown output is refused."""
    w = ref.q[0]
    x = np.concatenate([w + 1e-3, np.zeros(6)])
    c = ofmpc.Controller("second", robot, output="position_velocity", output_lead_s=0.04)
    c.reset(x)
    assert c.last_command is None
    c.step(x, w, ref.preview(0, 10))
    cmd = c.last_command
    assert set(cmd) == {"q_command", "qd_command", "qdd_command", "tau_command"}
    assert np.all(cmd["tau_command"] == 0.0)
    assert cmd["q_command"].shape == (6,) and np.all(np.isfinite(cmd["qdd_command"]))
    assert np.max(np.abs(cmd["q_command"] - w)) < 0.01
    t = ofmpc.Controller("second", robot)
    t.reset(x)
    t.step(x, w, ref.preview(0, 10))
    assert t.last_command is None
    with pytest.raises(ofmpc.OfmpcError, match="output="):
        ofmpc.Controller("second", robot, output="torq")


def test_an_adaptive_kind_identifies_from_the_drives_reported_torque(robot, ref):
    """set_applied_torque (issue 37): an arm at rest holding 2 kg the controller does not know,
    whose drives report the torque they hold it with; second-adaptive through a position
    output identifies it, and its command's torque feed-forward becomes the payload's gravity
    torque, g_loaded(q) − g_nominal(q) (what a drive on the nominal model lacks), to 1e-6 of
    it (measured 9e-9 after 200 samples; a centre of mass 5 cm off the flange is not
    determined at one pose, and the physically consistent estimate is then 2 % off). Without
    a report it identifies nothing (zeros). A report of another shape is refused."""
    w = ref.q[0]
    x = np.concatenate([w, np.zeros(6)])
    loaded = ofmpc.Robot.irb140()
    loaded.set_payload(2.0)
    zero = np.zeros(6)
    held = loaded.rnea(w, zero, zero)
    needed = held - robot.rnea(w, zero, zero)
    preview = np.tile(w, 10)
    for report in (False, True):
        c = ofmpc.Controller("second-adaptive", robot, output="position_velocity", output_lead_s=0.04)
        c.reset(x)
        for _ in range(200):
            if report:
                c.set_applied_torque(held)
            c.step(x, w, preview)
        ff = c.last_command["tau_command"]
        if report:
            assert np.max(np.abs(ff - needed)) <= 1e-6 * np.max(np.abs(needed)), (ff, needed)
        else:
            assert np.all(ff == 0.0)
    with pytest.raises(ofmpc.OfmpcError, match="tau"):
        c.set_applied_torque(np.zeros(5))
    # The same through the supervised controller, step for step.
    s = ofmpc.SupervisedController("second-adaptive", robot, output="position_velocity", output_lead_s=0.04)
    c = ofmpc.Controller("second-adaptive", robot, output="position_velocity", output_lead_s=0.04)
    s.reset(x)
    c.reset(x)
    for k in range(20):
        s.set_applied_torque(held)
        c.set_applied_torque(held)
        s.step(0.01 * k, x, w, preview)
        c.step(x, w, preview)
        np.testing.assert_array_equal(s.last_command["tau_command"], c.last_command["tau_command"])
    assert np.max(np.abs(s.last_command["tau_command"])) > 1.0


def test_the_command_pre_compensates_an_interface_s_smoothing(robot, ref):
    """output_smoothing_s=T: the command is the plan's q + T q̇, q̇ + T q̈ (the inverse of a
    first-order smoothing of time constant T, [mpc] output_smoothing_s; issue 37); refused
    when negative or with a torque output."""
    w = ref.q[0]
    x = np.concatenate([w + 1e-3, np.zeros(6)])
    cmds = []
    for t_s in (None, 0.03):
        c = ofmpc.Controller(
            "second", robot, output="position_velocity", output_lead_s=0.0045, output_smoothing_s=t_s
        )
        c.reset(x)
        c.step(x, w, ref.preview(0, 10))
        cmds.append(c.last_command)
    plain, smoothed = cmds
    assert np.max(np.abs(plain["qd_command"])) > 1e-3
    np.testing.assert_allclose(
        smoothed["q_command"], plain["q_command"] + 0.03 * plain["qd_command"], rtol=0, atol=1e-14
    )
    np.testing.assert_allclose(
        smoothed["qd_command"], plain["qd_command"] + 0.03 * plain["qdd_command"], rtol=0, atol=1e-12
    )
    # The stream model (output_cycle_s): the interface's own cycle and filter step; refused
    # without a smoothing to invert.
    c = ofmpc.Controller(
        "second", robot, output="position_velocity", output_lead_s=0.0045, output_smoothing_s=0.03,
        output_cycle_s=0.002, output_smoothing_step_s=0.001,
    )
    c.reset(x)
    c.step(x, w, ref.preview(0, 10))
    assert np.all(np.isfinite(c.last_command["q_command"]))
    assert np.max(np.abs(c.last_command["q_command"] - smoothed["q_command"])) > 0.0
    with pytest.raises(ofmpc.OfmpcError):
        ofmpc.Controller("second", robot, output="position_velocity", output_cycle_s=0.002)
    for bad in (dict(output="position_velocity", output_smoothing_s=-0.01), dict(output_smoothing_s=0.03)):
        with pytest.raises(ofmpc.OfmpcError, match="smoothing time constant"):
            ofmpc.Controller("second", robot, **bad)


def test_a_safe_stop_commands_a_braking_position(robot, ref):
    """SupervisedController (issue 37) in a position-interface run: the interface brings each
    joint to the commanded [q, q̇] one lead (40 ms, abb-egm's lag) after it was sent (an ideal
    drive behind a pure lag); an encoder slip of 5 mrad at 3 s passes the 1.5 mrad safety
    limit at speed. During the safe stop last_command is the stop law's braking trajectory:
    its speed never grows (to 1e-9 rad/s), it ends below 1e-6 rad/s with the status
    "stopped" and the arm at rest, while the controller's last command moved at > 0.1 rad/s
    (what the interface would otherwise keep receiving). With a torque output there is no
    command."""
    lead, ts, n = 0.04, 0.01, robot.dof
    c = ofmpc.SupervisedController(
        "second", robot, output="position_velocity", output_lead_s=lead,
        max_joint_error_rad=1.5e-3, q_du=1e-3,
    )
    assert c.last_status is None and c.last_command is None
    lag = round(lead / ts)
    sent = [np.concatenate([ref.q[0], np.zeros(n)])] * lag  # the commands in flight
    c.reset(sent[0])
    slip, statuses, speeds, stale = round(3.0 / ts), [], [], None
    samples = len(ref.q)
    for k in range(samples):
        x = sent.pop(0).copy()
        if k >= slip:
            x[0] += 5e-3  # the encoder slipped
        c.step(k * ts, x, ref.q[k], ref.preview(k, c.horizon))
        cmd = c.last_command
        sent.append(np.concatenate([cmd["q_command"], cmd["qd_command"]]))
        speed = float(np.max(np.abs(cmd["qd_command"])))
        statuses.append(c.last_status)
        speeds.append(speed)
        if c.last_status == "controlled":
            stale = speed
    k0 = statuses.index("stopping")
    assert k0 >= slip, f"stopped at sample {k0}, before the slip"
    assert set(statuses[:k0]) == {"controlled"}
    assert set(statuses[k0:]) <= {"stopping", "stopped"} and statuses[-1] == "stopped"
    assert stale > 0.1, stale
    stop = speeds[k0:]
    assert stop[0] < stale
    assert all(b <= a + 1e-9 for a, b in zip(stop, stop[1:])), "the stop's command sped up"
    assert stop[-1] < 1e-6, stop[-1]
    assert np.max(np.abs(sent[-1][n:])) < 1e-6  # the arm, one lead on, at rest too
    t = ofmpc.SupervisedController("second", robot)
    t.reset(sent[0])
    t.step(0.0, sent[0], ref.q[0], ref.preview(0, 10))
    assert t.last_status == "controlled" and t.last_command is None
    with pytest.raises(ofmpc.OfmpcError, match="preview"):
        t.step(0.0, sent[0], ref.q[0], np.zeros((10, 5)))
