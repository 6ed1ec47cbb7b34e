"""MuJoCo as the plant, ofmpc as the controller: the paper's experiment in a simulator
the control community trusts.

The IRB 140 is built in MuJoCo from the same URDF and drives.toml as ofmpc's model
(joint axes, inertials, armature, gravity 9.80665 m/s²); a payload the controller
does not know is attached at the flange; `ofmpc.Controller` closes the loop at
Ts = 10 ms with the torque held over the period (zero-order hold) while MuJoCo
integrates it with RK4 in 1 ms steps. Prints the steady and RMS errors.

    python examples/python/mujoco_closed_loop.py --payload 0.25
    python examples/python/mujoco_closed_loop.py --payload 1 --controllers first,second --hold 3

Needs: `pip install ./crates/ofmpc-py mujoco`.
"""

from __future__ import annotations

import argparse
import pathlib
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

try:
    import numpy as np

    import ofmpc
except ModuleNotFoundError as _e:  # pragma: no cover
    raise SystemExit(
        f"this example needs the Python package {_e.name!r}: install ofmpc's wheel with "
        "pip install ./crates/ofmpc-py (it brings numpy), then pip install mujoco, in the same "
        "environment (README, Python)"
    ) from _e

REPO = pathlib.Path(__file__).resolve().parents[2]
IRB140_URDF = REPO / "crates" / "ofmpc" / "robots" / "irb140" / "irb140.urdf"
IRB140_DRIVES = REPO / "crates" / "ofmpc" / "robots" / "irb140" / "drives.toml"


# ---------------------------------------------------------------- URDF → MJCF


def _floats(text: Optional[str], default: Sequence[float]) -> np.ndarray:
    return np.array([float(v) for v in text.split()]) if text else np.array(default, dtype=float)


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """URDF fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _quat(rot: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    m = rot
    t = np.trace(m)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = [0.0] * 4
        q[0] = (m[k, j] - m[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j, i] + m[i, j]) / s
        q[1 + k] = (m[k, i] + m[i, k]) / s
    q = np.array(q)
    return q / np.linalg.norm(q)


def _fmt(v: Sequence[float]) -> str:
    return " ".join(repr(float(x)) for x in v)


def _origin(el: Optional[ET.Element]) -> tuple:
    if el is None:
        return np.zeros(3), np.eye(3)
    return _floats(el.get("xyz"), [0, 0, 0]), _rpy_matrix(_floats(el.get("rpy"), [0, 0, 0]))


def _pose_attrs(pos: np.ndarray, rot: np.ndarray) -> Dict[str, str]:
    return {"pos": _fmt(pos), "quat": _fmt(_quat(rot))}


def _inertial(body: ET.Element, link: ET.Element) -> None:
    """Adds the link's <inertial> (inertia rotated into the body frame) to `body`."""
    inertial = link.find("inertial")
    if inertial is None:
        return
    pos, rot = _origin(inertial.find("origin"))
    mass = float(inertial.find("mass").get("value"))
    i = inertial.find("inertia")
    g = {k: float(i.get(k, 0.0)) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    tensor = np.array(
        [[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]], [g["ixz"], g["iyz"], g["izz"]]]
    )
    tensor = rot @ tensor @ rot.T
    full = [tensor[0, 0], tensor[1, 1], tensor[2, 2], tensor[0, 1], tensor[0, 2], tensor[1, 2]]
    ET.SubElement(body, "inertial", {"pos": _fmt(pos), "mass": repr(mass), "fullinertia": _fmt(full)})


def read_armature(drives: pathlib.Path) -> Dict[str, float]:
    """joint name → armature (kg·m²) from a drives.toml."""
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError:  # pragma: no cover
        try:
            import tomli as tomllib
        except ModuleNotFoundError as e:
            raise SystemExit("Python < 3.11 reads TOML with tomli: pip install tomli") from e
    with open(drives, "rb") as f:
        data = tomllib.load(f)
    return {name: float(d.get("armature_kgm2", 0.0)) for name, d in data.get("joints", {}).items()}


