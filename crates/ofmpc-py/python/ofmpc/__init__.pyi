"""Type stubs of the ``ofmpc`` package (Python bindings of the ofmpc Rust crates)."""

import os
from typing import Any, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
F64Array = npt.NDArray[np.float64]

STANDARD_GRAVITY: float
"""Standard gravity 9.80665 m/s², the default gravity of every robot."""
__version__: str

class OfmpcError(ValueError):
    """An error reported by the ofmpc library; the message says where and what to do."""

class Robot:
    """A serial robot: URDF kinematics and inertials, drives' armature, optional payload."""

    @staticmethod
    def irb140() -> Robot:
        """The built-in ABB IRB 140 with its drives (armature, torque and speed limits)."""
    @staticmethod
    def from_urdf(path: Union[str, os.PathLike[str]], drives: Optional[Union[str, os.PathLike[str]]] = None, tip: Optional[str] = None, tcp: Optional[ArrayLike] = None, start_q: Optional[ArrayLike] = None) -> Robot:
        """A robot from a URDF file, with an optional drives file (TOML), the link ending the
        chain (tip), the tool centre point relative to it (tcp, 4×4, m) and the start pose."""
    @property
    def tip(self) -> str:
        """The link that ends the chain."""
    @property
    def start_q(self) -> F64Array:
        """The start pose (rad; m for a prismatic joint)."""
    @property
    def dof(self) -> int:
        """Number of joints n."""
    @property
    def name(self) -> str: ...
    @property
    def joint_names(self) -> List[str]: ...
    @property
    def armature(self) -> F64Array:
        """Armature of every joint (kg·m²), added to the diagonal of H."""
    @property
    def gravity_vector(self) -> F64Array:
        """Gravity in the base frame, (0, 0, −9.80665) m/s² by default."""
    @property
    def payload(self) -> Optional[Tuple[float, F64Array, F64Array]]:
        """(mass_kg, com (3,), inertia about the com (3, 3)) or None."""
    def set_payload(
        self,
        mass_kg: float,
        com: Tuple[float, float, float] = (0.0, 0.0, 0.0),
        inertia: Optional[ArrayLike] = None,
    ) -> None:
        """Attaches a rigid payload at the flange (com in the flange frame, m); 0 kg removes it."""
    def rnea(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> F64Array:
        """τ = H(q) q̈ + C(q, q̇) q̇ + g(q), shape (n,)."""
    def mass_matrix(self, q: ArrayLike) -> F64Array:
        """H(q), armature included, shape (n, n)."""
    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> F64Array:
        """C(q, q̇) from Christoffel symbols (Ḣ − 2C skew-symmetric), shape (n, n)."""
    def gravity(self, q: ArrayLike) -> F64Array:
        """g(q), shape (n,)."""
    def flange_pose(self, q: ArrayLike) -> F64Array:
        """Flange pose in the base frame, 4×4 homogeneous matrix."""
    def flange_jacobian(self, q: ArrayLike) -> F64Array:
        """Geometric flange Jacobian (6, n), linear rows first, base frame."""
    def forward_dynamics(self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> F64Array:
        """q̈ = H⁻¹ (τ − C q̇ − g), shape (n,)."""
    def copy(self) -> Robot: ...

class Reference:
    """A joint reference w_k sampled every ts seconds along a program."""

    @property
    def t(self) -> F64Array:
        """Sample times (K,)."""
    @property
    def q(self) -> F64Array:
        """Joint positions (K, n)."""
    @property
    def qd(self) -> F64Array:
        """Joint velocities (K, n)."""
    @property
    def qdd(self) -> F64Array:
        """Joint accelerations (K, n)."""
    @property
    def cartesian(self) -> F64Array:
        """Flange position of the reference (K, 3), m."""
    @property
    def lines(self) -> List[int]: ...
    @property
    def ts(self) -> float: ...
    @property
    def dof(self) -> int: ...
    @property
    def duration(self) -> float: ...
    @property
    def warnings(self) -> List[str]: ...
    def w(self, k: int) -> F64Array:
        """w_k (n,); past the end the last sample."""
    def preview(self, k: int, horizon: int) -> F64Array:
        """w_{k+1..k+N} as (N, n), the last sample held past the end; N ≤ 1000 (MAX_HORIZON), else OfmpcError."""
    def __len__(self) -> int: ...

class Controller:
    """A predictive controller of the paper: "usual" (Eq. 43), "first" (Eq. 32/37), "second" (Eq. 34/39).

    Its model of the robot is a copy of ``robot`` at construction (payload included).
    Weights (square roots: the cost uses QᵀQ), each a number (times I) or one per joint:
    ``q_yw`` (output error), ``q_dy`` (output increment), ``q_du`` (input increment),
    ``q_u`` (input, usual MPC). Defaults: the paper's tuning. The baselines ``"pid"``,
    ``"ctc"``, ``"ctc-adaptive"``, ``"dob-mpc"`` take their bandwidths (rad/s, a number or
    one per joint) the same way: ``pid_bandwidth`` (default 60), ``ctc_bandwidth`` (150),
    ``dob_observer_bandwidth`` (100). ``solver="dense-qr"``, ``"structured"`` or ``"auto"``
    (the default) chooses the least-squares solver, as ``[mpc] solver`` does.
    ``gains=True`` (``[mpc] gains``) hands out the first-stage feedback law of every step
    (``last_gains``; structured solver, the paper's kinds and their adaptive variants).
    ``output="position_velocity"`` or ``"velocity"`` (``[mpc] output``, with
    ``output_lead_s``) hands out the predicted command (``last_command``);
    ``output_smoothing_s=T`` (``[mpc] output_smoothing_s``) pre-compensates an interface's
    first-order smoothing of time constant T: q + T q̇, q̇ + T q̈, q̈ + T q⃛; with
    ``output_cycle_s`` (and ``output_smoothing_step_s``; ``[mpc]`` keys of the same names) the
    command instead models the interface's stream: the smoothing's exact discrete inverse as
    the interface runs it every step, the acceleration at the period's middle, and a copy of
    the smoothed acceleration (docs: command modes, "The stream model").
    """

    def __init__(
        self,
        kind: str,
        robot: Robot,
        ts: float = 0.01,
        horizon: int = 10,
        gains: bool = False,
        output: str = "torque",
        output_lead_s: Optional[float] = None,
        output_smoothing_s: Optional[float] = None,
        output_cycle_s: Optional[float] = None,
        output_smoothing_step_s: Optional[float] = None,
        **weights: Union[float, Sequence[float], str],
    ) -> None: ...
    @property
    def kind(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def horizon(self) -> int: ...
    @property
    def ts(self) -> float: ...
    @property
    def input(self) -> F64Array:
        """u of the last step (n,)."""
    @property
    def last_info(self) -> Optional[dict]:
        """{"cost", "r_diag_ratio", "zoh_squarings"} of the last step."""
    @property
    def last_telemetry(self) -> Optional[dict]:
        """{"model_time_us", "solve_time_us", "total_time_us", "qp_iterations",
        "active_constraints", "budget_slack_us", "fallback", "budget_hit"} of the last step
        (fallback: "none", "best_feasible", "shifted_plan" or "hold")."""
    @property
    def last_gains(self) -> Optional[dict]:
        """With gains=True: {"gain": K (n, 2n), "tau_ff": τ_k (n,), "x_lin": x_k (2n,)} of the
        last step, so that between MPC samples τ ≈ tau_ff + K (x − x_lin); else None."""
    @property
    def last_command(self) -> Optional[dict]:
        """With output="position_velocity" or "velocity": {"q_command", "qd_command",
        "qdd_command", "tau_command"} (n,) each, the state its model predicted
        output_lead_s ahead, of the last step, and the identified payload's torque
        feed-forward (zeros unless an adaptive kind is given set_applied_torque); else None."""
    def set_applied_torque(self, tau: ArrayLike) -> None:
        """The torque the drives applied over the period that just ended (n,), for an
        interface that reports it: call before step. The adaptive kinds then identify their
        payload from it also through a position or velocity output; others ignore it."""
    def reset(self, x0: ArrayLike) -> None:
        """Starts a run at the measured state x0 = [q; q̇] (2n,); required before the first step."""
    def step(self, x: ArrayLike, w_k: ArrayLike, preview: ArrayLike) -> F64Array:
        """Measured x (2n,), reference w_k (n,), preview (N, n) or (N·n,) → torque τ_k (n,).

        Raises OfmpcError before the first reset, and for an argument of another shape (a
        transposed preview, a column x) or a complex, datetime or string dtype, naming it."""

class SupervisedController:
    """The controller behind its guard (``ofmpc::sim::SupervisedController``): measurement
    repair, plausibility check, safety limit (``max_joint_error_rad``), divergence rule and
    safe stop. With ``output="position_velocity"`` or ``"velocity"``, ``last_command`` is
    what to send to the interface: the controller's predicted command while it controls, the
    stop law's braking trajectory one lead ahead during a safe stop.
    """

    def __init__(
        self,
        kind: str,
        robot: Robot,
        ts: float = 0.01,
        horizon: int = 10,
        output: str = "torque",
        output_lead_s: Optional[float] = None,
        safe_stop: bool = True,
        plausibility_check: bool = False,
        max_joint_error_rad: Optional[float] = None,
        delay_samples: int = 0,
        output_smoothing_s: Optional[float] = None,
        output_cycle_s: Optional[float] = None,
        output_smoothing_step_s: Optional[float] = None,
        **weights: Union[float, Sequence[float], str],
    ) -> None: ...
    @property
    def dof(self) -> int: ...
    @property
    def horizon(self) -> int: ...
    @property
    def ts(self) -> float: ...
    @property
    def last_status(self) -> Optional[str]:
        """"controlled", "repaired_measurement", "stopping", "stopped", "diverged" or
        "non_finite_error" of the last step; None before the first."""
    @property
    def last_command(self) -> Optional[dict]:
        """With output="position_velocity" or "velocity": {"q_command", "qd_command",
        "qdd_command", "tau_command"} (n,) each of the last step — the controller's, or during
        a safe stop the stop law's braking trajectory output_lead_s ahead (to rest, then
        holding; no torque feed-forward); else None."""
    def set_applied_torque(self, tau: ArrayLike) -> None:
        """The torque the drives applied over the period that just ended (n,), as
        Controller.set_applied_torque; call before step."""
    def reset(self, x0: ArrayLike) -> None:
        """Starts a run at the reading x0 = [q; q̇] (2n,): no stop in progress."""
    def step(self, t: float, x: ArrayLike, w_k: ArrayLike, preview: ArrayLike) -> F64Array:
        """Time t (s), raw reading x (2n,; NaN where lost), reference w_k (n,), preview
        (N, n) or (N·n,) → torque (n,): the controller's, or the stop law's during a stop."""

def read_program(
    program: Union[str, os.PathLike[str]],
    origin: Optional[Sequence[float]] = None,
    robot: Optional[Robot] = None,
    tool_table: Optional[Union[str, os.PathLike[str]]] = None,
) -> dict:
    """Reads a program as ``ofmpc inspect program`` does (mm, machine coordinates)."""

def plan(
    program: Union[str, os.PathLike[str]],
    robot: Robot,
    ts: float = 0.01,
    origin: Optional[Sequence[float]] = None,
    *,
    profile: str = "septic",
    max_speed: float = 0.5,
    max_accel: float = 2.5,
    rpy_deg: Optional[Sequence[float]] = None,
) -> Reference:
    """Plans a program (path, G-code text or "paper") for ``robot``; origin in mm."""

def run(scenario: Union[Mapping[str, Any], str, os.PathLike[str]]) -> dict:
    """Runs a scenario (dict with the TOML keys, or a path) and returns metrics.json's content."""
