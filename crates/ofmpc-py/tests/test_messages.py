"""Issue #22 item 17 from Python: values JSON cannot carry name their key; Controller()'s
keyword arguments are named as Python names them (solver= is one); URDF errors have a line;
a cause is said once."""

from __future__ import annotations

import math

import pytest

import ofmpc
from conftest import IRB140_URDF


@pytest.mark.parametrize(
    "scenario, message",
    [
        ({"mpc": {"ts": math.nan}}, r"scenario: mpc\.ts = nan: give a finite number"),
        ({"payload": {"masses_kg": [0.0, math.inf]}}, r"payload\.masses_kg\[1\] = inf"),
        ({"simulation": {"hold_s": 10**30}}, r"simulation\.hold_s = an integer of 100 bits"),
    ],
)
def test_non_finite_and_huge_values_name_their_key(scenario, message):
    with pytest.raises(ofmpc.OfmpcError, match=message):
        ofmpc.run(scenario)


def test_controller_keywords_are_named_as_python_names_them():
    robot = ofmpc.Robot.irb140()
    c = ofmpc.Controller("second", robot, solver="structured", horizon=12)
    d = ofmpc.Controller("second", robot, solver="dense-qr", horizon=12)
    assert c.horizon == d.horizon == 12
    with pytest.raises(ofmpc.OfmpcError, match=r'solver=fast: give "dense-qr", "structured" or "auto"'):
        ofmpc.Controller("second", robot, solver="fast")
    with pytest.raises(ofmpc.OfmpcError, match=r'unknown weight or keyword argument "solvr"'):
        ofmpc.Controller("second", robot, solvr="structured")
    with pytest.raises(ofmpc.OfmpcError, match=r"q_dy=x: give a number"):
        ofmpc.Controller("second", robot, q_dy="x")


def test_urdf_errors_have_a_line_and_a_payload_limit_is_said_once(tmp_path):
    text = IRB140_URDF.read_text()
    at = text.index('<mass value="') + len('<mass value="')
    bad = text[:at] + "1,5" + text[at:]
    p = tmp_path / "comma.urdf"
    p.write_text(bad)
    line = bad[: bad.index("1,5")].count("\n") + 1
    with pytest.raises(ofmpc.OfmpcError, match=rf"invalid float literal \(line {line}, column \d+: <mass"):
        ofmpc.Robot.from_urdf(p)
    with pytest.raises(ofmpc.OfmpcError) as e:
        ofmpc.run({"mpc": {"model_payload_kg": 1e6}})
    assert str(e.value).count("more than 1000 times") == 1, str(e.value)
    assert "[mpc] model_payload_kg = 1000000" in str(e.value)
