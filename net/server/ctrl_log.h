/* SPDX-License-Identifier: Apache-2.0
 * net/server/ctrl_log.h — the controller's log, as a UR keeps one (the Log tab of the teach
 * pendant): every robot message urtwin sends on the primary interface (program text, popups,
 * runtime exceptions, safety events) and every dashboard addToLog line, with the controller
 * time, in a bounded ring. The dashboard's saveLog, generate flight report and generate support
 * file write it into the log folder (urtwin --log-dir). I/O thread only: no locks.
 */
#ifndef URT_NET_SERVER_CTRL_LOG_H
#define URT_NET_SERVER_CTRL_LOG_H

#include <stddef.h>
#include <stdint.h>

#define URT_CTRL_LOG_LINES 4096  /* the newest lines kept (older ones are counted, not kept) */
#define URT_CTRL_LOG_LINE 320    /* one line, time and level included                       */

typedef struct urt_ctrl_log {
  char (*line)[URT_CTRL_LOG_LINE];  /* URT_CTRL_LOG_LINES entries, allocated by init */
  uint64_t n;                       /* lines added since start                       */
  uint64_t saved;                   /* lines written to log_history.txt so far       */
  uint64_t reports, support_files;  /* files written so far (their ids)              */
} urt_ctrl_log_t;

/* Returns 0 or -1 (no memory). */
int urt_ctrl_log_init(urt_ctrl_log_t *l);
void urt_ctrl_log_free(urt_ctrl_log_t *l);

/* One line: "   12.345 INFO  text" (controller time [s], level). Control characters in text
 * become spaces; a long text is cut to the line. */
void urt_ctrl_log_add(urt_ctrl_log_t *l, double time, const char *level, const char *text);

/* The files, in dir (which must exist). Each returns 0 and the file's path in path, or -1 and
 * why in path (one line). header: lines that open a flight report (robot, version, state).
 * - save: appends the lines not yet saved to dir/log_history.txt;
 * - flight report: dir/flight_report_<id>.txt, the header then every line kept; *id is set;
 * - support file: dir/ur_support_file_<id>.zip, a zip archive (stored, CRC-32 checked) of
 *   log_history.txt (every line kept) and flight_report.txt (header and lines). */
int urt_ctrl_log_save(urt_ctrl_log_t *l, const char *dir, char *path, size_t path_sz);
int urt_ctrl_log_flight_report(urt_ctrl_log_t *l, const char *dir, const char *header,
                               uint64_t *id, char *path, size_t path_sz);
int urt_ctrl_log_support_file(urt_ctrl_log_t *l, const char *dir, const char *header,
                              char *path, size_t path_sz);

#endif
