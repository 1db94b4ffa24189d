/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/thread.h — start a thread with a stack of a stated size, and raise it to
 * SCHED_FIFO. With --lock-memory
 * (mlockall MCL_FUTURE) every page of every thread stack becomes resident, so threads ask for
 * what they need instead of glibc's 8 MiB default. */
#ifndef URT_THREAD_H
#define URT_THREAD_H

#include <pthread.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* pthread_create with a stack of stack_bytes (rounded up to the minimum). Context: non-RT.
 * Returns 0 or the positive error number of pthread_create. */
int urt_thread_start(pthread_t *t, void *(*fn)(void *), void *arg, size_t stack_bytes);

/* Best effort: run thread t under SCHED_FIFO at priority (> 0; 0 does nothing). A refusal (no
 * CAP_SYS_NICE) prints one warning naming the thread (what) and leaves it as it was: the
 * emulator must also run unprivileged. Context: non-RT. Returns 0 or the error number. */
int urt_thread_set_fifo(pthread_t t, int priority, const char *what);

/* Join thread t, waiting at most timeout_s seconds: a thread stuck in a library call (LCM,
 * Cyclone) must not hang the emulator's shutdown. On timeout it prints one line naming the
 * thread (who: "urt_lcm: publisher"), detaches it and returns -1: the caller must then keep
 * what the thread uses alive. Context: non-RT. Returns 0 once joined. */
int urt_thread_join_bounded(pthread_t t, int timeout_s, const char *who);

#ifdef __cplusplus
}
#endif
#endif
