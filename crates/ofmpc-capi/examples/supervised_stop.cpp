// The supervised controller's command through the C++ wrapper (issue 37): with
// [mpc] output = "position_velocity" the step gives, besides the torque, the position,
// velocity and acceleration to send to an interface that closes its own joint loop. When
// a safe stop begins (here: an encoder slip of 5 mrad on joint 1 at 3 s passes the 1.5 mrad
// safety limit), the command is the stop law's braking trajectory one lead time ahead: it
// decelerates to rest and holds, where the controller's last command (a moving target)
// would otherwise keep being streamed. Runs the paper's path on the simulated plant.
//   supervised_stop PROGRAM.gcode
// Exits 0 when the command came to rest as it should (run by tests/examples.rs under ASAN).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ofmpc.hpp"

namespace {

const char *kSettings =
    "[mpc]\nq_du = 1e-3\noutput = \"position_velocity\"\noutput_lead_s = 0.04\n"
    "[simulation]\nsafe_stop = true\n[safety]\nmax_joint_error_rad = 1.5e-3\n";

double max_abs(const std::vector<double> &v) {
  double m = 0.0;
  for (double x : v) m = std::fmax(m, std::fabs(x));
  return m;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s PROGRAM.gcode\n", argv[0]);
    return 2;
  }
  std::ifstream f(argv[1]);
  std::stringstream text;
  text << f.rdbuf();
  const std::string gcode = text.str();
  auto robot = ofmpc::Robot::builtin("irb140");
  if (!robot) return 3;
  auto sup = ofmpc::SupervisedController::create(robot.value(), "second", kSettings);
  if (!sup) return 4;
  auto &c = sup.value();
  auto plan = ofmpc::Plan::from_gcode(robot.value(), gcode.c_str(), c.ts());
  if (!plan) return 5;
  auto sim = ofmpc::Sim::create(robot.value(), plan.value(), kSettings, 0.25);
  if (!sim) return 6;
  const std::size_t n = c.dof(), horizon = c.horizon(), samples = sim.value().samples();
  const std::size_t slip = static_cast<std::size_t>(3.0 / c.ts());
  std::vector<double> x(2 * n), w(n), preview(horizon * n), tau(n), q(n), qd(n), qdd(n);
  ofmpc_supervised_status status = OFMPC_SUPERVISED_DIVERGED;
  double last_controlled = 0.0, previous = 0.0, first_stop = -1.0;
  std::size_t stop_at = 0;
  for (std::size_t k = 0; k < samples; ++k) {
    if (!sim.value().read(x)) return 7;
    if (k >= slip) x[0] += 5e-3;  // the encoder slipped
    if (k == 0 && !c.reset(x)) return 8;
    if (!plan.value().reference(k, w) || !plan.value().preview(k, horizon, preview)) return 9;
    if (!c.step(k * c.ts(), x, w, preview, tau, status, q, qd, qdd)) return 10;
    const double speed = max_abs(qd);
    if (status == OFMPC_SUPERVISED_CONTROLLED) {
      last_controlled = speed;
    } else if (status == OFMPC_SUPERVISED_STOPPING || status == OFMPC_SUPERVISED_STOPPED) {
      if (stop_at == 0) {
        stop_at = k;
        first_stop = speed;
      } else if (speed > previous + 1e-9) {
        std::printf("the stop's command sped up at sample %zu: %g -> %g rad/s\n", k, previous,
                    speed);
        return 11;
      }
      previous = speed;
    } else {
      return 12;
    }
    if (!sim.value().apply(tau, 0.0)) return 13;
  }
  std::printf("stop at %.2f s; controller's last command %.4f rad/s, the stop's first %.4f, "
              "its last %.3g\n",
              stop_at * c.ts(), last_controlled, first_stop, previous);
  if (stop_at < slip || last_controlled < 0.1 || first_stop >= last_controlled) return 14;
  if (previous > 1e-6 || status != OFMPC_SUPERVISED_STOPPED) return 15;
  return 0;
}
