/* SPDX-License-Identifier: Apache-2.0
 * net/server/ctrl_log.c — the controller's log and the files the dashboard writes from it
 * (ctrl_log.h). Files are written whole to a temporary name and renamed, so a reader never
 * sees half a report.
 */
#define _GNU_SOURCE
#include "ctrl_log.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int urt_ctrl_log_init(urt_ctrl_log_t *l) {
  memset(l, 0, sizeof *l);
  l->line = calloc(URT_CTRL_LOG_LINES, sizeof *l->line);
  return l->line ? 0 : -1;
}

void urt_ctrl_log_free(urt_ctrl_log_t *l) {
  free(l->line);
  l->line = NULL;
}

void urt_ctrl_log_add(urt_ctrl_log_t *l, double time, const char *level, const char *text) {
  if (!l->line) {
    return;
  }
  char *out = l->line[l->n % URT_CTRL_LOG_LINES];
  int k = snprintf(out, URT_CTRL_LOG_LINE, "%10.3f %-5s ", time, level);
  if (k < 0) {
    k = 0;
  }
  size_t i = (size_t)k;
  for (const char *p = text; *p && i + 1 < URT_CTRL_LOG_LINE; p++) {
    out[i++] = (unsigned char)*p < 0x20 || *p == 0x7f ? ' ' : *p;
  }
  out[i] = '\0';
  l->n++;
}

static uint64_t first_kept(const urt_ctrl_log_t *l) {
  return l->n > URT_CTRL_LOG_LINES ? l->n - URT_CTRL_LOG_LINES : 0;
}

static int fail(char *path, size_t path_sz, const char *what, const char *file) {
  snprintf(path, path_sz, "%s %s: %s", what, file, strerror(errno));
  return -1;
}

// Lines [from, l->n) into f; a note first when older lines were no longer kept.
static void put_lines(const urt_ctrl_log_t *l, uint64_t from, FILE *f) {
  uint64_t kept = first_kept(l);
  if (from < kept) {
    fprintf(f, "(%llu older lines no longer kept)\n", (unsigned long long)(kept - from));
    from = kept;
  }
  for (uint64_t k = from; k < l->n; k++) {
    fprintf(f, "%s\n", l->line[k % URT_CTRL_LOG_LINES]);
  }
}

int urt_ctrl_log_save(urt_ctrl_log_t *l, const char *dir, char *path, size_t path_sz) {
  char file[1200];
  snprintf(file, sizeof file, "%s/log_history.txt", dir);
  FILE *f = fopen(file, "a");
  if (!f) {
    return fail(path, path_sz, "cannot open", file);
  }
  put_lines(l, l->saved, f);
  bool ok = fflush(f) == 0 && !ferror(f);
  ok = fclose(f) == 0 && ok;
  if (!ok) {
    return fail(path, path_sz, "cannot write", file);
  }
  l->saved = l->n;
  snprintf(path, path_sz, "%s", file);
  return 0;
}

// Write text to dir/name through a temporary file and a rename.
static int write_whole(const char *file, const void *data, size_t len, char *path,
                       size_t path_sz) {
  char tmp[1300];
  snprintf(tmp, sizeof tmp, "%s.tmp", file);
  FILE *f = fopen(tmp, "wb");
  if (!f) {
    return fail(path, path_sz, "cannot open", tmp);
  }
  bool ok = fwrite(data, 1, len, f) == len;
  ok = fflush(f) == 0 && ok;
  ok = fclose(f) == 0 && ok;
  if (!ok || rename(tmp, file) != 0) {
    int saved = errno;
    unlink(tmp);
    errno = saved;
    return fail(path, path_sz, "cannot write", file);
  }
  snprintf(path, path_sz, "%s", file);
  return 0;
}

// The report's text (header, then every line kept) in a malloc'd buffer; NULL without memory.
static char *report_text(const urt_ctrl_log_t *l, const char *header, size_t *len) {
  char *buf = NULL;
  FILE *m = open_memstream(&buf, len);
  if (!m) {
    return NULL;
  }
  fputs(header, m);
  put_lines(l, first_kept(l), m);
  if (fclose(m) != 0) {
    free(buf);
    return NULL;
  }
  return buf;
}

static char *log_text(const urt_ctrl_log_t *l, size_t *len) { return report_text(l, "", len); }

