/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_model_load.c — urt_model_load(): config/ur5.yaml loads in SI units, overrides
 * apply, and every error path returns its code with an exact "file:line: key: reason" message.
 * Bad files are config/ur5.yaml with one edit, written to a temporary file, so the tests follow
 * the real file's layout and line numbers. */
#define _GNU_SOURCE
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_model.h"
#include "test_support.h"
#include "urt/core.h"

static const double kPi = 3.14159265358979323846;

//---- fixtures: the real file, edited copies, temporary files ----

static char *ur5_text;  // config/ur5.yaml, read once per group

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  assert_int_equal(fseek(f, 0, SEEK_END), 0);
  long n = ftell(f);
  assert_true(n > 0);
  rewind(f);
  char *s = malloc((size_t)n + 1);
  assert_non_null(s);
  assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
  s[n] = '\0';
  fclose(f);
  return s;
}

static int group_setup(void **state) {
  (void)state;
  ur5_text = read_text(urt_test_path("config/ur5.yaml"));
  return 0;
}

static int group_teardown(void **state) {
  (void)state;
  free(ur5_text);
  return 0;
}

// 1-based line of the character at offset off
static int line_at(const char *text, size_t off) {
  int line = 1;
  for (size_t i = 0; i < off; i++) {
    line += text[i] == '\n';
  }
  return line;
}

// Offset of the first needle after the first anchor (anchor NULL: from the start); fails the
// test if either is missing, so a changed config file shows up here and not as a wrong line.
static size_t find_after(const char *text, const char *anchor, const char *needle) {
  const char *from = text;
  if (anchor) {
    from = strstr(text, anchor);
    if (!from) {
      fail_msg("anchor '%s' not in config/ur5.yaml", anchor);
    }
  }
  const char *p = strstr(from, needle);
  if (!p) {
    fail_msg("'%s' not in config/ur5.yaml after '%s'", needle, anchor ? anchor : "(start)");
  }
  return (size_t)(p - text);
}

// Copy of text with the needle found by find_after replaced; *line gets the needle's line.
static char *edit(const char *text, const char *anchor, const char *needle, const char *repl,
                  int *line) {
  size_t off = find_after(text, anchor, needle);
  if (line) {
    *line = line_at(text, off);
  }
  size_t n = strlen(text), nn = strlen(needle), nr = strlen(repl);
  char *out = malloc(n - nn + nr + 1);
  assert_non_null(out);
  memcpy(out, text, off);
  memcpy(out + off, repl, nr);
  memcpy(out + off + nr, text + off + nn, n - off - nn + 1);
  return out;
}

// Copy of text without the whole line that holds the needle.
static char *delete_line(const char *text, const char *anchor, const char *needle, int *line) {
  size_t off = find_after(text, anchor, needle);
  size_t b = off, e = off;
  while (b > 0 && text[b - 1] != '\n') {
    b--;
  }
  while (text[e] && text[e] != '\n') {
    e++;
  }
  if (text[e] == '\n') {
    e++;
  }
  if (line) {
    *line = line_at(text, off);
  }
  size_t n = strlen(text);
  char *out = malloc(n - (e - b) + 1);
  assert_non_null(out);
  memcpy(out, text, b);
  memcpy(out + b, text + e, n - e + 1);
  return out;
}

// Write text to a fresh temporary file; path receives its name.
static void write_temp(const char *text, char path[64]) {
  snprintf(path, 64, "/tmp/urt_model_load_XXXXXX");
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  size_t n = strlen(text);
  assert_int_equal(write(fd, text, n), (ssize_t)n);
  close(fd);
}

// Load text (written to a temp file) and expect failure code and exactly the message built from
// fmt, where fmt's first conversion is the temp file's path.
static void expect_error(const char *text, const char *const *overrides, int code,
                         const char *fmt, ...) {
  char path[64], want[1200], err[1200] = "";
  write_temp(text, path);
  va_list ap;
  va_start(ap, fmt);
  char rest[1024];
  vsnprintf(rest, sizeof rest, fmt, ap);
  va_end(ap);
  snprintf(want, sizeof want, "%s%s", path, rest);

  urt_model_t *m = NULL;
  int rc = urt_model_load(path, overrides, &m, err, sizeof err);
  unlink(path);
  assert_int_equal(rc, code);
  assert_null(m);  // on failure *out is untouched
  assert_string_equal(err, want);
}

