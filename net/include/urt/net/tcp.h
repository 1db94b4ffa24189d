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

typedef struct urt_tcp_conn {
  int fd;
  int port_kind;            /* which server accepted it (caller's enum)            */
  uint8_t *out;             /* pending output bytes [out_head, out_len)            */
  size_t out_head, out_len, out_cap;
  uint64_t sent_msgs, dropped_msgs;  /* messages queued / refused for lack of room  */
  uint64_t bytes_in;
  void *user;               /* per-protocol state (framer, parser, …)              */
  bool want_write;          /* EPOLLOUT is armed                                  */
  bool closing;             /* flush what is queued, then close                    */
  int64_t last_progress_ns; /* CLOCK_MONOTONIC when output last drained or moved    */
} urt_tcp_conn_t;

/* Accept one connection (non-blocking, TCP_NODELAY) with an output buffer of out_cap bytes.
 * Returns NULL when nothing is pending or on error. */
urt_tcp_conn_t *urt_tcp_accept(int listen_fd, int port_kind, size_t out_cap);

/* Queue one whole message. If it does not fit in the free space it is dropped (counted) and
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
