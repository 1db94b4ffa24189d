/* SPDX-License-Identifier: Apache-2.0
 * tests/fuzz/fuzz_dds_config.c — the --dds-config well-formedness check on arbitrary text:
 * never reads past the string, always answers 0 or URT_ECONFIG with a message. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "urt/errors.h"
#include "urt/net/dds_config_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = malloc(size + 1);
  if (text == NULL) {
    return 0;
  }
  memcpy(text, data, size);
  text[size] = '\0';
  char err[160];
  err[0] = '\0';
  int rc = urt_dds_config_check(text, err, sizeof err);
  if (rc != 0 && (rc != URT_ECONFIG || strncmp(err, "line ", 5) != 0)) {
    abort();
  }
  free(text);
  return 0;
}
