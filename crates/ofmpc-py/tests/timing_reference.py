"""A time-optimal reference for the G64 timing: TOPP-RA (Pham & Pham 2018, the `toppra`
package from PyPI) on ofmpc's own blended path, with the same limits and no jerk limit.

The path is ofmpc's sampled G64 reference (Cartesian positions and joint positions every
`ts`), re-parameterised by its arc length `s`. It is cut into sections at its stops (the
samples where the path is at rest): a stop is a boundary condition of both timings, so the
reference is timed rest to rest on each section. On each section TOPP-RA sees the path
`[q_1(s) … q_n(s), s]` (a cubic spline through the samples, thinned to at least
`SPACING` apart) with

- each joint's speed and acceleration limit (`max_speed_rad_s`, `max_accel_rad_s2` of the
  robot's drives file);
- on the last coordinate, `s` itself: the speed limit `min(F, √(a/κ))` (the move's feed,
  the centripetal limit on the path's curvature `κ = |p''(s)|`) and the tangential
  acceleration limit `a`.

Durations come from TOPP-RA's gridded profile: `Δt = 2 Δs / (ṡ_i + ṡ_{i+1})` (constant `s̈`
between grid points, section 3 of the paper).
"""

from __future__ import annotations

import tomllib

import numpy as np

# Smallest spacing (m) of the samples a section's splines go through: samples closer than
# this (near a stop, at 1 ms) would make the cubic spline ill-conditioned.
SPACING = 1e-4
# Largest number of TOPP-RA grid points of one section.
MAX_GRID = 20_000
# Path speed (m/s) below which a sample is at rest (a stop between sections).
REST_SPEED = 2e-4


def drive_limits(drives_toml) -> tuple[np.ndarray, np.ndarray]:
    """Joint speed and acceleration limits of a drives file, in joint order."""
    with open(drives_toml, "rb") as f:
        joints = tomllib.load(f)["joints"]
    names = sorted(joints)
    vel = np.array([joints[n]["max_speed_rad_s"] for n in names])
    acc = np.array([joints[n]["max_accel_rad_s2"] for n in names])
    return vel, acc


def sections(cart: np.ndarray, ts: float) -> list[np.ndarray]:
    """Index ranges of the moving parts between stops (each with its rest samples at both
    ends)."""
    speed = np.zeros(len(cart))
    speed[1:-1] = np.linalg.norm(cart[2:] - cart[:-2], axis=1) / (2 * ts)
    moving = speed >= REST_SPEED
    out = []
    k = 0
    n = len(cart)
    while k < n:
        if not moving[k]:
            k += 1
            continue
        start = k
        while k < n and moving[k]:
            k += 1
        out.append(np.arange(max(start - 1, 0), min(k + 1, n)))
    return out


def _thin(s: np.ndarray) -> np.ndarray:
    """Indices of samples at least SPACING (or length / MAX_GRID) apart, both ends kept."""
    spacing = max(SPACING, (s[-1] - s[0]) / MAX_GRID)
    keep = [0]
    for i in range(1, len(s) - 1):
        if s[i] - s[keep[-1]] >= spacing and s[-1] - s[i] >= 0.5 * spacing:
            keep.append(i)
    keep.append(len(s) - 1)
    return np.array(keep)


def section_duration(cart, q, feed, vel, acc, a_path) -> float:
    """TOPP-RA's time-optimal duration, rest to rest, of one section."""
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    ta.setup_logging("WARNING")
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(cart, axis=0), axis=1))])
    if s[-1] < 1e-6:
        return 0.0
    idx = _thin(s)
    ss, pts, qs, fs = s[idx], cart[idx], q[idx], feed[idx]
    if len(ss) < 3:
        # A tiny section: rest to rest at ±a.
        return 2.0 * np.sqrt(s[-1] / a_path)
    way = np.hstack([qs, ss[:, None]])
    path = ta.SplineInterpolator(ss, way)
    geom = ta.SplineInterpolator(ss, pts)
    kappa = np.linalg.norm(geom(ss, 2), axis=1)
    vmax = np.minimum(fs, np.sqrt(a_path / np.maximum(kappa, 1e-12)))
    n = q.shape[1]

    def vlim(x):
        v = float(np.interp(x, ss, vmax))
        lim = np.empty((n + 1, 2))
        lim[:n, 0], lim[:n, 1] = -vel, vel
        lim[n] = (-v, v)
        return lim

    alim = np.empty((n + 1, 2))
    alim[:n, 0], alim[:n, 1] = -acc, acc
    alim[n] = (-a_path, a_path)
    cons = [
        constraint.JointVelocityConstraintVarying(vlim),
        constraint.JointAccelerationConstraint(alim),
    ]
    inst = algo.TOPPRA(cons, path, gridpoints=ss, parametrizer="ParametrizeConstAccel")
    _sdd, sd, _v, _k = inst.compute_parameterization(0.0, 0.0, return_data=True)
    if sd is None:
        raise RuntimeError("TOPP-RA found no parameterisation")
    sd = np.maximum(sd, 0.0)
    den = sd[1:] + sd[:-1]
    ds = np.diff(ss)
    # Intervals at rest at both ends (none but a degenerate grid): rest to rest at ±a.
    dt = np.where(den > 0, 2 * ds / np.maximum(den, 1e-300), 2 * np.sqrt(ds / a_path))
    return float(dt.sum())


def reference_duration(ref, feeds_by_line, rapid, vel, acc, a_path) -> tuple[float, int]:
    """(time-optimal duration, number of stops inside the program) of ofmpc's sampled path
    `ref` (a `Reference`): feeds from `feeds_by_line` (m/s, `rapid` for lines without F)."""
    cart, q, lines = np.asarray(ref.cartesian), np.asarray(ref.q), np.asarray(ref.lines)
    feed = np.array([feeds_by_line.get(int(ln), rapid) for ln in lines])
    parts = sections(cart, ref.ts)
    total = sum(section_duration(cart[p], q[p], feed[p], vel, acc, a_path) for p in parts)
    return total, max(len(parts) - 1, 0)


def feeds(program_json: dict, rapid: float) -> dict:
    """Feed (m/s) of each program line of `ofmpc.read_program`'s moves."""
    out = {}
    for m in program_json["moves"]:
        f = m.get("feed_mm_s")
        out[int(m["line"])] = rapid if (f is None or m["kind"] == "rapid") else f * 1e-3
    return out
