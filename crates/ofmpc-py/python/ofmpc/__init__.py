"""ofmpc: offset-free model predictive control of industrial robots, from Python.

The computation runs in Rust (the ``ofmpc`` crate); this package is a thin
layer over it: numpy arrays in and out, ``OfmpcError`` (a ``ValueError``)
with the library's messages.

>>> import ofmpc
>>> robot = ofmpc.Robot.irb140()
>>> ref = ofmpc.plan("paper", robot)               # the paper's Table I path
>>> ctl = ofmpc.Controller("second", robot)         # the paper's tuning
>>> x = list(ref.q[0]) + [0.0] * robot.dof
>>> ctl.reset(x)
>>> tau = ctl.step(x, ref.q[0], ref.preview(0, ctl.horizon))
>>> metrics = ofmpc.run({"controllers": ["first"], "payload": {"masses_kg": [0.25]}})
"""

from __future__ import annotations

import json
import os
import re
import stat
from typing import Any, Mapping, Optional, Sequence, Tuple, Union

from ._ofmpc import (
    STANDARD_GRAVITY,
    Controller,
    OfmpcError,
    Reference,
    Robot,
    SupervisedController,
    __version__,
    _plan,
    _read_program,
    _run_file,
    _run_json,
)

__all__ = [
    "Controller",
    "OfmpcError",
    "Reference",
    "Robot",
    "STANDARD_GRAVITY",
    "SupervisedController",
    "__version__",
    "plan",
    "read_program",
    "run",
]

_PROGRAM_SUFFIXES = (".gcode", ".nc", ".ngc", ".tap", ".cnc", ".txt")


# The largest program read (bytes), as the command's limit (ofmpc_scenario::MAX_PROGRAM_BYTES).
_MAX_PROGRAM_BYTES = 64 << 20


def _read_program_file(path: str) -> str:
    """The file's text: at most _MAX_PROGRAM_BYTES are read (a /dev/zero is never read whole);
    text that is not UTF-8 is an OfmpcError naming the byte, line and the encoding to use."""
    # Opened without blocking and refused unless a regular file (issue #36: a named pipe with
    # no writer waited forever), as every reader of the library does (ofmpc::input).
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with open(fd, "rb") as f:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = (
                "a folder" if stat.S_ISDIR(mode)
                else "a named pipe (FIFO)" if stat.S_ISFIFO(mode)
                else "a character device" if stat.S_ISCHR(mode)
                else "a block device" if stat.S_ISBLK(mode)
                else "a socket" if stat.S_ISSOCK(mode)
                else "not a regular file"
            )
            raise OfmpcError(
                f"{path}: it is {kind}, not a regular file (a read would wait or never end): "
                "give the path of a file"
            )
        data = f.read(_MAX_PROGRAM_BYTES + 1)
    if len(data) > _MAX_PROGRAM_BYTES:
        raise OfmpcError(
            f"{path}: it is larger than the limit of {_MAX_PROGRAM_BYTES} bytes "
            f"({_MAX_PROGRAM_BYTES >> 20} MiB; reading stopped there): split it, or check that it is the file you meant"
        )
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        enc = "UTF-16" if data[:2] in (b"\xff\xfe", b"\xfe\xff") else "LATIN1"
        line = data[: e.start].count(b"\n") + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise OfmpcError(
            f"{path}: not UTF-8 text: byte {e.start} (line {line}, column {col}) is 0x{data[e.start]:02x}: "
            f"save it as UTF-8 (e.g. iconv -f {enc} -t UTF-8)"
        ) from None


# One word with a folder separator or a file extension: a file name, not G-code.
_LOOKS_LIKE_FILE = re.compile(r"^[^\s;()]*(/[^\s;()]*|\.[A-Za-z][A-Za-z0-9_]*)$")


def _program_text(program: Union[str, "os.PathLike[str]"]) -> Tuple[Optional[str], str]:
    """(text or None for the built-in program, name for messages)."""
    if isinstance(program, os.PathLike):
        path = os.fspath(program)
        return _read_program_file(path), path
    if not isinstance(program, str):
        raise TypeError(f"program must be a path, G-code text or 'paper', not {type(program).__name__}")
    if program.strip().lower() == "paper":
        return None, "paper-table1.gcode (built in)"
    if "\n" not in program and os.path.exists(program):
        return _read_program_file(program), program
    one_line = "\n" not in program.strip()
    if one_line and (
        program.strip().lower().endswith(_PROGRAM_SUFFIXES) or _LOOKS_LIKE_FILE.match(program.strip())
    ):
        raise FileNotFoundError(f"program file {program!r} does not exist (give a path, G-code text or 'paper')")
    return program, "program"


