/* SPDX-License-Identifier: Apache-2.0
 * net/server/program_play.c — the dashboard's programs: `load` compiles a .urp to URScript
 * (net/urp) and keeps it, `play` hands the loaded program to the runner. A URScript file is
 * read at play, as before. A .urp holding External Control nodes first fetches its program
 * from the configured remote PC, as the URCap does when PolyScope generates the program; that
 * exchange can take seconds (a 5 s connect, 500 ms reads), so it runs on its own thread, never
 * on the I/O thread (every port keeps serving) nor near the physics.
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "emulator_internal.h"

static int is_urp(const char *path) {
  size_t n = strlen(path);
  return n >= 4 && strcasecmp(path + n - 4, ".urp") == 0;
}

int urt__program_prepare(void *user, const char *host_path, char *why, size_t why_sz) {
  urt_emulator_t *e = user;
  if (!is_urp(host_path)) {
    urt_urp_free(e->urp);  // a URScript file: read when played
    e->urp = NULL;
    return 0;
  }
  // the file's name as the def's name when the program's own is unusable
  char base[256];
  snprintf(base, sizeof base, "%s", strrchr(host_path, '/') ? strrchr(host_path, '/') + 1 : host_path);
  base[strlen(base) - 4] = '\0';
  urt_urp_options_t opt = {.script_root = e->cfg.programs_dir, .fallback_name = base};
  urt_urp_program_t *p = NULL;
  if (urt_urp_compile_file(host_path, &opt, &p, why, why_sz) != 0) {
    return -1;  // the loaded program stays what it was
  }
  urt_urp_free(e->urp);
  e->urp = p;
  return 0;
}

//---- URScript files ----

// The file was resolved under the programs directory by `load`; O_NOFOLLOW closes the window in
// which it could have been swapped for a link since.
static void play_script_file(urt_emulator_t *e) {
  int fd = open(e->dash.program_path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  struct stat st;
  if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size <= 0 ||
      st.st_size > (off_t)URT_SCRIPT_MAX_TEXT) {
    if (fd >= 0) {
      close(fd);
    }
    urt__script_broadcast_text(e, "urtwin: the loaded program cannot be read");
    return;
  }
  char *text = malloc((size_t)st.st_size);
  ssize_t got = text ? read(fd, text, (size_t)st.st_size) : -1;
  close(fd);
  if (got == st.st_size) {
    urt_runner_submit(e->runner, text, (size_t)got);
  }
  free(text);
}

//---- .urp with External Control nodes: the fetch thread ----

typedef struct fetch_job {
  urt_emulator_t *e;
  char *tmpl;     /* the program's template (a copy: a new load may free the program) */
  size_t len;
} fetch_job;

static void *fetch_main(void *arg) {
  fetch_job *job = arg;
  urt_emulator_t *e = job->e;
  urt_urcap_config_t cfg = {.host = e->ec_host, .port = e->ec_port, .cancel = &e->fetch_cancel};
  char *reply = NULL, *header = NULL, *body = NULL, *text = NULL;
  size_t reply_len = 0, text_len = 0;
  // a failed fetch still yields a program: the URCap's blocking popup at the node
  urt_urcap_fetch(&cfg, &reply, &reply_len);
  if (reply && urt_urcap_split(reply, reply_len, &header, &body) == 0 &&
      urt_urp_render_template(job->tmpl, job->len, header, body, &text, &text_len) == 0) {
    pthread_mutex_lock(&e->fetch_lock);
    if (!atomic_load(&e->fetch_cancel)) {
      urt_runner_submit(e->runner, text, text_len);
    }
    pthread_mutex_unlock(&e->fetch_lock);
  }
  free(text);
  free(header);
  free(body);
  free(reply);
  free(job->tmpl);
  free(job);
  atomic_store(&e->fetch_busy, 0);
  return NULL;
}

static void join_fetch(urt_emulator_t *e) {
  if (e->fetch_started) {
    pthread_join(e->fetch_thread, NULL);
    e->fetch_started = false;
  }
}

static void play_urp(urt_emulator_t *e) {
  if (urt_urp_external_nodes(e->urp) == 0) {
    char *text = NULL;
    size_t len = 0;
    if (urt_urp_render(e->urp, NULL, NULL, &text, &len) == 0) {
      urt_runner_submit(e->runner, text, len);
    }
    free(text);
    return;
  }
  if (atomic_load(&e->fetch_busy)) {
    // on its way to the runner already; or a stopped fetch still winding down: play once it
    // has (urt__program_tick), so that stop-then-play never loses the play
    e->fetch_replay = atomic_load(&e->fetch_cancel) != 0;
    return;
  }
  join_fetch(e);  // a finished one
  fetch_job *job = calloc(1, sizeof *job);
  size_t len = 0;
  const char *tmpl = urt_urp_template(e->urp, &len);
  if (job) {
    job->tmpl = malloc(len);
  }
  if (!job || !job->tmpl) {
    free(job);
    urt__script_broadcast_text(e, "urtwin: out of memory playing the program");
    return;
  }
  memcpy(job->tmpl, tmpl, len);
  job->len = len;
  job->e = e;
  atomic_store(&e->fetch_cancel, 0);
  atomic_store(&e->fetch_busy, 1);
  if (pthread_create(&e->fetch_thread, NULL, fetch_main, job) != 0) {
    atomic_store(&e->fetch_busy, 0);
    free(job->tmpl);
    free(job);
    urt__script_broadcast_text(e, "urtwin: cannot start the External Control fetch");
    return;
  }
  e->fetch_started = true;
}

//---- the dashboard's entry points (I/O thread) ----

void urt__program_play(urt_emulator_t *e) {
  if (e->urp) {
    play_urp(e);
  } else {
    play_script_file(e);
  }
}

void urt__program_tick(urt_emulator_t *e) {
  if (e->fetch_replay && !atomic_load(&e->fetch_busy)) {
    e->fetch_replay = false;
    if (e->urp) {
      play_urp(e);
    }
  }
}

int urt__program_state(urt_emulator_t *e, int snapshot_state) {
  // a program whose External Control fetch is under way is starting: to the dashboard it
  // plays (a real controller answers `play` once it has started), so `stop` reaches it
  if (snapshot_state == URT_PROGRAM_STOPPED && atomic_load(&e->fetch_busy) &&
      !atomic_load(&e->fetch_cancel)) {
    return URT_PROGRAM_PLAYING;
  }
  return snapshot_state;
}

void urt__program_cancel(urt_emulator_t *e) {
  e->fetch_replay = false;
  pthread_mutex_lock(&e->fetch_lock);
  atomic_store(&e->fetch_cancel, 1);
  pthread_mutex_unlock(&e->fetch_lock);
}

void urt__program_shutdown(urt_emulator_t *e) {
  urt__program_cancel(e);
  join_fetch(e);  // bounded: the fetch looks at the cancel flag every 50 ms
  urt_urp_free(e->urp);
  e->urp = NULL;
}