def mjcf_from_urdf(
    urdf: pathlib.Path,
    drives: Optional[pathlib.Path],
    payload_kg: float = 0.0,
    payload_com: Sequence[float] = (0.0, 0.0, 0.0),
    gravity: float = ofmpc.STANDARD_GRAVITY,
    timestep: float = 1e-3,
) -> str:
    """MJCF of a fixed-base serial URDF robot: one hinge (revolute) or slide (prismatic)
    per moving joint with the drives' armature, one motor per joint (torque, gear 1,
    unlimited), no contacts, no damping; massless leaf links (the flange) become sites;
    a point payload of `payload_kg` at `payload_com` in the flange frame."""
    root = ET.parse(urdf).getroot()
    links = {l.get("name"): l for l in root.findall("link")}
    joints = root.findall("joint")
    children = {j.get("child") for j in joints}
    base = next(n for n in links if n not in children)
    by_parent: Dict[str, List[ET.Element]] = {}
    for j in joints:
        by_parent.setdefault(j.find("parent").get("link"), []).append(j)
    armature = read_armature(drives) if drives else {}

    mj = ET.Element("mujoco", {"model": root.get("name", "robot")})
    ET.SubElement(mj, "compiler", {"angle": "radian", "inertiafromgeom": "false", "autolimits": "true"})
    option = ET.SubElement(
        mj, "option", {"gravity": f"0 0 {-gravity!r}", "timestep": repr(timestep), "integrator": "RK4"}
    )
    ET.SubElement(option, "flag", {"contact": "disable"})
    world = ET.SubElement(mj, "worldbody")
    actuator = ET.SubElement(mj, "actuator")
    flange_name = None

    def add(parent_body: ET.Element, link_name: str) -> None:
        nonlocal flange_name
        for j in by_parent.get(link_name, []):
            child = j.find("child").get("link")
            pos, rot = _origin(j.find("origin"))
            kind = j.get("type")
            leaf = not by_parent.get(child) and links[child].find("inertial") is None
            if kind == "fixed" and leaf:
                ET.SubElement(parent_body, "site", {"name": child, **_pose_attrs(pos, rot)})
                flange_name = child
                continue
            body = ET.SubElement(parent_body, "body", {"name": child, **_pose_attrs(pos, rot)})
            _inertial(body, links[child])
            if kind in ("revolute", "continuous", "prismatic"):
                name = j.get("name")
                attrs = {
                    "name": name,
                    "type": "slide" if kind == "prismatic" else "hinge",
                    "axis": _fmt(_floats(j.find("axis").get("xyz") if j.find("axis") is not None else None, [1, 0, 0])),
                    "armature": repr(armature.get(name, 0.0)),
                }
                # No range: the controller, not a joint stop, keeps the joint in range.
                ET.SubElement(body, "joint", attrs)
                ET.SubElement(actuator, "motor", {"name": name, "joint": name, "gear": "1"})
            elif kind != "fixed":
                raise ValueError(f"{urdf}: joint {j.get('name')!r} of type {kind!r} is not supported")
            add(body, child)

    add(world, base)
    if flange_name is None:
        raise ValueError(f"{urdf}: no massless leaf link (flange) found")
    if payload_kg > 0.0:
        # The payload: a point mass at `payload_com` in the flange frame, welded to
        # the flange's parent body (the site's body).
        site = next(s for s in mj.iter("site") if s.get("name") == flange_name)
        holder = next(b for b in mj.iter("body") if site in list(b))
        spos = _floats(site.get("pos"), [0, 0, 0])
        w, x, y, z = _floats(site.get("quat"), [1, 0, 0, 0])
        srot = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        payload = ET.SubElement(holder, "body", {"name": "payload", **_pose_attrs(spos, srot)})
        # MuJoCo needs a positive inertia: 1e-12 kg·m² is a point mass at this scale.
        ET.SubElement(
            payload,
            "inertial",
            {"pos": _fmt(payload_com), "mass": repr(float(payload_kg)), "diaginertia": "1e-12 1e-12 1e-12"},
        )
    return ET.tostring(mj, encoding="unicode")


# ---------------------------------------------------------------- closed loop


@dataclass
class LoopResult:
    """One closed-loop run; errors are reference − measured."""

    controller: str
    payload_kg: float
    t: np.ndarray
    joint_error: np.ndarray  # (K, n) rad
    cartesian_error: np.ndarray  # (K, 3) m
    tau: np.ndarray  # (K, n) N·m
    step_us: np.ndarray  # controller step wall times (µs)
    steady_window_s: float
    metrics: Dict[str, float] = field(default_factory=dict)

    def summarize(self) -> Dict[str, float]:
        steady = self.t >= self.t[-1] - self.steady_window_s + 1e-9
        norm = np.linalg.norm(self.cartesian_error, axis=1) * 1e3
        self.metrics = {
            "cartesian_error_rms_mm": float(np.sqrt(np.mean(norm**2))),
            "cartesian_error_max_mm": float(norm.max()),
            "steady_cartesian_error_mm": float(norm[steady].max()),
            "steady_joint_error_max_rad": float(np.abs(self.joint_error[steady]).max()),
            "step_time_median_us": float(np.median(self.step_us)),
        }
        return self.metrics


