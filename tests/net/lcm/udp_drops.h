/* SPDX-License-Identifier: Apache-2.0
 * tests/net/lcm/udp_drops.h — counting messages that loopback UDP itself lost.
 *
 * udpm over loopback is still UDP: when a receiving thread is descheduled (2 cores, sanitizers,
 * other tests beside it) its socket buffer fills and the kernel drops datagrams. Each such drop
 * is counted by the kernel: a socket's full buffer in /proc/net/snmp (Udp RcvbufErrors), the
 * loopback device's full backlog in /proc/net/softnet_stat (second column). A test counting
 * arrivals takes these counters before and after and accepts a shortfall only up to the drops
 * the kernel counted meanwhile; a message missing that the kernel did not drop is the
 * publisher's fault and fails. The counters are the whole network namespace's, so drops of other
 * tests running beside this one may be counted too: the check is one-sided, never spurious. */
#ifndef URT_TESTS_NET_LCM_UDP_DROPS_H
#define URT_TESTS_NET_LCM_UDP_DROPS_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Receive buffers of the tests' sockets: large, so that drops are rare (the kernel caps it at
// net.core.rmem_max; LCM warns when it does).
#define UDP_DROPS_URL_OPTIONS "ttl=0&recv_buf_size=4194304"

// Udp RcvbufErrors of /proc/net/snmp: its header line names the columns, the next the values
static long udp_drops__rcvbuf_errors(void) {
  FILE *f = fopen("/proc/net/snmp", "r");
  if (!f) {
    return 0;
  }
  char head[1024], vals[1024];
  long result = 0;
  while (fgets(head, sizeof head, f)) {
    if (strncmp(head, "Udp:", 4) != 0 || !fgets(vals, sizeof vals, f)) {
      continue;
    }
    char *hs = NULL, *vs = NULL;
    char *h = strtok_r(head, " \n", &hs), *v = strtok_r(vals, " \n", &vs);
    while (h && v) {
      if (strcmp(h, "RcvbufErrors") == 0) {
        result = atol(v);
      }
      h = strtok_r(NULL, " \n", &hs);
      v = strtok_r(NULL, " \n", &vs);
    }
    break;
  }
  fclose(f);
  return result;
}

// the backlog drops of every CPU: /proc/net/softnet_stat's second column, in hexadecimal
static long udp_drops__backlog_drops(void) {
  FILE *f = fopen("/proc/net/softnet_stat", "r");
  if (!f) {
    return 0;
  }
  long total = 0;
  unsigned long processed, dropped;
  char rest[512];
  while (fscanf(f, "%lx %lx", &processed, &dropped) == 2) {
    total += (long)dropped;
    if (!fgets(rest, sizeof rest, f)) {
      break;
    }
  }
  fclose(f);
  return total;
}

// every datagram this network namespace's kernel has dropped so far on receipt
static long udp_drops_now(void) {
  return udp_drops__rcvbuf_errors() + udp_drops__backlog_drops();
}

#endif
