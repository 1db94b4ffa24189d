/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/script_run.h — run a URScript text on the fake controller and read back
 * what it printed: textmsg(x) is how these tests see a builtin's value. */
#ifndef URT_TEST_SCRIPT_RUN_H
#define URT_TEST_SCRIPT_RUN_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fake_host.h"
#include "script.h"
#include "test_support.h"

typedef struct script_run {
  fake_host f;
  urt_script_host_t host;
  uint64_t motion_id;
  us_err err;
  int version[3];  /* the controller's software version (all 0: the newest) */
} script_run;

/* a fresh run on a fresh fake host (a CMocka setup's body) */
static inline void sr_reset(script_run *r) {
  memset(r, 0, sizeof *r);
  fake_init(&r->f, &r->host);
}

/* the emulated controller's software version */
static inline void sr_version(script_run *r, int major, int minor, int bugfix) {
  r->version[0] = major;
  r->version[1] = minor;
  r->version[2] = bugfix;
}

/* parse and run; returns urt__us_run's result (the error in r->err) */
static inline int sr_run(script_run *r, const char *text) {
  us_prog *p = NULL;
  if (urt__us_parse(text, strlen(text), &p, &r->err) != 0) {
    fail_msg("parse: %u:%u %s", r->err.line, r->err.column, r->err.text);
  }
  us_hooks h = {.host = &r->host, .motion_id = &r->motion_id, .step_budget = 100000,
                .wait_timeout_ms = 1, .version = {r->version[0], r->version[1], r->version[2]}};
  int rc = urt__us_run(p, &h, &r->err);
  urt__us_prog_free(p);
  return rc;
}

static inline void sr_must(script_run *r, const char *text) {
  if (sr_run(r, text) != 0) fail_msg("run: %u:%u %s", r->err.line, r->err.column, r->err.text);
}

/* run text, which must fail with an error containing part */
static inline void sr_fails_with(script_run *r, const char *text, const char *part) {
  assert_int_not_equal(sr_run(r, text), 0);
  if (!strstr(r->err.text, part)) fail_msg("error \"%s\" lacks \"%s\"", r->err.text, part);
}

/* the numbers in message k ("p[1,2]", "[1,2]", "3"), at most n; returns how many */
static inline int sr_nums(const script_run *r, int k, double *x, int n) {
  if (k >= r->f.n_msg) fail_msg("message %d of %d", k, r->f.n_msg);
  const char *s = r->f.msg[k].text;
  int got = 0;
  while (*s && got < n) {
    char *e;
    double v = strtod(s, &e);
    if (e != s && (s == r->f.msg[k].text || strchr("[,", s[-1]))) {
      x[got++] = v;
      s = e;
    } else {
      s++;
    }
  }
  return got;
}

/* message k holds exactly the n numbers want, each within tol */
static inline void sr_expect(const script_run *r, int k, const double *want, int n, double tol) {
  double x[64];
  int got = sr_nums(r, k, x, 64);
  if (got != n) fail_msg("message %d \"%s\": %d numbers, expected %d", k, r->f.msg[k].text, got, n);
  for (int j = 0; j < n; j++) {
    if (!(fabs(x[j] - want[j]) <= tol)) {
      fail_msg("message %d \"%s\": element %d is %.9g, expected %.9g", k, r->f.msg[k].text, j,
               x[j], want[j]);
    }
  }
}

#endif
