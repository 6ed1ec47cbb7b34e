// The C++ wrapper's first-stage gains ([mpc] gains = true) and predicted command
// ([mpc] output = "position_velocity"), issue 37: a linear feedback between MPC samples,
// τ = tau_ff + K (x − x_lin), and the position/velocity command one lead time ahead.
// Exits 0 when both came through (run by tests/examples.rs under ASAN).
#include <cmath>
#include <cstdio>
#include <vector>

#include "ofmpc.hpp"

int main() {
  auto robot = ofmpc::Robot::builtin("irb140");
  if (!robot) return 1;
  auto mpc = ofmpc::Controller::create(robot.value(), "second", "[mpc]\ngains = true\n");
  auto pv = ofmpc::Controller::create(
      robot.value(), "second", "[mpc]\noutput = \"position_velocity\"\noutput_lead_s = 0.04\n");
  auto refused = ofmpc::Controller::create(robot.value(), "pid", "[mpc]\ngains = true\n");
  if (!mpc || !pv || refused) return 2;
  std::vector<double> x{0.1, 0.4, -0.2, 0.0, 0.5, 0.0, 0, 0, 0, 0, 0, 0};
  std::vector<double> w{0.12, 0.41, -0.19, 0.01, 0.5, 0.0};
  std::vector<double> preview;
  for (int j = 0; j < 10; ++j) preview.insert(preview.end(), w.begin(), w.end());
  std::vector<double> tau(6), gain(72), tau_ff(6), x_lin(12);
  ofmpc::StepInfo info;
  if (!mpc.value().reset(x) || !mpc.value().step(x, w, preview, tau, info)) return 3;
  if (!mpc.value().gains(gain, tau_ff, x_lin)) return 4;
  // The inner loop's torque one state change later.
  std::vector<double> dx(12, 1e-5), inner(6);
  for (int i = 0; i < 6; ++i) {
    inner[i] = tau_ff[i];
    for (int j = 0; j < 12; ++j) inner[i] += gain[i * 12 + j] * (x[j] + dx[j] - x_lin[j]);
  }
  std::printf("tau_ff[1] %.6f inner[1] %.6f\n", tau_ff[1], inner[1]);
  if (tau_ff != tau || x_lin != x || inner == tau_ff) return 5;
  std::vector<double> q(6), qd(6), qdd(6), tau2(6);
  if (!pv.value().reset(x) || !pv.value().step(x, w, preview, tau2, info, q, qd, qdd)) return 6;
  std::printf("q_command[0] %.6f qd_command[0] %.6f qdd_command[0] %.6f\n", q[0], qd[0], qdd[0]);
  if (q[0] == 0.0 || !std::isfinite(qdd[0])) return 7;
  return 0;
}