//---- success ----

static void test_model_load__loads_ur5_in_si_units(void **state) {
  (void)state;
  const char *path = urt_test_path("config/ur5.yaml");
  urt_model_t *m = NULL;
  char err[512] = "";
  int rc = urt_model_load(path, NULL, &m, err, sizeof err);
  if (rc != 0) {
    fail_msg("urt_model_load: %d %s", rc, err);
  }
  assert_non_null(m);
  assert_string_equal(m->name, "UR5");
  assert_string_equal(m->source, path);

  // simulation
  assert_near(m->dt, 5e-5, 0.0);
  assert_true(m->seed == 1);
  assert_int_equal(m->drives_engaged, 1);
  assert_near(m->substep_h_max, 5e-6, 0.0);
  assert_near(m->substep_ratio, 0.015, 0.0);
  assert_int_equal(m->refine_every, 0);  // optional, absent from ur5.yaml: never forced

  // arm: Table 4 mm/deg converted to m/rad, Table 5 with the link-1 ×1e-4 restored
  assert_near(m->arm.link[0].a, 0.110e-3, 1e-15);
  assert_near(m->arm.link[1].a, -0.425156, 1e-15);
  assert_near(m->arm.link[0].d, 0.089084, 1e-15);
  assert_near(m->arm.link[0].alpha, 89.905 * kPi / 180, 1e-15);
  assert_near(m->arm.link[4].alpha, -90.013 * kPi / 180, 1e-15);
  assert_near(m->arm.link[2].beta, 0.071 * kPi / 180, 1e-15);
  assert_near(m->arm.link[5].theta, -0.006 * kPi / 180, 1e-15);
  assert_near(m->arm.link[0].inertia[0], 67e-4, 1e-15);
  assert_near(m->arm.link[2].inertia[4], 34e-4, 1e-15);
  assert_near(m->arm.link[5].mass, 0.1879, 0.0);
  assert_near(m->arm.link[1].com[2], 0.11336, 0.0);
  assert_near(m->arm.gravity[2], -9.81, 0.0);

  // joints, motors, gears
  assert_string_equal(m->joint[0].name, "base");
  assert_string_equal(m->joint[5].name, "wrist3");
  assert_int_equal(m->joint[2].size, 'A');
  assert_int_equal(m->joint[3].size, 'B');
  assert_near(m->joint[0].q_max, 2 * kPi, 1e-15);
  assert_near(m->q0[1], -kPi / 2, 1e-15);
  assert_near(m->motor[1].kt, 0.1361, 0.0);
  assert_near(m->motor[1].ke, 0.1361, 0.0);
  assert_near(m->motor[0].l, 0.83e-3, 0.0);
  assert_near(m->motor[4].j, 2.076e-5, 0.0);
  assert_near(m->gear[0].r_g, 0.03065, 0.0);
  assert_near(m->gear[5].r_g, 0.0169, 0.0);
  assert_near(m->gear[3].alpha_t, kPi / 6, 1e-15);
  assert_near(m->gear[2].k_cs, 1.98e7, 0.0);
  assert_near(m->gear[4].k_cs, 6.23e6, 0.0);
  assert_near(m->gear[0].z_cs, 202, 0.0);
  assert_near(m->control[5].p_pos, 3250, 0.0);
  assert_near(m->control[2].p_cur, 30, 0.0);

  // derived by the loader: v_net, i_max = T_max/(k_t τ), sensor quanta
  assert_near(m->control[0].v_net, 48.0, 0.0);
  assert_near(m->control[0].i_max, 150.0 / (0.1350 * 101), 1e-12);
  assert_near(m->control[4].i_max, 28.0 / (0.0865 * 101), 1e-12);
  assert_near(m->sensors[0].lsb_i, 3.0 * m->control[0].i_max / 4096, 1e-15);
  assert_near(m->sensors[3].lsb_q, 2 * kPi / 262144, 1e-18);
  assert_near(m->sensors[3].lsb_w, 2 * kPi / 262144 / 5e-5, 1e-12);
  assert_near(m->sensors[1].f_i, 20000, 0.0);
  assert_near(m->sensors[1].zeta_w, 0.7, 0.0);
  assert_near(m->sensors[2].sigma_q, 1e-5, 0.0);
  assert_int_equal(m->sensors[0].noise, 1);
  assert_int_equal(m->sensors[0].quantise, 1);

  // friction: the common part copied into every joint
  assert_int_equal(m->friction[5].enabled, 1);
  assert_near(m->friction[5].sigma0, 5e6, 0.0);
  assert_near(m->friction[0].f_c, 8.0, 0.0);
  assert_near(m->friction[5].f_c, 2.0, 0.0);
  assert_near(m->friction[0].k_q, 10.0, 0.0);
  assert_near(m->friction[3].k_q, 5.0, 0.0);

  urt_model_free(m);
}

