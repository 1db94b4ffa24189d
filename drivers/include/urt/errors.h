/* SPDX-License-Identifier: Apache-2.0
 * drivers/include/urt/errors.h — one list of error codes for the whole project.
 * Every fallible function returns 0 (or a count) on success and a negative code on failure;
 * on failure, outputs and state are left unchanged. */
#ifndef URT_ERRORS_H
#define URT_ERRORS_H

#ifdef __cplusplus
extern "C" {
#endif

#define URT_ERR_LIST(X)                                  \
  X(URT_OK, 0, "success")                                \
  X(URT_EINVAL, -1, "invalid argument")                  \
  X(URT_ERANGE, -2, "parameter out of range")            \
  X(URT_ENOSPC, -3, "output buffer too small")           \
  X(URT_EIO, -4, "I/O error")                            \
  X(URT_EPROTO, -5, "protocol violation by peer")        \
  X(URT_EAGAIN, -6, "resource busy, try again")          \
  X(URT_ECONFIG, -7, "invalid configuration")            \
  X(URT_ENOMEM, -8, "out of memory")                     \
  X(URT_EPSTOP, -9, "protective stop: command refused")  \
  X(URT_ESOLVER, -10, "numerical solver failure")

enum {
#define URT_ERR_ENUM(name, code, text) name = (code),
  URT_ERR_LIST(URT_ERR_ENUM)
#undef URT_ERR_ENUM
};

/* Human-readable text for a URT_E* code. Context: any. Never returns NULL. */
const char *urt_strerror(int code);

#ifdef __cplusplus
}
#endif
#endif
