/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/spsc_ring.h — a fixed-capacity single-producer single-consumer ring of
 * fixed-size POD messages (style.md §13: clients → physics). The producer never waits: a push
 * into a full ring fails and is counted. The consumer drains at its own pace. Storage is
 * caller-owned, so nothing allocates after init.
 */
#ifndef URT_SPSC_RING_H
#define URT_SPSC_RING_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct urt_spsc_ring {
  _Alignas(64) _Atomic uint64_t head;  /* next slot to write (producer) */
  _Alignas(64) _Atomic uint64_t tail;  /* next slot to read (consumer)  */
  _Alignas(64) _Atomic uint64_t dropped; /* pushes refused because full (written by the
                                          producer only, read by anyone: relaxed) */
  size_t elem_size;                    /* bytes per message */
  size_t capacity;                     /* messages, a power of two */
  unsigned char *slots;                /* capacity · elem_size bytes, caller-owned */
} urt_spsc_ring_t;

/* Use storage (capacity · elem_size bytes, capacity a power of two) as an empty ring.
 * Context: init. Returns 0 or URT_EINVAL. */
int urt_spsc_ring_init(urt_spsc_ring_t *r, void *storage, size_t capacity, size_t elem_size);

/* Copy one message in. Returns false (and counts it in r->dropped) when the ring is full.
 * Context: the single producer thread. */
bool urt_spsc_ring_try_push(urt_spsc_ring_t *r, const void *msg);

/* Copy the oldest message out. Returns false when the ring is empty.
 * Context: the single consumer thread (the RT thread). */
bool urt_spsc_ring_try_pop(urt_spsc_ring_t *r, void *msg);

/* Messages waiting (a snapshot; exact only from the producer or the consumer). Context: any. */
size_t urt_spsc_ring_size(const urt_spsc_ring_t *r);

#ifdef __cplusplus
}
#endif
#endif
