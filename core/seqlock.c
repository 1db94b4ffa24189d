/* SPDX-License-Identifier: Apache-2.0
 * core/seqlock.c — single-writer sequence lock over a fixed POD payload. Contract in
 * urt/seqlock.h. */
#include "urt/seqlock.h"

#include <string.h>

#include "urt/errors.h"

int urt_seqlock_init(urt_seqlock_t *s, size_t size) {
  if (size == 0 || size > URT_SEQLOCK_MAX_BYTES) {
    return URT_EINVAL;
  }
  atomic_init(&s->seq, 0);
  s->size = size;
  s->n_words = (size + 7) / 8;
  for (size_t i = 0; i < URT_SEQLOCK_MAX_BYTES / 8; i++) {
    atomic_init(&s->words[i], 0);
  }
  return URT_OK;
}

void urt_seqlock_write(urt_seqlock_t *s, const void *src) {
  const unsigned char *p = src;
  uint64_t seq = atomic_load_explicit(&s->seq, memory_order_relaxed);

  // odd: readers that start now, or are copying, will retry. The release fence keeps the
  // payload stores below from moving above the odd store.
  atomic_store_explicit(&s->seq, seq + 1, memory_order_relaxed);
  atomic_thread_fence(memory_order_release);
  for (size_t i = 0; i < s->n_words; i++) {
    uint64_t w = 0;
    // the tail of a payload that is not a whole number of words is padded with zeros
    size_t left = s->size - 8 * i;
    memcpy(&w, p + 8 * i, left >= 8 ? 8 : left);
    atomic_store_explicit(&s->words[i], w, memory_order_relaxed);
  }

  // even again: publishes the payload
  atomic_store_explicit(&s->seq, seq + 2, memory_order_release);
}

int64_t urt_seqlock_read(const urt_seqlock_t *s, void *dst, unsigned max_tries) {
  unsigned char *p = dst;
  for (unsigned tries = 0; max_tries == 0 || tries < max_tries; tries++) {
    uint64_t before = atomic_load_explicit(&s->seq, memory_order_acquire);
    if (before & 1) {
      continue;  // a write is under way
    }
    for (size_t i = 0; i < s->n_words; i++) {
      uint64_t w = atomic_load_explicit(&s->words[i], memory_order_relaxed);
      size_t left = s->size - 8 * i;
      memcpy(p + 8 * i, &w, left >= 8 ? 8 : left);
    }

    // the acquire fence keeps the payload loads above from moving below the second read
    atomic_thread_fence(memory_order_acquire);
    uint64_t after = atomic_load_explicit(&s->seq, memory_order_relaxed);
    if (before == after) {
      return (int64_t)(before / 2);
    }
  }
  return URT_EAGAIN;
}
