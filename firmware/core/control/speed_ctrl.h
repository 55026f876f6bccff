/*
 * speed_ctrl.h - speed PI producing a torque reference, with a reference
 * slew-rate (acceleration) limit and torque-limit feedback: the torque
 * limits may change every call (e.g. from the DFVC's MTPV limit) and the
 * integrator never winds up against them. The slew-limited reference's
 * acceleration times j_ff is fed forward, so a ramp ends without overshoot.
 */
#ifndef FD_CONTROL_SPEED_CTRL_H
#define FD_CONTROL_SPEED_CTRL_H

#include "math/pi_ctrl.h"

typedef struct {
  float kp;         /* [N m s/rad] */
  float ki;         /* [N m/rad] */
  float ts;         /* speed-loop period [s] */
  float accel_max;  /* reference slew limit [rad/s^2], mechanical */
  float torque_max; /* static torque limit [N m] */
  float j_ff;       /* inertia for the acceleration feed-forward [kg m^2], 0 = none */
} speed_ctrl_cfg_t;

typedef struct {
  speed_ctrl_cfg_t cfg;
  pi_ctrl_t pi;
  float w_ref_ramped; /* slew-limited speed reference [rad/s] */
  float inv_ts;       /* 1 / cfg.ts: the feed-forward's derivative without a division */
} speed_ctrl_t;

void speed_ctrl_init(speed_ctrl_t *sc, const speed_ctrl_cfg_t *cfg);
/* New gains and limits while running (a LIVE parameter): the integral and
 * the ramp carry on. */
void speed_ctrl_retune(speed_ctrl_t *sc, const speed_ctrl_cfg_t *cfg);
/* Bumpless start from the measured speed and the torque in force. */
void speed_ctrl_reset(speed_ctrl_t *sc, float w_meas, float torque_now);
/* Gains from inertia J and desired bandwidth wb (PI zero at wb/4). */
void speed_ctrl_design(speed_ctrl_cfg_t *cfg, float j, float wb);
/* w_ref, w: mechanical speed [rad/s]; t_min/t_max: dynamic torque limits
 * (clamped again to +-torque_max). Returns the torque reference [N m]. */
float speed_ctrl_update(speed_ctrl_t *sc, float w_ref, float w, float t_min, float t_max);

#endif
