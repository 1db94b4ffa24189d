/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/tcp.h — non-blocking TCP plumbing for the I/O thread: listeners bound to
 * one address, and connections with a bounded output buffer. A client that does not read never
 * slows anyone: when its buffer is full, whole messages are dropped for it (and counted),
 * never waited for. Context: the I/O thread only (nothing here is thread-safe).
 */
#ifndef URT_NET_TCP_H
#define URT_NET_TCP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Open a non-blocking listening socket on addr:port (SO_REUSEADDR, backlog 64).
 * Returns the fd or a negative URT_E* code; err receives "bind 127.0.0.1:30003: …". */
int urt_tcp_listen(const char *addr, int port, char *err, size_t err_sz);

/* Output memory shared by every connection of one server: buffers grow on demand, and a growth
 * that would take `used` beyond `limit` is refused (the message is dropped for that client,
 * as when its own cap is reached), so that clients that never read cannot run the process out
 * of memory together. */
typedef struct urt_tcp_budget {
  size_t used, limit;       /* bytes of output buffers allocated / allowed         */
  uint64_t refused;         /* growths refused for the budget                      */
} urt_tcp_budget_t;

typedef struct urt_tcp_conn {
  int fd;
  int port_kind;            /* which server accepted it (caller's enum)            */
  uint8_t *out;             /* pending output bytes [out_head, out_len)            */
  size_t out_head, out_len, out_cap;
  size_t out_max;           /* out_cap grows on demand up to this                   */
  urt_tcp_budget_t *budget; /* Nullable: no shared budget                            */
  uint64_t sent_msgs, dropped_msgs;  /* messages queued / refused for lack of room  */
  uint64_t bytes_in;
  void *user;               /* per-protocol state (framer, parser, …)              */
  bool want_write;          /* EPOLLOUT is armed                                  */
  bool write_blocked;       /* the last write met a full socket: wait for EPOLLOUT  */
  bool closing;             /* flush what is queued, then close                    */
  int64_t last_progress_ns; /* CLOCK_MONOTONIC when output last drained or moved    */
} urt_tcp_conn_t;

/* A spare descriptor (/dev/null) held so that a full descriptor table can still drain a
 * listener: returns it or -1. */
int urt_tcp_reserve_open(void);

/* What urt_tcp_accept_fd found. */
enum {
  URT_TCP_NONE = -1,      /* nothing pending                                              */
  URT_TCP_NO_FDS = -2,    /* EMFILE/ENFILE: the connection was taken with the reserve
                             descriptor and closed at once (the listener would otherwise stay
                             readable and the caller spin); the reserve is re-opened          */
  URT_TCP_NO_FDS_STUCK = -3, /* EMFILE/ENFILE and no reserve to drain with: pause the listener */
  URT_TCP_FAILED = -4     /* another error on one connection (ECONNABORTED, …): try the next */
};

/* Accept one pending connection (non-blocking, close-on-exec, TCP_NODELAY). Returns its fd or
 * one of the URT_TCP_* codes above. Nullable: reserve_fd (then no reserve trick). */
int urt_tcp_accept_fd(int listen_fd, int *reserve_fd);

/* Wrap an accepted fd with an output buffer that starts small and grows to out_max bytes
 * within budget. Returns NULL (fd untouched) when out of memory. Nullable: budget. */
urt_tcp_conn_t *urt_tcp_conn_new(int fd, int port_kind, size_t out_max, urt_tcp_budget_t *budget);

/* Queue one whole message, growing the buffer (doubling, up to out_max and within the budget)
 * when needed. If it still does not fit it is dropped (counted) and
 * false is returned: messages are never cut, so the stream stays framed. urt_tcp_flush writes. */
bool urt_tcp_send(urt_tcp_conn_t *c, const void *msg, size_t len);

/* Write as much queued output as the socket takes. Returns false when the peer is gone. */
bool urt_tcp_flush(urt_tcp_conn_t *c);

/* Bytes still queued. */
size_t urt_tcp_pending(const urt_tcp_conn_t *c);

/* Seconds the connection has had output queued without the peer taking any of it. */
double urt_tcp_stalled_for(const urt_tcp_conn_t *c);

/* Shrink the kernel's send buffer (so that a peer that stops reading shows as stalled soon). */
void urt_tcp_set_sndbuf(urt_tcp_conn_t *c, int bytes);

/* Close the socket and free the connection (user state is the caller's to free first). */
void urt_tcp_close(urt_tcp_conn_t *c);

#ifdef __cplusplus
}
#endif
#endif
