/* SPDX-License-Identifier: Apache-2.0
 * net/urscript/script_controller.c — how a running URScript program meets the controller:
 * controller time (snapshots, waiting for the next tick), the command queue, motions submitted
 * and waited on, and the refusal messages of motions.
 *
 * Every wait goes through urt__us_wait_tick (a yield to the scheduler, which alone calls
 * host->wait_tick) and every reading through host->snapshot; a secondary program may not wait.
 */
#include <math.h>
#include <stdio.h>

#include "script_vm.h"

#define SUBMIT_RETRY_TICKS 100

/* what the controller had at the end of the slice's own tick, as on a controller, where the
 * program runs in the cycle: a thread woken late runs its missed slices back to back, and read
 * live they saw a later tick's set-point, one that the set-point moved on to while the thread
 * was away. URCL's spline starts each point from get_joint_positions(): read ahead by L
 * periods, its quintic took the arm for further along than the stream's own time and slowed it
 * down (shoulder set-point -10 rad/s² in one period, stream_late_probe). The newest snapshot
 * when the tick has left the controller's history (or before the first tick). */
void urt__us_snap_at(const urt_script_host_t *h, uint64_t tick, urt_snapshot_t *out) {
  if (!h->snapshot_at || tick == 0 || h->snapshot_at(h->ctx, tick, out) != 0) {
    h->snapshot(h->ctx, out);
  }
}

urt_snapshot_t *urt__us_snap(vm *V) {
  urt__us_snap_at(V->h->host, V->tick, &V->snap);
  return &V->snap;
}

/* the one primitive every wait goes through: yield this URScript thread until the next
 * controller tick (script_sched.c). Cancellation is the scheduler's: a stopped program's thread
 * wakes here with X_ERR and unwinds. A secondary program may not wait at all. */
int urt__us_wait_tick(vm *V, const us_node *at) {
  if (V->prog->secondary) {
    return urt__us_fail(V, at, "Blocking call in a secondary program");
  }
  return urt__us_yield(V);
}

int urt__us_submit(vm *V, const us_node *at, const urt_ctrl_cmd_t *cmd) {
  // stamped with the tick whose slice issues it: the controller sees how late it comes
  // (a runner thread woken late delivers several ticks' commands at once; core/motion_speedj.cpp)
  urt_ctrl_cmd_t stamped = *cmd;
  stamped.tick = V->tick;
  for (int tries = 0; tries <= SUBMIT_RETRY_TICKS; tries++) {
    if (V->h->host->submit(V->h->host->ctx, &stamped)) {
      return X_OK;
    }
    if (V->prog->secondary) {
      break;  // a secondary program must not wait: report at once
    }
    if (urt__us_wait_tick(V, at) != X_OK) {
      return X_ERR;
    }
  }
  return urt__us_fail(V, at, "Controller command queue is full");
}

bool urt__us_version_at_least(const vm *V, int major, int minor, int bugfix) {
  const int *v = V->h->version;
  if (v[0] == 0 && v[1] == 0 && v[2] == 0) return true;
  if (v[0] != major) return v[0] > major;
  if (v[1] != minor) return v[1] > minor;
  return v[2] >= bugfix;
}

int urt__us_require_version(vm *V, const us_node *at, const char *what, int major, int minor,
                            int bugfix) {
  if (urt__us_version_at_least(V, major, minor, bugfix)) {
    return X_OK;
  }
  const int *v = V->h->version;
  char since[24];
  if (bugfix) {
    snprintf(since, sizeof since, "%d.%d.%d", major, minor, bugfix);
  } else {
    snprintf(since, sizeof since, "%d.%d", major, minor);
  }
  return urt__us_fail(V, at, "%s is not available on software %d.%d.%d (UR added it in %s)", what,
                      v[0], v[1], v[2], since);
}

bool urt__us_safety_ok(const urt_snapshot_t *s) {
  return s->safety_mode == URT_SAFETY_MODE_NORMAL || s->safety_mode == URT_SAFETY_MODE_REDUCED;
}

static const char *fault_text(uint32_t f, const char *unknown) {
  if (f & URT_CTRL_FAULT_NOT_RUNNING) return "robot is not running";
  if (f & URT_CTRL_FAULT_BAD_TARGET) return "invalid target";
  if (f & URT_CTRL_FAULT_IK) return "no inverse kinematics solution";
  if (f & URT_CTRL_FAULT_BAD_ARGUMENT) return "argument out of range";
  if (f & URT_CTRL_FAULT_PSTOP) return "protective stop";
  if (f & URT_CTRL_FAULT_JOINT) return "joint fault";
  return unknown;
}

bool urt__us_motion_refused(const urt_snapshot_t *s, const char *what, const char *unknown,
                            char *text, size_t n) {
  if (s->robot_mode != URT_ROBOT_MODE_RUNNING && !s->ctrl_fault) {
    snprintf(text, n, "%s: motion refused (robot is not running; robot mode %d)", what,
             (int)s->robot_mode);
    return true;
  }
  if (s->ctrl_fault || !urt__us_safety_ok(s)) {
    snprintf(text, n, "%s: motion refused or aborted (%s; safety mode %d)", what,
             fault_text(s->ctrl_fault, unknown), (int)s->safety_mode);
    return true;
  }
  return false;
}