int urt_ctrl_log_flight_report(urt_ctrl_log_t *l, const char *dir, const char *header,
                               uint64_t *id, char *path, size_t path_sz) {
  size_t len = 0;
  char *text = report_text(l, header, &len);
  if (!text) {
    snprintf(path, path_sz, "out of memory");
    return -1;
  }
  char file[1200];
  snprintf(file, sizeof file, "%s/flight_report_%llu.txt", dir,
           (unsigned long long)(l->reports + 1));
  int rc = write_whole(file, text, len, path, path_sz);
  free(text);
  if (rc == 0) {
    *id = ++l->reports;
  }
  return rc;
}

//---- a zip archive of stored (uncompressed) entries: PKWARE APPNOTE 4.3 ----

static uint32_t crc32_of(const unsigned char *p, size_t n) {
  uint32_t c = 0xffffffffu;
  for (size_t i = 0; i < n; i++) {
    c ^= p[i];
    for (int k = 0; k < 8; k++) {
      c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
  }
  return ~c;
}

static void le16(FILE *f, unsigned v) {
  fputc((int)(v & 0xff), f);
  fputc((int)(v >> 8 & 0xff), f);
}

static void le32(FILE *f, uint32_t v) {
  le16(f, v & 0xffff);
  le16(f, v >> 16);
}

typedef struct zip_entry {
  const char *name;
  const char *data;
  size_t len;
  uint32_t crc, offset;
} zip_entry_t;

static void zip_write(FILE *f, zip_entry_t *e, int n) {
  // time 00:00, date 1980-01-01 (DOS epoch): the archive's bytes depend on its content only
  for (int i = 0; i < n; i++) {
    e[i].crc = crc32_of((const unsigned char *)e[i].data, e[i].len);
    e[i].offset = (uint32_t)ftell(f);
    le32(f, 0x04034b50u);
    le16(f, 10), le16(f, 0), le16(f, 0), le16(f, 0), le16(f, 0x21);
    le32(f, e[i].crc), le32(f, (uint32_t)e[i].len), le32(f, (uint32_t)e[i].len);
    le16(f, (unsigned)strlen(e[i].name)), le16(f, 0);
    fputs(e[i].name, f);
    fwrite(e[i].data, 1, e[i].len, f);
  }
  uint32_t cd = (uint32_t)ftell(f);
  for (int i = 0; i < n; i++) {
    le32(f, 0x02014b50u);
    le16(f, 20), le16(f, 10), le16(f, 0), le16(f, 0), le16(f, 0), le16(f, 0x21);
    le32(f, e[i].crc), le32(f, (uint32_t)e[i].len), le32(f, (uint32_t)e[i].len);
    le16(f, (unsigned)strlen(e[i].name)), le16(f, 0), le16(f, 0), le16(f, 0), le16(f, 0);
    le32(f, 0), le32(f, e[i].offset);
    fputs(e[i].name, f);
  }
  uint32_t end = (uint32_t)ftell(f);
  le32(f, 0x06054b50u);
  le16(f, 0), le16(f, 0), le16(f, (unsigned)n), le16(f, (unsigned)n);
  le32(f, end - cd), le32(f, cd), le16(f, 0);
}

int urt_ctrl_log_support_file(urt_ctrl_log_t *l, const char *dir, const char *header,
                              char *path, size_t path_sz) {
  size_t log_len = 0, rep_len = 0, zip_len = 0;
  char *log = log_text(l, &log_len), *rep = report_text(l, header, &rep_len), *zip = NULL;
  FILE *m = log && rep ? open_memstream(&zip, &zip_len) : NULL;
  int rc = -1;
  if (m) {
    zip_entry_t e[2] = {{"log_history.txt", log, log_len, 0, 0},
                        {"flight_report.txt", rep, rep_len, 0, 0}};
    zip_write(m, e, 2);
    if (fclose(m) == 0) {
      char file[1200];
      snprintf(file, sizeof file, "%s/ur_support_file_%llu.zip", dir,
               (unsigned long long)(l->support_files + 1));
      rc = write_whole(file, zip, zip_len, path, path_sz);
      if (rc == 0) {
        l->support_files++;
      }
    } else {
      snprintf(path, path_sz, "out of memory");
    }
  } else {
    snprintf(path, path_sz, "out of memory");
  }
  free(zip);
  free(log);
  free(rep);
  return rc;
}
