/* SPDX-License-Identifier: Apache-2.0
 * tests/support/test_model.h — load config/ur5.yaml with overrides, failing the test on error. */
#ifndef URT_TEST_MODEL_H
#define URT_TEST_MODEL_H

#include "urt/core.h"

/* overrides: NULL-terminated "key=value" list or NULL. Never returns NULL (fails instead). */
urt_model_t *urt_test_model(const char *const *overrides);

/* 1 if every state of every joint is finite, else 0. */
int urt_test_state_finite(const urt_data_t *d);

/* The deterministic drive: noise and quantisation off (for comparisons with references). */
extern const char *const urt_test_quiet[];

#endif
