/* SPDX-License-Identifier: Apache-2.0
 * tests/support/test_model.h — load config/ur5.yaml with overrides, failing the test on error. */
#ifndef URT_TEST_MODEL_H
#define URT_TEST_MODEL_H

#include "urt/core.h"

/* overrides: NULL-terminated "key=value" list or NULL. Never returns NULL (fails instead). */
urt_model_t *urt_test_model(const char *const *overrides);

/* The deterministic drive: noise and quantisation off (for comparisons with references). */
extern const char *const urt_test_quiet[];

#endif