static void test_model_load__applies_overrides_in_both_list_syntaxes(void **state) {
  (void)state;
  const char *const set[] = {"joints.1.motor.kt=0.2", "joints[2].motor.kt = 0.3",
                             "sensors.noise=false",   "arm.gravity=[0, -9.8, 0]",
                             "simulation.dt=1e-4",    "arm.links[5].mass=1.5",
                             NULL};
  urt_model_t *m = NULL;
  char err[512] = "";
  int rc = urt_model_load(urt_test_path("config/ur5.yaml"), set, &m, err, sizeof err);
  if (rc != 0) {
    fail_msg("urt_model_load: %d %s", rc, err);
  }
  assert_near(m->motor[1].kt, 0.2, 0.0);
  assert_near(m->motor[2].kt, 0.3, 0.0);
  assert_near(m->motor[0].kt, 0.1350, 0.0);
  assert_int_equal(m->sensors[4].noise, 0);
  assert_near(m->arm.gravity[1], -9.8, 0.0);
  assert_near(m->dt, 1e-4, 0.0);
  assert_near(m->arm.link[5].mass, 1.5, 0.0);
  // derived values follow the overridden inputs
  assert_near(m->control[1].i_max, 150.0 / (0.2 * 101), 1e-12);
  assert_near(m->sensors[0].lsb_w, 2 * kPi / 262144 / 1e-4, 1e-12);
  urt_model_free(m);
}

//---- file errors, one per kind ----

static void test_model_load__rejects_unknown_key(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "k_t: 0.1361", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[1].motor.k_t: unknown key", line);
  free(bad);
}

static void test_model_load__rejects_missing_key(void **state) {
  (void)state;
  int kt_line;
  char *bad = delete_line(ur5_text, "name: shoulder", "kt: 0.1361", &kt_line);
  // reported at the parent map's line: "motor:" of the shoulder
  int motor_line = line_at(ur5_text, find_after(ur5_text, "name: shoulder", "motor:"));
  assert_true(motor_line < kt_line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[1].motor.kt: missing key", motor_line);
  free(bad);
}

static void test_model_load__rejects_wrong_type(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "kt: abc", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[1].motor.kt: must be a number (got 'abc')",
               line);
  free(bad);
}

static void test_model_load__rejects_quoted_number(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "kt: \"0.1361\"", &line);
  expect_error(bad, NULL, URT_ECONFIG,
               ":%d: joints[1].motor.kt: must be a number, not a quoted string (got \"0.1361\")",
               line);
  free(bad);
}

static void test_model_load__rejects_map_where_number_expected(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, NULL, "dt: 5.0e-5", "dt: {value: 5.0e-5}", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: simulation.dt: must be a number (got a map)", line);
  free(bad);
}

static void test_model_load__rejects_out_of_range_value(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "kt: -0.1", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[1].motor.kt: must be > 0 (got -0.1)", line);
  free(bad);
}

static void test_model_load__rejects_a_refine_every_that_is_not_a_step_count(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, NULL, "substep_ratio: 0.015",
                   "substep_ratio: 0.015\n  refine_every: -40", &line);
  expect_error(bad, NULL, URT_ECONFIG,
               ":%d: simulation.refine_every: must be an integer in [0, 4294967295] (got '-40')",
               line + 1);
  free(bad);
}

