/* SPDX-License-Identifier: Apache-2.0
 * net/lcm/lcm_bridge.c — the LCM publisher and command-subscriber threads over a tick source.
 * Context: non-RT throughout; nothing here runs on the physics thread. */
#include "urt/net/lcm_bridge.h"

#include <errno.h>
#include <lcm/lcm.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "urt/errors.h"
#include "urt/thread.h"
#include "urt/net/lcm_sender.h"

#define WAIT_MS 50        /* how often the threads look at the stop flag        */
#define JOIN_TIMEOUT_S 2  /* bounded join                                       */
#define REPEAT_MS 100     /* lockstep: repeat the newest status this often while idle */

typedef struct counters {
  _Atomic uint64_t status_sent, status_repeated, ticks_lost, drive_sent, drive_lost,
      publish_errors;
  _Atomic uint64_t cmd_received, cmd_accepted, cmd_rejected, cmd_dropped, last_tick;
  _Atomic uint64_t io_received, io_accepted, io_rejected, io_dropped;
  _Atomic uint64_t fault_received, fault_accepted, fault_rejected, fault_dropped, truth_sent;
} counters_t;

struct urt_lcm_bridge {
  urt_lcm_source_t src;
  char *url, *status_channel, *drive_channel, *command_channel, *io_channel;
  char *fault_channel, *truth_channel;
  double drive_rate;
  int lockstep;

  lcm_t *pub;                 /* publisher thread only (lcm_publish is thread-safe anyway) */
  lcm_t *sub;                 /* subscriber thread only; NULL without a command channel     */
  lcm_subscription_t *subscription, *io_subscription, *fault_subscription;

  pthread_t pub_thread, sub_thread;
  int pub_running, sub_running;
  int abandoned;              /* a join timed out: never free                               */
  atomic_int stop;

  uint64_t cmd_id;            /* motion id of the DIRECT commands (subscriber thread)      */
  counters_t n;
};

//---- helpers ----------------------------------------------------------------------------------

static void set_err(char *err, size_t err_sz, const char *fmt, const char *arg) {
  if (err != NULL && err_sz > 0) {
    snprintf(err, err_sz, fmt, arg);
  }
}

static char *dup_or(const char *s, const char *fallback) {
  const char *v = s != NULL ? s : fallback;
  size_t n = strlen(v) + 1;
  char *d = malloc(n);
  if (d != NULL) {
    memcpy(d, v, n);
  }
  return d;
}

