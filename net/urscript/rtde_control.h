/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/rtde_control.h — private: ur_rtde's `rtde_control` program run natively
 * (clients.md §2.3–2.8). The runner hands every main unit to urt__rc_recognise first; a unit
 * that is ur_rtde 1.6.5's control script (any version it prunes it for) runs through
 * urt__rc_run instead of the URScript interpreter: the same register protocol, one loop
 * iteration per controller tick, motions through host->submit.
 */
#ifndef URT_NET_URSCRIPT_RTDE_CONTROL_H
#define URT_NET_URSCRIPT_RTDE_CONTROL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "script.h"

#define URT_RC_MAX_CMD 256  /* command ids 0..255 */

/* One waypoint of the path ur_rtde injects into exec_move_path() for movePath / moveJ(path) /
 * moveL(path): `movej([…],a=…,v=…,r=…)`, `movel(p[…],…)`, `movep(…)`. */
typedef struct urt__rc_move {
  char kind;         /* 'j' movej, 'l' movel, 'p' movep, 'c' movec                */
  bool is_pose;      /* the target was written p[…] (a pose), else […] (joints)   */
  double x[6];       /* target: joint positions [rad] or pose [m, rad]            */
  double a, v, r;    /* acceleration, speed, blend radius as written               */
  uint32_t line;     /* 1-based line in the unit                                  */
} urt__rc_move;

/* What recognition learnt from the text. */
typedef struct urt__rc_info {
  int reg_offset_int, reg_offset_float;  /* 0, or 24 with FLAG_UPPER_RANGE_REGISTERS        */
  char tag[128];                         /* "RTDE Control Script Loaded (14.02.2024-12:23)" */
  /* process_cmd(): has_cmd[id] when it has a branch for id; has_body[id] when that branch
   * does something (version pruning leaves `dummy_op = 1` bodies, e.g. 66..71 before 5.21) */
  uint8_t has_cmd[URT_RC_MAX_CMD], has_body[URT_RC_MAX_CMD];
  uint32_t cmd_line[URT_RC_MAX_CMD];     /* 1-based line of the branch (error messages)     */
  /* the injected path (malloc'ed; NULL when none) and the first line it could not read */
  urt__rc_move *path;
  int n_path;
  uint32_t path_bad_line;                /* 0: every line of exec_move_path() understood    */
} urt__rc_info;

/* Recognise ur_rtde's control script: it starts with `def rtde_control():`, holds the version
 * tag line `textmsg("RTDE Control Script Loaded (…)")`, and both register offsets parse, also in
 * the injected form `reg_offset_int = # int register offset\n0` (the value on the next line).
 * Returns true and fills *out (free with urt__rc_info_free), or false (*out zeroed, nothing
 * allocated). Context: any (no I/O). */
bool urt__rc_recognise(const char *text, size_t len, urt__rc_info *out);
void urt__rc_info_free(urt__rc_info *info);

/* Run the recognised program until stopScript (255), a runtime error, a watchdog timeout or a
 * cancel from h->poll. Returns 0 (ended by stopScript) or -1 with err filled (US_ERR_CANCEL
 * for a stop from outside). Context: the runner thread (blocks on host->wait_tick). */
int urt__rc_run(const urt__rc_info *info, const us_hooks *h, us_err *err);

#endif
