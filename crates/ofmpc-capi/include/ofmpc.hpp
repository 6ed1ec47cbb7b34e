// ofmpc.hpp — a header-only C++17 wrapper of the C API (ofmpc.h): RAII handles with custom
// deleters, pointer+size views, a Result<T> carrying the status and the message, [[nodiscard]].
// No exception is thrown; the per-sample calls allocate nothing.
#ifndef OFMPC_HPP
#define OFMPC_HPP

#include "ofmpc.h"

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ofmpc {

/// A read-only view of `size` doubles (C++17 has no std::span).
struct ConstView {
  const double *data = nullptr;
  std::size_t size = 0;
  ConstView() = default;
  ConstView(const double *d, std::size_t n) : data(d), size(n) {}
  ConstView(const std::vector<double> &v) : data(v.data()), size(v.size()) {}  // NOLINT
  const double &operator[](std::size_t i) const { return data[i]; }
};

/// A writable view of `size` doubles.
struct View {
  double *data = nullptr;
  std::size_t size = 0;
  View() = default;
  View(double *d, std::size_t n) : data(d), size(n) {}
  View(std::vector<double> &v) : data(v.data()), size(v.size()) {}  // NOLINT
  double &operator[](std::size_t i) const { return data[i]; }
  operator ConstView() const { return {data, size}; }  // NOLINT
};

/// The status of a call and, on failure, the library's message.
class Error {
 public:
  Error() = default;
  explicit Error(ofmpc_status s) : status_(s), message_(s == OFMPC_OK ? "" : ofmpc_last_error()) {}
  [[nodiscard]] ofmpc_status status() const { return status_; }
  [[nodiscard]] bool ok() const { return status_ == OFMPC_OK; }
  [[nodiscard]] const std::string &message() const { return message_; }
  [[nodiscard]] std::string what() const {
    return std::string(ofmpc_status_name(status_)) + ": " + message_;
  }

 private:
  ofmpc_status status_ = OFMPC_OK;
  std::string message_;
};

/// A value or the error that prevented it (expected-like).
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}     // NOLINT
  Result(Error error) : error_(std::move(error)) {}  // NOLINT
  [[nodiscard]] bool ok() const { return error_.ok(); }
  explicit operator bool() const { return ok(); }
  [[nodiscard]] const Error &error() const { return error_; }
  /// The value (only when ok()).
  [[nodiscard]] T &value() { return value_; }
  [[nodiscard]] T &&take() { return std::move(value_); }

 private:
  T value_{};
  Error error_{};
};

/// A status-only result.
using Status = Result<bool>;

namespace detail {
[[nodiscard]] inline Status status(ofmpc_status s) {
  if (s == OFMPC_OK) return Status(true);
  return Status(Error(s));
}
template <typename H, void (*Free)(H *)>
struct Deleter {
  void operator()(H *h) const { Free(h); }
};
template <typename H, void (*Free)(H *)>
using Handle = std::unique_ptr<H, Deleter<H, Free>>;
/// The command arrays of an output record (`ofmpc_step_output`,
/// `ofmpc_supervised_output`): each non-empty view asked for (an empty one: NULL), their
/// common length the first non-empty one's.
template <typename Out>
void ask_command(Out &out, View q, View qd, View qdd, View tau) {
  std::size_t len = 0;
  for (View v : {q, qd, qdd, tau}) {
    if (len == 0) len = v.size;
  }
  out.q_command = q.size ? q.data : nullptr;
  out.qd_command = qd.size ? qd.data : nullptr;
  out.qdd_command = qdd.size ? qdd.data : nullptr;
  out.tau_command = tau.size ? tau.data : nullptr;
  out.command_len = len;
}
}  // namespace detail

