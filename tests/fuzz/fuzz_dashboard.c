/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_dashboard.c — arbitrary bytes, in arbitrary chunks, through the dashboard
 * framer and command handler (net/dashboard).
 *
 * Input layout: byte 0 picks the emulated version and remote control, bytes 1–4 the robot
 * state, byte 5 seeds the chunk sizes; the rest is the client's byte stream.
 * Invariants: one reply per "\n" received, every reply exactly one "\n"-terminated line with
 * no "\r" and no NUL, no crash, no out-of-bounds access.
 */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "urt/net/dashboard.h"

static char g_programs[64];

/* Remove the directory again when libFuzzer exits. */
static void remove_programs_dir(void) {
  static const char *const names[] = {"a.urp", "default.installation", "out.urp"};
  char path[128];
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
    snprintf(path, sizeof path, "%s/%s", g_programs, names[i]);
    unlink(path);
  }
  rmdir(g_programs);
}

/* A programs directory with one program, one installation and a link out, made once. */
static void make_programs_dir(void) {
  char tmpl[] = "/tmp/urt_fuzz_dash_XXXXXX";
  if (!mkdtemp(tmpl)) {
    abort();
  }
  snprintf(g_programs, sizeof g_programs, "%s", tmpl);
  atexit(remove_programs_dir);
  char path[128];
  snprintf(path, sizeof path, "%s/a.urp", g_programs);
  FILE *f = fopen(path, "w");
  if (f) {
    fputs("<urp/>\n", f);
    fclose(f);
  }
  snprintf(path, sizeof path, "%s/default.installation", g_programs);
  f = fopen(path, "w");
  if (f) {
    fputs("inst\n", f);
    fclose(f);
  }
  snprintf(path, sizeof path, "%s/out.urp", g_programs);
  if (symlink("/etc/passwd", path) != 0) {
    // not needed for the invariants
  }
}

static void check_reply(const char *reply, size_t n, size_t cap) {
  if (n < 1 || n >= cap || reply[n] != '\0' || reply[n - 1] != '\n' ||
      memchr(reply, '\n', n) != reply + n - 1 || memchr(reply, '\r', n) ||
      memchr(reply, '\0', n)) {
    abort();
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (!g_programs[0]) {
    make_programs_dir();
  }
  if (size < 6) {
    return 0;
  }

  // configuration and robot state from the first bytes
  static const urt_version_t versions[] = {
      {5, 19, 0, 1210631, "Oct 23 2024"}, {5, 3, 1, 1000, "Jan 1 2019"},
      {3, 15, 8, 106339, "Sep 14 2023"},  {1, 8, 0, 1, "Jan 1 2012"}};
  urt_dashboard_ctx_t ctx = {.version = versions[data[0] & 3],
                             .serial_number = "20235501783",
                             .robot_model = "UR5",
                             .programs_dir = g_programs,
                             .programs_alias = (data[0] & 8) ? "/programs" : NULL,
                             .program_exts = (data[0] & 16) ? ".urp,.script" : NULL};
  static urt_dashboard_state_t st;
  urt_dashboard_state_init(&st);
  st.remote_control = !(data[0] & 4);
  urt_dashboard_robot_t robot = {(int8_t)data[1], (int8_t)data[2], (int8_t)data[3],
                                 data[4] % 7, (double)(data[5] & 7) - 1.0};
  uint32_t seed = data[5];
  data += 6;
  size_t n = size - 6;

  // feed the stream in pseudo-random chunks; one reply per completed line
  static urt_dashboard_framer_t f;
  urt_dashboard_framer_init(&f);
  static char reply[URT_DASHBOARD_REPLY_MAX];
  static urt_dashboard_action_t act;
  size_t newlines = 0, replies = 0;
  for (size_t i = 0; i < n; i++) {
    newlines += data[i] == '\n';
  }
  while (n > 0) {
    seed = seed * 1103515245u + 12345u;
    size_t chunk = 1 + (seed >> 16) % 64;
    if (chunk > n) {
      chunk = n;
    }
    const char *p = (const char *)data;
    size_t left = chunk;
    while (left > 0) {
      size_t used = 0;
      urt_dashboard_line_t line;
      int got = urt_dashboard_framer_next(&f, p, left, &used, &line);
      if (used < 1 || used > left) {
        abort();
      }
      p += used;
      left -= used;
      if (!got) {
        continue;
      }
      if (line.len > URT_DASHBOARD_LINE_MAX || memchr(line.text, '\n', line.len)) {
        abort();
      }

      // alternate a full and a tight reply buffer
      size_t cap = (replies & 1) ? 1 + (seed % 64) : sizeof reply;
      size_t len = urt_dashboard_handle(&ctx, &robot, &st, &line, reply, cap, &act);
      replies++;
      if (cap >= 2) {
        check_reply(reply, len, cap);
      } else if (len != 0) {
        abort();
      }
      if (act.n_ctrl < 0 || act.n_ctrl > 2) {
        abort();
      }
    }
    data += chunk;
    n -= chunk;
  }
  if (replies != newlines) {
    abort();
  }
  return 0;
}
