/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_socket.h — private: the TCP client sockets a URScript program opens by
 * name (socket_open … socket_close), with the host policy (loopback unless allowed).
 *
 * Nothing here blocks: connects are non-blocking and polled, receives drain what the kernel
 * holds into a fixed per-socket buffer, sends go out in one non-blocking write with
 * TCP_NODELAY (URCL acts only on a recv() of exactly the 4 bytes of one reply). The builtins
 * (script_builtins_socket.c) do the waiting, in controller ticks, through urt__us_wait_tick,
 * so a read blocks only the URScript thread that makes it. Memory is fixed when the table is
 * made: no allocation per call. The runner owns one table and closes every socket when a
 * program ends, before the next one starts (external_control.md §2.1, §6).
 */
#ifndef URT_NET_URSCRIPT_SCRIPT_SOCKET_H
#define URT_NET_URSCRIPT_SCRIPT_SOCKET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define US_SOCK_MAX 32          /* sockets open at once                                   */
#define US_SOCK_NAME 64         /* bytes of a socket name, NUL included                   */
#define US_SOCK_RX 8192         /* receive buffer per socket (a read takes at most 1024)  */
#define US_SOCK_TX 8192         /* the rest of a write the kernel took only in part        */
#define US_SOCK_MAX_ALLOW 16    /* --script-allow-host entries                             */
#define US_SOCK_HOST 256        /* bytes of one host name, NUL included                   */

typedef enum us_sock_state {
  US_SOCK_FREE = 0,
  US_SOCK_CONNECTING,
  US_SOCK_OPEN,
} us_sock_state;

typedef struct us_sock {
  int state;                /* us_sock_state */
  int fd;
  bool eof;                 /* the peer closed its side (or receiving failed): reads end */
  bool broken;              /* a send failed: sends end                                 */
  char name[US_SOCK_NAME];
  size_t rx_n;              /* bytes in rx */
  size_t tx_n;              /* bytes a partial write left, sent before anything newer */
  uint64_t rx_tick;         /* 1 + the controller tick of the last receive (0: none yet) */
  uint8_t rx[US_SOCK_RX];
  uint8_t tx[US_SOCK_TX];
} us_sock;

typedef struct us_sockets {
  us_sock s[US_SOCK_MAX];
  int n_allow;
  char allow[US_SOCK_MAX_ALLOW][US_SOCK_HOST];
  /* socket_opens that waited for a peer on this machine to accept (b_socket_open), and the
   * most ticks one waited: read by the runner's statistics (any thread, relaxed) */
  uint64_t accept_waits, accept_wait_max;
} us_sockets;

/* An empty table (heap: it is large) allowing loopback and the n named hosts (copied; a
 * host longer than US_SOCK_HOST-1 or more than US_SOCK_MAX_ALLOW of them: NULL). Nullable:
 * allow when n is 0. */
us_sockets *urt__us_sockets_new(const char *const *allow, int n);

/* Close every socket and free the table. Nullable: t. */
void urt__us_sockets_free(us_sockets *t);

/* Close every open socket (the end of a program). Nullable: t. */
void urt__us_sockets_close_all(us_sockets *t);

/* Shut down the sending side of every open socket, wait at most timeout_ms (wall time) for
 * each peer to close its end, then close them all: the peers have seen the disconnect. */
void urt__us_sockets_close_all_wait(us_sockets *t, int timeout_ms);

/* The socket named name (connecting or open), or NULL. */
us_sock *urt__us_sock_find(us_sockets *t, const char *name);

enum {
  US_SOCK_OK = 0,
  US_SOCK_ERR_HOST = -1,     /* host not allowed (text names it)                   */
  US_SOCK_ERR_RESOLVE = -2,  /* an allowed name that does not resolve              */
  US_SOCK_ERR_FULL = -3,     /* US_SOCK_MAX sockets open                            */
  US_SOCK_ERR_CONNECT = -4,  /* the connect failed at once (refused, unreachable)   */
  US_SOCK_ERR_ARG = -5,      /* name too long, port out of range                    */
};

/* Start a non-blocking connect of socket name to host:port (closing a socket of that name
 * first). Returns US_SOCK_OK with *out (connecting or already open), or an error with a
 * message in text. Loopback (127.0.0.0/8, ::1, "localhost") is always allowed; any other host
 * only when it is in the table's allow list, compared as written. */
int urt__us_sock_connect(us_sockets *t, const char *name, const char *host, int port,
                         us_sock **out, char *text, size_t n);

/* Advance a connecting socket: 1 open, 0 still connecting, -1 failed (the socket is freed). */
int urt__us_sock_poll_connect(us_sock *s);

/* How many connections the listener this open socket dialled holds that it has not accepted
 * yet (its accept queue, the rx_queue of its LISTEN line in /proc/self/net/tcp or tcp6), when
 * that listener is on this machine; -1 when it is not, or the kernel does not say. Reads a
 * /proc file (a system call, no wait): only at the end of a socket_open, once per tick while it
 * waits for the accept (at most 0.1 s, b_socket_open), on the runner thread, never the physics'. */
int urt__us_sock_peer_backlog(const us_sock *s);

/* Push out a queued rest of a write and, once per controller tick, move what the kernel holds
 * into s->rx (up to its capacity); sets s->eof when the peer closed. Reads within one tick see
 * what had arrived at the tick's first read, never bytes that came while the slice ran: a
 * program's reads depend on the ticks, not on how long the slice took, and a loop draining a
 * socket a client floods (URCL's tool_contact_example writes without pause) reads at most one
 * buffer per tick and then waits, instead of running without end in one tick. Never blocks. */
void urt__us_sock_fill(us_sock *s, uint64_t tick);

/* Drop the first n bytes of s->rx. */
void urt__us_sock_consume(us_sock *s, size_t n);

/* Send n bytes in one non-blocking write (after any rest of an earlier one): true when the
 * kernel took them, or took part and the rest is queued for the next fill or send; false when
 * the socket is not open or the data does not fit (nothing of it is sent then). */
bool urt__us_sock_send(us_sock *s, const void *buf, size_t n);

/* Close and free one socket. Nullable: s. */
void urt__us_sock_close(us_sock *s);

#endif
