/* SPDX-License-Identifier: Apache-2.0
 * net/server/emulator.c — the I/O thread behind every TCP port (emulator.h): one epoll loop
 * serves all clients and is the single producer of client commands into the hard loop. The
 * loop writes an eventfd after each tick (urt_loop_set_notify_fd), so new ticks arrive in the
 * same epoll loop as socket events. What each port does lives in port_script.c, port_rtde.c and
 * port_dashboard.c, the runner's view of the emulator in script_host.c; this file owns the
 * connections and the tick fan-out.
 */
#define _GNU_SOURCE
#include "urt/net/emulator.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include "emulator_internal.h"
#include "urt/core.h"
#include "urt/thread.h"

static const int kBasePort[URT__N_PORTS] = {30001, 30002, 30003, 30011, 30012, 30013, 30004, 29999};

/* Output room per client: about a second of 30003 packets at 500 Hz, or a minute of 10 Hz
 * state; beyond it, whole messages are dropped for that client. An RTDE client whose output
 * has not moved for RTDE_STALL_LIMIT has stopped reading and is disconnected (30001–30003 only
 * drop: ur_rtde's ScriptClient never reads 30003 and must stay connected). */
#define RT_OUT_CAP (512 * 1024)
#define STATE_OUT_CAP (1024 * 1024)
#define RTDE_SNDBUF (256 * 1024)
#define RTDE_STALL_LIMIT 2.0  /* [s], below ur_rtde's own 2.5 s read deadline */
#define READ_CHUNK 65536
#define MAX_EVENTS 64
#define THREAD_STACK (512 * 1024)
#define ACCEPTS_PER_EVENT 64
#define LISTEN_BACKOFF_NS 100000000LL  /* 100 ms without a spare descriptor */
#define REFUSAL_LOG_NS 1000000000LL

/* epoll user data: listeners and the two eventfds are tagged small integers; connections are
 * pointers (always > 4096). */
enum { TAG_TICK = 1, TAG_MSG = 2, TAG_LISTEN0 = 16 };

static const urt__port_ops_t *ops_of(int kind) {
  switch (kind) {
    case PORT_RTDE: return &urt__port_rtde_ops;
    case PORT_DASHBOARD: return &urt__port_dashboard_ops;
    default: return &urt__port_script_ops;
  }
}

//---- helpers for the ports ----

uint64_t urt__timestamp_us(const urt_emulator_t *e) {
  urt_snapshot_t s;
  urt_loop_read_latest(e->loop, &s);
  return (uint64_t)(s.time * 1e6 + 0.5);
}

