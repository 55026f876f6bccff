/*
 * map_load.c - flux-map files for the SIL (map_load.h).
 */
#define _POSIX_C_SOURCE 200809L /* popen, mkstemp */
#include "map_load.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef FD_SOURCE_DIR
#define FD_SOURCE_DIR "."
#endif
#ifndef FD_TOOLS_PYTHON
#define FD_TOOLS_PYTHON ""
#endif

static map_load_t loaded[MAP_LOAD_MAX];
static int n_loaded;

static int ends_with(const char *s, const char *suffix) {
  const size_t n = strlen(s), m = strlen(suffix);
  return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int readable(const char *p) {
  FILE *f = fopen(p, "rb");
  if (f != NULL) {
    fclose(f);
  }
  return f != NULL;
}

/* The file relative to the scenario's folder, then to the repository. */
static int resolve(const char *file, const char *origin, char *out, size_t n) {
  if (file[0] == '/') {
    return snprintf(out, n, "%s", file) < (int)n && readable(out) ? 0 : -1;
  }
  const char *slash = strrchr(origin, '/');
  const int dir = slash != NULL ? (int)(slash - origin) : 0;
  if (slash != NULL && snprintf(out, n, "%.*s/%s", dir, origin, file) < (int)n && readable(out)) {
    return 0;
  }
  if (snprintf(out, n, "%s", file) < (int)n && readable(out)) {
    return 0;
  }
  return snprintf(out, n, "%s/%s", FD_SOURCE_DIR, file) < (int)n && readable(out) ? 0 : -1;
}

static const char *python(void) {
  const char *env = getenv("FLUXDRIVE_PYTHON");
  if (env != NULL && env[0] != '\0') {
    return env;
  }
  return FD_TOOLS_PYTHON[0] != '\0' && readable(FD_TOOLS_PYTHON) ? FD_TOOLS_PYTHON : "python3";
}

/* .npz / .csv -> a temporary .fdmap through the map tool; the tool's own
 * message (file, check, cell) on failure. */
static int convert(const char *src, int pole_pairs, char *tmp, size_t tmpn, char *err,
                   size_t errlen) {
  if (strchr(src, '\'') != NULL) {
    snprintf(err, errlen, "%s: a map path may not contain a quote", src);
    return -1;
  }
  snprintf(tmp, tmpn, "/tmp/fluxdrive-map-XXXXXX");
  const int fd = mkstemp(tmp);
  if (fd < 0) {
    snprintf(err, errlen, "%s: cannot create a temporary file", src);
    return -1;
  }
  close(fd);
  char cmd[2048], pp[32] = "";
  if (pole_pairs > 0) {
    snprintf(pp, sizeof pp, " --pole-pairs %d", pole_pairs);
  }
  snprintf(cmd, sizeof cmd, "'%s' -m fluxdrive map convert '%s' -o '%s'%s 2>&1", python(), src, tmp,
           pp);
  FILE *p = popen(cmd, "r");
  /* the output's last 511 bytes (a line at a time; lines longer than the
   * buffer are cut): the tool's message is at its end */
  char out[512] = "";
  size_t got = 0;
  char line[512];
  while (p != NULL && fgets(line, sizeof line, p) != NULL) {
    const size_t n = strlen(line);
    if (got + n > sizeof out - 1) {
      got = 0;
    }
    memcpy(out + got, line, n);
    got += n;
  }
  out[got] = '\0';
  const int rc = p != NULL ? pclose(p) : -1;
  if (rc != 0) {
    /* the tool's message is its last line (a traceback's is the exception) */
    while (got > 0 && (out[got - 1] == '\n' || out[got - 1] == ' ')) {
      out[--got] = '\0';
    }
    const char *nl = strrchr(out, '\n');
    const char *msg = nl != NULL ? nl + 1 : out;
    snprintf(err, errlen, "%s: the map tool refused it: %s", src,
             got > 0 ? msg : "(no message; is the tools venv installed? scripts/setup.sh)");
    remove(tmp);
    return -1;
  }
  return 0;
}

enum { MAX_BYTES = 4 * (12 + 2 * 64 * 64 + 2 + 4 * 128 + 1) };

/* The file's bytes in a buffer of MAX_BYTES + 4 (zeroed); NULL on failure. */
static uint32_t *read_file(const char *path, const char *shown, size_t *n, char *err,
                           size_t errlen) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    snprintf(err, errlen, "%s: cannot open", shown);
    return NULL;
  }
  uint32_t *w = calloc(MAX_BYTES / 4 + 1, 4);
  *n = w != NULL ? fread(w, 1, MAX_BYTES + 1, f) : 0;
  fclose(f);
  if (w == NULL) {
    snprintf(err, errlen, "%s: out of memory", shown);
  }
  return w;
}

/* The blob's size checks (n bytes in w, a buffer of MAX_BYTES + 4). */
static int check_blob(const uint32_t *w, size_t n, const char *shown, char *err, size_t errlen) {
  if (n > MAX_BYTES || n < 16u || (n & 3u) != 0u || w[2] != n) {
    snprintf(err, errlen, "%s: %s", shown,
             n > MAX_BYTES        ? "larger than the largest map blob"
             : (n & 3u) || n < 16 ? "not a whole number of 32-bit words"
                                  : "size does not match the header");
    return -1;
  }
  return 0;
}

