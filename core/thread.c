/* SPDX-License-Identifier: Apache-2.0
 * core/thread.c — threads with a stated stack size, and their SCHED_FIFO priority (thread.h). */
#include "urt/thread.h"

#include <limits.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>

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

int urt_thread_set_fifo(pthread_t t, int priority, const char *what) {
  if (priority <= 0) {
    return 0;
  }
  struct sched_param sp = {.sched_priority = priority};
  int rc = pthread_setschedparam(t, SCHED_FIFO, &sp);
  if (rc != 0) {
    fprintf(stderr, "urtwin: warning: SCHED_FIFO priority %d for the %s refused (%s); running as "
            "SCHED_OTHER\n", priority, what, strerror(rc));
  }
  return rc;
}
