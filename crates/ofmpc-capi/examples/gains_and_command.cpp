// The C++ wrapper's first-stage gains ([mpc] gains = true) and predicted command
// ([mpc] output = "position_velocity"), issue 37: a linear feedback between MPC samples,
// τ = tau_ff + K (x − x_lin), and the position/velocity command one lead time ahead; an
// adaptive kind given the drives' applied torque (set_applied_torque) sends the identified
// payload's torque feed-forward with its command.
// Exits 0 when all came through (run by tests/examples.rs under ASAN).
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
  // second-adaptive through a position interface whose drives report holding the arm with
  // 20 N·m more on joint 2 than the nominal model needs (a payload the controller does not
  // know): the feed-forward grows towards it; a report of the wrong size is refused.
  auto ad = ofmpc::Controller::create(
      robot.value(), "second-adaptive",
      "[mpc]\noutput = \"position_velocity\"\noutput_lead_s = 0.04\n");
  if (!ad) return 8;
  std::vector<double> x0(x.begin(), x.begin() + 6), still(12, 0.0), ff(6), held(6), none(6);
  std::copy(x0.begin(), x0.end(), still.begin());
  std::vector<double> w0(x0), preview0;
  for (int j = 0; j < 10; ++j) preview0.insert(preview0.end(), w0.begin(), w0.end());
  if (!ad.value().reset(still) || !ad.value().step(still, w0, preview0, tau2, info)) return 9;
  // The nominal holding torque: the first step's torque at rest is the model's gravity.
  held = tau2;
  held[1] += 20.0;
  if (ad.value().set_applied_torque(std::vector<double>(5))) return 10;
  for (int k = 0; k < 50; ++k) {
    if (!ad.value().set_applied_torque(held)) return 11;
    if (!ad.value().step(still, w0, preview0, tau2, info, q, qd, qdd, ff)) return 12;
  }
  std::printf("tau_command[1] %.4f payload %.3f kg\n", ff[1], info.payload_estimate_kg);
  if (!(std::fabs(ff[1]) > 1.0) || !(info.payload_estimate_kg > 0.0)) return 13;
  return 0;
}