static void test_model_load__rejects_a_payload_the_ur5_cannot_carry(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "payload:", "mass: 0.0", "mass: 5.5", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: payload.mass: must be in [0, 5] (got 5.5)", line);
  free(bad);
  bad = edit(ur5_text, "payload:", "cog: [0.0, 0.0, 0.0]", "cog: [0.0, 0.0, 1.5]", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: payload.cog[2]: must be in [-1, 1] (got 1.5)", line);
  free(bad);
  // a negative principal moment (UR's rule; a tensor that is merely no body's is taken)
  bad = edit(ur5_text, "payload:", "inertia: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
             "inertia: [0.01, -0.01, 0.01, 0.0, 0.0, 0.0]", &line);
  expect_error(bad, NULL, URT_ECONFIG,
               ":%d: payload.inertia: payload inertia Ixx, Iyy and Izz must not be negative", line);
  free(bad);
}

static void test_model_load__payload_override_reaches_the_model(void **state) {
  (void)state;
  const char *const ov[] = {"payload.mass=3.0", "payload.cog=[0.0, 0.0, 0.1]",
                            "payload.inertia=[0.004, 0.005, 0.003, 0.0005, 0.0, -0.0004]", NULL};
  urt_model_t *m = urt_test_model(ov);
  assert_true(m->payload.mass == 3.0 && m->payload.cog[2] == 0.1 && m->payload.inertia[5] == -0.0004);
  urt_data_t d;
  assert_int_equal(urt_data_init(m, &d, NULL), 0);
  assert_memory_equal(&d.live.payload, &m->payload, sizeof m->payload);  // the run starts with it
  urt_model_free(m);
}

static void test_model_load__rejects_non_finite_value(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: elbow", "r: 0.30", "r: .inf", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[2].motor.r: must be finite (got .inf)", line);
  free(bad);
}

static void test_model_load__rejects_angle_in_degrees(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, NULL, "alpha: 1.569138264005502", "alpha: 89.905", &line);
  expect_error(bad, NULL, URT_ECONFIG,
               ":%d: arm.links[0].alpha: must be in [-pi, pi] rad (got 89.905)", line);
  free(bad);
}

static void test_model_load__rejects_table5_inertia_typo(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, NULL, "inertia: [67.0e-4, 64.0e-4, 67.0e-4,",
                   "inertia: [67.0, 64.0, 67.0,", &line);
  expect_error(bad, NULL, URT_ECONFIG,
               ":%d: arm.links[0].inertia: moments must be <= mass * 1 m^2 (3.7 kg m^2): a "
               "value not in kg m^2, or a missing 1e-4?",
               line);
  free(bad);
}

static void test_model_load__rejects_bad_size_letter(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: wrist1", "size: B", "size: C", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[3].size: must be A or B (got 'C')", line);
  free(bad);
}

static void test_model_load__rejects_wrong_list_length(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, NULL, "gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, -9.81]", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: arm.gravity: must be a list of 3 (got 2)", line);
  free(bad);
}

static void test_model_load__rejects_five_joints(void **state) {
  (void)state;
  // cut everything from the last joint on: the list has 5 elements
  size_t off = find_after(ur5_text, NULL, "  - name: wrist3");
  char *bad = strdup(ur5_text);
  assert_non_null(bad);
  bad[off] = '\0';
  int line = line_at(ur5_text, find_after(ur5_text, NULL, "\njoints:") + 1);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints: must be a list of 6 (got 5)", line);
  free(bad);
}

static void test_model_load__rejects_duplicate_key(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "kt: 0.1361\n      kt: 0.2", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: joints[1].motor.kt: duplicate key (first at line %d)",
               line + 1, line);
  free(bad);
}

static void test_model_load__rejects_yaml_syntax_error(void **state) {
  (void)state;
  int line;
  char *bad = edit(ur5_text, "name: shoulder", "kt: 0.1361", "kt: 0.1361: 2", &line);
  expect_error(bad, NULL, URT_ECONFIG, ":%d: syntax error: illegal map value", line);
  free(bad);
}

static void test_model_load__rejects_empty_file(void **state) {
  (void)state;
  expect_error("# nothing here\n", NULL, URT_ECONFIG,
               ":1: (document): must be a map (got nothing)");
}

static void test_model_load__reports_missing_file_as_eio(void **state) {
  (void)state;
  const char *path = "/tmp/urt_model_load_no_such_dir/ur5.yaml";
  char err[512] = "";
  urt_model_t *m = NULL;
  assert_int_equal(urt_model_load(path, NULL, &m, err, sizeof err), URT_EIO);
  assert_null(m);
  assert_string_equal(err, "/tmp/urt_model_load_no_such_dir/ur5.yaml: cannot open: "
                           "No such file or directory");
}

static void test_model_load__accepts_null_err_buffer(void **state) {
  (void)state;
  urt_model_t *m = NULL;
  const char *const set[] = {"joints.0.motor.kt=0", NULL};
  assert_int_equal(urt_model_load(urt_test_path("config/ur5.yaml"), set, &m, NULL, 0),
                   URT_ECONFIG);
  assert_null(m);
}