void urt__send_to(urt_emulator_t *e, bool (*want)(int kind), const uint8_t *buf, size_t len,
                  _Atomic uint64_t *sent, _Atomic uint64_t *dropped) {
  for (urt__client_t *c = e->clients; c; c = c->next) {
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

void urt__submit(urt_emulator_t *e, ring_kind_t ring, const urt_ctrl_cmd_t *cmd) {
  if (!urt_loop_submit(e->loop, e->ring[ring], cmd)) {
    urt__script_broadcast_text(e, "urtwin: controller command dropped: command ring full");
  }
}

void urt__submit_kind(urt_emulator_t *e, ring_kind_t ring, int kind) {
  urt_ctrl_cmd_t cmd = {.kind = kind};
  urt__submit(e, ring, &cmd);
}

//---- ticks ----

// Hand every tick published since the last call to the ports, in order.
static void stream_ticks(urt_emulator_t *e) {
  uint64_t newest = urt_loop_latest_tick(e->loop);
  if (e->streamed_tick + URT_LOOP_HISTORY - 8 < newest) {
    // fell behind the history: skip what is gone, and count it
    uint64_t resume = newest - (URT_LOOP_HISTORY - 8);
    atomic_fetch_add(&e->ticks_lost, resume - e->streamed_tick);
    e->streamed_tick = resume;
  }
  static _Thread_local urt_snapshot_t s;
  if (newest > e->streamed_tick) {
    urt__rtde_apply_inputs(e);
  }
  for (uint64_t k = e->streamed_tick + 1; k <= newest; k++) {
    if (urt_loop_read(e->loop, k, &s) != URT_OK) {
      atomic_fetch_add(&e->ticks_lost, 1);
      continue;
    }
    urt__dashboard_tick(e, &s);  // first: the protective stop's start, for the 5 s rule
    const bool safety_changed = urt__script_safety_tick(e, &s);
    urt__script_stream_tick(e, &s, safety_changed);
    urt__rtde_stream_tick(e, &s);
  }
  e->streamed_tick = newest;
}

//---- clients ----

static void arm_output(urt_emulator_t *e, urt__client_t *c) {
  bool want = urt_tcp_pending(c->conn) > 0;
  if (want == c->conn->want_write) {
    return;
  }
  struct epoll_event ev = {.events = EPOLLIN | EPOLLRDHUP | (want ? EPOLLOUT : 0), .data.ptr = c};
  epoll_ctl(e->epoll_fd, EPOLL_CTL_MOD, c->conn->fd, &ev);
  c->conn->want_write = want;
}

static void close_client(urt_emulator_t *e, urt__client_t *c) {
  for (urt__client_t **p = &e->clients; *p; p = &(*p)->next) {
    if (*p == c) {
      *p = c->next;
      break;
    }
  }
  epoll_ctl(e->epoll_fd, EPOLL_CTL_DEL, c->conn->fd, NULL);
  const urt__port_ops_t *ops = ops_of(c->conn->port_kind);
  if (ops->close) {
    ops->close(e, c);
  }
  e->port_clients[c->conn->port_kind]--;
  urt_tcp_close(c->conn);
  free(c);
  atomic_fetch_sub(&e->n_clients, 1);
}

static int64_t mono_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

// Refusals are logged at most once a second, as counts: a flood must not become a log flood.
static void log_refusals(urt_emulator_t *e, bool force) {
  int64_t now = mono_ns();
  if (!force && now - e->last_refusal_log_ns < REFUSAL_LOG_NS) {
    return;
  }
  for (int k = 0; k < URT__N_PORTS; k++) {
    if (e->unlogged_cap[k]) {
      fprintf(stderr, "urtwin: port %d: %llu connection(s) refused, %d clients already (the cap, "
              "--max-clients)\n", kBasePort[k] + e->cfg.port_offset,
              (unsigned long long)e->unlogged_cap[k], e->max_clients);
      e->unlogged_cap[k] = 0;
    }
  }
  if (e->unlogged_fds) {
    fprintf(stderr, "urtwin: %llu connection(s) refused: no file descriptor left (EMFILE/ENFILE; "
            "raise `ulimit -n` or lower --max-clients)\n", (unsigned long long)e->unlogged_fds);
    e->unlogged_fds = 0;
  }
  e->last_refusal_log_ns = now;
}

static void listener_events(urt_emulator_t *e, int kind, uint32_t events) {
  struct epoll_event ev = {.events = events, .data.ptr = (void *)(uintptr_t)(TAG_LISTEN0 + kind)};
  epoll_ctl(e->epoll_fd, EPOLL_CTL_MOD, e->listen_fd[kind], &ev);
}

// Listeners paused for lack of descriptors listen again once their back-off is over.
static void resume_listeners(urt_emulator_t *e) {
  int64_t now = mono_ns();
  for (int k = 0; k < URT__N_PORTS; k++) {
    if (e->listen_paused_until_ns[k] && now >= e->listen_paused_until_ns[k]) {
      e->listen_paused_until_ns[k] = 0;
      if (e->reserve_fd < 0) {
        e->reserve_fd = urt_tcp_reserve_open();
      }
      listener_events(e, k, EPOLLIN);
    }
  }
}

static void on_accept(urt_emulator_t *e, int kind) {
  // bounded per event (the listener is level-triggered: the rest comes next round)
  for (int n = 0; n < ACCEPTS_PER_EVENT; n++) {
    int fd = urt_tcp_accept_fd(e->listen_fd[kind], &e->reserve_fd);
    if (fd == URT_TCP_NONE) {
      return;
    }
    if (fd == URT_TCP_FAILED) {
      continue;
    }
    if (fd == URT_TCP_NO_FDS || fd == URT_TCP_NO_FDS_STUCK) {
      atomic_fetch_add(&e->refused_fds, 1);
      e->unlogged_fds++;
      if (fd == URT_TCP_NO_FDS_STUCK) {
        // not even a spare: stop listening for a while instead of waking on it in a loop
        e->listen_paused_until_ns[kind] = mono_ns() + LISTEN_BACKOFF_NS;
        listener_events(e, kind, 0);
        return;
      }
      continue;
    }
    if (e->port_clients[kind] >= e->max_clients) {
      close(fd);  // at the cap: an orderly close, the peer reads EOF
      atomic_fetch_add(&e->refused_cap, 1);
      e->unlogged_cap[kind]++;
      continue;
    }
    urt_tcp_conn_t *conn = urt_tcp_conn_new(
        fd, kind, kind == PORT_RT || kind == PORT_RT_RO ? RT_OUT_CAP : STATE_OUT_CAP,
        &e->out_budget);
    if (!conn) {
      close(fd);
      continue;
    }
    urt__client_t *c = calloc(1, sizeof *c);
    const urt__port_ops_t *ops = ops_of(kind);
    if (c) {
      c->conn = conn;
    }
    struct epoll_event ev = {.events = EPOLLIN | EPOLLRDHUP, .data.ptr = c};
    if (!c || (ops->open && !ops->open(e, c)) ||
        epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, conn->fd, &ev) != 0) {
      if (c && ops->close) {
        ops->close(e, c);
      }
      free(c);
      urt_tcp_close(conn);
      continue;
    }
    if (kind == PORT_RTDE) {
      urt_tcp_set_sndbuf(conn, RTDE_SNDBUF);
    }
    c->next = e->clients;
    e->clients = c;
    e->port_clients[kind]++;
    atomic_fetch_add(&e->n_clients, 1);
  }
}

static void on_readable(urt_emulator_t *e, urt__client_t *c) {
  static _Thread_local uint8_t buf[READ_CHUNK];
  const urt__port_ops_t *ops = ops_of(c->conn->port_kind);
  // bounded per event: a flooding client cannot starve the others
  for (int round = 0; round < 4; round++) {
    ssize_t n = read(c->conn->fd, buf, sizeof buf);
    if (n > 0) {
      c->conn->bytes_in += (uint64_t)n;
      if (!c->conn->closing && ops->input && !ops->input(e, c, buf, (size_t)n)) {
        c->conn->closing = true;
      }
      if ((size_t)n < sizeof buf) {
        return;
      }
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      return;
    }
    if (ops->eof) {
      ops->eof(e, c);
    }
    close_client(e, c);
    return;
  }
}

static void flush_all(urt_emulator_t *e) {
  urt__client_t *next;
  for (urt__client_t *c = e->clients; c; c = next) {
    next = c->next;
    if (c->conn->port_kind == PORT_RTDE && urt_tcp_stalled_for(c->conn) > RTDE_STALL_LIMIT) {
      close_client(e, c);  // stopped reading: dropped after a bound, never waited for
      continue;
    }
    // a client whose socket was full is written again only once epoll says it has room: a
    // crowd of clients that never read costs no system call per tick
    if (urt_tcp_pending(c->conn) > 0 && !c->conn->write_blocked && !urt_tcp_flush(c->conn)) {
      close_client(e, c);
      continue;
    }
    if (c->conn->closing && urt_tcp_pending(c->conn) == 0) {
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
    urt__script_broadcast(e, &msg);
  }
}

//---- threads ----

static void *io_main(void *arg) {
  urt_emulator_t *e = arg;
  // just below the physics thread: the streams' jitter is the I/O thread's wake-up latency
  urt_thread_set_fifo(pthread_self(), e->cfg.rt_priority, "I/O thread");
  pthread_setname_np(pthread_self(), "urt-io");  // so that its CPU time can be told apart
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
      } else if (tag >= TAG_LISTEN0 && tag < TAG_LISTEN0 + URT__N_PORTS) {
        on_accept(e, (int)(tag - TAG_LISTEN0));
      } else {
        urt__client_t *c = ev[i].data.ptr;
        if (ev[i].events & (EPOLLOUT | EPOLLHUP | EPOLLERR)) {
          c->conn->write_blocked = false;  // room again: flush_all below writes what is queued
        }
        if (ev[i].events & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
          on_readable(e, c);  // may close the client
        }
      }
    }
    flush_all(e);
    resume_listeners(e);
    log_refusals(e, false);
    atomic_store_explicit(&e->out_bytes, e->out_budget.used, memory_order_relaxed);
    atomic_store_explicit(&e->out_refused, e->out_budget.refused, memory_order_relaxed);
  }
  log_refusals(e, true);
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
  if (urt_ctrl_log_init(&e->log) != 0) {
    free(e);
    return URT_ENOMEM;
  }
  e->loop = loop;
  e->m = urt_loop_model(loop);
  e->cfg = *cfg;
  snprintf(e->bind, sizeof e->bind, "%s", cfg->bind ? cfg->bind : "127.0.0.1");
  e->cfg.bind = e->bind;
  e->epoll_fd = e->tick_fd = e->msg_fd = -1;
  e->max_clients = cfg->max_clients > 0 ? cfg->max_clients : URT_EMULATOR_MAX_CLIENTS;
  e->out_budget.limit = cfg->out_budget > 0 ? cfg->out_budget : URT_EMULATOR_OUT_BUDGET;
  e->reserve_fd = urt_tcp_reserve_open();
  e->pstop_since = -1.0;
  e->last_safety_mode = -1;
  for (int k = 0; k < URT__N_PORTS; k++) {
    e->listen_fd[k] = -1;
  }
  pthread_mutex_init(&e->msg_lock, NULL);
  pthread_mutex_init(&e->reg_lock, NULL);
  urt__inputs_latch(e, 0);  // the bank as it starts holds from tick 1
  urt_primary_robot_info_from_model(&e->cfg.version, e->m, &e->info);
  e->state_every = (uint64_t)(0.1 / urt_loop_period(loop) + 0.5);  // 10 Hz
  urt_rtde_registry_init(&e->rtde_registry);

  // the dashboard's fixed configuration
  e->dash_ctx.version = e->cfg.version;
  snprintf(e->dash_ctx.serial_number, sizeof e->dash_ctx.serial_number, "%s",
           cfg->serial_number ? cfg->serial_number : "20235501783");
  snprintf(e->dash_ctx.robot_model, sizeof e->dash_ctx.robot_model, "%.15s", e->m->name);
  if (cfg->programs_dir) {
    snprintf(e->programs_dir, sizeof e->programs_dir, "%s", cfg->programs_dir);
    e->dash_ctx.programs_dir = e->programs_dir;
    e->cfg.programs_dir = e->programs_dir;
  }
  // what a real controller shows; URSim's is /ursim/programs (URCL's tests load from it)
  snprintf(e->programs_alias, sizeof e->programs_alias, "%s",
           cfg->programs_alias && cfg->programs_alias[0] == '/' ? cfg->programs_alias
                                                                 : "/programs");
  e->dash_ctx.programs_alias = e->programs_alias;
  e->dash_ctx.program_exts = ".urp,.script";
  e->dash_ctx.prepare_program = urt__program_prepare;  // `load` compiles a .urp
  e->dash_ctx.prepare_user = e;
  e->dash_ctx.write_log = urt__dashboard_write_log;
  e->dash_ctx.write_log_user = e;
  if (cfg->log_dir) {
    snprintf(e->log_dir, sizeof e->log_dir, "%s", cfg->log_dir);
    e->cfg.log_dir = e->log_dir;
  }
  pthread_mutex_init(&e->fetch_lock, NULL);
  snprintf(e->ec_host, sizeof e->ec_host, "%s",
           cfg->external_control_host ? cfg->external_control_host : "127.0.0.1");
  e->ec_port = cfg->external_control_port > 0 ? cfg->external_control_port : 50002;
  e->cfg.external_control_host = e->ec_host;
  e->cfg.external_control_port = e->ec_port;
  urt_dashboard_state_init(&e->dash);
  e->dash.remote_control = !cfg->local_control;
  e->dash.remote_control_off = cfg->remote_control_off && !cfg->local_control;

  if (!urt_urcap_host_is_loopback(e->ec_host) || e->ec_port > 65535) {
    snprintf(err, err_sz,
             "external control host %s:%d: only loopback addresses (127.0.0.0/8) are allowed",
             e->ec_host, e->ec_port);
    urt_emulator_destroy(e);
    return URT_EINVAL;
  }
  static const char *const kRingName[URT__N_RINGS] = {"primary", "rtde", "dashboard"};
  bool rings_ok = true;
  for (int r = 0; r < URT__N_RINGS; r++) {
    e->ring[r] = urt_loop_add_producer(loop, kRingName[r]);
    rings_ok = rings_ok && e->ring[r] >= 0;
  }
  e->runner_producer = urt_loop_add_producer(loop, "urscript");
  if (!rings_ok || e->runner_producer < 0) {
    snprintf(err, err_sz, "no free command ring for the TCP servers");
    urt_emulator_destroy(e);
    return URT_ENOSPC;
  }
  for (int k = 0; k < URT__N_PORTS; k++) {
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
  urt_loop_set_notify_fd(loop, e->tick_fd);
  struct epoll_event ev = {.events = EPOLLIN};
  ev.data.ptr = (void *)(uintptr_t)TAG_TICK;
  epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->tick_fd, &ev);
  ev.data.ptr = (void *)(uintptr_t)TAG_MSG;
  epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->msg_fd, &ev);
  for (int k = 0; k < URT__N_PORTS; k++) {
    ev.data.ptr = (void *)(uintptr_t)(TAG_LISTEN0 + k);
    epoll_ctl(e->epoll_fd, EPOLL_CTL_ADD, e->listen_fd[k], &ev);
  }
  urt_script_host_t host = urt__script_host(e);
  // the script thread shares the I/O thread's priority: both feed the physics thread's rings
  urt_runner_config_t rcfg = {.rt_priority = e->cfg.rt_priority,
                              .allow_hosts = e->cfg.script_allow_hosts,
                              .n_allow_hosts = e->cfg.n_script_allow_hosts,
                              .version = {e->cfg.version.major, e->cfg.version.minor,
                                          e->cfg.version.bugfix}};
  if (urt_runner_create(&host, &rcfg, &e->runner) != 0) {
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
  // the ports start after the newest tick, and a safety-mode change is news against its mode
  // (before tick 1: the controller's first, NORMAL); taken from the first tick streamed
  // instead, a protective stop in it went unreported (a program's protective_stop() sent at
  // once, with the I/O thread late to start)
  urt_snapshot_t s0;
  e->streamed_tick = urt_loop_read_latest(e->loop, &s0);
  e->last_safety_mode = e->streamed_tick > 0 ? s0.safety_mode : URT_SAFETY_MODE_NORMAL;
  if (urt_thread_start(&e->io_thread, io_main, e, THREAD_STACK) != 0) {
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
  pthread_join(e->io_thread, NULL);
  e->started = 0;
}

void urt_emulator_destroy(urt_emulator_t *e) {
  if (!e) {
    return;
  }
  urt_emulator_stop(e);
  urt_loop_set_notify_fd(e->loop, -1);  // returns once the loop is done with tick_fd
  urt__program_shutdown(e);  // its fetch thread submits to the runner: before the runner goes
  urt_runner_destroy(e->runner);
  while (e->clients) {
    close_client(e, e->clients);
  }
  for (int k = 0; k < URT__N_PORTS; k++) {
    if (e->listen_fd[k] >= 0) {
      close(e->listen_fd[k]);
    }
  }
  if (e->reserve_fd >= 0) close(e->reserve_fd);
  if (e->epoll_fd >= 0) close(e->epoll_fd);
  if (e->tick_fd >= 0) close(e->tick_fd);
  if (e->msg_fd >= 0) close(e->msg_fd);
  pthread_mutex_destroy(&e->msg_lock);
  pthread_mutex_destroy(&e->reg_lock);
  pthread_mutex_destroy(&e->fetch_lock);
  urt_ctrl_log_free(&e->log);
  free(e);
}

void urt_emulator_get_stats(const urt_emulator_t *e, urt_emulator_stats_t *out) {
  out->clients = atomic_load(&e->n_clients);
  out->rt_packets = atomic_load(&e->rt_packets);
  out->rt_dropped = atomic_load(&e->rt_dropped);
  out->state_messages = atomic_load(&e->state_messages);
  out->ticks_lost = atomic_load(&e->ticks_lost);
  out->scripts = atomic_load(&e->scripts);
  out->refused_cap = atomic_load(&e->refused_cap);
  out->refused_fds = atomic_load(&e->refused_fds);
  out->out_bytes = atomic_load(&e->out_bytes);
  out->out_refused = atomic_load(&e->out_refused);
  if (e->runner) {
    urt_runner_tick_stats(e->runner, &out->script_tick);
  } else {
    memset(&out->script_tick, 0, sizeof out->script_tick);
  }
}

int urt_emulator_shutdown_requested(const urt_emulator_t *e) {
  return atomic_load(&e->shutdown_requested);
}
