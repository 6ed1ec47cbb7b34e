"""Issue #36 from Python: keywords that do not apply to a controller's kind are refused
naming the keyword and the kind; a FIFO given as a program is refused at once; a deeply
nested URDF and a robot of absurd dimension raise a Python exception (no segfault, no
abort); plan() answers Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import pytest

import ofmpc


@pytest.mark.parametrize(
    "kind, keyword",
    [
        ("pid", {"q_yw": 5.0}),
        ("pid", {"ctc_bandwidth": 100.0}),
        ("ctc", {"pid_bandwidth": 60.0}),
        ("second", {"pid_bandwidth": 60.0}),
        ("usual", {"dob_observer_bandwidth": 40.0}),
        ("ctc-adaptive", {"solver": "structured"}),
    ],
)
def test_keywords_that_do_not_apply_are_refused(kind, keyword):
    robot = ofmpc.Robot.irb140()
    (name,) = keyword
    with pytest.raises(ofmpc.OfmpcError, match=rf"{name}= does not apply to a \"{kind}\" controller"):
        ofmpc.Controller(kind, robot, **keyword)


def test_keywords_that_apply_are_taken():
    robot = ofmpc.Robot.irb140()
    assert ofmpc.Controller("pid", robot, pid_bandwidth=60.0).kind == "pid"
    assert ofmpc.Controller("dob-mpc", robot, q_yw=5.0, dob_observer_bandwidth=40.0).kind == "dob-mpc"
    assert ofmpc.Controller("second", robot, q_yw=5.0, solver="structured").kind == "second"


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are a Unix thing")
def test_a_fifo_program_is_refused_at_once(tmp_path):
    fifo = tmp_path / "p.ngc"
    os.mkfifo(fifo)
    with pytest.raises(ofmpc.OfmpcError, match=r"it is a named pipe \(FIFO\)"):
        ofmpc.plan(str(fifo), ofmpc.Robot.irb140())
    with pytest.raises(ofmpc.OfmpcError, match=r"it is a named pipe \(FIFO\)"):
        ofmpc.Robot.from_urdf(str(fifo))


def test_deep_urdf_and_absurd_dimension_raise(tmp_path):
    deep = tmp_path / "deep.urdf"
    deep.write_text('<robot name="x">\n' + "<a>" * 30000 + "</a>" * 30000 + "</robot>\n")
    with pytest.raises(ofmpc.OfmpcError, match="nested more than 256 deep"):
        ofmpc.Robot.from_urdf(str(deep))
    big = tmp_path / "big.urdf"
    parts = ['<robot name="big"><link name="l0"/>']
    for i in range(20000):
        parts.append(
            f'<link name="l{i + 1}"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" '
            f'ixy="0" ixz="0" iyz="0"/></inertial></link><joint name="j{i}" type="revolute">'
            f'<parent link="l{i}"/><child link="l{i + 1}"/><axis xyz="0 0 1"/>'
            f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        )
    parts.append("</robot>")
    big.write_text("".join(parts))
    with pytest.raises(ofmpc.OfmpcError, match="more than the limit of 1000"):
        ofmpc.Robot.from_urdf(str(big))


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child")
def test_plan_answers_ctrl_c(tmp_path):
    """A program that takes long to plan: SIGINT raises KeyboardInterrupt within seconds."""
    program = tmp_path / "long.ngc"
    program.write_text("G21 G90\nG0 X500 Y0 Z600\n" + "".join(
        f"G1 X{500 + (i % 2) * 0.01:.2f} Y0 Z600 F6000\n" for i in range(200000)
    ))
    code = textwrap.dedent(
        f"""
        import ofmpc, sys, time
        print("ready", flush=True)
        try:
            ofmpc.plan({str(program)!r}, ofmpc.Robot.irb140())
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "ready"
    import time

    time.sleep(1.0)
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert out.strip() in ("interrupted", "finished"), out


def test_a_program_that_expands_without_bound_raises():
    """G83 with a tiny peck over 100 m makes millions of moves from one line: read_program
    raises naming the move limit and the line (it aborted the interpreter before)."""
    text = "G21 G90\nG0 X0 Y0 Z5\nG83 X0 Y0 Z-100000 R1 Q0.0001\nM2\n"
    with pytest.raises(ofmpc.OfmpcError, match=r"line 3.*more than 250000 moves \(the limit\)"):
        ofmpc.read_program(text)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child")
def test_read_program_answers_ctrl_c(tmp_path):
    """A program whose loop runs for seconds: SIGINT during read_program raises
    KeyboardInterrupt (or the read ends) within seconds, not after the loop."""
    code = textwrap.dedent(
        """
        import ofmpc
        text = "#1=0\\no1 while [#1 LT 9000000]\\n#1=[#1+1]\\no1 endwhile\\nM2\\n"
        print("ready", flush=True)
        try:
            ofmpc.read_program(text)
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
        except ofmpc.OfmpcError:
            print("finished", flush=True)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "ready"
    import time

    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert out.strip() in ("interrupted", "finished"), out
