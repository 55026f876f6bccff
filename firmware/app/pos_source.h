/*
 * pos_source.h - where the rotor angle comes from, behind one table of
 * sources {name, capabilities, init, reset, update, align}; one row per
 * entry of POS_SOURCE_LIST (drive_enums.h). The encoder today; the
 * sensorless sources (Direct Flux Control, IVD, Kalman filter) come as more
 * rows with the same estimate.
 *
 * Every period the source turns the HAL's sample set into an estimate
 * {theta, omega, t, valid, health}: the electrical angle at instant t of the
 * period (relative to its start, as the HAL's timestamps), the electrical
 * speed, whether the estimate can be used, and the distance of this
 * period's measurement from the source's own prediction (a plausibility
 * measure: the drive raises the `position` fault beyond pos_err_max).
 */
#ifndef FLUXDRIVE_POS_SOURCE_H
#define FLUXDRIVE_POS_SOURCE_H

#include <stdbool.h>
#include <stdint.h>

#include "drive_config.h"
#include "estimation/angle_pll.h"
#include "hal.h"

typedef struct {
  float theta;  /* electrical angle at t [rad], (-pi, pi] */
  float omega;  /* electrical speed [rad/s] (smooth: protections, laws) */
  float rate;   /* angle rate over the last period [rad/s] (no lag; average it) */
  float t;      /* instant of theta after the period start [s] */
  bool valid;   /* false: no usable measurement this period */
  float health; /* |measurement - prediction| [rad electrical] */
} pos_estimate_t;

enum {
  POS_CAP_ALIGN = 1u << 0 /* the angle offset can be found by an alignment */
};

typedef union {
  struct {
    angle_pll_t pll;
    float offset; /* electrical angle at encoder zero in force [rad] */
    float half;   /* half a count [rad mechanical] */
    bool started; /* the PLL has seen a measurement since reset */
  } enc;
} pos_state_t;

typedef struct {
  const char *name;
  uint32_t caps; /* POS_CAP_* */
  void (*init)(pos_state_t *s, const drive_config_t *cfg);
  void (*reset)(pos_state_t *s);
  void (*update)(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                 pos_estimate_t *out);
  /* The rotor is held at electrical angle theta: take it as the reference
   * (alignment). Only for POS_CAP_ALIGN. */
  void (*align)(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp, float theta);
} pos_source_row_t;

/* The row of a source (NULL out of range). */
const pos_source_row_t *pos_source(pos_source_t src);

#endif
