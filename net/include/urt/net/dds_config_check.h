/* SPDX-License-Identifier: Apache-2.0
 * net/include/urt/net/dds_config_check.h — is a Cyclone DDS configuration well-formed XML?
 * Cyclone 0.10's parser accepts a file cut short (unclosed elements) without a word and then
 * runs on its defaults — for urtwin possibly off loopback. So urtwin checks the file itself
 * first: elements nest and close, attribute values are quoted, the root is <CycloneDDS>, nothing
 * but comments and white space follows it. Cyclone still judges the content (unknown elements,
 * bad values). Pure. */
#ifndef URT_NET_DDS_CONFIG_CHECK_H
#define URT_NET_DDS_CONFIG_CHECK_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Returns 0 when well-formed, else URT_ECONFIG with the line and the reason in err. */
int urt_dds_config_check(const char *xml, char *err, size_t err_sz);

#ifdef __cplusplus
}
#endif
#endif
