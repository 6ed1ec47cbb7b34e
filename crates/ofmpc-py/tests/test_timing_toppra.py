"""The G64 timing against a time-optimal reference (issue 26): TOPP-RA from PyPI on
ofmpc's own blended path with the same limits, no jerk limit (`timing_reference.py`), on
the benchmark programs (`timing_programs.py`).

Targets asserted on every program: the G64 duration is at most 1.10 × the reference plus
0.1 s per section between stops (the jerk filter's window, T_j = 2a/j = 0.1 s at the
default 2.5 m/s² and 50 m/s³, which a reference without a jerk limit does not pay; the
program's start and end count as stops), and never longer than the same program under
G61. And the issue's single cases: the 90° corner at F30000 within 1.0 s."""

from __future__ import annotations

import pytest

import ofmpc
from conftest import IRB140_DRIVES
from timing_programs import benchmarks, exact_stop
from timing_reference import drive_limits, feeds, reference_duration

toppra = pytest.importorskip("toppra")

TS = 0.002
RAPID = 0.5  # m/s: the planner's default path speed of moves without F (G0)
ACCEL = 2.5  # m/s²: the planner's default path acceleration

# Cases the timing did not bring within the bound (issue 26 open items): expected to fail
# (strict: a case that starts passing fails the run, so it is moved out of this list and the
# bound holds for it from then on). None left.
NOT_YET: dict[str, str] = {}

_PROGRAMS = benchmarks()


@pytest.fixture(scope="module")
def robot():
    return ofmpc.Robot.irb140()


@pytest.fixture(scope="module")
def limits():
    return drive_limits(IRB140_DRIVES)


def _params():
    for name in _PROGRAMS:
        marks = [pytest.mark.xfail(reason=NOT_YET[name], strict=True)] if name in NOT_YET else []
        yield pytest.param(name, marks=marks, id=name)


@pytest.mark.parametrize("name", list(_params()))
def test_g64_is_near_time_optimal(name, robot, limits):
    text = _PROGRAMS[name]
    g64 = ofmpc.plan(text, robot, ts=TS)
    vel, acc = limits
    ref, stops = reference_duration(g64, feeds(ofmpc.read_program(text, robot=robot), RAPID), RAPID, vel, acc, ACCEL)
    bound = 1.10 * ref + 0.1 * (stops + 1)
    assert g64.duration <= bound, f"{name}: G64 {g64.duration:.3f} s > {bound:.3f} s (TOPP-RA {ref:.3f} s, {stops} stops)"


@pytest.mark.parametrize("name", list(_PROGRAMS))
def test_g64_is_never_slower_than_g61(name, robot):
    text = _PROGRAMS[name]
    g64 = ofmpc.plan(text, robot, ts=TS)
    g61 = ofmpc.plan(exact_stop(text), robot, ts=TS)
    assert g64.duration <= g61.duration + TS, f"{name}: G64 {g64.duration:.3f} s > G61 {g61.duration:.3f} s"


def test_the_issue_cases(robot):
    corner = ofmpc.plan(_PROGRAMS["corner_90_f30000"], robot, ts=TS)
    assert corner.duration <= 1.0 + 1e-9


def test_the_reference_is_time_optimal_on_a_line(robot, limits):
    """On a straight 100 mm move at F30000 (no joint limit binding) the reference is the
    bang-bang profile: 2 × 0.2 s accelerating to 0.5 m/s over 50 mm each way = 0.4 s."""
    text = "G21 G90 G64 P0.1\nG0 X450 Y0 Z400\nG1 X550 F30000\n"
    g64 = ofmpc.plan(text, robot, ts=TS)
    vel, acc = limits
    ref, stops = reference_duration(g64, feeds(ofmpc.read_program(text, robot=robot), RAPID), RAPID, vel, acc, ACCEL)
    assert stops == 0
    assert abs(ref - 0.4) < 0.01, ref
