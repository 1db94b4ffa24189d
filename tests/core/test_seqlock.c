/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_seqlock.c — core/seqlock.c */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/seqlock.h"

// A payload whose words must all agree: a torn copy shows as a mix of two writes.
#define N_WORDS 200
typedef struct payload {
  uint64_t w[N_WORDS];
  unsigned char tail[5];  // not a whole number of words
} payload_t;

static void fill(payload_t *p, uint64_t k) {
  for (int i = 0; i < N_WORDS; i++) {
    p->w[i] = k;
  }
  memset(p->tail, (int)(k & 0xff), sizeof p->tail);
}

static int consistent(const payload_t *p) {
  for (int i = 1; i < N_WORDS; i++) {
    if (p->w[i] != p->w[0]) {
      return 0;
    }
  }
  for (size_t i = 0; i < sizeof p->tail; i++) {
    if (p->tail[i] != (unsigned char)(p->w[0] & 0xff)) {
      return 0;
    }
  }
  return 1;
}

static void test_seqlock_init__refuses_empty_and_oversized_payloads(void **state) {
  (void)state;
  urt_seqlock_t *s = malloc(sizeof *s);
  assert_int_equal(urt_seqlock_init(s, 0), URT_EINVAL);
  assert_int_equal(urt_seqlock_init(s, URT_SEQLOCK_MAX_BYTES + 1), URT_EINVAL);
  assert_int_equal(urt_seqlock_init(s, sizeof(payload_t)), 0);
  free(s);
}

static void test_seqlock__read_returns_what_was_written_with_its_sequence(void **state) {
  (void)state;
  urt_seqlock_t *s = malloc(sizeof *s);
  payload_t in, out;
  assert_int_equal(urt_seqlock_init(s, sizeof in), 0);
  memset(&out, 0x55, sizeof out);
  assert_int_equal(urt_seqlock_read(s, &out, 1), 0);
  fill(&in, 7);
  urt_seqlock_write(s, &in);
  assert_int_equal(urt_seqlock_read(s, &out, 1), 1);
  assert_memory_equal(&in, &out, sizeof in);
  fill(&in, 8);
  urt_seqlock_write(s, &in);
  assert_int_equal(urt_seqlock_read(s, &out, 1), 2);
  assert_memory_equal(&in, &out, sizeof in);
  free(s);
}

typedef struct race {
  urt_seqlock_t *s;
  uint64_t writes;
  _Atomic int done;
} race_t;

static void *writer(void *arg) {
  race_t *r = arg;
  payload_t p;
  for (uint64_t k = 1; k <= r->writes; k++) {
    fill(&p, k);
    urt_seqlock_write(r->s, &p);
  }
  atomic_store(&r->done, 1);
  return NULL;
}

static void test_seqlock__concurrent_reader_never_sees_a_torn_payload(void **state) {
  (void)state;
  race_t r = {malloc(sizeof(urt_seqlock_t)), 200000, 0};
  assert_int_equal(urt_seqlock_init(r.s, sizeof(payload_t)), 0);
  pthread_t t;
  assert_int_equal(pthread_create(&t, NULL, writer, &r), 0);

  // read until the writer is done: every successful copy is whole and never goes backwards
  long reads = 0, retries = 0;
  uint64_t last = 0;
  payload_t p;
  while (!atomic_load(&r.done) || reads == 0) {
    int64_t seq = urt_seqlock_read(r.s, &p, 64);
    if (seq < 0) {
      retries++;
      continue;
    }
    reads++;
    assert_true(consistent(&p));
    assert_true(p.w[0] >= last);
    assert_int_equal((uint64_t)seq, p.w[0]);
    last = p.w[0];
  }
  pthread_join(t, NULL);
  assert_int_equal(urt_seqlock_read(r.s, &p, 0), (int64_t)r.writes);
  print_message("%ld consistent reads, %ld gave up after 64 tries\n", reads, retries);
  free(r.s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_seqlock_init__refuses_empty_and_oversized_payloads),
      cmocka_unit_test(test_seqlock__read_returns_what_was_written_with_its_sequence),
      cmocka_unit_test(test_seqlock__concurrent_reader_never_sees_a_torn_payload),
  };
  return cmocka_run_group_tests_name("core/seqlock", tests, NULL, NULL);
}
