/* SPDX-License-Identifier: Apache-2.0
 * tests/net/urscript/urscript_check_probe.c — compiles the URScript unit on stdin (parse and
 * name check, urt_script_check) and prints {"ok": …, "line": …, "column": …, "text": "…"}: the
 * compile error the runner would report, for tests/python/test_rtde_control_script.py. */
#include <stdio.h>
#include <stdlib.h>

#include "urt/net/urscript.h"

int main(void) {
  size_t cap = URT_SCRIPT_MAX_TEXT + 1, n = 0;
  char *buf = malloc(cap);
  if (!buf) return 2;
  size_t got;
  while (n < cap && (got = fread(buf + n, 1, cap - n, stdin)) > 0) n += got;
  urt_script_msg_t m = {0};
  int rc = urt_script_check(buf, n, &m);
  printf("{\"ok\": %s, \"line\": %u, \"column\": %u, \"text\": \"", rc == 0 ? "true" : "false",
         rc == 0 ? 0u : m.line, rc == 0 ? 0u : m.column);
  for (const char *c = rc == 0 ? "" : m.text; *c; c++) {
    if (*c == '"' || *c == '\\') putchar('\\');
    if ((unsigned char)*c >= 0x20) putchar(*c);
  }
  printf("\"}\n");
  free(buf);
  return 0;
}
