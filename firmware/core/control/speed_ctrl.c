/*
 * speed_ctrl.c - speed PI -> torque reference with a slew-limited speed
 * reference and dynamic torque limits (anti-windup through pi_ctrl).
 */
#include "control/speed_ctrl.h"

#include <math.h>

#include "math/fd_math.h"

FD_COLD void speed_ctrl_init(speed_ctrl_t *sc, const speed_ctrl_cfg_t *cfg) {
  sc->cfg = *cfg;
  const float tm = fabsf(cfg->torque_max);
  sc->cfg.torque_max = tm;
  pi_ctrl_init(&sc->pi, cfg->kp, cfg->ki, cfg->ts, -tm, tm);
  sc->w_ref_ramped = 0.0f;
  sc->inv_ts = 1.0f / cfg->ts;
}

FD_COLD void speed_ctrl_retune(speed_ctrl_t *sc, const speed_ctrl_cfg_t *cfg) {
  sc->cfg = *cfg;
  sc->cfg.torque_max = fabsf(cfg->torque_max);
  sc->pi.kp = cfg->kp;
  sc->pi.ki = cfg->ki;
  sc->pi.ts = cfg->ts;
  sc->inv_ts = 1.0f / cfg->ts;
}

/* pi_ctrl_set_limits(-tm, tm) then pi_ctrl_reset(torque_now), in line: tm
 * = |torque_max| is never below -tm, so of set_limits' cases only a NaN
 * (the limits kept) can arise. The drive's first speed-loop period runs
 * it with the loop and the law's MTPA on the new torque (issue 24 point
 * 8: the sensorless worst case). */
void speed_ctrl_reset(speed_ctrl_t *sc, float w_meas, float torque_now) {
  const float tm = sc->cfg.torque_max;
  pi_ctrl_t *pi = &sc->pi;
  if (!isnan(tm)) {
    pi->out_min = -tm;
    pi->out_max = tm;
  }
  /* zero error -> output = torque_now */
  pi->integ = fd_isfinite(torque_now) ? pi_ctrl_clamp(torque_now, pi->out_min, pi->out_max) : 0.0f;
  sc->w_ref_ramped = fd_isfinite(w_meas) ? w_meas : 0.0f;
}

/* Open loop (kp s + ki)/(J s^2): kp = J wb puts the crossover near wb, the
 * PI zero ki/kp = wb/4 keeps ~76 deg of phase margin. The closed loop has a
 * double pole at wb/2 (critically damped): J s^2 + kp s + ki. */
void speed_ctrl_design(speed_ctrl_cfg_t *cfg, float j, float wb) {
  cfg->kp = j * wb;
  cfg->ki = cfg->kp * wb * 0.25f;
  cfg->j_ff = j;
}

float speed_ctrl_update(speed_ctrl_t *sc, float w_ref, float w, float t_min, float t_max) {
  const float tm = sc->cfg.torque_max;
  const float step = sc->cfg.accel_max * sc->cfg.ts;
  const float w_prev = sc->w_ref_ramped;
  if (fd_isfinite(w_ref)) {
    const float dw = w_ref - sc->w_ref_ramped;
    if (dw > step) {
      sc->w_ref_ramped += step;
    } else if (dw < -step) {
      sc->w_ref_ramped -= step;
    } else {
      sc->w_ref_ramped = w_ref;
    }
  }
  /* dynamic limits, clamped to the static one; NaN means "no extra limit" */
  const float hi = (t_max < tm) ? t_max : tm;
  const float lo = (t_min > -tm) ? t_min : -tm;
  /* set_limits and update in line (pi_ctrl.h): the loop's ISR is the
   * drive's worst (issue 24 point 8) */
  pi_ctrl_limits_in(&sc->pi, lo, hi);
  /* Acceleration feed-forward J dw_ref/dt: the PI integral need not carry the
   * ramp's torque, so it does not overshoot when the ramp ends. */
  /* Clamped to the limits in force: an infeasible ramp (a speed step) would
   * otherwise ask for J dw/dt far beyond them and the anti-windup park the
   * integral at limit - FF (-4000 N m for a 2625 rpm step), reversing the
   * torque when the ramp ends. */
  const float t_acc = fd_clampf(sc->cfg.j_ff * (sc->w_ref_ramped - w_prev) * sc->inv_ts, lo, hi);
  return pi_ctrl_step(&sc->pi, sc->w_ref_ramped - w, t_acc, sc->pi.out_min, sc->pi.out_max);
}