/* The plant's map from the blob's grid (float values, as the core sees). */
static plant_fluxmap_t *plant_map(const flux_map_t *m, const char *shown, char *err,
                                  size_t errlen) {
  const size_t n = (size_t)m->nd * m->nq;
  double *pd = malloc(2 * n * sizeof *pd);
  if (pd == NULL) {
    snprintf(err, errlen, "%s: out of memory", shown);
    return NULL;
  }
  for (size_t o = 0; o < n; ++o) {
    float a, b;
    memcpy(&a, &m->psi_d[o], sizeof a);
    memcpy(&b, &m->psi_q[o], sizeof b);
    pd[o] = a;
    pd[n + o] = b;
  }
  const plant_fluxmap_grid_t g = {(int)m->nd, (int)m->nq, m->id0, m->did,
                                  m->iq0,     m->diq,     pd,     pd + n};
  plant_fluxmap_t *pm = NULL;
  char why[256];
  if (plant_fluxmap_create(&g, &pm, why, sizeof why) != 0) {
    snprintf(err, errlen, "%s: the plant cannot invert it: %s", shown, why);
    pm = NULL;
  }
  free(pd);
  return pm;
}

/* The blob in w (n bytes, a buffer of MAX_BYTES + 4 the entry takes on
 * success) checked, parsed and inverted for the plant into *e. */
static int load_words(uint32_t *w, size_t n, const char *shown, map_load_t *e, char *err,
                      size_t errlen) {
  if (check_blob(w, n, shown, err, errlen) != 0) {
    return -1;
  }
  flux_map_status_t st;
  if (flux_map_parse(&e->map, w, (uint32_t)n, &st) != 0) {
    if (st.k >= 0) {
      snprintf(err, errlen, "%s: %s at grid cell (%d, %d)", shown, flux_map_err_str(st.code), st.j,
               st.k);
    } else if (st.j >= 0) {
      snprintf(err, errlen, "%s: %s (at %d)", shown, flux_map_err_str(st.code), st.j);
    } else {
      snprintf(err, errlen, "%s: %s", shown, flux_map_err_str(st.code));
    }
    return -1;
  }
  e->plant = plant_map(&e->map, shown, err, errlen);
  if (e->plant == NULL) {
    return -1;
  }
  e->words = w;
  e->size = (uint32_t)n;
  return 0;
}

int map_load_bytes(const void *bytes, size_t n, const char *shown, map_load_t *e, char *err,
                   size_t errlen) {
  memset(e, 0, sizeof *e);
  if (n > MAX_BYTES) {
    snprintf(err, errlen, "%s: larger than the largest map blob", shown);
    return -1;
  }
  uint32_t *w = calloc(MAX_BYTES / 4 + 1, 4);
  if (w == NULL) {
    snprintf(err, errlen, "%s: out of memory", shown);
    return -1;
  }
  if (n > 0u) {
    memcpy(w, bytes, n);
  }
  if (load_words(w, n, shown, e, err, errlen) != 0) {
    free(w);
    return -1;
  }
  return 0;
}

void map_load_release(map_load_t *e) {
  plant_fluxmap_free(e->plant);
  free((void *)e->words); /* map_load_bytes allocated it */
  memset(e, 0, sizeof *e);
}

const map_load_t *map_load(const char *file, const char *origin, int pole_pairs, char *err,
                           size_t errlen) {
  char path[512];
  if (resolve(file, origin, path, sizeof path) != 0) {
    snprintf(err, errlen,
             "%s: cannot open (relative paths: from the scenario's folder or the "
             "repository)",
             file);
    return NULL;
  }
  const int tool = ends_with(path, ".npz") || ends_with(path, ".csv");
  const int pp_asked = tool && pole_pairs > 0 ? pole_pairs : 0; /* a blob has its own */
  for (int k = 0; k < n_loaded; ++k) {
    if (strcmp(loaded[k].path, path) == 0 && loaded[k].pole_pairs_asked == pp_asked) {
      return &loaded[k];
    }
  }
  if (n_loaded >= MAP_LOAD_MAX) {
    snprintf(err, errlen, "%s: more than %d map files in one process", file, MAP_LOAD_MAX);
    return NULL;
  }
  if (!tool && !ends_with(path, ".fdmap")) {
    snprintf(err, errlen, "%s: unknown map format (.fdmap, .npz, .csv)", file);
    return NULL;
  }
  char tmp[64] = "";
  if (tool && convert(path, pp_asked, tmp, sizeof tmp, err, errlen) != 0) {
    return NULL;
  }
  map_load_t *e = &loaded[n_loaded];
  size_t n = 0;
  uint32_t *w = read_file(tool ? tmp : path, file, &n, err, errlen);
  if (tool) {
    remove(tmp);
  }
  if (w == NULL) {
    return NULL;
  }
  if (load_words(w, n, file, e, err, errlen) != 0) {
    free(w);
    return NULL;
  }
  snprintf(e->path, sizeof e->path, "%s", path);
  e->pole_pairs_asked = pp_asked;
  n_loaded++;
  return e;
}
