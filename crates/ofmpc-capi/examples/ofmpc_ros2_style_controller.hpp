// A controller shaped like a ros2_control controller (controller_interface::ControllerInterface):
// the class a real plugin would wrap. ROS 2 is not needed to build it: the lifecycle returns, the
// time and the interfaces are plain types here (a plugin maps them one to one: CallbackReturn,
// rclcpp::Time / rclcpp::Duration in seconds, hardware_interface::LoanedStateInterface /
// LoanedCommandInterface as the double each one loans).
//
//   on_configure(params): robot, plan (G-code), supervised controller, buffers — every allocation
//   on_activate(): reset at the state read from the state interfaces
//   update(time, period): reference and preview of the sample, one supervised step, the effort
//                         commands written; allocates nothing, takes no lock
//   on_deactivate(): commands to zero
#ifndef OFMPC_ROS2_STYLE_CONTROLLER_HPP
#define OFMPC_ROS2_STYLE_CONTROLLER_HPP

#include "ofmpc.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace ofmpc_ros2 {

enum class CallbackReturn { SUCCESS, FAILURE, ERROR };
enum class return_type { OK, ERROR };

/// What a plugin reads from its ROS parameters.
struct Params {
  std::string robot = "irb140";
  std::string kind = "second";
  std::string settings_toml;  // the scenario's [mpc], [simulation], [safety], [plant] tables
  std::string gcode;          // the program to follow
  std::vector<std::string> joints;
};

class OfmpcController {
 public:
  /// "<joint>/effort" for every joint (command_interface_configuration).
  std::vector<std::string> command_interface_names() const {
    std::vector<std::string> names;
    for (const auto &j : params_.joints) names.push_back(j + "/effort");
    return names;
  }
  /// "<joint>/position" then "<joint>/velocity" (state_interface_configuration).
  std::vector<std::string> state_interface_names() const {
    std::vector<std::string> names;
    for (const auto &j : params_.joints) names.push_back(j + "/position");
    for (const auto &j : params_.joints) names.push_back(j + "/velocity");
    return names;
  }

  CallbackReturn on_configure(const Params &params) {
    params_ = params;
    auto robot = ofmpc::Robot::builtin(params.robot.c_str());
    if (!robot) return fail("robot", robot.error());
    robot_ = robot.take();
    auto ctrl = ofmpc::SupervisedController::create(robot_, params.kind.c_str(),
                                                     params.settings_toml.c_str());
    if (!ctrl) return fail("controller", ctrl.error());
    ctrl_ = ctrl.take();
    ts_ = ctrl_.ts();
    auto plan = ofmpc::Plan::from_gcode(robot_, params.gcode.c_str(), ts_);
    if (!plan) return fail("plan", plan.error());
    plan_ = plan.take();
    n_ = ctrl_.dof();
    if (params.joints.size() != n_) {
      std::fprintf(stderr, "on_configure: %zu joints named, the robot has %zu\n",
                   params.joints.size(), n_);
      return CallbackReturn::ERROR;
    }
    x_.assign(2 * n_, 0.0);
    w_.assign(n_, 0.0);
    preview_.assign(ctrl_.horizon() * n_, 0.0);
    tau_.assign(n_, 0.0);
    return CallbackReturn::SUCCESS;
  }

  /// The loaned interfaces, in the order of the *_interface_names() (assign_interfaces).
  void assign_interfaces(std::vector<const double *> state, std::vector<double *> command) {
    state_ = std::move(state);
    command_ = std::move(command);
  }

  CallbackReturn on_activate() {
    if (state_.size() != 2 * n_ || command_.size() != n_) return CallbackReturn::ERROR;
    read_state();
    auto st = ctrl_.reset(x_);
    if (!st) return fail("reset", st.error());
    return CallbackReturn::SUCCESS;
  }

  CallbackReturn on_deactivate() {
    for (double *c : command_) *c = 0.0;
    return CallbackReturn::SUCCESS;
  }

  /// One control period: `time` since activation (s), `period` since the last update (s).
  return_type update(double time, double /*period*/) {
    const auto k = static_cast<std::size_t>(std::llround(time / ts_));
    read_state();
    if (!plan_.reference(k, w_).ok() || !plan_.preview(k, ctrl_.horizon(), preview_).ok())
      return return_type::ERROR;
    if (!ctrl_.step(time, x_, w_, preview_, tau_, status_).ok()) return return_type::ERROR;
    for (std::size_t i = 0; i < n_; ++i) *command_[i] = tau_[i];
    return return_type::OK;
  }

  /// What produced the last command (controlled, repaired, stopping, stopped, diverged).
  ofmpc_supervised_status last_status() const { return status_; }
  double period() const { return ts_; }
  std::size_t samples() const { return plan_.len(); }

 private:
  void read_state() {
    for (std::size_t i = 0; i < 2 * n_; ++i) x_[i] = *state_[i];
  }
  CallbackReturn fail(const char *what, const ofmpc::Error &e) {
    std::fprintf(stderr, "on_configure: %s: %s\n", what, e.what().c_str());
    return CallbackReturn::ERROR;
  }

  Params params_;
  ofmpc::Robot robot_;
  ofmpc::SupervisedController ctrl_;
  ofmpc::Plan plan_;
  double ts_ = 0.0;
  std::size_t n_ = 0;
  std::vector<const double *> state_;
  std::vector<double *> command_;
  std::vector<double> x_, w_, preview_, tau_;
  ofmpc_supervised_status status_ = OFMPC_SUPERVISED_CONTROLLED;
};

}  // namespace ofmpc_ros2

#endif
