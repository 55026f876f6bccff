/*
 * drive_params.c - parameter get/set by CAN id on a running drive (main
 * loop side; drive_params.h).
 */
#include "drive_params.h"

#include <stddef.h>

drive_param_status_t drive_params_get(const drive_t *drv, uint8_t id, float *value) {
  const drive_param_t *p = drive_params_find(id);
  if (p == NULL) {
    return DRIVE_PARAM_UNKNOWN;
  }
  *value = drive_param_get(drive_requested_config(drv), p);
  return DRIVE_PARAM_OK;
}

drive_param_status_t drive_params_set(drive_t *drv, uint8_t id, float value,
                                      drive_config_err_t *err) {
  drive_config_err_t dummy = {"", ""};
  if (err == NULL) {
    err = &dummy;
  }
  const drive_param_t *p = drive_params_find(id);
  if (p == NULL) {
    return DRIVE_PARAM_UNKNOWN;
  }
  if (p->access == DRIVE_PARAM_RO) {
    return DRIVE_PARAM_READ_ONLY;
  }
  if (!drive_param_in_range(p, value)) {
    return DRIVE_PARAM_RANGE;
  }
  /* the ISR's state, one word: a race with a start only delays the
   * non-LIVE part until the gates are off again (drive.h) */
  if (drive_state_enabled(drv->state) && p->access != DRIVE_PARAM_LIVE) {
    return DRIVE_PARAM_RUNNING;
  }
  drive_config_t next = *drive_requested_config(drv);
  drive_param_set(&next, p, value);
  if (drive_request_config(drv, &next, err) != 0) {
    return DRIVE_PARAM_INCONSISTENT;
  }
  return DRIVE_PARAM_OK;
}
