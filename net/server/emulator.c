/* SPDX-License-Identifier: Apache-2.0
 * net/server/emulator.c — the I/O thread behind ports 30001–30003 and 30011–30013
 * (emulator.h). One epoll loop serves every client; it is the single producer of client
 * commands into the hard loop. A relay thread turns the loop's futex wake-ups into an eventfd
 * so that new ticks arrive in the same epoll loop as socket events.
 */
#define _GNU_SOURCE
#include "urt/net/emulator.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "urt/core.h"
#include "urt/net/primary.h"
#include "urt/net/rt_packet.h"
#include "urt/net/script_framer.h"
#include "urt/net/tcp.h"
#include "urt/net/urscript.h"
#include "urt/thread.h"

/* What each port does (protocols.md §0.2). */
typedef enum port_kind {
  PORT_PRIMARY = 0,     /* 30001: version, state at 10 Hz, robot messages; takes URScript */
  PORT_SECONDARY,       /* 30002: version, state at 10 Hz; takes URScript                 */
  PORT_RT,              /* 30003: a packet every controller tick; takes URScript          */
  PORT_PRIMARY_RO,      /* 30011 */
  PORT_SECONDARY_RO,    /* 30012 */
  PORT_RT_RO,           /* 30013 */
  N_PORTS
} port_kind_t;

static const int kBasePort[N_PORTS] = {30001, 30002, 30003, 30011, 30012, 30013};

static bool port_takes_script(int kind) { return kind <= PORT_RT; }
static bool port_is_rt(int kind) { return kind == PORT_RT || kind == PORT_RT_RO; }
static bool port_is_primary(int kind) { return kind == PORT_PRIMARY || kind == PORT_PRIMARY_RO; }
static bool port_is_state(int kind) { return !port_is_rt(kind); }

/* Output room per client: about a second of 30003 packets at 500 Hz, or a minute of 10 Hz
 * state; beyond it, whole messages are dropped for that client. */
#define RT_OUT_CAP (512 * 1024)
#define STATE_OUT_CAP (1024 * 1024)
#define READ_CHUNK 65536
#define MSG_QUEUE 256       /* robot messages waiting for the I/O thread */
#define MAX_EVENTS 64
#define THREAD_STACK (512 * 1024)

/* epoll user data: listeners and the two eventfds are tagged small integers; connections are
 * pointers (always > 4096). */
enum { TAG_TICK = 1, TAG_MSG = 2, TAG_LISTEN0 = 16 };

typedef struct client {
  urt_tcp_conn_t *conn;
  urt_script_framer_t framer;
  struct client *next;
} client_t;

struct urt_emulator {
  urt_loop_t *loop;
  const urt_model_t *m;
  urt_emulator_config_t cfg;
  char bind[64];
  urt_primary_robot_info_t info;
  int producer;                 /* this thread's command ring */
  urt_runner_t *runner;
  int runner_producer;          /* the runner thread's command ring */

  int listen_fd[N_PORTS];
  int epoll_fd, tick_fd, msg_fd;
  client_t *clients;
  uint64_t streamed_tick;       /* last tick sent to the 30003 clients */
  uint64_t state_every;         /* ticks between robot-state messages (10 Hz) */

  /* runner → I/O thread */
  pthread_mutex_t msg_lock;
  urt_script_msg_t msg_queue[MSG_QUEUE];
  unsigned msg_head, msg_len;
  uint64_t msg_dropped;

  pthread_t io_thread, relay_thread;
  _Atomic int stop;
  int started;

  _Atomic uint64_t n_clients, rt_packets, rt_dropped, state_messages, ticks_lost, scripts;
};

//---- the runner's host: the loop, seen from the runner thread ----

static bool host_submit(void *ctx, const urt_ctrl_cmd_t *cmd) {
  urt_emulator_t *e = ctx;
  return urt_loop_submit(e->loop, e->runner_producer, cmd);
}

static uint64_t host_wait_tick(void *ctx, uint64_t after, int timeout_ms) {
  urt_emulator_t *e = ctx;
  return urt_loop_wait(e->loop, after, timeout_ms);
}

static void host_snapshot(void *ctx, urt_snapshot_t *out) {
  urt_emulator_t *e = ctx;
  urt_loop_read_latest(e->loop, out);
}

