/* SPDX-License-Identifier: Apache-2.0
 * core/version.c — the one symbol of its own in liburtwin.so, the shared build of the whole
 * C API that the Python cross-checks load with ctypes. */
const char *urt_version(void) { return "0.1.0"; }