/// The robot model.
class Robot {
 public:
  /// The built-in robot `name` ("irb140").
  [[nodiscard]] static Result<Robot> builtin(const char *name) {
    ofmpc_robot *r = nullptr;
    ofmpc_status s = ofmpc_robot_new_builtin(name, &r);
    if (s != OFMPC_OK) return Error(s);
    return Robot(r);
  }
  /// A URDF text with an optional drives TOML text (nullptr: none).
  [[nodiscard]] static Result<Robot> urdf(const char *urdf, const char *drives_toml = nullptr) {
    ofmpc_robot *r = nullptr;
    ofmpc_status s = ofmpc_robot_new_urdf(urdf, drives_toml, &r);
    if (s != OFMPC_OK) return Error(s);
    return Robot(r);
  }
  /// A URDF file with an optional drives file (nullptr: none).
  [[nodiscard]] static Result<Robot> urdf_file(const char *urdf_path, const char *drives_path = nullptr) {
    ofmpc_robot *r = nullptr;
    ofmpc_status s = ofmpc_robot_new_urdf_file(urdf_path, drives_path, &r);
    if (s != OFMPC_OK) return Error(s);
    return Robot(r);
  }
  Robot() = default;
  [[nodiscard]] std::size_t dof() const { return ofmpc_robot_dof(h_.get()); }
  [[nodiscard]] const ofmpc_robot *get() const { return h_.get(); }

 private:
  explicit Robot(ofmpc_robot *r) : h_(r) {}
  detail::Handle<ofmpc_robot, ofmpc_robot_free> h_;
};

/// A G-code text planned into a joint reference.
class Plan {
 public:
  [[nodiscard]] static Result<Plan> from_gcode(const Robot &robot, const char *gcode, double ts) {
    ofmpc_plan *p = nullptr;
    ofmpc_status s = ofmpc_plan_new(robot.get(), gcode, ts, &p);
    if (s != OFMPC_OK) return Error(s);
    return Plan(p);
  }
  Plan() = default;
  [[nodiscard]] std::size_t len() const { return ofmpc_plan_len(h_.get()); }
  [[nodiscard]] std::size_t dof() const { return ofmpc_plan_dof(h_.get()); }
  [[nodiscard]] double ts() const { return ofmpc_plan_ts(h_.get()); }
  /// w_k into `w` (n values).
  [[nodiscard]] Status reference(std::size_t k, View w) const {
    return detail::status(ofmpc_plan_reference(h_.get(), k, w.data, w.size));
  }
  /// w_{k+1} … w_{k+N} into `preview` (N·n values).
  [[nodiscard]] Status preview(std::size_t k, std::size_t horizon, View preview) const {
    return detail::status(ofmpc_plan_preview(h_.get(), k, horizon, preview.data, preview.size));
  }
  [[nodiscard]] const ofmpc_plan *get() const { return h_.get(); }

 private:
  explicit Plan(ofmpc_plan *p) : h_(p) {}
  detail::Handle<ofmpc_plan, ofmpc_plan_free> h_;
};

/// What a step reports besides the torque (the C record without its buffer).
struct StepInfo {
  ofmpc_step_status status = OFMPC_STEP_SOLVED;
  unsigned qp_iterations = 0;
  double cost = 0.0;
  double payload_estimate_kg = 0.0;
  std::uint64_t solve_time_ns = 0;
};

