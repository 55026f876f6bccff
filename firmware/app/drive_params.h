/*
 * drive_params.h - the drive's parameters by number, for the CAN protocol:
 * a table of (id, name, field of drive_config_t, range, access).
 *
 * A write is checked against the parameter's range, then the whole set is
 * validated by drive_config_check() on a copy (so i_max above i_trip is
 * refused) and applied through drive_set_config(). Access:
 *   DRIVE_PARAM_RO    read only (timing: ts, slow_div)
 *   DRIVE_PARAM_IDLE  written with the gates off only (idle or fault): the
 *                     control laws, PLL and speed loop are re-derived
 *   DRIVE_PARAM_LIVE  also while running (protections, limits, speed loop)
 * The numbers and names are those of the REPLY.reply_param value table in
 * can/fluxdrive.dbc (tests/can checks they agree).
 */
#ifndef FLUXDRIVE_DRIVE_PARAMS_H
#define FLUXDRIVE_DRIVE_PARAMS_H

#include <stdint.h>

#include "drive.h"

typedef enum {
  DRIVE_PARAM_RO = 0,
  DRIVE_PARAM_IDLE = 1,
  DRIVE_PARAM_LIVE = 2
} drive_param_access_t;
typedef enum { DRIVE_PARAM_F32 = 0, DRIVE_PARAM_U16 = 1 } drive_param_type_t;

typedef struct {
  const char *name;
  float min, max;
  uint16_t offset; /* offsetof(drive_config_t, field) */
  uint8_t id;
  uint8_t type;   /* drive_param_type_t */
  uint8_t access; /* drive_param_access_t */
} drive_param_t;

typedef enum {
  DRIVE_PARAM_OK = 0,
  DRIVE_PARAM_UNKNOWN,      /* no such id */
  DRIVE_PARAM_READ_ONLY,    /* DRIVE_PARAM_RO */
  DRIVE_PARAM_RANGE,        /* outside [min, max], not finite, not an integer for U16 */
  DRIVE_PARAM_RUNNING,      /* DRIVE_PARAM_IDLE while the drive is enabled */
  DRIVE_PARAM_INCONSISTENT, /* drive_config_check refused the set (*field) */
} drive_param_status_t;

/* The table, its length, lookup by id (NULL if unknown). */
const drive_param_t *drive_params_table(unsigned *count);
const drive_param_t *drive_params_find(uint8_t id);

/* Value in force. DRIVE_PARAM_OK or DRIVE_PARAM_UNKNOWN. */
drive_param_status_t drive_params_get(const drive_t *drv, uint8_t id, float *value);
/* Validated write (see above); *field names the parameter drive_config_check
 * refused (field may be NULL). Nothing changes unless DRIVE_PARAM_OK. */
drive_param_status_t drive_params_set(drive_t *drv, uint8_t id, float value, const char **field);

#endif
