/* SPDX-License-Identifier: Apache-2.0
 * core/thread.c — threads with a stated stack size (thread.h). */
#include "urt/thread.h"

#include <limits.h>

int urt_thread_start(pthread_t *t, void *(*fn)(void *), void *arg, size_t stack_bytes) {
  pthread_attr_t attr;
  int rc = pthread_attr_init(&attr);
  if (rc != 0) {
    return rc;
  }
  if (stack_bytes < PTHREAD_STACK_MIN) {
    stack_bytes = PTHREAD_STACK_MIN;
  }
  rc = pthread_attr_setstacksize(&attr, stack_bytes);
  if (rc == 0) {
    rc = pthread_create(t, &attr, fn, arg);
  }
  pthread_attr_destroy(&attr);
  return rc;
}