/// A controller (wraps ofmpc::Controller).
class Controller {
 public:
  /// The controller `kind` ("second", "pid", …) from a scenario's [mpc]/[baselines]/[plant]
  /// tables as TOML text (nullptr: the paper's tuning).
  [[nodiscard]] static Result<Controller> create(const Robot &robot, const char *kind,
                                                 const char *settings_toml = nullptr) {
    ofmpc_controller *c = nullptr;
    ofmpc_status s = ofmpc_controller_new(robot.get(), kind, settings_toml, &c);
    if (s != OFMPC_OK) return Error(s);
    return Controller(c);
  }
  Controller() = default;
  [[nodiscard]] std::size_t dof() const { return ofmpc_controller_dof(h_.get()); }
  [[nodiscard]] std::size_t horizon() const { return ofmpc_controller_horizon(h_.get()); }
  [[nodiscard]] double ts() const { return ofmpc_controller_ts(h_.get()); }
  [[nodiscard]] Status reset(ConstView x0) {
    return detail::status(ofmpc_controller_reset(h_.get(), x0.data, x0.size));
  }
  /// One step: the torque into `tau`, the rest into `info`. Allocates nothing.
  [[nodiscard]] Status step(ConstView x, ConstView w, ConstView preview, View tau,
                            StepInfo &info) {
    return step(x, w, preview, tau, info, View{}, View{}, View{}, View{});
  }
  /// One step with a position or velocity output ([mpc] output): as `step`, and the
  /// positions, velocities and accelerations its model predicted one lead time ahead into
  /// `q_command`, `qd_command`, `qdd_command` (n each; an empty view: not asked for).
  [[nodiscard]] Status step(ConstView x, ConstView w, ConstView preview, View tau,
                            StepInfo &info, View q_command, View qd_command,
                            View qdd_command) {
    return step(x, w, preview, tau, info, q_command, qd_command, qdd_command, View{});
  }
  /// The torque the drives applied over the period that just ended (n), for an interface
  /// that closes its own loop and reports it: call it before `step`. The adaptive kinds then
  /// identify their payload from it (also through a position or velocity output).
  [[nodiscard]] Status set_applied_torque(ConstView tau) {
    return detail::status(ofmpc_controller_set_applied_torque(h_.get(), tau.data, tau.size));
  }
  /// As the command overload of `step`, and the command's torque feed-forward (the
  /// identified payload's torque, for an interface that adds one) into `tau_command` (n).
  [[nodiscard]] Status step(ConstView x, ConstView w, ConstView preview, View tau,
                            StepInfo &info, View q_command, View qd_command, View qdd_command,
                            View tau_command) {
    ofmpc_step_input in{sizeof in, x.data, x.size, w.data, w.size, preview.data, preview.size};
    ofmpc_step_output out{};
    out.size = sizeof out;
    out.tau = tau.data;
    out.tau_len = tau.size;
    detail::ask_command(out, q_command, qd_command, qdd_command, tau_command);
    ofmpc_status s = ofmpc_controller_step(h_.get(), &in, &out);
    if (s == OFMPC_OK) {
      info.status = out.status;
      info.qp_iterations = out.qp_iterations;
      info.cost = out.cost;
      info.payload_estimate_kg = out.payload_estimate_kg;
      info.solve_time_ns = out.solve_time_ns;
    }
    return detail::status(s);
  }
  /// The last step's telemetry (times, QP iterations, fallback level) into `t`.
  [[nodiscard]] Status telemetry(ofmpc_step_telemetry &t) const {
    t = ofmpc_step_telemetry{};
    t.size = sizeof t;
    return detail::status(ofmpc_controller_telemetry(h_.get(), &t));
  }
  /// With [mpc] gains = true: the last step's first-stage feedback law, K (n × 2n,
  /// row-major) into `gain`, τ_k into `tau_ff`, x_k into `x_lin`, so that between MPC
  /// samples τ = tau_ff + K (x − x_lin). Allocates nothing.
  [[nodiscard]] Status gains(View gain, View tau_ff, View x_lin) const {
    return detail::status(ofmpc_controller_gains(h_.get(), gain.data, gain.size, tau_ff.data,
                                                 tau_ff.size, x_lin.data, x_lin.size));
  }

 private:
  explicit Controller(ofmpc_controller *c) : h_(c) {}
  detail::Handle<ofmpc_controller, ofmpc_controller_free> h_;
};

