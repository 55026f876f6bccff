/*
 * drive_params.c - the parameter table and validated get/set.
 */
#include "drive_params.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define F  DRIVE_PARAM_F32
#define U  DRIVE_PARAM_U16
#define RO DRIVE_PARAM_RO
#define ID DRIVE_PARAM_IDLE
#define LV DRIVE_PARAM_LIVE
#define P(id, field, type, access, lo, hi)                                                         \
  {                                                                                                \
#field, lo, hi, (uint16_t)offsetof(drive_config_t, field), id, (uint8_t)(type),                \
        (uint8_t)(access)                                                                          \
  }

/* Ranges: what drive_config_check accepts for the field alone; the checks
 * between fields (i_trip >= i_max ...) are drive_config_check's. */
static const drive_param_t table[] = {
    /* machine (the controller's estimates) */
    P(1, pole_pairs, F, ID, 1.0f, 100.0f),
    P(2, rs, F, ID, 1e-5f, 1e3f),
    P(3, ld, F, ID, 1e-7f, 10.0f),
    P(4, lq, F, ID, 1e-7f, 10.0f),
    P(5, lambda_m, F, ID, 0.0f, 10.0f),
    P(6, inertia, F, ID, 1e-9f, 1e3f),
    /* limits and protections */
    P(10, i_max, F, ID, 1e-3f, 1e4f),
    P(11, torque_max, F, LV, 0.0f, 1e5f),
    P(12, speed_max, F, LV, 0.0f, 1e5f),
    P(13, v_margin, F, ID, 0.1f, 1.0f),
    P(14, i_trip, F, LV, 1e-3f, 1e4f),
    P(15, v_dc_max, F, LV, 1.0f, 1e4f),
    P(16, v_dc_min, F, LV, 0.0f, 1e4f),
    P(17, speed_trip, F, LV, 1e-3f, 1e5f),
    P(18, offset_max, F, LV, 0.0f, 1e3f),
    P(19, delta_max, F, ID, 0.1f, 1.5f),
    P(20, vsd_max, F, ID, 0.0f, 1e4f),
    P(21, flux_min, F, ID, 0.0f, 10.0f),
    /* controller gains */
    P(30, current_bw, F, ID, 1.0f, 1e5f),
    P(31, speed_bw, F, LV, 0.1f, 1e5f),
    P(32, accel_max, F, LV, 1e-3f, 1e7f),
    P(33, pll_bw, F, ID, 1.0f, 1e5f),
    P(34, flux_obs_wc, F, ID, 0.0f, 1e5f),
    P(35, dfvc_flux_bw, F, ID, 1.0f, 1e5f),
    P(36, dfvc_iqs_bw, F, ID, 1.0f, 1e5f),
    P(37, enc_offset, F, ID, -7.0f, 7.0f),
    /* timing and calibration */
    P(40, ts, F, RO, 1e-6f, 1e-2f),
    P(41, slow_div, U, RO, 1.0f, 1000.0f),
    P(42, dead_time, F, ID, 0.0f, 2.5e-3f),
    P(43, offset_samples, U, ID, 1.0f, 60000.0f),
};

const drive_param_t *drive_params_table(unsigned *count) {
  *count = (unsigned)(sizeof table / sizeof table[0]);
  return table;
}

const drive_param_t *drive_params_find(uint8_t id) {
  for (unsigned i = 0; i < sizeof table / sizeof table[0]; ++i) {
    if (table[i].id == id) {
      return &table[i];
    }
  }
  return NULL;
}

static float read_field(const drive_config_t *cfg, const drive_param_t *p) {
  const unsigned char *base = (const unsigned char *)cfg + p->offset;
  if (p->type == DRIVE_PARAM_U16) {
    uint16_t u;
    memcpy(&u, base, sizeof u);
    return (float)u;
  }
  float f;
  memcpy(&f, base, sizeof f);
  return f;
}

static void write_field(drive_config_t *cfg, const drive_param_t *p, float v) {
  unsigned char *base = (unsigned char *)cfg + p->offset;
  if (p->type == DRIVE_PARAM_U16) {
    uint16_t u = (uint16_t)v;
    memcpy(base, &u, sizeof u);
  } else {
    memcpy(base, &v, sizeof v);
  }
}

drive_param_status_t drive_params_get(const drive_t *drv, uint8_t id, float *value) {
  const drive_param_t *p = drive_params_find(id);
  if (p == NULL) {
    return DRIVE_PARAM_UNKNOWN;
  }
  *value = read_field(&drv->cfg, p);
  return DRIVE_PARAM_OK;
}

drive_param_status_t drive_params_set(drive_t *drv, uint8_t id, float value, const char **field) {
  const char *dummy = "";
  if (field == NULL) {
    field = &dummy;
  }
  *field = "";
  const drive_param_t *p = drive_params_find(id);
  if (p == NULL) {
    return DRIVE_PARAM_UNKNOWN;
  }
  if (p->access == DRIVE_PARAM_RO) {
    return DRIVE_PARAM_READ_ONLY;
  }
  if (!isfinite(value) || value < p->min || value > p->max ||
      (p->type == DRIVE_PARAM_U16 && fabsf(value - roundf(value)) > 0.0f)) {
    return DRIVE_PARAM_RANGE;
  }
  bool running = drv->state == DRIVE_STATE_RUN || drv->state == DRIVE_STATE_OFFSET_CAL;
  if (running && p->access != DRIVE_PARAM_LIVE) {
    return DRIVE_PARAM_RUNNING;
  }
  drive_config_t next = drv->cfg;
  write_field(&next, p, value);
  if (drive_set_config(drv, &next, field) != 0) {
    return DRIVE_PARAM_INCONSISTENT;
  }
  return DRIVE_PARAM_OK;
}
