/*
 * drive_config.h - the drive's parameter set: the struct generated from the
 * parameter table (drive_param_table.h), its defaults, the descriptors of
 * its fields and its validation.
 */
#ifndef FLUXDRIVE_DRIVE_CONFIG_H
#define FLUXDRIVE_DRIVE_CONFIG_H

#include <stdint.h>

#include "drive_enums.h"
#include "drive_param_table.h"
#include "model/flux_map.h"

#define DRIVE_PARAM_CTYPE_F32  float
#define DRIVE_PARAM_CTYPE_U16  uint16_t
#define DRIVE_PARAM_CTYPE_U32  uint32_t
#define DRIVE_PARAM_CTYPE_LAW  drive_law_t
#define DRIVE_PARAM_CTYPE_MODE drive_mode_t
#define DRIVE_PARAM_CTYPE_POS  pos_source_t
#define DRIVE_PARAM_CTYPE_MAP  const uint32_t *

/* One field per row of DRIVE_PARAM_TABLE, in table order. */
typedef struct {
#define DRIVE_CONFIG_FIELD(id, name, type, ...) DRIVE_PARAM_CTYPE_##type name;
  DRIVE_PARAM_TABLE(DRIVE_CONFIG_FIELD)
#undef DRIVE_CONFIG_FIELD
} drive_config_t;

/* Number of parameters (rows of the table): "0 +1 +1 ...", the bare "+1"
 * is the point of this arm. */
#define DRIVE_PARAM_ONE(...) +1 // NOLINT(bugprone-macro-parentheses)
enum { DRIVE_PARAM_COUNT = 0 DRIVE_PARAM_TABLE(DRIVE_PARAM_ONE) };
#undef DRIVE_PARAM_ONE

typedef enum {
  DRIVE_PARAM_F32 = 0,
  DRIVE_PARAM_U16,
  DRIVE_PARAM_U32,
  DRIVE_PARAM_LAW,
  DRIVE_PARAM_MODE,
  DRIVE_PARAM_POS,
  DRIVE_PARAM_MAP
} drive_param_type_t;

typedef enum {
  DRIVE_PARAM_RO = 0,
  DRIVE_PARAM_IDLE = 1,
  DRIVE_PARAM_LIVE = 2
} drive_param_access_t;

/* A row of the table as data. min/max of an enum are 0 and count - 1. */
typedef struct {
  const char *name;
  const char *unit;
  const char *scenario; /* scenario key, "section.key" */
  const char *doc;
  float def, min, max;
  uint16_t offset; /* offsetof(drive_config_t, name) */
  uint8_t id;
  uint8_t type;   /* drive_param_type_t */
  uint8_t access; /* drive_param_access_t */
} drive_param_t;

/* The table, its length; lookup by CAN id and by name (NULL if unknown). */
const drive_param_t *drive_params_table(unsigned *count);
const drive_param_t *drive_params_find(uint8_t id);
const drive_param_t *drive_params_by_name(const char *name);
/* Field value as float (integers and enums converted exactly; a map: the
 * low 24 bits of its blob's CRC word, 0 for none). */
float drive_param_get(const drive_config_t *cfg, const drive_param_t *p);
/* Sets the field from a float, without any check (a map: 0 clears it,
 * other values leave it as it is: a blob is not a number). */
void drive_param_set(drive_config_t *cfg, const drive_param_t *p, float v);
/* 1 when v is finite, inside [min, max] and, for integer and enum types,
 * an integer. */
int drive_param_in_range(const drive_param_t *p, float v);

/* Why a parameter set was refused: the field and a short reason (static
 * strings). field is "" when the set is valid. */
typedef struct {
  const char *field;
  const char *reason;
} drive_config_err_t;

/* The table's defaults (Rubino 2020, Table I machine). */
void drive_config_default(drive_config_t *cfg);
/* 0 when valid, else -1 with *err naming the first bad field: its range
 * (table) first, then the relations between fields. err may be NULL. */
int drive_config_check(const drive_config_t *cfg, drive_config_err_t *err);
/* The flux map of cfg parsed into *map: 0 when cfg has a valid map, 1 when
 * it has none (linear machine), -1 with *err when the blob is refused. */
int drive_config_map(const drive_config_t *cfg, flux_map_t *map, drive_config_err_t *err);

#endif
