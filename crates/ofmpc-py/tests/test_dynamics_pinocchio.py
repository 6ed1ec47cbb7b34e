"""ofmpc's rigid-body algorithms against Pinocchio (`pin` on PyPI) on the IRB 140.

Both models come from the same URDF; both get the drives' armature and the same
payload (a rigid body at the flange), and the same gravity constant
(ofmpc.STANDARD_GRAVITY = 9.80665 m/s²; Pinocchio's default is 9.81).
"""

from __future__ import annotations

import numpy as np
import pytest

import ofmpc
from conftest import IRB140_DRIVES, IRB140_URDF, rel_err

pin = pytest.importorskip("pinocchio")

TOL = 1e-10
# A payload that is not a special case: off-centre, with a full inertia tensor.
PAYLOAD_MASS = 1.7
PAYLOAD_COM = (0.012, -0.021, 0.054)
PAYLOAD_INERTIA = np.array([[4e-3, 2e-4, -1e-4], [2e-4, 5e-3, 3e-4], [-1e-4, 3e-4, 3e-3]])


def armature_from_drives() -> np.ndarray:
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError:  # pragma: no cover
        import tomli as tomllib
    with open(IRB140_DRIVES, "rb") as f:
        d = tomllib.load(f)
    return np.array([d["joints"][f"joint_{i}"]["armature_kgm2"] for i in range(1, 7)])


def models(payload: bool):
    """(ofmpc robot, pinocchio model, pinocchio data, flange frame id)."""
    robot = ofmpc.Robot.from_urdf(IRB140_URDF, drives=IRB140_DRIVES)
    model = pin.buildModelFromUrdf(str(IRB140_URDF))
    model.gravity.linear = np.array([0.0, 0.0, -ofmpc.STANDARD_GRAVITY])
    model.armature = armature_from_drives()
    fid = model.getFrameId("flange")
    if payload:
        robot.set_payload(PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
        frame = model.frames[fid]
        body = pin.Inertia(PAYLOAD_MASS, np.array(PAYLOAD_COM), PAYLOAD_INERTIA)
        model.inertias[frame.parentJoint] += frame.placement.act(body)
    return robot, model, model.createData(), fid


def random_states(model, count: int, seed: int):
    rng = np.random.default_rng(seed)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    for _ in range(count):
        yield rng.uniform(lo, hi), rng.normal(0.0, 1.5, model.nv), rng.normal(0.0, 3.0, model.nv)


def test_the_models_agree_on_the_basics():
    robot, model, _, _ = models(payload=False)
    assert robot.dof == model.nq == model.nv == 6
    assert robot.joint_names == [model.names[i] for i in range(1, model.njoints)]
    np.testing.assert_array_equal(robot.armature, armature_from_drives())
    np.testing.assert_array_equal(robot.gravity_vector, model.gravity.linear)


@pytest.mark.parametrize("payload", [False, True], ids=["no-payload", "payload"])
def test_rnea_mass_matrix_gravity_and_flange_pose_equal_pinocchio(payload):
    robot, model, data, fid = models(payload)
    worst = {}
    for q, v, a in random_states(model, 50, seed=7 if payload else 3):
        tau = pin.rnea(model, data, q, v, a)
        h = pin.crba(model, data, q)
        h = np.triu(h) + np.triu(h, 1).T  # Pinocchio fills the upper triangle
        g = pin.computeGeneralizedGravity(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        pose = data.oMf[fid].homogeneous
        errs = {
            "rnea": rel_err(robot.rnea(q, v, a), tau),
            "mass_matrix": rel_err(robot.mass_matrix(q), h),
            "gravity": rel_err(robot.gravity(q), g),
            "flange_pose": rel_err(robot.flange_pose(q), pose),
        }
        for k, e in errs.items():
            worst[k] = max(worst.get(k, 0.0), e)
    print(f"payload={payload}: worst relative errors vs Pinocchio {worst}")
    assert all(e < TOL for e in worst.values()), worst


@pytest.mark.parametrize("payload", [False, True], ids=["no-payload", "payload"])
def test_coriolis_matrix_equals_pinocchio(payload):
    """C(q, q̇): compared entry by entry with pin.computeCoriolisMatrix, and through
    what defines it: C q̇ = rnea(q, q̇, 0) − g (Pinocchio's nonlinear effects minus
    gravity) and Ḣ − 2C skew-symmetric with Pinocchio's Ḣ (dccrba / finite difference)."""
    robot, model, data, _ = models(payload)
    worst_c, worst_cv, worst_skew = 0.0, 0.0, 0.0
    for q, v, _ in random_states(model, 50, seed=11 if payload else 5):
        c = robot.coriolis_matrix(q, v)
        c_pin = pin.computeCoriolisMatrix(model, data, q, v)
        worst_c = max(worst_c, rel_err(c, c_pin))
        cv_pin = pin.nonLinearEffects(model, data, q, v) - pin.computeGeneralizedGravity(model, data, q)
        worst_cv = max(worst_cv, rel_err(c @ v, cv_pin))
        # Ḣ = Σ_k ∂H/∂q_k q̇_k by a central difference of Pinocchio's H along q̇.
        eps = 1e-6
        hp = pin.crba(model, data, pin.integrate(model, q, v * eps))
        hm = pin.crba(model, data, pin.integrate(model, q, -v * eps))
        hdot = (np.triu(hp) + np.triu(hp, 1).T - np.triu(hm) - np.triu(hm, 1).T) / (2 * eps)
        n = hdot - 2 * c
        worst_skew = max(worst_skew, float(np.abs(n + n.T).max() / np.abs(hdot).max()))
    print(
        f"payload={payload}: C vs Pinocchio {worst_c:.2e}, C·q̇ vs Pinocchio {worst_cv:.2e}, "
        f"(Ḣ − 2C) + (Ḣ − 2C)ᵀ relative {worst_skew:.2e} (Ḣ by finite difference)"
    )
    assert worst_c < TOL
    assert worst_cv < TOL
    assert worst_skew < 1e-6  # limited by the finite difference of Ḣ, not by C