static int64_t wall_utime(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void bump(_Atomic uint64_t *c, uint64_t n) {
  atomic_fetch_add_explicit(c, n, memory_order_relaxed);
}

//---- publisher thread -------------------------------------------------------------------------

typedef struct pub_state {
  uint64_t next_tick, next_seq;
  double next_drive_time;
  uint8_t *buf;
  int cap;
  urtwin_lcmt_urtwin_status last;  /* the newest status sent (lockstep repeats)   */
  int have_last;
  int64_t last_sent_utime;         /* wall clock of the last status sent [us]      */
  urt_lcm_fault_truth_buf_t truth; /* the fault truth's message and arrays         */
} pub_state_t;

static void send_status(urt_lcm_bridge_t *b, pub_state_t *ps, urtwin_lcmt_urtwin_status *msg,
                        _Atomic uint64_t *counter) {
  int len = urtwin_lcmt_urtwin_status_encode(ps->buf, 0, ps->cap, msg);
  if (len < 0 || lcm_publish(b->pub, b->status_channel, ps->buf, (unsigned)len) != 0) {
    bump(&b->n.publish_errors, 1);
  } else {
    bump(counter, 1);
  }
  ps->last_sent_utime = msg->publish_utime;
}

// the tick's fault truth, beside its status (the buffer holds the largest message: 16 faults)
static void send_truth(urt_lcm_bridge_t *b, pub_state_t *ps, const urt_snapshot_t *snap) {
  urt_lcm_fault_truth_fill(snap, &ps->truth);
  int len = urtwin_lcmt_urtwin_fault_truth_encode(ps->buf, 0, ps->cap, &ps->truth.msg);
  if (len < 0 || lcm_publish(b->pub, b->truth_channel, ps->buf, (unsigned)len) != 0) {
    bump(&b->n.publish_errors, 1);
  } else {
    bump(&b->n.truth_sent, 1);
  }
}

// publish every tick in [next_tick, newest]; skip (and count) ticks already overwritten
static void publish_ticks(urt_lcm_bridge_t *b, pub_state_t *ps, uint64_t newest) {
  urt_snapshot_t snap;
  urtwin_lcmt_urtwin_status msg;

  while (ps->next_tick <= newest && !atomic_load(&b->stop)) {
    int rc = b->src.read(b->src.ctx, ps->next_tick, &snap);
    if (rc == URT_ERANGE) {
      // fell out of the history: resume half a history behind the newest, where the writer
      // cannot overtake us again before we get there
      uint64_t resume = newest > URT_LOOP_HISTORY / 2 ? newest - URT_LOOP_HISTORY / 2 : 0;
      if (resume <= ps->next_tick) {
        resume = ps->next_tick + 1;
      }
      bump(&b->n.ticks_lost, resume - ps->next_tick);
      ps->next_tick = resume;
      continue;
    }
    if (rc != 0) {
      break;  // not published yet
    }

    // fill, encode into the thread's buffer, send
    urt_lcm_status_fill(&snap, wall_utime(), (int64_t)atomic_load(&b->n.ticks_lost), &msg);
    send_status(b, ps, &msg, &b->n.status_sent);
    if (b->truth_channel[0] != '\0') {
      send_truth(b, ps, &snap);
    }
    if (b->lockstep) {
      ps->last = msg;
      ps->have_last = 1;
    }
    atomic_store_explicit(&b->n.last_tick, snap.tick, memory_order_relaxed);
    ps->next_tick++;
  }
}

// publish the drive samples made since the last call, decimated to drive_rate by sample time
static void publish_drive(urt_lcm_bridge_t *b, pub_state_t *ps) {
  urt_drive_sample_t d;
  urtwin_lcmt_urtwin_drive msg;
  uint64_t newest = b->src.latest_drive(b->src.ctx);

  while (ps->next_seq <= newest && !atomic_load(&b->stop)) {
    int rc = b->src.read_drive(b->src.ctx, ps->next_seq, &d);
    if (rc == URT_ERANGE) {
      // the drive history's length is the loop's business: jump to the newest sample
      uint64_t resume = newest > ps->next_seq ? newest : ps->next_seq + 1;
      bump(&b->n.drive_lost, resume - ps->next_seq);
      ps->next_seq = resume;
      continue;
    }
    if (rc != 0) {
      break;
    }
    ps->next_seq++;

    // decimate: at most one message per 1/drive_rate of physics time
    if (b->drive_rate > 0) {
      if (d.time < ps->next_drive_time - 1e-9) {
        continue;
      }
      ps->next_drive_time += 1.0 / b->drive_rate;
      if (ps->next_drive_time < d.time) {
        ps->next_drive_time = d.time + 1.0 / b->drive_rate;
      }
    }

    urt_lcm_drive_fill(&d, (int64_t)atomic_load(&b->n.drive_lost), &msg);
    int len = urtwin_lcmt_urtwin_drive_encode(ps->buf, 0, ps->cap, &msg);
    if (len < 0 || lcm_publish(b->pub, b->drive_channel, ps->buf, (unsigned)len) != 0) {
      bump(&b->n.publish_errors, 1);
    } else {
      bump(&b->n.drive_sent, 1);
    }
  }
}

static void *pub_main(void *arg) {
  urt_lcm_bridge_t *b = arg;
  urtwin_lcmt_urtwin_status s0;
  urtwin_lcmt_urtwin_drive d0;
  memset(&s0, 0, sizeof s0);
  memset(&d0, 0, sizeof d0);

  // one encode buffer for both messages (fixed-size arrays: the size never changes)
  pub_state_t ps = {0};
  int ns = urtwin_lcmt_urtwin_status_encoded_size(&s0);
  int nd = urtwin_lcmt_urtwin_drive_encoded_size(&d0);
  ps.cap = ns > nd ? ns : nd;
  uint8_t buf[4096];
  ps.buf = buf;
  if (ps.cap > (int)sizeof buf) {
    fprintf(stderr, "urt_lcm: message larger than the encode buffer (%d bytes)\n", ps.cap);
    return NULL;
  }
  // the fault truth varies in size, at most 16 faults of about 50 bytes each (a class name of
  // at most 19 characters, 25 bytes of numbers) plus 44: the whole buffer holds it with room
  ps.cap = (int)sizeof buf;

  // start at the newest tick and drive sample (what a late subscriber would see first)
  uint64_t newest = b->src.wait(b->src.ctx, 0, 0);
  ps.next_tick = newest > 0 ? newest : 1;
  uint64_t dnewest = b->src.latest_drive(b->src.ctx);
  ps.next_seq = dnewest > 0 ? dnewest : 1;
  ps.next_drive_time = -1.0;

  while (!atomic_load(&b->stop)) {
    newest = b->src.wait(b->src.ctx, ps.next_tick - 1, WAIT_MS);
    if (b->status_channel[0] != '\0') {
      publish_ticks(b, &ps, newest);

      // lockstep waits for a command, and a client waits for a status: repeat the newest
      // (same tick) while idle, so a client that subscribed after it went out can start
      int64_t now = wall_utime();
      if (b->lockstep && ps.have_last && now - ps.last_sent_utime >= REPEAT_MS * 1000) {
        ps.last.publish_utime = now;
        send_status(b, &ps, &ps.last, &b->n.status_repeated);
      }
    } else {
      ps.next_tick = newest + 1;
    }
    if (b->drive_channel[0] != '\0') {
      publish_drive(b, &ps);
    }
  }
  return NULL;
}

//---- subscriber thread ------------------------------------------------------------------------

static void on_command(const lcm_recv_buf_t *rbuf, const char *channel, void *user) {
  urt_lcm_bridge_t *b = user;
  urt_ctrl_cmd_t cmd;
  bump(&b->n.cmd_received, 1);

  // decode and check: a bad message is counted and dropped, never applied
  if (urt_lcm_command_decode(rbuf->data, rbuf->data_size, b->cmd_id + 1, &cmd) != 0) {
    bump(&b->n.cmd_rejected, 1);
    return;
  }

  // hand it to the physics thread; in lockstep the command also pays for its tick
  if (!b->src.submit(b->src.ctx, &cmd)) {
    bump(&b->n.cmd_dropped, 1);
    return;
  }
  b->cmd_id++;
  bump(&b->n.cmd_accepted, 1);
  if (b->lockstep) {
    b->src.grant(b->src.ctx, 1);
  }
}

// Input levels: one SET_INPUTS on the same ring as the commands; never grants a tick (the
// inputs are the world's, not a step request).
static void on_io(const lcm_recv_buf_t *rbuf, const char *channel, void *user) {
  (void)channel;
  urt_lcm_bridge_t *b = user;
  urt_ctrl_cmd_t cmd;
  bump(&b->n.io_received, 1);
  if (urt_lcm_io_decode(rbuf->data, rbuf->data_size, &cmd) != 0) {
    bump(&b->n.io_rejected, 1);
    return;
  }
  if (!b->src.submit(b->src.ctx, &cmd)) {
    bump(&b->n.io_dropped, 1);
    return;
  }
  bump(&b->n.io_accepted, 1);
}

// Live faults: one URT_CTRL_FAULT on the same ring, checked against the model first (a refusal
// is counted here, and nothing reaches the physics); never grants a tick.
static void on_fault(const lcm_recv_buf_t *rbuf, const char *channel, void *user) {
  (void)channel;
  urt_lcm_bridge_t *b = user;
  urt_ctrl_cmd_t cmd;
  bump(&b->n.fault_received, 1);
  if (urt_lcm_fault_decode(rbuf->data, rbuf->data_size, b->src.model, &cmd) != 0) {
    bump(&b->n.fault_rejected, 1);
    return;
  }
  if (!b->src.submit(b->src.ctx, &cmd)) {
    bump(&b->n.fault_dropped, 1);
    return;
  }
  bump(&b->n.fault_accepted, 1);
}

static void *sub_main(void *arg) {
  urt_lcm_bridge_t *b = arg;
  while (!atomic_load(&b->stop)) {
    // returns 0 on timeout, >0 after a message, <0 on error (then do not spin)
    if (lcm_handle_timeout(b->sub, WAIT_MS) < 0) {
      struct timespec ts = {0, WAIT_MS * 1000000L};
      nanosleep(&ts, NULL);
    }
  }
  return NULL;
}

//---- lifecycle --------------------------------------------------------------------------------

void urt_lcm_config_default(urt_lcm_config_t *cfg) {
  memset(cfg, 0, sizeof *cfg);
}

static void free_bridge(urt_lcm_bridge_t *b) {
  if (b->sub != NULL) {
    if (b->subscription != NULL) {
      lcm_unsubscribe(b->sub, b->subscription);
    }
    if (b->io_subscription != NULL) {
      lcm_unsubscribe(b->sub, b->io_subscription);
    }
    if (b->fault_subscription != NULL) {
      lcm_unsubscribe(b->sub, b->fault_subscription);
    }
    lcm_destroy(b->sub);
  }
  if (b->pub != NULL) {
    lcm_destroy(b->pub);
  }
  if (b->src.release != NULL) {
    b->src.release(b->src.ctx);
  }
  free(b->url);
  free(b->status_channel);
  free(b->drive_channel);
  free(b->command_channel);
  free(b->io_channel);
  free(b->fault_channel);
  free(b->truth_channel);
  free(b);
}

int urt_lcm_bridge_create_source(const urt_lcm_source_t *src, const urt_lcm_config_t *cfg,
                                 urt_lcm_bridge_t **out, char *err, size_t err_sz) {
  urt_lcm_config_t defaults;
  if (cfg == NULL) {
    urt_lcm_config_default(&defaults);
    cfg = &defaults;
  }

  // check the source and the config before anything is opened
  if (src == NULL || src->wait == NULL || src->read == NULL || src->latest_drive == NULL ||
      src->read_drive == NULL || src->submit == NULL || src->grant == NULL || out == NULL) {
    set_err(err, err_sz, "lcm: %s", "incomplete source");
    if (src != NULL && src->release != NULL) {
      src->release(src->ctx);
    }
    return URT_EINVAL;
  }
  if (!(cfg->drive_rate >= 0) || (cfg->lockstep != 0 && cfg->lockstep != 1)) {
    set_err(err, err_sz, "lcm: %s", "drive_rate must be >= 0 and lockstep 0 or 1");
    if (src->release != NULL) {
      src->release(src->ctx);
    }
    return URT_EINVAL;
  }

  urt_lcm_bridge_t *b = calloc(1, sizeof *b);
  if (b == NULL) {
    if (src->release != NULL) {
      src->release(src->ctx);
    }
    return URT_ENOMEM;
  }
  b->src = *src;
  b->drive_rate = cfg->drive_rate;
  b->lockstep = cfg->lockstep;
  b->url = dup_or(cfg->url, URT_LCM_DEFAULT_URL);
  b->status_channel = dup_or(cfg->status_channel, URT_LCM_DEFAULT_STATUS);
  b->drive_channel = dup_or(cfg->drive_channel, URT_LCM_DEFAULT_DRIVE);
  b->command_channel = dup_or(cfg->command_channel, URT_LCM_DEFAULT_COMMAND);
  b->io_channel = dup_or(cfg->io_channel, URT_LCM_DEFAULT_IO);
  b->fault_channel = dup_or(cfg->fault_channel, URT_LCM_DEFAULT_FAULT);
  b->truth_channel = dup_or(cfg->fault_truth_channel, URT_LCM_DEFAULT_FAULT_TRUTH);
  if (b->url == NULL || b->status_channel == NULL || b->drive_channel == NULL ||
      b->command_channel == NULL || b->io_channel == NULL || b->fault_channel == NULL ||
      b->truth_channel == NULL) {
    free_bridge(b);
    return URT_ENOMEM;
  }

  // LCM refuses longer channel names at publish time: say so now
  if (strlen(b->status_channel) > LCM_MAX_CHANNEL_NAME_LENGTH ||
      strlen(b->drive_channel) > LCM_MAX_CHANNEL_NAME_LENGTH ||
      strlen(b->command_channel) > LCM_MAX_CHANNEL_NAME_LENGTH ||
      strlen(b->io_channel) > LCM_MAX_CHANNEL_NAME_LENGTH ||
      strlen(b->fault_channel) > LCM_MAX_CHANNEL_NAME_LENGTH ||
      strlen(b->truth_channel) > LCM_MAX_CHANNEL_NAME_LENGTH) {
    set_err(err, err_sz, "lcm: channel names are limited to %s characters", "63");
    free_bridge(b);
    return URT_EINVAL;
  }

  // open: one instance publishes, the other (if any) subscribes, so the publisher never
  // carries a receive socket
  b->pub = lcm_create(b->url);
  if (b->pub == NULL) {
    set_err(err, err_sz, "lcm: cannot open %s (bad URL, or no multicast route: see "
            "tools/lcm_loopback_route.sh)", b->url);
    free_bridge(b);
    return URT_EIO;
  }
  if (b->command_channel[0] != '\0' || b->io_channel[0] != '\0' ||
      b->fault_channel[0] != '\0') {
    b->sub = lcm_create(b->url);
    bool ok = b->sub != NULL;
    if (ok && b->command_channel[0] != '\0') {
      b->subscription = lcm_subscribe(b->sub, b->command_channel, on_command, b);
      ok = b->subscription != NULL;
    }
    if (ok && b->io_channel[0] != '\0') {
      b->io_subscription = lcm_subscribe(b->sub, b->io_channel, on_io, b);
      ok = b->io_subscription != NULL;
    }
    if (ok && b->fault_channel[0] != '\0') {
      b->fault_subscription = lcm_subscribe(b->sub, b->fault_channel, on_fault, b);
      ok = b->fault_subscription != NULL;
    }
    if (!ok) {
      set_err(err, err_sz, "lcm: cannot subscribe on %s", b->url);
      free_bridge(b);
      return URT_EIO;
    }
  }
  *out = b;
  return 0;
}

int urt_lcm_bridge_start(urt_lcm_bridge_t *b) {
  if (b->pub_running || b->sub_running) {
    return URT_EINVAL;
  }
  atomic_store(&b->stop, 0);

  // lockstep: one tick up front, so the first status exists before the first command
  if (b->lockstep) {
    b->src.grant(b->src.ctx, 1);
  }
  if (urt_thread_start(&b->pub_thread, pub_main, b, 512 * 1024) != 0) {
    return URT_EIO;
  }
  b->pub_running = 1;
  if (b->sub != NULL) {
    if (urt_thread_start(&b->sub_thread, sub_main, b, 512 * 1024) != 0) {
      urt_lcm_bridge_stop(b);
      return URT_EIO;
    }
    b->sub_running = 1;
  }
  return 0;
}

static void join_bounded(urt_lcm_bridge_t *b, pthread_t t, const char *name) {
  char who[64];
  snprintf(who, sizeof who, "urt_lcm: %s", name);
  if (urt_thread_join_bounded(t, JOIN_TIMEOUT_S, who) != 0) {
    b->abandoned = 1;
  }
}

void urt_lcm_bridge_stop(urt_lcm_bridge_t *b) {
  atomic_store(&b->stop, 1);
  if (b->pub_running) {
    join_bounded(b, b->pub_thread, "publisher");
    b->pub_running = 0;
  }
  if (b->sub_running) {
    join_bounded(b, b->sub_thread, "subscriber");
    b->sub_running = 0;
  }
}

void urt_lcm_bridge_destroy(urt_lcm_bridge_t *b) {
  if (b == NULL) {
    return;
  }
  urt_lcm_bridge_stop(b);
  if (b->abandoned) {
    return;  // a thread may still touch it
  }
  free_bridge(b);
}

void urt_lcm_bridge_get_stats(const urt_lcm_bridge_t *b, urt_lcm_stats_t *out) {
  counters_t *n = (counters_t *)&b->n;
  out->status_sent = atomic_load(&n->status_sent);
  out->status_repeated = atomic_load(&n->status_repeated);
  out->ticks_lost = atomic_load(&n->ticks_lost);
  out->drive_sent = atomic_load(&n->drive_sent);
  out->drive_lost = atomic_load(&n->drive_lost);
  out->publish_errors = atomic_load(&n->publish_errors);
  out->cmd_received = atomic_load(&n->cmd_received);
  out->cmd_accepted = atomic_load(&n->cmd_accepted);
  out->cmd_rejected = atomic_load(&n->cmd_rejected);
  out->cmd_dropped = atomic_load(&n->cmd_dropped);
  out->io_received = atomic_load(&n->io_received);
  out->io_accepted = atomic_load(&n->io_accepted);
  out->io_rejected = atomic_load(&n->io_rejected);
  out->io_dropped = atomic_load(&n->io_dropped);
  out->fault_received = atomic_load(&n->fault_received);
  out->fault_accepted = atomic_load(&n->fault_accepted);
  out->fault_rejected = atomic_load(&n->fault_rejected);
  out->fault_dropped = atomic_load(&n->fault_dropped);
  out->truth_sent = atomic_load(&n->truth_sent);
  out->last_tick = atomic_load(&n->last_tick);
}
