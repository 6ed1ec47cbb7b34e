"""The benchmark programs of the G64 timing (issue 26), generated here: the paper's path,
a CAM zigzag pocket of 0.2 mm segments, a torture test of random lines and arcs and a spiral
of 1000 tangent arcs (the project's own programs, of the kind of LinuxCNC's `tort.ngc` and
`arcspiral.ngc`, which are not copied), and the single cases of the issue. Each is a
`G64 P…` text; `exact_stop(text)` is the same program under `G61`.

All points lie in the IRB 140's workspace around (500, 0, 400) mm, base frame."""

from __future__ import annotations

import math
import pathlib

import numpy as np

PAPER = (pathlib.Path(__file__).resolve().parents[2] / "ofmpc" / "data" / "paper-table1.gcode").read_text()


def exact_stop(text: str) -> str:
    """The program under G61: every `G64 P…` word replaced."""
    import re

    return re.sub(r"G64( P[0-9.]+)?", "G61", text)


def paper(p: float = 0.1) -> str:
    return PAPER.replace("G21 G90", f"G21 G90 G64 P{p}", 1)


def zigzag(seg: float = 0.2, width: float = 40.0, passes: int = 11, step: float = 2.0) -> str:
    """A zigzag pocket at F3000: passes of `width` mm cut into `seg` mm segments (three
    decimals, a slight waviness as CAM output has), `step` mm apart."""
    out = ["G21 G90 G64 P0.01", "G0 X480 Y-10 Z400"]
    first = True
    for k in range(passes):
        y = -10.0 + k * step
        xs = np.arange(0.0, width + 1e-9, seg)
        if k % 2:
            xs = xs[::-1]
        for i, x in enumerate(xs):
            yy = y + 0.02 * math.sin(0.3 * x)
            word = f"X{480 + x:.3f} Y{yy:.3f}"
            if first:
                out.append(f"G1 {word} F3000")
                first = False
            elif i or k:
                out.append(word)
    return "\n".join(out) + "\n"


def _arc_word(start, end, rng, ccw):
    """G2/G3 to `end` from `start` with a random centre on the chord's bisector."""
    mid = 0.5 * (start + end)
    chord = end - start
    perp = np.array([-chord[1], chord[0]]) / max(np.linalg.norm(chord), 1e-12)
    centre = mid + perp * rng.uniform(-1.5, 1.5) * np.linalg.norm(chord)
    i, j = centre - start
    return f"{'G3' if ccw else 'G2'} X{end[0]:.4f} Y{end[1]:.4f} I{i:.4f} J{j:.4f}"


def torture(n: int = 200, seed: int = 1) -> str:
    """Random lines and arcs (XY plane, 40 mm box) with random feeds and a few rapids."""
    rng = np.random.default_rng(seed)
    out = ["G21 G90 G17 G64 P0.05", "G0 X500 Y0 Z400"]
    pos = np.array([500.0, 0.0])
    for k in range(n):
        end = np.array([500.0, 0.0]) + rng.uniform(-20, 20, 2)
        feed = rng.choice([600, 1500, 3000, 6000])
        r = rng.uniform()
        if r < 0.1:
            out.append(f"G0 X{end[0]:.4f} Y{end[1]:.4f}")
        elif r < 0.5:
            out.append(f"G1 X{end[0]:.4f} Y{end[1]:.4f} F{feed}")
        else:
            out.append(_arc_word(pos, end, rng, rng.uniform() < 0.5) + f" F{feed}")
        pos = end
    return "\n".join(out) + "\n"


def arcspiral(n: int = 1000, r0: float = 1.0, r1: float = 6.0) -> str:
    """`n` quarter circles, counter-clockwise, each tangent to the next, radius growing
    from `r0` to `r1` mm; three decimals (near-tangent kinks at the joins), F6000."""
    out = ["G21 G90 G17 G64 P0.01"]
    centre = np.array([500.0, 0.0])
    phi = 0.0
    p = centre + r0 * np.array([1.0, 0.0])
    out.append(f"G0 X{p[0]:.3f} Y{p[1]:.3f} Z400")
    for k in range(n):
        r = r0 + (r1 - r0) * k / max(n - 1, 1)
        c = p - r * np.array([math.cos(phi), math.sin(phi)])
        phi += math.pi / 2
        q = c + r * np.array([math.cos(phi), math.sin(phi)])
        i, j = c - p
        out.append(f"G3 X{q[0]:.3f} Y{q[1]:.3f} I{i:.3f} J{j:.3f}" + (" F6000" if k == 0 else ""))
        p = q
    return "\n".join(out) + "\n"


CASES = {
    "corner_90_f30000": "G21 G90 G64 P0.1\nG0 X450 Y-50 Z400\nG1 X550 F30000\nY50\n",
    "rapid_between_feeds": "G21 G90 G64 P0.1\nG0 X450 Y0 Z400\nG1 X460 F300\nG0 X500\nG1 X510 F300\n",
    "out_and_back_f30000": "G21 G90 G64 P0.1\nG0 X450 Y0 Z400\nG1 X550 F30000\nX450\n",
    "short_segment_between_lines": "G21 G90 G64 P0.1\nG0 X400 Y0 Z400\nG1 X500 F6000\nX500.05\nX600 Y10\n",
    "arc_10um_between_lines": "G21 G90 G17 G64 P0.1\nG0 X400 Y0 Z400\nG1 X500 F6000\nG2 X500.01 Y0 I0.005 J0.1\nG1 X600 Y20\n",
    # Issue 38: a 200 mm square at F12000 whose 90° corners are blended (44 mm/s), not stopped.
    "square_200_f12000_p05": "G21 G90 G64 P0.5\nG0 X400 Y-100 Z400\nG1 X600 F12000\nY100\nX400\nY-100\n",
}


def benchmarks() -> dict:
    """Every benchmark program by name."""
    return {
        "paper_p0.1": paper(0.1),
        "zigzag_0.2mm": zigzag(),
        "torture": torture(),
        "arcspiral": arcspiral(),
        **CASES,
    }
