// The paper's path through the C++ wrapper, twice: the controller stepped directly, and the
// ros2_control-shaped controller (ofmpc_ros2_style_controller.hpp) driven by a hardware loop
// over plain double interfaces. Both against the simulated plant; prints each run's metrics
// (compare with `ofmpc run`'s metrics.json) and step-time percentiles.
//
//   paper_loop_cpp SCENARIO.toml PROGRAM.gcode KIND PAYLOAD_KG
#include "ofmpc.hpp"
#include "ofmpc_ros2_style_controller.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::string read_file(const char *path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    std::fprintf(stderr, "error: cannot open %s\n", path);
    std::exit(1);
  }
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

template <typename T>
T must(ofmpc::Result<T> r, const char *what) {
  if (!r) {
    std::fprintf(stderr, "error: %s: %s\n", what, r.error().what().c_str());
    std::exit(1);
  }
  return r.take();
}

void must(const ofmpc::Status &s, const char *what) {
  if (!s) {
    std::fprintf(stderr, "error: %s: %s\n", what, s.error().what().c_str());
    std::exit(1);
  }
}

void print(const char *label, const ofmpc_metrics &m, std::vector<double> step_us) {
  std::sort(step_us.begin(), step_us.end());
  auto q = [&](double p) { return step_us[static_cast<std::size_t>(p * (step_us.size() - 1) + 0.5)]; };
  std::printf("%s samples %zu\n", label, m.samples);
  std::printf("%s cartesian_error_rms_mm %.17g\n", label, m.cartesian_error_rms_mm);
  std::printf("%s cartesian_error_max_mm %.17g\n", label, m.cartesian_error_max_mm);
  std::printf("%s steady_cartesian_error_mm %.17g\n", label, m.steady_cartesian_error_mm);
  std::printf("%s steady_joint_error_max_rad %.17g\n", label, m.steady_joint_error_max_rad);
  std::printf("%s step_us_p50 %.3f\n%s step_us_p99 %.3f\n%s step_us_max %.3f\n", label, q(0.5),
              label, q(0.99), label, step_us.back());
}

double now_us() {
  using namespace std::chrono;
  return duration<double, std::micro>(steady_clock::now().time_since_epoch()).count();
}

/// The controller stepped directly.
void direct(const std::string &settings, const std::string &gcode, const char *kind, double kg) {
  auto robot = must(ofmpc::Robot::builtin("irb140"), "robot");
  auto ctrl = must(ofmpc::Controller::create(robot, kind, settings.c_str()), "controller");
  auto plan = must(ofmpc::Plan::from_gcode(robot, gcode.c_str(), ctrl.ts()), "plan");
  auto sim = must(ofmpc::Sim::create(robot, plan, settings.c_str(), kg), "sim");
  const std::size_t n = ctrl.dof(), horizon = ctrl.horizon(), samples = sim.samples();
  std::vector<double> x(2 * n), w(n), preview(horizon * n), tau(n), step_us(samples);
  ofmpc::StepInfo info;
  for (std::size_t k = 0; k < samples; ++k) {
    must(sim.read(x), "read");
    if (k == 0) must(ctrl.reset(x), "reset");
    must(plan.reference(k, w), "reference");
    must(plan.preview(k, horizon, preview), "preview");
    const double t0 = now_us();
    must(ctrl.step(x, w, preview, tau, info), "step");
    step_us[k] = now_us() - t0;
    must(sim.apply(tau, step_us[k]), "apply");
  }
  print("direct", must(sim.metrics(), "metrics"), step_us);
}

/// The ros2_control-shaped controller, over plain double interfaces.
void ros2_style(const std::string &settings, const std::string &gcode, const char *kind, double kg) {
  ofmpc_ros2::OfmpcController c;
  ofmpc_ros2::Params p;
  p.kind = kind;
  p.settings_toml = settings;
  p.gcode = gcode;
  p.joints = {"joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"};
  if (c.on_configure(p) != ofmpc_ros2::CallbackReturn::SUCCESS) std::exit(1);
  // The "hardware": the simulated plant behind the interfaces' doubles.
  auto robot = must(ofmpc::Robot::builtin("irb140"), "robot");
  auto plan = must(ofmpc::Plan::from_gcode(robot, gcode.c_str(), c.period()), "plan");
  auto sim = must(ofmpc::Sim::create(robot, plan, settings.c_str(), kg), "sim");
  const std::size_t n = p.joints.size(), samples = sim.samples();
  std::vector<double> state(2 * n), command(n), step_us(samples);
  std::vector<const double *> state_if;
  std::vector<double *> command_if;
  for (auto &s : state) state_if.push_back(&s);
  for (auto &u : command) command_if.push_back(&u);
  c.assign_interfaces(state_if, command_if);
  must(sim.read(state), "read");
  if (c.on_activate() != ofmpc_ros2::CallbackReturn::SUCCESS) std::exit(1);
  for (std::size_t k = 0; k < samples; ++k) {
    must(sim.read(state), "read");  // the hardware's read()
    const double t0 = now_us();
    if (c.update(k * c.period(), c.period()) != ofmpc_ros2::return_type::OK) {
      std::fprintf(stderr, "error: update failed at sample %zu: %s\n", k, ofmpc_last_error());
      std::exit(1);
    }
    step_us[k] = now_us() - t0;
    must(sim.apply(command, step_us[k]), "apply");  // the hardware's write()
  }
  c.on_deactivate();
  print("ros2", must(sim.metrics(), "metrics"), step_us);
}

}  // namespace

int main(int argc, char **argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s SCENARIO.toml PROGRAM.gcode KIND PAYLOAD_KG\n", argv[0]);
    return 2;
  }
  const std::string settings = read_file(argv[1]), gcode = read_file(argv[2]);
  const double kg = std::strtod(argv[4], nullptr);
  direct(settings, gcode, argv[3], kg);
  ros2_style(settings, gcode, argv[3], kg);
  return 0;
}
