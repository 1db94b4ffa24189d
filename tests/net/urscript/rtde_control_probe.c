/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/rtde_control_probe.c — read one URScript unit (a file, or stdin) and print
 * what the native rtde_control recogniser learns from it, as one JSON object. Used by
 * tests/python/test_rtde_control_script.py on the scripts ur_rtde generates itself. */
#include <stdio.h>
#include <stdlib.h>

#include "rtde_control.h"

int main(int argc, char **argv) {
  FILE *f = argc > 1 ? fopen(argv[1], "rb") : stdin;
  if (!f) {
    perror(argv[1]);
    return 2;
  }
  size_t cap = 1u << 20, len = 0;
  char *text = malloc(cap);
  size_t n;
  while (text && len < cap && (n = fread(text + len, 1, cap - len, f)) > 0) len += n;
  if (f != stdin) fclose(f);
  if (!text) return 2;

  urt__rc_info rc;
  bool ok = urt__rc_recognise(text, len, &rc);
  printf("{\"recognised\": %s, \"reg_offset_int\": %d, \"reg_offset_float\": %d, \"tag\": \"%s\", "
         "\"path_bad_line\": %u, \"path\": [",
         ok ? "true" : "false", rc.reg_offset_int, rc.reg_offset_float, rc.tag, rc.path_bad_line);
  for (int i = 0; i < rc.n_path; i++) {
    const urt__rc_move *m = &rc.path[i];
    printf("%s{\"kind\": \"%c\", \"pose\": %s, \"x\": [%.17g, %.17g, %.17g, %.17g, %.17g, %.17g], "
           "\"a\": %.17g, \"v\": %.17g, \"r\": %.17g}",
           i ? ", " : "", m->kind, m->is_pose ? "true" : "false", m->x[0], m->x[1], m->x[2], m->x[3],
           m->x[4], m->x[5], m->a, m->v, m->r);
  }
  printf("], \"commands\": [");
  int first = 1;
  for (int id = 0; id < URT_RC_MAX_CMD; id++) {
    if (rc.has_cmd[id]) {
      printf("%s[%d, %d]", first ? "" : ", ", id, rc.has_body[id]);
      first = 0;
    }
  }
  printf("]}\n");
  urt__rc_info_free(&rc);
  free(text);
  return 0;
}
