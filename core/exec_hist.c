/* SPDX-License-Identifier: Apache-2.0
 * core/exec_hist.c — the duration histogram (exec_hist.h). The writer uses relaxed loads and
 * stores rather than read-modify-write instructions: it is the only writer, and a reader that
 * sees a sample in one word and not yet in another is at most one sample off.
 */
#include "urt/exec_hist.h"

#include <math.h>

static int bin_of(uint64_t ns) {
  if (ns < 1024) {
    return (int)(ns >> 6);  // 16 linear bins of 64 ns
  }
  int octave = 63 - __builtin_clzll(ns) - 10;  // 0 for [1024, 2048) ns
  if (octave >= URT_EXEC_HIST_OCTAVES) {
    return URT_EXEC_HIST_BINS - 1;
  }
  int sub = (int)(ns >> (octave + 6)) - URT_EXEC_HIST_SUB;  // 0..15 within the octave
  return URT_EXEC_HIST_SUB * (1 + octave) + sub;
}

static double upper_edge_ns(int b) {
  if (b < URT_EXEC_HIST_SUB) {
    return (double)((uint64_t)(b + 1) << 6);
  }
  int octave = b / URT_EXEC_HIST_SUB - 1, sub = b % URT_EXEC_HIST_SUB;
  return ldexp((double)(URT_EXEC_HIST_SUB + sub + 1), octave + 6);
}

static void bump(urt_exec_hist_word_t *w, uint64_t by) {
  atomic_store_explicit(w, atomic_load_explicit(w, memory_order_relaxed) + by,
                        memory_order_relaxed);
}

void urt_exec_hist_add(urt_exec_hist_t *h, uint64_t ns) {
  bump(&h->bin[bin_of(ns)], 1);
  bump(&h->count, 1);
  if (ns > atomic_load_explicit(&h->max_ns, memory_order_relaxed)) {
    atomic_store_explicit(&h->max_ns, ns, memory_order_relaxed);
  }
}

double urt_exec_hist_max(const urt_exec_hist_t *h) {
  return (double)atomic_load_explicit(&h->max_ns, memory_order_relaxed) * 1e-9;
}

uint64_t urt_exec_hist_count(const urt_exec_hist_t *h) {
  return atomic_load_explicit(&h->count, memory_order_relaxed);
}

uint64_t urt_exec_hist_count_from(const urt_exec_hist_t *h, double s) {
  uint64_t n = 0;
  double ns = s * 1e9;
  int from = ns <= 0.0 ? 0 : ns >= 18446744073709549568.0 ? URT_EXEC_HIST_BINS - 1
                                                          : bin_of((uint64_t)ns);
  for (int b = from; b < URT_EXEC_HIST_BINS; b++) {
    n += atomic_load_explicit(&h->bin[b], memory_order_relaxed);
  }
  return n;
}

double urt_exec_hist_quantile(const urt_exec_hist_t *h, double q) {
  uint64_t bins[URT_EXEC_HIST_BINS], total = 0;
  for (int b = 0; b < URT_EXEC_HIST_BINS; b++) {
    bins[b] = atomic_load_explicit(&h->bin[b], memory_order_relaxed);
    total += bins[b];
  }
  if (total == 0) {
    return 0.0;
  }
  double max_ns = (double)atomic_load_explicit(&h->max_ns, memory_order_relaxed);
  uint64_t rank = (uint64_t)ceil(q * (double)total);
  rank = rank < 1 ? 1 : rank > total ? total : rank;
  uint64_t seen = 0;
  for (int b = 0; b < URT_EXEC_HIST_BINS; b++) {
    seen += bins[b];
    if (seen >= rank) {
      double edge = upper_edge_ns(b);
      return (edge < max_ns ? edge : max_ns) * 1e-9;
    }
  }
  return max_ns * 1e-9;
}
