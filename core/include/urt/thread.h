/* SPDX-License-Identifier: Apache-2.0
 * core/include/urt/thread.h — start a thread with a stack of a stated size. With --lock-memory
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

#ifdef __cplusplus
}
#endif
#endif
