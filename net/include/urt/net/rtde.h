/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/rtde.h — the RTDE protocol (port 30004) as a pure, socket-free codec:
 * the variable tables, one state machine per connection, and the registry that decides which
 * connection owns which input (protocols.md §2, clients.md §1).
 *
 *   client bytes ──urt_rtde_session_feed()──▶ replies (urt_rtde_session_output)
 *                                         └──▶ decoded inputs (urt_rtde_session_take_inputs)
 *   every controller tick: urt_rtde_session_encode_data(session, snapshot, registers) ──▶ U
 *
 * Nothing here touches a socket, a clock, a global or the heap: the caller owns every struct
 * (a session is ~45 kB; allocate it once per connection). Context: the I/O thread only; nothing
 * is thread-safe.
 */
#ifndef URT_NET_RTDE_H
#define URT_NET_RTDE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "urt/net/version.h"
#include "urt/snapshot.h"

#ifdef __cplusplus
extern "C" {
#endif

//---- wire constants ----

/* Package types (protocols.md §2.1). */
enum {
  URT_RTDE_REQUEST_PROTOCOL_VERSION = 'V',  /* 86  */
  URT_RTDE_GET_URCONTROL_VERSION = 'v',     /* 118 */
  URT_RTDE_TEXT_MESSAGE = 'M',              /* 77  */
  URT_RTDE_DATA_PACKAGE = 'U',              /* 85  */
  URT_RTDE_SETUP_OUTPUTS = 'O',             /* 79  */
  URT_RTDE_SETUP_INPUTS = 'I',              /* 73  */
  URT_RTDE_START = 'S',                     /* 83  */
  URT_RTDE_PAUSE = 'P'                      /* 80  */
};

/* RTDE data types (protocols.md §2.3). */
typedef enum urt_rtde_type {
  URT_RTDE_BOOL = 0,
  URT_RTDE_UINT8,
  URT_RTDE_UINT32,
  URT_RTDE_UINT64,
  URT_RTDE_INT32,
  URT_RTDE_DOUBLE,
  URT_RTDE_VECTOR3D,
  URT_RTDE_VECTOR6D,
  URT_RTDE_VECTOR6INT32,
  URT_RTDE_VECTOR6UINT32,
  URT_RTDE_NTYPES
} urt_rtde_type_t;

#define URT_RTDE_MAX_PACKAGE 8192        /* largest client package accepted [bytes]       */
#define URT_RTDE_REPLY_CAP 16384         /* pending reply bytes a session can hold         */
#define URT_RTDE_MAX_FIELDS 512          /* fields in one recipe                            */
#define URT_RTDE_MAX_INPUT_RECIPES 64    /* input recipes per connection (ids 1..64)        */
#define URT_RTDE_INPUT_POOL 4096         /* fields over all input recipes of a connection   */
#define URT_RTDE_NREG 48                 /* int and double registers per direction          */
#define URT_RTDE_NBITREG 128             /* bit registers per direction                     */
#define URT_RTDE_MAX_DATA (4 + URT_RTDE_MAX_FIELDS * 48)  /* largest data package [bytes]   */

/* Token of a type as UR writes it ("DOUBLE", "VECTOR6D", …); its size on the wire [bytes]. */
const char *urt_rtde_type_name(urt_rtde_type_t t);
size_t urt_rtde_type_size(urt_rtde_type_t t);

//---- variable tables ----

/* Pack a controller version for comparisons: 5.5.1 → 50501. */
#define URT_RTDE_VER(maj, min, bug) ((maj) * 10000 + (min) * 100 + (bug))
#define URT_RTDE_NEVER 0x7fffffff

/* One resolved recipe field: what to copy and its wire type. */
typedef struct urt_rtde_field {
  uint16_t var;   /* output: urt__rtde output kind; input: input variable id  */
  uint8_t index;  /* register number for the register families, else 0        */
  uint8_t type;   /* urt_rtde_type_t                                          */
} urt_rtde_field_t;

/* Resolve an output name for the emulated version. Returns 0 and fills *f, or URT_EINVAL when
 * UR's controller of that version would answer NOT_FOUND, or when urtwin has no model for the
 * output (urt_rtde_output_unmodelled): refused rather than sent as a stand-in zero.
 * Context: any (setup only; linear). */
int urt_rtde_output_lookup(const char *name, size_t len, const urt_version_t *v,
                           urt_rtde_field_t *f);

/* 1 when UR documents the output but urtwin has no model for it (net/rtde/README.md). */
int urt_rtde_output_unmodelled(const char *name, size_t len);

/* Resolve an input name likewise (f->var is the input variable id < urt_rtde_input_count()). */
int urt_rtde_input_lookup(const char *name, size_t len, const urt_version_t *v,
                          urt_rtde_field_t *f);
int urt_rtde_input_count(void);

/* Iterate the tables (documentation, tests): the i-th fixed (non-register) name, or NULL past
 * the end; *type, *since_cb3 and *since_e receive its type and first versions (URT_RTDE_NEVER if
 * the line never had it). Nullable: type, since_cb3, since_e. */
const char *urt_rtde_output_name(int i, urt_rtde_type_t *type, int *since_cb3, int *since_e);
const char *urt_rtde_input_name(int i, urt_rtde_type_t *type, int *since_cb3, int *since_e);

//---- registers and inputs ----

/* The general-purpose registers, both directions. Outputs (output_*_register_*) are written by
 * URScript; inputs (input_*_register_*) by RTDE clients and read back as outputs. */
typedef struct urt_rtde_registers {
  int32_t in_int[URT_RTDE_NREG], out_int[URT_RTDE_NREG];
  double in_double[URT_RTDE_NREG], out_double[URT_RTDE_NREG];
  uint8_t in_bit[URT_RTDE_NBITREG], out_bit[URT_RTDE_NBITREG];  /* 0 or 1 */
  /* how many client data packages wrote each input int/double register (a watchdog sees a
   * register refreshed even when the value is the same) */
  uint32_t in_int_writes[URT_RTDE_NREG], in_double_writes[URT_RTDE_NREG];
} urt_rtde_registers_t;

/* What clients asked the controller to change since the last take: effects, already folded
 * through the masks (apply as x = (x & ~mask) | (value & mask)). */
enum {
  URT_RTDE_IN_SPEED_SLIDER = 1u << 0,   /* speed_slider_fraction is new                      */
  URT_RTDE_IN_EXT_FT = 1u << 1,         /* external_force_torque is new                      */
};
typedef struct urt_rtde_inputs {
  uint32_t set;                          /* URT_RTDE_IN_* flags                             */
  double speed_slider_fraction;          /* 0..1                                            */
  double external_force_torque[6];       /* [N, N m]                                        */
  uint8_t std_do_mask, std_do;           /* standard digital outputs 0–7                    */
  uint8_t conf_do_mask, conf_do;         /* configurable digital outputs 0–7                */
  uint8_t tool_do_mask, tool_do;         /* tool digital outputs 0–1                        */
  uint8_t ao_mask;                       /* bit i: standard analog output i changed         */
  uint8_t ao_type;                       /* bit i: domain of output i, 0 current, 1 voltage */
  double ao[2];                          /* ratio 0..1 of full scale                        */
  uint64_t int_set, double_set;          /* bit i: input_{int,double}_register_i written    */
  uint64_t bit_set[2], bit_val[2];       /* bit i of 128: input bit register i written/value*/
  int32_t int_reg[URT_RTDE_NREG];
  double double_reg[URT_RTDE_NREG];
} urt_rtde_inputs_t;

/* Fold src (newer) into dst (older), as if both had been applied in order. */
void urt_rtde_inputs_merge(urt_rtde_inputs_t *dst, const urt_rtde_inputs_t *src);

/* Copy the register part of the inputs into the bank's in_* arrays; count every int register
 * write in in_int_writes. */
void urt_rtde_inputs_apply_registers(const urt_rtde_inputs_t *in, urt_rtde_registers_t *r);

//---- registry: which connection owns which input ----

/* Shared by all sessions of one server. "Only one RTDE client is allowed to control a specific
 * variable at any time": an input claimed by one session answers IN_USE to every other until
 * the owner closes. Caller-owned; zero it with urt_rtde_registry_init. */
typedef struct urt_rtde_registry {
  uint32_t owner[512];        /* input variable id → session id (0 = free)   */
  uint32_t next_id;           /* last session id handed out                  */
  int nsessions;              /* sessions attached                           */
} urt_rtde_registry_t;

void urt_rtde_registry_init(urt_rtde_registry_t *g);

//---- session: one connection ----

typedef struct urt_rtde_recipe {
  uint16_t first, count;      /* fields in the session's pool                 */
  uint16_t size;              /* data bytes after the recipe id               */
} urt_rtde_recipe_t;

typedef struct urt_rtde_stats {
  uint64_t packages;          /* complete client packages handled             */
  uint64_t unknown_type;      /* packages of an unknown type (skipped)        */
  uint64_t bad_input;         /* U packages with an unknown id or a wrong size */
  uint64_t inputs;            /* U packages applied                           */
  uint64_t data_sent;         /* data packages encoded                        */
  uint64_t text_messages;     /* M packages from the client                   */
} urt_rtde_stats_t;

typedef struct urt_rtde_session {
  urt_rtde_registry_t *registry;
  urt_version_t version;
  uint32_t id;                /* this session's owner id in the registry      */
  uint8_t protocol;           /* 1 until a V request for 2 is accepted        */
  bool started;               /* between an accepted S and a P                */
  bool closed;                /* unrecoverable protocol error: close the socket */
  int error;                  /* URT_E* code of that error                   */

  /* output recipe (one per connection) */
  bool out_valid;             /* a recipe without NOT_FOUND and a legal frequency */
  bool out_configured;        /* an O request was answered (valid or not)     */
  uint16_t out_count, out_size;
  uint32_t decimation;        /* controller ticks between data packages        */
  bool out_sent_any;          /* a data package was sent since S               */
  uint64_t next_tick;         /* first tick the next data package may use      */
  urt_rtde_field_t out[URT_RTDE_MAX_FIELDS];

  /* input recipes, ids 1..n_in */
  int n_in;
  uint16_t pool_used;
  urt_rtde_recipe_t in[URT_RTDE_MAX_INPUT_RECIPES];
  urt_rtde_field_t pool[URT_RTDE_INPUT_POOL];

  /* inputs: last received value of every variable (they persist) and pending effects */
  urt_rtde_inputs_t retained;
  uint32_t retained_slider_mask;
  uint8_t retained_std_do_mask, retained_conf_do_mask, retained_tool_do_mask, retained_ao_mask;
  urt_rtde_inputs_t pending;
  bool have_pending;

  /* byte buffers */
  size_t in_len;              /* bytes in inbuf, a partial package at most after handling */
  uint8_t inbuf[URT_RTDE_MAX_PACKAGE];
  size_t out_head, out_len;
  uint8_t outbuf[URT_RTDE_REPLY_CAP];

  urt_rtde_stats_t stats;
} urt_rtde_session_t;

/* Attach a fresh session to a registry, emulating controller version *v (its `v` reply and the
 * variables it knows; controller rate 500 Hz for 5.x, 125 Hz for 3.x). Protocol starts at 1. */
void urt_rtde_session_init(urt_rtde_session_t *s, urt_rtde_registry_t *g,
                           const urt_version_t *v);

/* Detach: release every input this session owns. Call when the connection closes. */
void urt_rtde_session_fini(urt_rtde_session_t *s);

/* Feed bytes received from the client, in any chunking. Handles every complete package and
 * queues its reply. Consumes fewer than n bytes only when the reply queue is too full to take
 * another reply (drain it with urt_rtde_session_output/_consume and feed the rest again).
 * Returns the bytes consumed, or URT_EPROTO once the stream is unrecoverable (package size < 3
 * or > URT_RTDE_MAX_PACKAGE); the session is then closed (urt_rtde_session_closed). */
long urt_rtde_session_feed(urt_rtde_session_t *s, const uint8_t *in, size_t n);

/* Zero-copy alternative to feed: where the caller may recv() into, and how much. */
uint8_t *urt_rtde_session_recv_buf(urt_rtde_session_t *s, size_t *space);
/* Account n bytes written into the recv buffer and handle them (as feed). Returns 0 or
 * URT_EPROTO. */
int urt_rtde_session_commit(urt_rtde_session_t *s, size_t n);

/* Pending reply bytes (to be sent before anything else). Returns their count; *p points at them. */
size_t urt_rtde_session_output(const urt_rtde_session_t *s, const uint8_t **p);
/* Drop the first n pending reply bytes (they were sent), then handle any packages that were
 * waiting for room in the reply queue. */
void urt_rtde_session_consume(urt_rtde_session_t *s, size_t n);

/* Take the input effects decoded since the last call. Returns true if there were any. */
bool urt_rtde_session_take_inputs(urt_rtde_session_t *s, urt_rtde_inputs_t *out);

/* Encode this tick's data package if one is due: the session is started, its output recipe is
 * valid, no reply is pending (the S reply always goes first) and snap->tick has reached the
 * recipe's next tick (per-recipe decimation floor(controller rate / frequency)). v2 packages
 * carry the recipe id, v1 packages do not.
 * Returns the bytes written (0 if none due) or URT_ENOSPC (state unchanged). Context: I/O thread,
 * no allocation. */
int urt_rtde_session_encode_data(urt_rtde_session_t *s, const urt_snapshot_t *snap,
                                 const urt_rtde_registers_t *r, uint8_t *out, size_t cap);

/* True once the connection must be closed (unrecoverable protocol error). */
bool urt_rtde_session_closed(const urt_rtde_session_t *s);

/* Encode one data package for a list of output fields, without a session (tests, tools).
 * recipe_id < 0 omits the id byte (protocol 1). Returns bytes written or URT_ENOSPC. */
int urt_rtde_encode_fields(const urt_rtde_field_t *f, int n, int recipe_id,
                           const urt_snapshot_t *snap, const urt_rtde_registers_t *r,
                           uint8_t *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