static void host_message(void *ctx, const urt_script_msg_t *msg) {
  urt_emulator_t *e = ctx;
  pthread_mutex_lock(&e->msg_lock);
  if (e->msg_len < MSG_QUEUE) {
    e->msg_queue[(e->msg_head + e->msg_len) % MSG_QUEUE] = *msg;
    e->msg_len++;
  } else {
    e->msg_dropped++;
  }
  pthread_mutex_unlock(&e->msg_lock);
  uint64_t one = 1;
  ssize_t rc = write(e->msg_fd, &one, sizeof one);
  (void)rc;  // a full eventfd counter still wakes the reader
}

static int host_inverse_kinematics(void *ctx, const double pose[6], const double qnear[URT_NJ],
                                   double q[URT_NJ]) {
  urt_emulator_t *e = ctx;
  return urt_ctrl_inverse_kinematics(e->m, pose, qnear, q);
}

//---- sending ----

static uint64_t timestamp_us(const urt_emulator_t *e) {
  urt_snapshot_t s;
  urt_loop_read_latest(e->loop, &s);
  return (uint64_t)(s.time * 1e6 + 0.5);
}

static void send_to(urt_emulator_t *e, bool (*want)(int kind), const uint8_t *buf, size_t len,
                    _Atomic uint64_t *sent, _Atomic uint64_t *dropped) {
  for (client_t *c = e->clients; c; c = c->next) {
    if (!want(c->conn->port_kind)) {
      continue;
    }
    if (urt_tcp_send(c->conn, buf, len)) {
      if (sent) {
        atomic_fetch_add_explicit(sent, 1, memory_order_relaxed);
      }
    } else if (dropped) {
      atomic_fetch_add_explicit(dropped, 1, memory_order_relaxed);
    }
  }
}

static void broadcast_message(urt_emulator_t *e, const urt_script_msg_t *msg) {
  uint8_t buf[URT_PRIMARY_MAX_MESSAGE];
  uint64_t ts = (uint64_t)(msg->time * 1e6 + 0.5);
  int n = URT_EINVAL;
  switch (msg->kind) {
    case URT_SCRIPT_MSG_TEXT:
      n = urt_primary_encode_text(ts, URT_PRIMARY_SOURCE_CONTROLLER, msg->text, buf, sizeof buf);
      break;
    case URT_SCRIPT_MSG_KEY:
      n = urt_primary_encode_key(ts, URT_PRIMARY_SOURCE_ROBOT_INTERFACE, msg->code, msg->argument,
                                 msg->title, msg->text, buf, sizeof buf);
      break;
    case URT_SCRIPT_MSG_RUNTIME_EXCEPTION:
      n = urt_primary_encode_runtime_exception(ts, URT_PRIMARY_SOURCE_RT_MACHINE, msg->line,
                                               msg->column, msg->text, buf, sizeof buf);
      break;
    default:
      break;
  }
  if (n > 0) {
    send_to(e, port_is_primary, buf, (size_t)n, NULL, NULL);
  }
}

// A controller event that is not from a program (e.g. an unreadable unit): a TEXT message.
static void broadcast_text(urt_emulator_t *e, const char *text) {
  urt_script_msg_t msg = {.kind = URT_SCRIPT_MSG_TEXT};
  msg.time = timestamp_us(e) * 1e-6;
  snprintf(msg.text, sizeof msg.text, "%s", text);
  broadcast_message(e, &msg);
}

// Stream every tick published since the last call: one 30003 packet per tick to every
// real-time client, and robot state at 10 Hz to the primary and secondary clients.
static void stream_ticks(urt_emulator_t *e) {
  uint64_t newest = urt_loop_latest_tick(e->loop);
  if (e->streamed_tick + URT_LOOP_HISTORY - 8 < newest) {
    // fell behind the history: skip what is gone, and count it
    uint64_t resume = newest - (URT_LOOP_HISTORY - 8);
    atomic_fetch_add(&e->ticks_lost, resume - e->streamed_tick);
    e->streamed_tick = resume;
  }
  static _Thread_local urt_snapshot_t s;
  uint8_t rt[URT_RT_PACKET_MAX];
  uint8_t state[URT_PRIMARY_MAX_MESSAGE];
  for (uint64_t k = e->streamed_tick + 1; k <= newest; k++) {
    if (urt_loop_read(e->loop, k, &s) != URT_OK) {
      atomic_fetch_add(&e->ticks_lost, 1);
      continue;
    }
    size_t n = urt_rt_packet_encode(&e->cfg.version, &s, rt, sizeof rt);
    if (n > 0) {
      send_to(e, port_is_rt, rt, n, &e->rt_packets, &e->rt_dropped);
    }
    if (k % e->state_every == 0) {
      int m = urt_primary_encode_robot_state(&e->cfg.version, &e->info, &s, state, sizeof state);
      if (m > 0) {
        send_to(e, port_is_state, state, (size_t)m, &e->state_messages, NULL);
      }
    }
  }
  e->streamed_tick = newest;
}

