/*
 * scenario_params.c - a parameter file over a scenario's drive
 * (scenario_params.h).
 */
#include "scenario_params.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drive.h"
#include "map_load.h"

static char *read_text(const char *path, char *err, size_t errlen) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    snprintf(err, errlen, "%s: cannot open", path);
    return NULL;
  }
  enum { MAX_SIZE = 1 << 16 };
  char *buf = malloc(MAX_SIZE + 1);
  const size_t n = buf != NULL ? fread(buf, 1, MAX_SIZE + 1, f) : 0;
  fclose(f);
  if (buf == NULL || n > MAX_SIZE) {
    snprintf(err, errlen, "%s: %s", path, buf == NULL ? "out of memory" : "larger than 64 KiB");
    free(buf);
    return NULL;
  }
  buf[n] = '\0';
  return buf;
}

/* An enumeration's value by name: its index, or -1. */
static int enum_index(const drive_param_t *p, const char *name) {
  for (unsigned v = 0; v <= (unsigned)p->max; ++v) {
    const char *n = p->type == DRIVE_PARAM_LAW    ? drive_law_name(v)
                    : p->type == DRIVE_PARAM_MODE ? drive_mode_name(v)
                                                  : drive_pos_source_name(v);
    if (n != NULL && strcmp(n, name) == 0) {
      return (int)v;
    }
  }
  return -1;
}

static int apply_one(drive_config_t *d, const scenario_t *sc, const cJSON *it, const char *path,
                     char *err, size_t errlen) {
  if (strcmp(it->string, "map") == 0) {
    if (!cJSON_IsString(it)) {
      snprintf(err, errlen, "%s: map: must be a flux-map file name", path);
      return -1;
    }
    if (sc->plant.machine.map == NULL) {
      snprintf(err, errlen, "%s: map: needs a flux-map machine in the scenario", path);
      return -1;
    }
    char why[640];
    const int pp = sc->plant.machine.pole_pairs;
    const map_load_t *e = map_load(it->valuestring, path, pp, why, sizeof why);
    if (e == NULL) {
      snprintf(err, errlen, "%s: map: %s", path, why);
      return -1;
    }
    if (e->map.pole_pairs != (float)pp) {
      snprintf(err, errlen, "%s: map: %s has %g pole pairs, the machine %d", path, it->valuestring,
               (double)e->map.pole_pairs, pp);
      return -1;
    }
    d->machine_map = e->words;
    return 0;
  }
  const drive_param_t *p = drive_params_by_name(it->string);
  if (p == NULL) {
    snprintf(err, errlen, "%s: %s: not a drive parameter (docs/parameters.md)", path, it->string);
    return -1;
  }
  if (p->type == DRIVE_PARAM_MAP) {
    snprintf(err, errlen, "%s: %s: give the drive's map as \"map\": FILE", path, it->string);
    return -1;
  }
  const bool named =
      p->type == DRIVE_PARAM_LAW || p->type == DRIVE_PARAM_MODE || p->type == DRIVE_PARAM_POS;
  float v;
  if (named) {
    const int k = cJSON_IsString(it) ? enum_index(p, it->valuestring) : -1;
    if (k < 0) {
      snprintf(err, errlen, "%s: %s: must be one of the names in docs/parameters.md", path,
               it->string);
      return -1;
    }
    v = (float)k;
  } else {
    if (!cJSON_IsNumber(it)) {
      snprintf(err, errlen, "%s: %s: must be a number", path, it->string);
      return -1;
    }
    v = (float)it->valuedouble;
  }
  if (!drive_param_in_range(p, v)) {
    snprintf(err, errlen, "%s: %s: %g outside [%g, %g]%s", path, it->string, it->valuedouble,
             (double)p->min, (double)p->max, p->type == DRIVE_PARAM_F32 ? "" : " (an integer)");
    return -1;
  }
  drive_param_set(d, p, v);
  return 0;
}

int scenario_apply_params(scenario_t *sc, const char *path, char *err, size_t errlen) {
  char *text = read_text(path, err, errlen);
  if (text == NULL) {
    return -1;
  }
  cJSON *root = cJSON_ParseWithOpts(text, NULL, 1);
  free(text);
  if (!cJSON_IsObject(root)) {
    snprintf(err, errlen, "%s: not a JSON object of parameters", path);
    cJSON_Delete(root);
    return -1;
  }
  drive_config_t d = sc->drive;
  int r = 0;
  for (const cJSON *it = root->child; it != NULL && r == 0; it = it->next) {
    /* "identified": the commissioning's record (fluxdrive commission), not a parameter */
    r = strcmp(it->string, "identified") == 0 ? 0 : apply_one(&d, sc, it, path, err, errlen);
  }
  cJSON_Delete(root);
  if (r == 0) {
    sc->drive = d;
  }
  return r;
}
