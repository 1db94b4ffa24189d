/* SPDX-License-Identifier: Apache-2.0
 * tests/net/codec/codec_dump.c — writes what the codecs produce for the fixture snapshot, so
 * tests/python/test_codec_urx.py can feed it to python-urx's own parsers.
 *
 *   urt_codec_dump secondary <version> <out>   VERSION + ROBOT_STATE + KEY, as on 30002
 *   urt_codec_dump rt <version> <out>          one 30003 packet
 *   urt_codec_dump frame [max_unit]            frames stdin, one line per unit on stdout:
 *                                              kind command error line len name
 */
#include <stdio.h>
#include <stdlib.h>

#include "codec_fixture.h"
#include "urt/core.h"
#include "urt/net/primary.h"
#include "urt/net/rt_packet.h"
#include "urt/net/script_framer.h"

static int write_file(const char *path, const uint8_t *b, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(b, 1, n, f) != n) {
    perror(path);
    return 1;
  }
  return fclose(f) != 0;
}

static void print_unit(void *user, const urt_script_unit_t *u) {
  printf("%d %d %d %llu %zu %.*s\n", (int)u->kind, (int)u->command, (int)u->error_code,
         (unsigned long long)u->line, u->len, (int)u->name_len, u->name ? u->name : "");
}

static int frame_stdin(size_t max_unit) {
  urt_script_framer_t f;
  urt_script_framer_init_max(&f, max_unit);
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, stdin)) > 0) {
    urt_script_framer_feed(&f, buf, n, print_unit, NULL);
  }
  urt_script_framer_finish(&f, print_unit, NULL);
  urt_script_framer_free(&f);
  return 0;
}

int main(int argc, char **argv) {
  if (argc >= 2 && strcmp(argv[1], "frame") == 0) {
    return frame_stdin(argc >= 3 ? (size_t)strtoull(argv[2], NULL, 10) : 0);
  }
  if (argc != 4) {
    fprintf(stderr, "usage: %s secondary|rt <version> <out> | frame [max_unit]\n", argv[0]);
    return 2;
  }
  urt_version_t v;
  if (urt_version_parse(argv[2], &v) != 0) {
    fprintf(stderr, "bad version %s\n", argv[2]);
    return 2;
  }
  urt_snapshot_t s;
  fixture_snapshot(&s);
  static uint8_t b[8192];
  size_t n = 0;

  if (strcmp(argv[1], "rt") == 0) {
    n = urt_rt_packet_encode(&v, &s, b, sizeof b);
    return n ? write_file(argv[3], b, n) : 1;
  }

  // the robot description from the real UR5 model
  urt_model_t *m = NULL;
  char err[512];
  if (urt_model_load(URT_SOURCE_DIR "/config/ur5.yaml", NULL, &m, err, sizeof err) != 0) {
    fprintf(stderr, "%s\n", err);
    return 1;
  }
  urt_primary_robot_info_t info;
  urt_primary_robot_info_from_model(&v, m, &info);
  urt_model_free(m);

  int k = urt_primary_encode_version(&v, 1000, b, sizeof b);
  if (k < 0) {
    return 1;
  }
  n += (size_t)k;
  k = urt_primary_encode_robot_state(&v, &info, &s, b + n, sizeof b - n);
  if (k < 0) {
    return 1;
  }
  n += (size_t)k;
  k = urt_primary_encode_key(12500000, URT_PRIMARY_SOURCE_ROBOT_INTERFACE, 0, 0,
                             "PROGRAM_XXX_STARTED", "script_1", b + n, sizeof b - n);
  if (k < 0) {
    return 1;
  }
  n += (size_t)k;
  return write_file(argv[3], b, n);
}