//---- clients ----

static void arm_output(urt_emulator_t *e, client_t *c) {
  bool want = urt_tcp_pending(c->conn) > 0;
  if (want == c->conn->want_write) {
    return;
  }
  struct epoll_event ev = {.events = EPOLLIN | EPOLLRDHUP | (want ? EPOLLOUT : 0), .data.ptr = c};
  epoll_ctl(e->epoll_fd, EPOLL_CTL_MOD, c->conn->fd, &ev);
  c->conn->want_write = want;
}

static void close_client(urt_emulator_t *e, client_t *c) {
  for (client_t **p = &e->clients; *p; p = &(*p)->next) {
    if (*p == c) {
      *p = c->next;
      break;
    }
  }
  epoll_ctl(e->epoll_fd, EPOLL_CTL_DEL, c->conn->fd, NULL);
  urt_script_framer_free(&c->framer);
  urt_tcp_close(c->conn);
  free(c);
  atomic_fetch_sub(&e->n_clients, 1);
}

static void submit_command(urt_emulator_t *e, int kind) {
  urt_ctrl_cmd_t cmd = {.kind = kind};
  if (!urt_loop_submit(e->loop, e->producer, &cmd)) {
    broadcast_text(e, "urtwin: controller command dropped: command ring full");
  }
}

// One framed unit from a client: a controller command line, a program or a statement.
static void on_unit(void *ctx, const urt_script_unit_t *u) {
  urt_emulator_t *e = ctx;
  atomic_fetch_add(&e->scripts, 1);
  switch (u->kind) {
    case URT_SCRIPT_UNIT_COMMAND:
      switch (u->command) {
        case URT_SCRIPT_CMD_POWER_ON: submit_command(e, URT_CTRL_POWER_ON); break;
        case URT_SCRIPT_CMD_POWER_OFF: submit_command(e, URT_CTRL_POWER_OFF); break;
        case URT_SCRIPT_CMD_BRAKE_RELEASE: submit_command(e, URT_CTRL_BRAKE_RELEASE); break;
        case URT_SCRIPT_CMD_UNLOCK_PSTOP: submit_command(e, URT_CTRL_UNLOCK_PSTOP); break;
        case URT_SCRIPT_CMD_STOP_PROGRAM: urt_runner_stop(e->runner); break;
        default: break;  // set sim / set real: urtwin is always a simulation
      }
      break;
    case URT_SCRIPT_UNIT_PROGRAM:
    case URT_SCRIPT_UNIT_SECONDARY:
    case URT_SCRIPT_UNIT_STATEMENT:
      if (urt_runner_submit(e->runner, u->text, u->len) != 0) {
        broadcast_text(e, "urtwin: script refused: too large or too many queued");
      }
      break;
    default: {
      char text[160];
      snprintf(text, sizeof text, "urtwin: script input dropped: %s", u->error ? u->error : "unreadable");
      broadcast_text(e, text);
    }
  }
}

static void on_accept(urt_emulator_t *e, int kind) {
  for (;;) {
    urt_tcp_conn_t *conn =
        urt_tcp_accept(e->listen_fd[kind], kind, port_is_rt(kind) ? RT_OUT_CAP : STATE_OUT_CAP);
    if (!conn) {
      return;
    }
    client_t *c = calloc(1, sizeof *c);
    if (!c) {
      urt_tcp_close(conn);
      return;
    }
    c->conn = conn;
    urt_script_framer_init(&c->framer);
    struct epoll_event ev = {.events = EPOLLIN | EPOLLRDHUP, .data.ptr = c};
    if (epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, conn->fd, &ev) != 0) {
      urt_script_framer_free(&c->framer);
      urt_tcp_close(conn);
      free(c);
      continue;
    }
    c->next = e->clients;
    e->clients = c;
    atomic_fetch_add(&e->n_clients, 1);
    if (port_is_state(kind)) {
      // the first message on the primary and secondary ports is the version (§4.2)
      uint8_t buf[256];
      int n = urt_primary_encode_version(&e->cfg.version, timestamp_us(e), buf, sizeof buf);
      if (n > 0) {
        urt_tcp_send(conn, buf, (size_t)n);
      }
    }
  }
}

