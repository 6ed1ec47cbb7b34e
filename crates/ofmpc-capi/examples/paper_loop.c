/* The paper's path through the C API: a controller and a simulated plant, one sample at a
 * time, as a real-time loop would run them. Prints the run's metrics (compare them with
 * `ofmpc run`'s metrics.json for the same scenario) and the step-time percentiles.
 *
 *   paper_loop SCENARIO.toml PROGRAM.gcode KIND PAYLOAD_KG
 *
 * Build: cc -std=c11 paper_loop.c $(pkg-config --cflags --libs ofmpc) -o paper_loop */
#define _POSIX_C_SOURCE 199309L
#include "ofmpc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Prints the failed call, its status and the library's message; exits 1. */
static void check(ofmpc_status st, const char *call) {
  if (st != OFMPC_OK) {
    fprintf(stderr, "error: %s: %s: %s\n", call, ofmpc_status_name(st), ofmpc_last_error());
    exit(1);
  }
}

/* The whole file at `path`, NUL-terminated (exits on failure). */
static char *read_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "error: cannot open %s\n", path);
    exit(1);
  }
  fseek(f, 0, SEEK_END);
  long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *text = malloc((size_t)len + 1);
  if (!text || fread(text, 1, (size_t)len, f) != (size_t)len) {
    fprintf(stderr, "error: cannot read %s\n", path);
    exit(1);
  }
  text[len] = '\0';
  fclose(f);
  return text;
}

static double now_us(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec * 1e6 + (double)t.tv_nsec * 1e-3;
}

static int by_value(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The q-quantile of the sorted `v` (nearest rank). */
static double quantile(const double *v, size_t len, double q) {
  size_t i = (size_t)(q * (double)(len - 1) + 0.5);
  return v[i < len ? i : len - 1];
}

int main(int argc, char **argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: %s SCENARIO.toml PROGRAM.gcode KIND PAYLOAD_KG\n", argv[0]);
    return 2;
  }
  if (strcmp(ofmpc_version(), OFMPC_VERSION) != 0) {
    fprintf(stderr, "error: header %s but library %s\n", OFMPC_VERSION, ofmpc_version());
    return 1;
  }
  char *settings = read_file(argv[1]);
  char *gcode = read_file(argv[2]);
  double payload_kg = strtod(argv[4], NULL);

  ofmpc_robot *robot = NULL;
  ofmpc_controller *ctrl = NULL;
  ofmpc_plan *plan = NULL;
  ofmpc_sim *sim = NULL;
  check(ofmpc_robot_new_builtin("irb140", &robot), "ofmpc_robot_new_builtin");
  check(ofmpc_controller_new(robot, argv[3], settings, &ctrl), "ofmpc_controller_new");
  check(ofmpc_plan_new(robot, gcode, ofmpc_controller_ts(ctrl), &plan), "ofmpc_plan_new");
  check(ofmpc_sim_new(robot, plan, settings, payload_kg, &sim), "ofmpc_sim_new");

  /* Every buffer before the loop: nothing is allocated per sample. */
  size_t n = ofmpc_controller_dof(ctrl), horizon = ofmpc_controller_horizon(ctrl);
  size_t samples = ofmpc_sim_samples(sim);
  double *x = calloc(2 * n, sizeof *x), *w = calloc(n, sizeof *w);
  double *preview = calloc(horizon * n, sizeof *preview), *tau = calloc(n, sizeof *tau);
  double *step_us = calloc(samples, sizeof *step_us);
  ofmpc_step_input in = {sizeof in, x, 2 * n, w, n, preview, horizon * n};
  ofmpc_step_output out;
  memset(&out, 0, sizeof out);
  out.size = sizeof out;
  out.tau = tau;
  out.tau_len = n;

  for (size_t k = 0; k < samples; k++) {
    check(ofmpc_sim_read(sim, x, 2 * n), "ofmpc_sim_read");
    if (k == 0) check(ofmpc_controller_reset(ctrl, x, 2 * n), "ofmpc_controller_reset");
    check(ofmpc_plan_reference(plan, k, w, n), "ofmpc_plan_reference");
    check(ofmpc_plan_preview(plan, k, horizon, preview, horizon * n), "ofmpc_plan_preview");
    double t0 = now_us();
    check(ofmpc_controller_step(ctrl, &in, &out), "ofmpc_controller_step");
    step_us[k] = now_us() - t0;
    if (out.status == OFMPC_STEP_HELD_LAST_TORQUE) {
      fprintf(stderr, "error: the step failed numerically at sample %zu\n", k);
      return 1;
    }
    check(ofmpc_sim_apply(sim, tau, n, step_us[k]), "ofmpc_sim_apply");
  }

  ofmpc_metrics m;
  memset(&m, 0, sizeof m);
  m.size = sizeof m;
  check(ofmpc_sim_metrics(sim, &m), "ofmpc_sim_metrics");
  qsort(step_us, samples, sizeof *step_us, by_value);
  printf("samples %zu\n", m.samples);
  printf("cartesian_error_rms_mm %.17g\n", m.cartesian_error_rms_mm);
  printf("cartesian_error_max_mm %.17g\n", m.cartesian_error_max_mm);
  printf("steady_cartesian_error_mm %.17g\n", m.steady_cartesian_error_mm);
  printf("steady_joint_error_max_rad %.17g\n", m.steady_joint_error_max_rad);
  printf("step_us_p50 %.3f\nstep_us_p99 %.3f\nstep_us_max %.3f\n", quantile(step_us, samples, 0.5),
         quantile(step_us, samples, 0.99), step_us[samples - 1]);
  printf("fits_1khz %s\n", quantile(step_us, samples, 0.99) < 1000.0 ? "yes" : "no");

  ofmpc_sim_free(sim);
  ofmpc_plan_free(plan);
  ofmpc_controller_free(ctrl);
  ofmpc_robot_free(robot);
  free(x), free(w), free(preview), free(tau), free(step_us), free(settings), free(gcode);
  return 0;
}
