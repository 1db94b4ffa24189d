/* SPDX-License-Identifier: Apache-2.0
 * core/errors.c — text for the URT_E* codes. */
#include "urt/errors.h"

const char *urt_strerror(int code) {
  switch (code) {
#define URT_ERR_CASE(name, value, text) \
  case value:                           \
    return text;
    URT_ERR_LIST(URT_ERR_CASE)
#undef URT_ERR_CASE
    default:
      return "unknown error";
  }
}