def closed_loop(
    kind: str,
    payload_kg: float,
    program: str = "paper",
    hold_s: float = 2.0,
    steady_window_s: float = 0.5,
    ts: float = 0.01,
    substep: float = 1e-3,
    path_s: Optional[float] = None,
    reference: Optional[ofmpc.Reference] = None,
) -> LoopResult:
    """Runs `kind` (its model: the robot without payload) against MuJoCo (with the
    payload) along `program`, then holds the last point for `hold_s`.

    `path_s` cuts the path after that many seconds (the hold then holds the sample
    reached), for short runs; `reference` reuses a planned reference."""
    try:
        import mujoco
    except ModuleNotFoundError as e:
        raise SystemExit(
            "this example needs MuJoCo's Python package: pip install mujoco "
            "(in the environment where ofmpc is installed)"
        ) from e

    robot = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)  # the controller's model
    ref = reference if reference is not None else ofmpc.plan(program, robot, ts=ts)
    w_all = ref.q
    cart_all = ref.cartesian
    if path_s is not None:
        keep = min(len(w_all), int(round(path_s / ts)) + 1)
        w_all, cart_all = w_all[:keep], cart_all[:keep]
    n = robot.dof
    k_path = len(w_all)
    total = k_path + int(round(hold_s / ts))

    model = mujoco.MjModel.from_xml_string(
        mjcf_from_urdf(IRB140_URDF, IRB140_DRIVES, payload_kg=payload_kg, timestep=substep)
    )
    substeps = int(round(ts / model.opt.timestep))
    if abs(substeps * model.opt.timestep - ts) > 1e-12:
        raise ValueError(f"Ts = {ts} s is not a multiple of the MuJoCo timestep {model.opt.timestep} s")
    data = mujoco.MjData(model)
    data.qpos[:] = w_all[0]
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    flange = model.site("flange").id

    controller = ofmpc.Controller(kind, robot, ts=ts)
    horizon = controller.horizon
    x = np.empty(2 * n)
    preview = np.empty((horizon, n))
    joint_error = np.empty((total, n))
    cart_error = np.empty((total, 3))
    taus = np.empty((total, n))
    step_us = np.empty(total)
    x[:n], x[n:] = data.qpos, data.qvel
    controller.reset(x)
    last = k_path - 1
    for k in range(total):
        x[:n], x[n:] = data.qpos, data.qvel
        w = w_all[min(k, last)]
        for j in range(horizon):
            preview[j] = w_all[min(k + 1 + j, last)]
        t0 = time.perf_counter()
        tau = controller.step(x, w, preview)
        step_us[k] = (time.perf_counter() - t0) * 1e6
        joint_error[k] = w - data.qpos
        cart_error[k] = cart_all[min(k, last)] - data.site_xpos[flange]
        taus[k] = tau
        data.ctrl[:] = tau  # zero-order hold over Ts: `substeps` RK4 steps of 1 ms
        mujoco.mj_step(model, data, nstep=substeps)
        if not np.all(np.isfinite(data.qpos)) or np.abs(joint_error[k]).max() > 0.2:
            raise RuntimeError(f"{kind}, {payload_kg} kg: diverged at t = {k * ts:.2f} s")
    result = LoopResult(
        controller=kind,
        payload_kg=payload_kg,
        t=np.arange(total) * ts,
        joint_error=joint_error,
        cartesian_error=cart_error,
        tau=taus,
        step_us=step_us,
        steady_window_s=steady_window_s,
    )
    result.summarize()
    return result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--payload", type=float, default=0.25, help="payload at the flange, unknown to the controller (kg)")
    p.add_argument("--controllers", default="usual,first,second", help="comma-separated: usual, first, second")
    p.add_argument("--program", default="paper", help="G-code file, or 'paper' (the paper's Table I)")
    p.add_argument("--hold", type=float, default=2.0, help="hold of the last point after the path (s)")
    args = p.parse_args()
    robot = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)
    ref = ofmpc.plan(args.program, robot)
    print(f"{ref!r}; MuJoCo plant with an unknown {args.payload} kg payload at the flange")
    print(f"{'controller':10} {'RMS Cart. (mm)':>15} {'steady Cart. (mm)':>18} {'steady joint (rad)':>19} {'step (µs)':>10} {'wall (s)':>9}")
    for kind in args.controllers.split(","):
        t0 = time.perf_counter()
        r = closed_loop(kind.strip(), args.payload, hold_s=args.hold, reference=ref)
        m = r.metrics
        print(
            f"{kind:10} {m['cartesian_error_rms_mm']:15.4g} {m['steady_cartesian_error_mm']:18.3g} "
            f"{m['steady_joint_error_max_rad']:19.3g} {m['step_time_median_us']:10.1f} {time.perf_counter() - t0:9.2f}"
        )


if __name__ == "__main__":
    main()
