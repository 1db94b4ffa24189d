/* SPDX-License-Identifier: Apache-2.0
 * net/lcm/lcm_bridge_loop.c — the bridge's tick source on the hard loop (urt/loop.h). Kept
 * apart from lcm_bridge.c so tests can run the threads over a fake source. */
#include <stdlib.h>

#include "urt/errors.h"
#include "urt/net/lcm_bridge.h"

typedef struct loop_source {
  urt_loop_t *loop;
  int producer;
} loop_source_t;

static uint64_t src_wait(void *ctx, uint64_t after, int ms) {
  return urt_loop_wait(((loop_source_t *)ctx)->loop, after, ms);
}

static int src_read(void *ctx, uint64_t tick, urt_snapshot_t *out) {
  return urt_loop_read(((loop_source_t *)ctx)->loop, tick, out);
}

static uint64_t src_latest_drive(void *ctx) {
  return urt_loop_latest_drive(((loop_source_t *)ctx)->loop);
}

static int src_read_drive(void *ctx, uint64_t seq, urt_drive_sample_t *out) {
  return urt_loop_read_drive(((loop_source_t *)ctx)->loop, seq, out);
}

static bool src_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  loop_source_t *s = ctx;
  return urt_loop_submit(s->loop, s->producer, cmd);
}

static void src_grant(void *ctx, uint64_t n) {
  urt_loop_grant(((loop_source_t *)ctx)->loop, n);
}

int urt_lcm_bridge_create(urt_loop_t *loop, const urt_lcm_config_t *cfg, urt_lcm_bridge_t **out,
                          char *err, size_t err_sz) {
  if (loop == NULL) {
    return URT_EINVAL;
  }

  // the subscriber thread is this ring's only producer
  int producer = urt_loop_add_producer(loop, "lcm");
  if (producer < 0) {
    return producer;
  }
  loop_source_t *s = malloc(sizeof *s);
  if (s == NULL) {
    return URT_ENOMEM;
  }
  s->loop = loop;
  s->producer = producer;
  urt_lcm_source_t src = {s,          src_wait,  src_read, src_latest_drive, src_read_drive,
                          src_submit, src_grant, free, urt_loop_model(loop)};
  return urt_lcm_bridge_create_source(&src, cfg, out, err, err_sz);
}
