/* SPDX-License-Identifier: Apache-2.0
 * core/spsc_ring.c — single-producer single-consumer ring. Contract in urt/spsc_ring.h. */
#include "urt/spsc_ring.h"

#include <string.h>

#include "urt/errors.h"

int urt_spsc_ring_init(urt_spsc_ring_t *r, void *storage, size_t capacity, size_t elem_size) {
  if (!storage || capacity == 0 || (capacity & (capacity - 1)) != 0 || elem_size == 0) {
    return URT_EINVAL;
  }
  atomic_init(&r->head, 0);
  atomic_init(&r->tail, 0);
  atomic_init(&r->dropped, 0);
  r->elem_size = elem_size;
  r->capacity = capacity;
  r->slots = storage;
  return URT_OK;
}

bool urt_spsc_ring_try_push(urt_spsc_ring_t *r, const void *msg) {
  // only the producer writes head, so a relaxed load of our own index is exact; the acquire
  // on tail pairs with the consumer's release, so the slot we reuse has been read
  uint64_t head = atomic_load_explicit(&r->head, memory_order_relaxed);
  uint64_t tail = atomic_load_explicit(&r->tail, memory_order_acquire);
  if (head - tail >= r->capacity) {
    // one writer, so load + store is exact; atomic so that a reader on another thread (the
    // loop's statistics) reads a whole value, not a torn or racing one
    atomic_store_explicit(&r->dropped, atomic_load_explicit(&r->dropped, memory_order_relaxed) + 1,
                          memory_order_relaxed);
    return false;
  }
  memcpy(r->slots + (head & (r->capacity - 1)) * r->elem_size, msg, r->elem_size);

  // release: the message bytes are visible before the new head
  atomic_store_explicit(&r->head, head + 1, memory_order_release);
  return true;
}

bool urt_spsc_ring_try_pop(urt_spsc_ring_t *r, void *msg) {
  uint64_t tail = atomic_load_explicit(&r->tail, memory_order_relaxed);
  uint64_t head = atomic_load_explicit(&r->head, memory_order_acquire);
  if (tail == head) {
    return false;
  }
  memcpy(msg, r->slots + (tail & (r->capacity - 1)) * r->elem_size, r->elem_size);

  // release: we are done with the slot before the producer may reuse it
  atomic_store_explicit(&r->tail, tail + 1, memory_order_release);
  return true;
}

size_t urt_spsc_ring_size(const urt_spsc_ring_t *r) {
  uint64_t head = atomic_load_explicit(&r->head, memory_order_acquire);
  uint64_t tail = atomic_load_explicit(&r->tail, memory_order_acquire);
  return (size_t)(head - tail);
}
