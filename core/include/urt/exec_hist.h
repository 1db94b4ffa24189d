/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/exec_hist.h — a fixed-size histogram of durations, for the physics thread's
 * time per controller period. One writer (the physics thread: no allocation, no lock, a few
 * instructions per sample), any number of readers. Bins are log-linear: 16 per octave above
 * 1.024 µs (64 ns wide below), so a quantile is reported as the upper edge of its bin, at most
 * 1/16 above the true value; the maximum is exact.
 */
#ifndef URT_EXEC_HIST_H
#define URT_EXEC_HIST_H

#include <stdint.h>

#ifdef __cplusplus
#include <atomic>
typedef std::atomic<uint64_t> urt_exec_hist_word_t;
extern "C" {
#else
#include <stdatomic.h>
typedef _Atomic uint64_t urt_exec_hist_word_t;
#endif

#define URT_EXEC_HIST_SUB 16      /* bins per octave                          */
#define URT_EXEC_HIST_OCTAVES 25  /* 1.024 µs · 2^25 ≈ 34 s: longer ones share the last bin */
#define URT_EXEC_HIST_BINS (URT_EXEC_HIST_SUB * (1 + URT_EXEC_HIST_OCTAVES))

typedef struct urt_exec_hist {
  urt_exec_hist_word_t bin[URT_EXEC_HIST_BINS];
  urt_exec_hist_word_t count, max_ns;
} urt_exec_hist_t;

/* Count one duration [ns]. Single writer; the histogram must start zeroed. */
void urt_exec_hist_add(urt_exec_hist_t *h, uint64_t ns);

/* The q-quantile (0 < q <= 1) of what was counted [s]: the upper edge of the bin holding it,
 * never above the maximum; 0 when nothing was counted. Any thread. */
double urt_exec_hist_quantile(const urt_exec_hist_t *h, double q);

/* How many samples lie in the bin holding s [s] or above: every sample >= s, and none below
 * s·(1 − 1/16) (64 ns below 1.024 µs). Any thread. */
uint64_t urt_exec_hist_count_from(const urt_exec_hist_t *h, double s);
/* The largest duration counted [s] and the number of samples. Any thread. */
double urt_exec_hist_max(const urt_exec_hist_t *h);
uint64_t urt_exec_hist_count(const urt_exec_hist_t *h);

#ifdef __cplusplus
}
#endif
#endif