static void test_model_load__truncates_long_message_to_err_sz(void **state) {
  (void)state;
  urt_model_t *m = NULL;
  char err[8];
  memset(err, 'x', sizeof err);
  const char *const set[] = {"joints.0.motor.kt=0", NULL};
  assert_int_equal(urt_model_load(urt_test_path("config/ur5.yaml"), set, &m, err, sizeof err),
                   URT_ECONFIG);
  assert_int_equal(strlen(err), sizeof err - 1);
}

// the calibration keys: per-joint Stribeck level and speed, asymmetry, current offset
static void test_model_load__loads_per_joint_friction_and_current_offset(void **state) {
  (void)state;
  const char *const set[] = {"joints.4.friction.k_static=0.7", "joints.4.friction.qd_s=0.2",
                             "joints.4.friction.asym=-0.25", "joints.2.current_offset=0.4",
                             "joints.5.friction.relax=300", NULL};
  urt_model_t *m = NULL;
  char err[512] = "";
  int rc = urt_model_load(urt_test_path("config/ur5.yaml"), set, &m, err, sizeof err);
  assert_int_equal(rc, URT_OK);
  assert_near(m->friction[4].k_static, 0.7, 0.0);
  assert_near(m->friction[4].qd_s, 0.2, 0.0);
  assert_near(m->friction[4].asym, -0.25, 0.0);
  assert_near(m->joint[2].i_offset, 0.4, 0.0);
  assert_near(m->friction[5].relax, 300.0, 0.0);
  // the others keep the paper's shared values
  assert_near(m->friction[3].k_static, 0.3, 0.0);
  assert_near(m->friction[3].qd_s, 0.5, 0.0);
  assert_near(m->friction[3].asym, 0.0, 0.0);
  assert_near(m->friction[3].relax, 0.0, 0.0);
  assert_near(m->joint[1].i_offset, 0.0, 0.0);
  urt_model_free(m);
}

//---- override errors ----