/* A protective stop met while running pauses the program (core/controller.cpp
 * protective_stop): the thread waits, with no runtime error, until the stop is unlocked and
 * the program resumed (dashboard `play`), or until the program is stopped (the scheduler
 * cancels the wait). URCL's test_send_script_blocking_fail_on_robot_errors relies on it: a
 * movel out of the workspace gives the stop's error code and no runtime exception, and after
 * the unlock the next program replaces the paused one. A stop that ends the program (a target
 * outside the joint limits) leaves it playing, and the motion's refusal is a runtime error. */
static bool paused_by_stop(const urt_snapshot_t *s) {
  return s->program_state == URT_PROGRAM_PAUSED && !urt__us_safety_ok(s);
}

static int wait_resumed(vm *V, const us_node *at) {
  while (V->snap.program_state == URT_PROGRAM_PAUSED || !urt__us_safety_ok(&V->snap) ||
         V->snap.robot_mode != URT_ROBOT_MODE_RUNNING) {
    if (urt__us_wait_tick(V, at) != X_OK) {
      return X_ERR;
    }
    urt__us_snap(V);
  }
  return X_OK;
}

/* X_OK when the controller runs the motion, or after a pause for a protective stop (the
 * streaming commands go on with their next call) */
static int motion_check(vm *V, const us_node *at, const char *what) {
  if (paused_by_stop(&V->snap)) {
    return wait_resumed(V, at);
  }
  char text[sizeof V->err->text];
  if (urt__us_motion_refused(&V->snap, what, "unknown", text, sizeof text)) {
    return urt__us_fail(V, at, "%s", text);
  }
  return X_OK;
}

/* submit a motion and, if wait, block until the controller reports it done */
int urt__us_motion(vm *V, const us_node *at, const char *what, urt_ctrl_cmd_t *cmd, bool wait) {
  if (V->prog->secondary) {
    return urt__us_fail(V, at, "%s is not allowed in a secondary program", what);
  }
  // a thread of a program paused by a protective stop issues its next motion once resumed
  if (paused_by_stop(urt__us_snap(V)) && wait_resumed(V, at) != X_OK) {
    return X_ERR;
  }
  for (;;) {
    cmd->id = ++*V->h->motion_id;
    if (urt__us_submit(V, at, cmd) != X_OK) {
      return X_ERR;
    }
    if (!wait) {
      return X_OK;
    }
    for (;;) {
      urt__us_snap(V);
      if (V->snap.motion_done_id >= cmd->id) {
        break;
      }
      if (!urt__us_safety_ok(&V->snap) || V->snap.robot_mode != URT_ROBOT_MODE_RUNNING) {
        break;  // refused or aborted: reported below
      }
      if (urt__us_wait_tick(V, at) != X_OK) {
        return X_ERR;
      }
    }
    if (!paused_by_stop(&V->snap)) {
      return motion_check(V, at, what);
    }
    // stopped on the way: once resumed the motion runs again from where the arm is, as a UR
    // program resumes the move it was paused in
    if (wait_resumed(V, at) != X_OK) {
      return X_ERR;
    }
  }
}

/* block for t seconds of controller time: ceil(t / period) ticks counted from this one (a
 * servoj with t = period takes exactly one tick), whatever the wall clock did meanwhile */
int urt__us_wait_for(vm *V, const us_node *at, double t, bool check_motion, const char *what) {
  double period = urt__us_snap(V)->period > 0 ? V->snap.period : 0.002;
  double n = ceil(t / period - 1e-6);
  uint64_t end = urt__us_run_tick(V) + (n > 0 ? (uint64_t)n : 0);
  while (urt__us_run_tick(V) < end) {
    if (urt__us_wait_tick(V, at) != X_OK) {
      return X_ERR;
    }
    urt__us_snap(V);
    if (check_motion && motion_check(V, at, what) != X_OK) {
      return X_ERR;
    }
  }
  return X_OK;
}

/* t seconds of motion time (script_vm.h): the tick's own scaling (snapshot_at), the newest
 * snapshot's when that tick has left the history; ends, as the controller's speedj, at the
 * first tick whose sum reaches t (less a millionth of a period, as urt__us_wait_for), after
 * at least one tick when t > 0.
 * A stream of them (the next starts in the tick the last ended, as URCL's spline runs one
 * speedj(qd, a, steptime) per step) keeps its motion time: what a wait ran past its t counts
 * toward the next. Without that, at a slider s whose 1/s is not whole every speedj lasted
 * ceil(1/s) ticks at s·qd: at s = 0.33, 4 ticks and 1.32 times its joint distance, and
 * URCL's 3 s spline to a pose ended 0.50 rad beyond it. The next command supersedes the
 * controller's speedj while that still runs (core/motion_speedj.cpp ends it by its own t). */
int urt__us_wait_scaled(vm *V, const us_node *at, double t, const char *what) {
  double period = urt__us_snap(V)->period > 0 ? V->snap.period : 0.002;
  double tau = V->motion_carry_tick == V->tick ? V->motion_carry : 0.0;
  V->motion_carry = 0.0;
  bool must_tick = t > 1e-6 * period;
  while (must_tick || tau < t - 1e-6 * period) {
    must_tick = false;
    if (urt__us_wait_tick(V, at) != X_OK) {
      return X_ERR;
    }
    urt__us_snap(V);
    if (motion_check(V, at, what) != X_OK) {
      return X_ERR;
    }
    // the tick's own motion time (urt__us_snap), not the reported speed_scaling: speedj's
    // limiter slows the arm, not its t
    tau += V->snap.motion_rate * period;
  }
  V->motion_carry = tau > t ? tau - t : 0.0;
  V->motion_carry_tick = V->tick;
  return X_OK;
}