def plan(
    program: Union[str, "os.PathLike[str]"],
    robot: Robot,
    ts: float = 0.01,
    origin: Optional[Sequence[float]] = None,
    *,
    profile: str = "septic",
    max_speed: float = 0.5,
    max_accel: float = 2.5,
    rpy_deg: Optional[Sequence[float]] = None,
) -> Reference:
    """Plans a G-code program for ``robot``: parse, time, map to joint space by IK.

    Args:
        program: a G-code file path, G-code text, or ``"paper"`` (the paper's Table I
            program, built in).
        robot: the robot whose inverse kinematics maps the path.
        ts: sample period of the reference (s); the controller's Ts.
        origin: G54 work offset ``(x, y, z)`` in mm (as ``--origin`` of the CLI) for
            programs that set none.
        profile: rest-to-rest time law of every segment, ``"septic"`` (the paper's) or
            ``"quintic"``.
        max_speed: path speed limit (m/s) of moves without an F word.
        max_accel: path acceleration limit (m/s²).
        rpy_deg: fixed flange orientation (roll, pitch, yaw in degrees, base frame);
            default: the orientation at q = 0.

    Returns:
        A :class:`Reference`: ``.t`` (K,), ``.q``/``.qd``/``.qdd`` (K, n),
        ``.cartesian`` (K, 3) and ``.preview(k, N)``.

    Raises:
        OfmpcError: the program does not parse (line and column in the message), a
            point is unreachable or outside the joint limits, a setting is invalid.
    """
    text, name = _program_text(program)
    o = None if origin is None else tuple(float(v) for v in origin)
    r = None if rpy_deg is None else tuple(float(v) for v in rpy_deg)
    if o is not None and len(o) != 3:
        raise OfmpcError(f"origin has {len(o)} values: give (x, y, z) in mm")
    if r is not None and len(r) != 3:
        raise OfmpcError(f"rpy_deg has {len(r)} values: give (roll, pitch, yaw) in degrees")
    return _plan(text, name, robot, float(ts), o, profile, float(max_speed), float(max_accel), r)


def read_program(
    program: Union[str, "os.PathLike[str]"],
    origin: Optional[Sequence[float]] = None,
    robot: Optional[Robot] = None,
    tool_table: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> dict:
    """Reads a G-code program without planning it, as ``ofmpc inspect program`` does.

    Args:
        program: a G-code file path, G-code text, or ``"paper"``.
        origin: G54 work offset ``(x, y, z)`` in mm; default none.
        robot: the program starts from the tool position of the robot's start pose;
            default: machine zero (0, 0, 0).
        tool_table: path of a tool table (LinuxCNC's ``.tbl`` format, lengths in mm) for
            ``G43 H<n>``; without one ``G43 H<n>`` is refused.

    Returns:
        ``{"units": "mm", "start", "tool_length_mm", "moves": [{"line", "kind", "end",
        "center", "normal", "turns", "feed_mm_s"}], "events", "messages", "warnings"}``,
        points in machine coordinates (mm).

    Raises:
        OfmpcError: the program does not read (line and column in the message).
    """
    text, name = _program_text(program)
    o = None if origin is None else tuple(float(v) for v in origin)
    if o is not None and len(o) != 3:
        raise OfmpcError(f"origin has {len(o)} values: give (x, y, z) in mm")
    t = None if tool_table is None else os.fspath(tool_table)
    return json.loads(_read_program(text, name, o, robot, t))


def _check_numbers(value: Any, key: str) -> None:
    """Raises OfmpcError naming the key (``mpc.ts``, ``payload.masses_kg[1]``) of a value JSON
    and TOML cannot carry: NaN, an infinity, or an integer beyond 64 bits (JSON would write
    them, and the scenario's reader would only say "expected value")."""
    import math

    if isinstance(value, Mapping):
        for k, v in value.items():
            _check_numbers(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_numbers(v, f"{key}[{i}]")
    elif isinstance(value, bool):
        return
    elif isinstance(value, int) and not -(2**63) <= value < 2**63:
        raise OfmpcError(
            f"scenario: {key} = an integer of {value.bit_length()} bits: out of range "
            "(integers have 64 bits; give a float for a large number)"
        )
    elif isinstance(value, float) and not math.isfinite(value):
        raise OfmpcError(f"scenario: {key} = {value}: give a finite number")


def run(scenario: Union[Mapping[str, Any], str, "os.PathLike[str]"]) -> dict:
    """Runs a scenario in Rust (the GIL released) and returns its metrics.

    Args:
        scenario: a dict with the keys of the TOML scenario file (see
            ``examples/scenario.toml``; relative paths are relative to the working
            directory), or the path of such a file (paths inside relative to it).
            Keys left out take their defaults; unknown keys are an error.

    Returns:
        The content of ``metrics.json`` of ``ofmpc run`` for the same scenario:
        ``{"runs": [{"name", "controller", "payload_kg", "joint_error_rms_rad", ...}]}``,
        one run per payload × controller (payloads outer). No file is written.

    Raises:
        OfmpcError: the scenario is invalid (the message names the key).
        KeyboardInterrupt: Ctrl-C during the runs: they stop at their next sample
            (signals are checked every 20 ms) and no result is returned.
    """
    if isinstance(scenario, Mapping):
        _check_numbers(scenario, "")
        text = _run_json(json.dumps(scenario))
    elif isinstance(scenario, (str, os.PathLike)):
        text = _run_file(os.fspath(scenario))
    else:
        raise TypeError(f"scenario must be a dict or a path, not {type(scenario).__name__}")
    return json.loads(text)
