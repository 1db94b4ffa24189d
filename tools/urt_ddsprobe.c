/* SPDX-License-Identifier: Apache-2.0
 * tools/urt_ddsprobe.c — a DDS subscriber of rt/joint_states that measures what it sees, for
 * `make bench` (tools/bench_dds.py runs 8 of them): the latency from the tick (the sample's
 * source timestamp, which urtwin sets to the wall time its physics thread published the tick)
 * to the moment this process takes it, and the gaps in the header stamps (one per tick).
 * In C so that what is measured is urtwin's DDS path, not a Python subscriber's speed.
 *
 *   urt_ddsprobe DOMAIN CONFIG.xml SECONDS [TOPIC]
 *   → one line: {"samples": N, "gaps": N, "p50_us": x, "p99_us": x, "max_us": x}
 * Exit status 0, or 2 on bad arguments, 1 when DDS cannot start.
 */
#include <dds/dds.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ros2_msgs.h"

#define PERIOD_NS 2000000  /* e-Series: 500 Hz */
#define MAX_SAMPLES (1 << 20)

static int64_t wall_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    return NULL;
  }
  char *buf = malloc(1 << 20);
  size_t n = buf ? fread(buf, 1, (1 << 20) - 1, f) : 0;
  fclose(f);
  if (buf) {
    buf[n] = '\0';
  }
  return buf;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: urt_ddsprobe DOMAIN CONFIG.xml SECONDS [TOPIC]\n");
    return 2;
  }
  int domain = atoi(argv[1]);
  double seconds = atof(argv[3]);
  const char *topic_name = argc > 4 ? argv[4] : "rt/joint_states";
  char *xml = slurp(argv[2]);
  if (xml == NULL || !(seconds > 0)) {
    fprintf(stderr, "urt_ddsprobe: cannot read %s or bad duration\n", argv[2]);
    return 2;
  }
  dds_entity_t dom = dds_create_domain((dds_domainid_t)domain, xml);
  free(xml);
  dds_entity_t pp = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (dom < 0 || pp < 0) {
    fprintf(stderr, "urt_ddsprobe: DDS: %s\n", dds_strretcode(pp < 0 ? pp : dom));
    return 1;
  }
  dds_entity_t tp = dds_create_topic(pp, &sensor_msgs_msg_dds__JointState__desc, topic_name, NULL, NULL);
  dds_qos_t *q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 64);
  dds_entity_t rd = dds_create_reader(pp, tp, q, NULL);
  dds_delete_qos(q);
  dds_entity_t ws = dds_create_waitset(pp);
  dds_entity_t cond = dds_create_readcondition(rd, DDS_ANY_STATE);
  dds_waitset_attach(ws, cond, 0);

  double *lat = malloc(MAX_SAMPLES * sizeof *lat);
  size_t n = 0, gaps = 0;
  int64_t last_stamp = 0;
  const int64_t end = wall_ns() + (int64_t)(seconds * 1e9);
  void *buf[16] = {NULL};
  dds_sample_info_t info[16];
  while (wall_ns() < end) {
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(100));
    int k = dds_take(rd, buf, info, 16, 16);
    int64_t now = wall_ns();
    for (int i = 0; i < k; i++) {
      if (!info[i].valid_data) {
        continue;
      }
      const sensor_msgs_msg_dds__JointState_ *s = buf[i];
      int64_t stamp = (int64_t)s->header.stamp.sec * 1000000000 + s->header.stamp.nanosec;
      if (last_stamp != 0 && stamp - last_stamp != PERIOD_NS) {
        gaps++;
      }
      last_stamp = stamp;
      if (n < MAX_SAMPLES) {
        lat[n++] = (double)(now - info[i].source_timestamp) / 1000.0;
      }
    }
    if (k > 0) {
      dds_return_loan(rd, buf, k);
    }
  }
  // the first samples include discovery: skip 50
  size_t skip = n > 100 ? 50 : 0;
  qsort(lat + skip, n - skip, sizeof *lat, cmp_double);
  size_t m = n - skip;
  printf("{\"samples\": %zu, \"gaps\": %zu, \"p50_us\": %.1f, \"p99_us\": %.1f, \"max_us\": %.1f}\n",
         n, gaps, m ? lat[skip + m / 2] : -1.0, m ? lat[skip + (size_t)(0.99 * (double)(m - 1))] : -1.0,
         m ? lat[n - 1] : -1.0);
  free(lat);
  dds_delete(dom);
  return 0;
}