static void test_model_load__rejects_asymmetry_of_one(void **state) {
  (void)state;
  const char *const set[] = {"joints.1.friction.asym=1", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[1].friction.asym: must be in (-1, 1) (got 1)");
}

static void test_model_load__rejects_a_negative_bristle_relaxation(void **state) {
  (void)state;
  const char *const set[] = {"joints.3.friction.relax=-1", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[3].friction.relax: must be in [0, 1000] (got -1)");
}

static void test_model_load__rejects_current_offset_beyond_a_fifth_of_i_max(void **state) {
  (void)state;
  const char *const set[] = {"joints.1.current_offset=3", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[1].current_offset: must be in [-0.2 i_max, 0.2 i_max] = "
               "[-2.18244, 2.18244] A (got 3)");
}

static void test_model_load__rejects_bad_override_value(void **state) {
  (void)state;
  const char *const set[] = {"joints.1.motor.kt=-0.1", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[1].motor.kt: must be > 0 (got -0.1)");
}

static void test_model_load__rejects_override_without_value(void **state) {
  (void)state;
  const char *const set[] = {"joints.1.motor.kt", NULL};
  expect_error(ur5_text, set, URT_ECONFIG, ":override: joints.1.motor.kt: expected key=value");
}

static void test_model_load__rejects_malformed_override_key(void **state) {
  (void)state;
  const char *const set[] = {"joints..motor=1", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints..motor: malformed key (write a.b.c, list elements as a.1.b or "
               "a[1].b)");
}

static void test_model_load__rejects_override_index_out_of_range(void **state) {
  (void)state;
  const char *const set[] = {"joints[6].motor.kt=0.1", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[6]: index out of range (list has 6 elements)");
}

static void test_model_load__rejects_override_of_unknown_key(void **state) {
  (void)state;
  const char *const set[] = {"simulation.dtt=1e-4", NULL};
  expect_error(ur5_text, set, URT_ECONFIG, ":override: simulation.dtt: unknown key");
}

static void test_model_load__rejects_override_with_bad_yaml(void **state) {
  (void)state;
  const char *const set[] = {"arm.gravity=[0, 0", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: arm.gravity: invalid YAML value: end of sequence flow not found");
}

static void test_model_load__rejects_override_that_breaks_a_cross_check(void **state) {
  (void)state;
  const char *const set[] = {"joints.0.q0=7", NULL};
  expect_error(ur5_text, set, URT_ECONFIG,
               ":override: joints[0].q0: must be in [q_min, q_max] = [-6.28319, 6.28319]");
}

static void test_model_load__reports_file_line_when_override_is_fine(void **state) {
  (void)state;
  // the override is valid; the error is in the file and keeps its line
  int line;
  char *bad = edit(ur5_text, "name: elbow", "kt: 0.1355", "kt: 0", &line);
  const char *const set[] = {"joints.1.motor.kt=0.2", NULL};
  expect_error(bad, set, URT_ECONFIG, ":%d: joints[2].motor.kt: must be > 0 (got 0)", line);
  free(bad);
}

static void test_model_load__thermal_by_drive_size(void **state) {
  (void)state;
  urt_model_t *m = urt_test_model(NULL);
  for (int j = 0; j < URT_NJ; j++) {
    assert_near(m->thermal[j].t_amb, 25.0, 0.0);
    assert_near(m->thermal[j].r_th, j < 3 ? 1.5 : 3.0, 0.0);
    assert_near(m->thermal[j].c_th, j < 3 ? 200.0 : 70.0, 0.0);
  }
  urt_model_free(m);
  const char *const set[] = {"thermal.B.c_th=0", NULL};
  expect_error(ur5_text, set, URT_ECONFIG, ":override: thermal.B.c_th: must be in (0, 1e+06] (got 0)");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_model_load__loads_ur5_in_si_units),
      cmocka_unit_test(test_model_load__applies_overrides_in_both_list_syntaxes),
      cmocka_unit_test(test_model_load__rejects_unknown_key),
      cmocka_unit_test(test_model_load__rejects_missing_key),
      cmocka_unit_test(test_model_load__rejects_wrong_type),
      cmocka_unit_test(test_model_load__rejects_quoted_number),
      cmocka_unit_test(test_model_load__rejects_map_where_number_expected),
      cmocka_unit_test(test_model_load__rejects_out_of_range_value),
      cmocka_unit_test(test_model_load__rejects_non_finite_value),
      cmocka_unit_test(test_model_load__rejects_angle_in_degrees),
      cmocka_unit_test(test_model_load__rejects_table5_inertia_typo),
      cmocka_unit_test(test_model_load__rejects_bad_size_letter),
      cmocka_unit_test(test_model_load__rejects_wrong_list_length),
      cmocka_unit_test(test_model_load__rejects_five_joints),
      cmocka_unit_test(test_model_load__rejects_duplicate_key),
      cmocka_unit_test(test_model_load__rejects_yaml_syntax_error),
      cmocka_unit_test(test_model_load__rejects_empty_file),
      cmocka_unit_test(test_model_load__reports_missing_file_as_eio),
      cmocka_unit_test(test_model_load__accepts_null_err_buffer),
      cmocka_unit_test(test_model_load__truncates_long_message_to_err_sz),
      cmocka_unit_test(test_model_load__loads_per_joint_friction_and_current_offset),
      cmocka_unit_test(test_model_load__rejects_asymmetry_of_one),
      cmocka_unit_test(test_model_load__rejects_a_negative_bristle_relaxation),
      cmocka_unit_test(test_model_load__rejects_current_offset_beyond_a_fifth_of_i_max),
      cmocka_unit_test(test_model_load__rejects_bad_override_value),
      cmocka_unit_test(test_model_load__thermal_by_drive_size),
      cmocka_unit_test(test_model_load__rejects_override_without_value),
      cmocka_unit_test(test_model_load__rejects_malformed_override_key),
      cmocka_unit_test(test_model_load__rejects_override_index_out_of_range),
      cmocka_unit_test(test_model_load__rejects_override_of_unknown_key),
      cmocka_unit_test(test_model_load__rejects_override_with_bad_yaml),
      cmocka_unit_test(test_model_load__rejects_a_refine_every_that_is_not_a_step_count),
      cmocka_unit_test(test_model_load__rejects_a_payload_the_ur5_cannot_carry),
      cmocka_unit_test(test_model_load__payload_override_reaches_the_model),
      cmocka_unit_test(test_model_load__rejects_override_that_breaks_a_cross_check),
      cmocka_unit_test(test_model_load__reports_file_line_when_override_is_fine),
  };
  return cmocka_run_group_tests_name("core/model_load", tests, group_setup, group_teardown);
}