static void on_readable(urt_emulator_t *e, client_t *c) {
  static _Thread_local char buf[READ_CHUNK];
  // bounded per event: a flooding client cannot starve the others
  for (int round = 0; round < 4; round++) {
    ssize_t n = read(c->conn->fd, buf, sizeof buf);
    if (n > 0) {
      c->conn->bytes_in += (uint64_t)n;
      if (port_takes_script(c->conn->port_kind)) {
        urt_script_framer_feed(&c->framer, buf, (size_t)n, on_unit, e);
      }  // the read-only twins ignore input, as the real ones do
      if ((size_t)n < sizeof buf) {
        return;
      }
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      return;
    }
    // EOF or error: a statement without its final newline still counts, as on a real robot
    if (port_takes_script(c->conn->port_kind)) {
      urt_script_framer_finish(&c->framer, on_unit, e);
    }
    close_client(e, c);
    return;
  }
}

static void flush_all(urt_emulator_t *e) {
  client_t *next;
  for (client_t *c = e->clients; c; c = next) {
    next = c->next;
    if (urt_tcp_pending(c->conn) == 0) {
      continue;
    }
    if (!urt_tcp_flush(c->conn)) {
      close_client(e, c);
      continue;
    }
    arm_output(e, c);
  }
}

static void drain_messages(urt_emulator_t *e) {
  uint64_t count;
  ssize_t rc = read(e->msg_fd, &count, sizeof count);
  (void)rc;
  for (;;) {
    urt_script_msg_t msg;
    pthread_mutex_lock(&e->msg_lock);
    bool have = e->msg_len > 0;
    if (have) {
      msg = e->msg_queue[e->msg_head];
      e->msg_head = (e->msg_head + 1) % MSG_QUEUE;
      e->msg_len--;
    }
    pthread_mutex_unlock(&e->msg_lock);
    if (!have) {
      break;
    }
    broadcast_message(e, &msg);
  }
}

//---- threads ----

static void *relay_main(void *arg) {
  urt_emulator_t *e = arg;
  uint64_t seen = urt_loop_latest_tick(e->loop);
  while (!atomic_load(&e->stop)) {
    uint64_t t = urt_loop_wait(e->loop, seen, 50);
    if (t > seen) {
      seen = t;
      uint64_t one = 1;
      ssize_t rc = write(e->tick_fd, &one, sizeof one);
      (void)rc;
    }
  }
  return NULL;
}

static void *io_main(void *arg) {
  urt_emulator_t *e = arg;
  struct epoll_event ev[MAX_EVENTS];
  while (!atomic_load(&e->stop)) {
    int n = epoll_wait(e->epoll_fd, ev, MAX_EVENTS, 50);
    for (int i = 0; i < n; i++) {
      uintptr_t tag = (uintptr_t)ev[i].data.ptr;
      if (tag == TAG_TICK) {
        uint64_t count;
        ssize_t rc = read(e->tick_fd, &count, sizeof count);
        (void)rc;
        stream_ticks(e);
      } else if (tag == TAG_MSG) {
        drain_messages(e);
      } else if (tag >= TAG_LISTEN0 && tag < TAG_LISTEN0 + N_PORTS) {
        on_accept(e, (int)(tag - TAG_LISTEN0));
      } else {
        client_t *c = ev[i].data.ptr;
        if (ev[i].events & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
          on_readable(e, c);  // may close c
        } else if (ev[i].events & EPOLLOUT) {
          c->conn->want_write = true;  // flush_all below
        }
      }
    }
    flush_all(e);
  }
  return NULL;
}

//---- life cycle ----