/// The controller behind its guard (wraps ofmpc::sim::SupervisedController).
class SupervisedController {
 public:
  /// As Controller::create; the guard's rules from [simulation] and [safety].
  [[nodiscard]] static Result<SupervisedController> create(const Robot &robot, const char *kind,
                                                           const char *settings_toml = nullptr) {
    ofmpc_supervised *c = nullptr;
    ofmpc_status s = ofmpc_supervised_new(robot.get(), kind, settings_toml, &c);
    if (s != OFMPC_OK) return Error(s);
    return SupervisedController(c);
  }
  SupervisedController() = default;
  [[nodiscard]] explicit operator bool() const { return h_ != nullptr; }
  [[nodiscard]] std::size_t dof() const { return ofmpc_supervised_dof(h_.get()); }
  [[nodiscard]] std::size_t horizon() const { return ofmpc_supervised_horizon(h_.get()); }
  [[nodiscard]] double ts() const { return ofmpc_supervised_ts(h_.get()); }
  [[nodiscard]] Status reset(ConstView x0) {
    return detail::status(ofmpc_supervised_reset(h_.get(), x0.data, x0.size));
  }
  /// One supervised sample at time `t`: the torque into `tau`. Allocates nothing.
  [[nodiscard]] Status step(double t, ConstView x, ConstView w, ConstView preview, View tau,
                            ofmpc_supervised_status &status) {
    return step(t, x, w, preview, tau, status, View{}, View{}, View{}, View{});
  }
  /// One supervised sample with a position or velocity output ([mpc] output): as `step`,
  /// and the command to send into `q_command`, `qd_command`, `qdd_command` (n each; an
  /// empty view: not asked for): the controller's, predicted one lead time ahead, while it
  /// controls; during a safe stop (status OFMPC_SUPERVISED_STOPPING / _STOPPED) the stop
  /// law's braking trajectory one lead time ahead, decelerating to rest, then holding.
  [[nodiscard]] Status step(double t, ConstView x, ConstView w, ConstView preview, View tau,
                            ofmpc_supervised_status &status, View q_command, View qd_command,
                            View qdd_command) {
    return step(t, x, w, preview, tau, status, q_command, qd_command, qdd_command, View{});
  }
  /// The torque the drives applied over the period that just ended (n), for the
  /// controller's identification (Controller::set_applied_torque); call it before `step`.
  [[nodiscard]] Status set_applied_torque(ConstView tau) {
    return detail::status(ofmpc_supervised_set_applied_torque(h_.get(), tau.data, tau.size));
  }
  /// As the command overload of `step`, and the command's torque feed-forward into
  /// `tau_command` (n; zeros during a safe stop).
  [[nodiscard]] Status step(double t, ConstView x, ConstView w, ConstView preview, View tau,
                            ofmpc_supervised_status &status, View q_command, View qd_command,
                            View qdd_command, View tau_command) {
    ofmpc_supervised_input in{sizeof in, t, x.data, x.size, w.data, w.size, preview.data,
                              preview.size};
    ofmpc_supervised_output out{};
    out.size = sizeof out;
    out.tau = tau.data;
    out.tau_len = tau.size;
    detail::ask_command(out, q_command, qd_command, qdd_command, tau_command);
    ofmpc_status s = ofmpc_supervised_step(h_.get(), &in, &out);
    if (s == OFMPC_OK) status = out.status;
    return detail::status(s);
  }
  /// The telemetry of the controller's last step (its last call; not the stop law's).
  [[nodiscard]] Status telemetry(ofmpc_step_telemetry &t) const {
    t = ofmpc_step_telemetry{};
    t.size = sizeof t;
    return detail::status(ofmpc_supervised_telemetry(h_.get(), &t));
  }

 private:
  explicit SupervisedController(ofmpc_supervised *c) : h_(c) {}
  detail::Handle<ofmpc_supervised, ofmpc_supervised_free> h_;
};

/// The simulated plant (tests, examples).
class Sim {
 public:
  [[nodiscard]] static Result<Sim> create(const Robot &robot, const Plan &plan,
                                          const char *settings_toml, double payload_kg) {
    ofmpc_sim *s = nullptr;
    ofmpc_status st = ofmpc_sim_new(robot.get(), plan.get(), settings_toml, payload_kg, &s);
    if (st != OFMPC_OK) return Error(st);
    return Sim(s);
  }
  Sim() = default;
  [[nodiscard]] std::size_t samples() const { return ofmpc_sim_samples(h_.get()); }
  [[nodiscard]] Status read(View x) { return detail::status(ofmpc_sim_read(h_.get(), x.data, x.size)); }
  [[nodiscard]] Status apply(ConstView tau, double step_us) {
    return detail::status(ofmpc_sim_apply(h_.get(), tau.data, tau.size, step_us));
  }
  [[nodiscard]] Result<ofmpc_metrics> metrics() const {
    ofmpc_metrics m{};
    m.size = sizeof m;
    ofmpc_status s = ofmpc_sim_metrics(h_.get(), &m);
    if (s != OFMPC_OK) return Error(s);
    return m;
  }

 private:
  explicit Sim(ofmpc_sim *s) : h_(s) {}
  detail::Handle<ofmpc_sim, ofmpc_sim_free> h_;
};

}  // namespace ofmpc

#endif  // OFMPC_HPP
