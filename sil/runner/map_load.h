/*
 * map_load.h - flux maps for the SIL: a scenario's `machine.map` file into
 * the blob the drive parses (the same bytes and the same parser,
 * flux_map_parse, as a board build's linked table) and the plant's inverse
 * map built from that blob's grid (sil/plant/plant_fluxmap.h).
 *
 * Files: `.fdmap` is read as it is; `.npz` and `.csv` go through the map
 * tool at start-up (`PYTHON -m fluxdrive map convert FILE -o TMP.fdmap`,
 * PYTHON from $FLUXDRIVE_PYTHON, else the build's tools venv, else
 * python3): the generator path of the board builds, so that SIL and
 * firmware see identical numbers. A relative path is taken from the
 * scenario file's folder, then from the repository root.
 *
 * Loaded maps are kept for the life of the process (the drive's parameter
 * set and the plant point into them), one entry per file, at most
 * MAP_LOAD_MAX files.
 */
#ifndef FD_SIL_MAP_LOAD_H
#define FD_SIL_MAP_LOAD_H

#include <stddef.h>
#include <stdint.h>

#include "model/flux_map.h"
#include "plant_fluxmap.h"

#define MAP_LOAD_MAX 8

typedef struct {
  char path[512];         /* the file as resolved */
  const uint32_t *words;  /* the blob (the drive's machine_map) */
  uint32_t size;          /* its bytes */
  int pole_pairs_asked;   /* the pole pairs given the map tool (0: the file's) */
  flux_map_t map;         /* parsed (for the runner's own use) */
  plant_fluxmap_t *plant; /* the plant's map */
} map_load_t;

/* Loads (or finds loaded) the map `file` of a scenario read from `origin`
 * (a path, or a name without folder). pole_pairs > 0: the scenario's, given
 * the map tool for a .npz / .csv (`--pole-pairs`: a file without them takes
 * them, a file with others is refused naming both); a .fdmap has its own
 * (the caller compares). NULL with a message in err (naming the file, the
 * check and the grid cell) on failure. */
const map_load_t *map_load(const char *file, const char *origin, int pole_pairs, char *err,
                           size_t errlen);

/* The same checks, parse and plant map for a file's contents in memory (n
 * bytes), into *e without the cache (e->path empty); 0, or -1 with a
 * message naming `shown`. map_load_release() frees what it holds. */
int map_load_bytes(const void *bytes, size_t n, const char *shown, map_load_t *e, char *err,
                   size_t errlen);
void map_load_release(map_load_t *e);

#endif