int urt_emulator_create(urt_loop_t *loop, const urt_emulator_config_t *cfg, urt_emulator_t **out,
                        char *err, size_t err_sz) {
  char scratch[256];
  if (!err) {
    err = scratch;
    err_sz = sizeof scratch;
  }
  urt_emulator_t *e = calloc(1, sizeof *e);
  if (!e) {
    return URT_ENOMEM;
  }
  e->loop = loop;
  e->m = urt_loop_model(loop);
  e->cfg = *cfg;
  snprintf(e->bind, sizeof e->bind, "%s", cfg->bind ? cfg->bind : "127.0.0.1");
  e->cfg.bind = e->bind;
  e->epoll_fd = e->tick_fd = e->msg_fd = -1;
  for (int k = 0; k < N_PORTS; k++) {
    e->listen_fd[k] = -1;
  }
  pthread_mutex_init(&e->msg_lock, NULL);
  urt_primary_robot_info_from_model(&e->cfg.version, e->m, &e->info);
  double period = urt_loop_period(loop);
  e->state_every = (uint64_t)(0.1 / period + 0.5);  // 10 Hz
  e->producer = urt_loop_add_producer(loop, "tcp");
  e->runner_producer = urt_loop_add_producer(loop, "urscript");
  if (e->producer < 0 || e->runner_producer < 0) {
    snprintf(err, err_sz, "no free command ring for the TCP servers");
    urt_emulator_destroy(e);
    return URT_ENOSPC;
  }
  for (int k = 0; k < N_PORTS; k++) {
    int fd = urt_tcp_listen(e->bind, kBasePort[k] + cfg->port_offset, err, err_sz);
    if (fd < 0) {
      urt_emulator_destroy(e);
      return URT_EIO;
    }
    e->listen_fd[k] = fd;
  }
  e->epoll_fd = epoll_create1(EPOLL_CLOEXEC);
  e->tick_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  e->msg_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (e->epoll_fd < 0 || e->tick_fd < 0 || e->msg_fd < 0) {
    snprintf(err, err_sz, "epoll/eventfd: %s", strerror(errno));
    urt_emulator_destroy(e);
    return URT_EIO;
  }
  struct epoll_event ev = {.events = EPOLLIN};
  ev.data.ptr = (void *)(uintptr_t)TAG_TICK;
  epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->tick_fd, &ev);
  ev.data.ptr = (void *)(uintptr_t)TAG_MSG;
  epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->msg_fd, &ev);
  for (int k = 0; k < N_PORTS; k++) {
    ev.data.ptr = (void *)(uintptr_t)(TAG_LISTEN0 + k);
    epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->listen_fd[k], &ev);
  }
  urt_script_host_t host = {
      .ctx = e,
      .submit = host_submit,
      .wait_tick = host_wait_tick,
      .snapshot = host_snapshot,
      .message = host_message,
      .inverse_kinematics = host_inverse_kinematics,
  };
  if (urt_runner_create(&host, NULL, &e->runner) != 0) {
    snprintf(err, err_sz, "cannot start the URScript runner");
    urt_emulator_destroy(e);
    return URT_EIO;
  }
  *out = e;
  return URT_OK;
}

int urt_emulator_start(urt_emulator_t *e) {
  if (e->started) {
    return URT_OK;
  }
  atomic_store(&e->stop, 0);
  e->streamed_tick = urt_loop_latest_tick(e->loop);
  if (urt_thread_start(&e->io_thread, io_main, e, THREAD_STACK) != 0) {
    return URT_EIO;
  }
  if (urt_thread_start(&e->relay_thread, relay_main, e, THREAD_STACK) != 0) {
    atomic_store(&e->stop, 1);
    pthread_join(e->io_thread, NULL);
    return URT_EIO;
  }
  e->started = 1;
  return URT_OK;
}

void urt_emulator_stop(urt_emulator_t *e) {
  if (!e->started) {
    return;
  }
  atomic_store(&e->stop, 1);
  pthread_join(e->relay_thread, NULL);
  pthread_join(e->io_thread, NULL);
  e->started = 0;
}

void urt_emulator_destroy(urt_emulator_t *e) {
  if (!e) {
    return;
  }
  urt_emulator_stop(e);
  urt_runner_destroy(e->runner);
  while (e->clients) {
    close_client(e, e->clients);
  }
  for (int k = 0; k < N_PORTS; k++) {
    if (e->listen_fd[k] >= 0) {
      close(e->listen_fd[k]);
    }
  }
  if (e->epoll_fd >= 0) close(e->epoll_fd);
  if (e->tick_fd >= 0) close(e->tick_fd);
  if (e->msg_fd >= 0) close(e->msg_fd);
  pthread_mutex_destroy(&e->msg_lock);
  free(e);
}

void urt_emulator_get_stats(const urt_emulator_t *e, urt_emulator_stats_t *out) {
  out->clients = atomic_load(&e->n_clients);
  out->rt_packets = atomic_load(&e->rt_packets);
  out->rt_dropped = atomic_load(&e->rt_dropped);
  out->state_messages = atomic_load(&e->state_messages);
  out->ticks_lost = atomic_load(&e->ticks_lost);
  out->scripts = atomic_load(&e->scripts);
}
