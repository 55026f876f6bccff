/*
 * drive_params.h - the drive's parameters by CAN id (PARAM_REQ): the
 * descriptors of drive_config.h applied to a running drive_t.
 *
 * A write is checked against the parameter's range and access, then the
 * whole set is validated (drive_request_config: relations between fields,
 * the law in force still available) and posted to the ISR, which applies
 * it at its next period. Access:
 *   DRIVE_PARAM_RO    read only
 *   DRIVE_PARAM_IDLE  written with the gates off only (idle or fault)
 *   DRIVE_PARAM_LIVE  also while running
 * The numbers and names are those of the REPLY.reply_param value table in
 * can/fluxdrive.dbc, generated from the same table (tests: params/agreement).
 */
#ifndef FLUXDRIVE_DRIVE_PARAMS_H
#define FLUXDRIVE_DRIVE_PARAMS_H

#include <stdint.h>

#include "drive.h"

typedef enum {
  DRIVE_PARAM_OK = 0,
  DRIVE_PARAM_UNKNOWN,      /* no such id */
  DRIVE_PARAM_READ_ONLY,    /* DRIVE_PARAM_RO */
  DRIVE_PARAM_RANGE,        /* outside [min, max], not finite, not an integer */
  DRIVE_PARAM_RUNNING,      /* DRIVE_PARAM_IDLE while the drive is enabled */
  DRIVE_PARAM_INCONSISTENT, /* the set was refused (*err) */
} drive_param_status_t;

/* Value requested last (in force once the ISR has taken it). */
drive_param_status_t drive_params_get(const drive_t *drv, uint8_t id, float *value);
/* Validated write; *err (may be NULL) names the field and the reason when
 * the set is refused. Nothing changes unless DRIVE_PARAM_OK. */
drive_param_status_t drive_params_set(drive_t *drv, uint8_t id, float value,
                                      drive_config_err_t *err);

#endif
