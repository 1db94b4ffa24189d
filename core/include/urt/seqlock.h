/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/seqlock.h — one writer publishes a fixed-size POD payload; any number of
 * readers copy it out without ever blocking the writer (style.md §13: physics → telemetry).
 *
 * The writer makes the sequence odd, stores the payload as relaxed atomic words, then makes it
 * even again; a reader retries while the sequence is odd or changed during its copy. The payload
 * is copied as 64-bit atomic words, so the protocol is race-free in the C11 memory model (no
 * formally racy memcpy). It must not contain pointers: readers get a copy, not a reference.
 */
#ifndef URT_SEQLOCK_H
#define URT_SEQLOCK_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define URT_SEQLOCK_MAX_BYTES 4096 /* largest payload [bytes] */

typedef struct urt_seqlock {
  _Alignas(64) _Atomic uint64_t seq;  /* even: stable; odd: a write is under way */
  size_t size;                        /* payload size [bytes] */
  size_t n_words;                     /* payload size in 64-bit words, rounded up */
  _Alignas(64) _Atomic uint64_t words[URT_SEQLOCK_MAX_BYTES / 8];
} urt_seqlock_t;

/* Prepare for a payload of size bytes (rounded up to 8), zero-filled. Context: init.
 * Returns 0 or URT_EINVAL when size is 0 or above URT_SEQLOCK_MAX_BYTES. */
int urt_seqlock_init(urt_seqlock_t *s, size_t size);

/* Publish size bytes from src (the size given to init). Never blocks, never fails.
 * Context: the single writer (the RT thread). */
void urt_seqlock_write(urt_seqlock_t *s, const void *src);

/* Copy the latest complete payload into dst. Retries while a write overlaps the copy, at most
 * max_tries times (0: until it succeeds). Context: any reader thread.
 * Returns the even sequence number of the copy (> 0 once something was written, 0 for the
 * initial zero payload), or URT_EAGAIN if every try overlapped a write (dst then holds a torn
 * copy: do not use it). */
int64_t urt_seqlock_read(const urt_seqlock_t *s, void *dst, unsigned max_tries);

#ifdef __cplusplus
}
#endif
#endif
