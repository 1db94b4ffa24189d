/* SPDX-License-Identifier: Apache-2.0
 * tests/core/test_spsc_ring.c — core/spsc_ring.c */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"
#include "urt/errors.h"
#include "urt/spsc_ring.h"

typedef struct msg {
  uint64_t seq;
  double payload[5];
} msg_t;

static void test_spsc_ring_init__refuses_bad_capacity(void **state) {
  (void)state;
  urt_spsc_ring_t r;
  msg_t storage[8];
  assert_int_equal(urt_spsc_ring_init(&r, storage, 6, sizeof(msg_t)), URT_EINVAL);
  assert_int_equal(urt_spsc_ring_init(&r, storage, 0, sizeof(msg_t)), URT_EINVAL);
  assert_int_equal(urt_spsc_ring_init(&r, NULL, 8, sizeof(msg_t)), URT_EINVAL);
  assert_int_equal(urt_spsc_ring_init(&r, storage, 8, sizeof(msg_t)), 0);
}

static void test_spsc_ring__full_ring_refuses_and_counts_then_drains_in_order(void **state) {
  (void)state;
  urt_spsc_ring_t r;
  msg_t storage[4], m = {0};
  assert_int_equal(urt_spsc_ring_init(&r, storage, 4, sizeof m), 0);
  for (uint64_t k = 0; k < 4; k++) {
    m.seq = k;
    assert_true(urt_spsc_ring_try_push(&r, &m));
  }
  m.seq = 99;
  assert_false(urt_spsc_ring_try_push(&r, &m));
  assert_int_equal(r.dropped, 1);
  assert_int_equal(urt_spsc_ring_size(&r), 4);
  for (uint64_t k = 0; k < 4; k++) {
    assert_true(urt_spsc_ring_try_pop(&r, &m));
    assert_int_equal(m.seq, k);
  }
  assert_false(urt_spsc_ring_try_pop(&r, &m));
}

typedef struct race {
  urt_spsc_ring_t ring;
  uint64_t n;
} race_t;

static void *producer(void *arg) {
  race_t *r = arg;
  msg_t m;
  for (uint64_t k = 0; k < r->n;) {
    m.seq = k;
    for (int i = 0; i < 5; i++) {
      m.payload[i] = (double)k + i;
    }
    if (urt_spsc_ring_try_push(&r->ring, &m)) {
      k++;
    }
  }
  return NULL;
}

static void test_spsc_ring__concurrent_producer_and_consumer_lose_nothing(void **state) {
  (void)state;
  race_t r;
  msg_t *storage = malloc(64 * sizeof *storage);
  r.n = 500000;
  assert_int_equal(urt_spsc_ring_init(&r.ring, storage, 64, sizeof(msg_t)), 0);
  pthread_t t;
  assert_int_equal(pthread_create(&t, NULL, producer, &r), 0);

  // every message arrives once, in order, whole
  uint64_t next = 0;
  msg_t m;
  while (next < r.n) {
    if (!urt_spsc_ring_try_pop(&r.ring, &m)) {
      continue;
    }
    assert_int_equal(m.seq, next);
    for (int i = 0; i < 5; i++) {
      assert_true(m.payload[i] == (double)next + i);
    }
    next++;
  }
  pthread_join(t, NULL);
  assert_false(urt_spsc_ring_try_pop(&r.ring, &m));
  print_message("%llu messages, %llu pushes refused while full\n", (unsigned long long)r.n,
                (unsigned long long)r.ring.dropped);
  free(storage);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_spsc_ring_init__refuses_bad_capacity),
      cmocka_unit_test(test_spsc_ring__full_ring_refuses_and_counts_then_drains_in_order),
      cmocka_unit_test(test_spsc_ring__concurrent_producer_and_consumer_lose_nothing),
  };
  return cmocka_run_group_tests_name("core/spsc_ring", tests, NULL, NULL);
}
