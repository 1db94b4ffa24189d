/* SPDX-License-Identifier: Apache-2.0
 * core/thread.c — threads with a stated stack size, and their SCHED_FIFO priority (thread.h). */
#define _GNU_SOURCE /* pthread_timedjoin_np */
#include "urt/thread.h"

#include <limits.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

int urt_thread_start(pthread_t *t, void *(*fn)(void *), void *arg, size_t stack_bytes) {
  pthread_attr_t attr;
  int rc = pthread_attr_init(&attr);
  if (rc != 0) {
    return rc;
  }
  if (stack_bytes < (size_t)PTHREAD_STACK_MIN) {
    stack_bytes = (size_t)PTHREAD_STACK_MIN;
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

int urt_thread_join_bounded(pthread_t t, int timeout_s, const char *who) {
  struct timespec deadline;
  clock_gettime(CLOCK_REALTIME, &deadline);
  deadline.tv_sec += timeout_s;
  int rc = pthread_timedjoin_np(t, NULL, &deadline);
  if (rc != 0) {
    fprintf(stderr, "%s thread did not stop within %d s (%s); abandoning it\n", who, timeout_s,
            strerror(rc));
    pthread_detach(t);
    return -1;
  }
  return 0;
}
