/*
 * proc_flux.c - identification of the PM flux lambda_m with an encoder
 * (issue 25 f): the rotor spun by the current loop on the encoder (the
 * identified offset and pole pairs in force) at id_speed, forward and
 * back, a speed loop (P) on the q current and a d current i_d = 0.7 i
 * (i = id_i_test); over a window of steady speed the mean rotor-frame
 * voltage asked v, current i and electrical speed w (the encoder's
 * change over the window) give lambda_m from the steady-state model
 *   v_d = R_s i_d - w L_q i_q + e_d,  v_q = R_s i_q + w L_d i_d + w lambda_m + e_q
 * (e: the inverter's voltage error, along -i for dead time and device
 * drops: the fundamental of -sgn(i_x) per phase). The component of v
 * across the current, n = (-i_q, i_d) / |i|, has neither R_s i nor e:
 *   v . n = w |i| (L_q u_q^2 + L_d u_d^2) + w lambda_m u_d,  u = i / |i|,
 * so lambda_m = (v . n / w - |i| (L_q u_q^2 + L_d u_d^2)) / u_d with L_d,
 * L_q from the parameter set (the ldq procedure's); the d current keeps
 * u_d near 1. The two directions are averaged: an error of the encoder's
 * offset eps turns v by eps and adds +-eps R_s i / w terms of opposite
 * sign. (VESC measures lambda from the observer at speed, PMC (rombrew/
 * phobia, pm_probe_spinup / "E" probe) from the back-EMF under its own
 * FOC; both learnt from, not copied.)
 * Error: the inductances' 5 % times L |i| / lambda_m (|i| small), the
 * voltage the modulator writes against the one asked (linear range).
 * Bounds: |i| <= i (tripped above PROC_ID_TRIP i + 5 % i_max), speed
 * id_speed (tripped overspeed above 1.2 id_speed_max), voltage v_max.
 */
#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"
#include "proc.h"

#define PROC_FLUX_ID      0.7f /* the d current and the q current's limit, x i */
#define PROC_FLUX_TRIP    1.3f
#define PROC_FLUX_SETTLE  0.2f  /* at speed before the window [s] */
#define PROC_FLUX_WIN     0.3f  /* the window [s], at least ... */
#define PROC_FLUX_TURNS   4.0f  /* ... this many electrical turns (at most 2 s) */
#define PROC_FLUX_BW      20.0f /* the speed loop's bandwidth [rad/s] */
#define PROC_FLUX_RAMP    1.0f  /* the longest ramp to id_speed [s] ... */
#define PROC_FLUX_ACC     0.3f  /* ... else at this fraction of the torque of i q [rad/s^2] */
#define PROC_FLUX_TIMEOUT 10.0f /* a phase longer: failed (the rotor does not follow) */

/* phases: ramp, settle, measure forward (0 .. 2), the same back (3 .. 5),
 * then the ramp to standstill */
enum { PH_RAMP = 0, PH_SETTLE = 1, PH_MEAS = 2, PH_BACK = 3, PH_STOP = 6 };

FD_COLD static void flux_init(proc_state_t *st, const proc_setup_t *su) {
  proc_flux_t *f = &st->flux;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&f->cc, &ccfg);
  proc_enc_unwrap_reset(&f->u);
  f->n = f->n_all = 0u;
  f->phase = PH_RAMP;
  f->w_ref = 0.0f;
  f->th0 = 0.0f;
  for (unsigned k = 0; k < 4u; ++k) {
    f->sum[k] = 0.0f;
  }
  f->sum_n = 0u;
  f->lam[0] = f->lam[1] = 0.0f;
  f->w[0] = f->w[1] = 0.0f;
  f->limited = 0u;
  f->v_prev = (dq_t){0.0f, 0.0f};
}

/* The ramp's rate [rad/s^2 mechanical]: PROC_FLUX_ACC of the q current's
 * torque over the inertia (parameters), or id_speed in PROC_FLUX_RAMP. */
FD_COLD static float flux_acc(const drive_config_t *c, float lambda_m, float i) {
  const float a_t = PROC_FLUX_ACC * 1.5f * c->pole_pairs * lambda_m * PROC_FLUX_ID * i / c->inertia;
  const float a_min = proc_id_speed(c) / PROC_FLUX_RAMP;
  return a_t > a_min ? a_t : a_min;
}

/* lambda_m from the window's means (the equation above) */
FD_COLD static float flux_lambda(const machine_t *m, const float mean[4], float w) {
  const float i = sqrtf(mean[2] * mean[2] + mean[3] * mean[3]);
  if (!(i > 0.0f) || !(fabsf(w) > 0.0f)) {
    return 0.0f;
  }
  const float ud = mean[2] / i, uq = mean[3] / i;
  /* mut: flux_inductance_term */
  const float vn = -uq * mean[0] + ud * mean[1];
  return (vn / w - i * (m->lq * uq * uq + m->ld * ud * ud)) / ud;
}

FD_COLD static int flux_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                             proc_out_t *out) {
  proc_flux_t *f = &st->flux;
  const drive_config_t *c = su->cfg;
  const float i = proc_id_current(c);
  const float w_id = proc_id_speed(c), w_max = proc_id_speed_max(c);
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  if (!in->pos->valid || !in->s->enc_valid || !fd_isfinite(in->s->enc_angle)) {
    out->fault = DRIVE_FAULT_POSITION;
    return PROC_FAILED;
  }
  const float lim = PROC_FLUX_TRIP * i + 0.05f * c->i_max;
  if (!(in->i_ab.alpha * in->i_ab.alpha + in->i_ab.beta * in->i_ab.beta <= lim * lim)) {
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  const float we = in->pos->omega, wm = we / c->pole_pairs;
  if (!(fabsf(wm) <= 1.2f * w_max)) {
    out->fault = DRIVE_FAULT_OVERSPEED;
    return PROC_FAILED;
  }
  const float th = proc_enc_unwrap(&f->u, in->s->enc_angle);
  const sincos_t sc = frames_sincos(in->pos->theta);
  const dq_t idq = frames_park(in->i_ab, sc);
  const unsigned dir_k = f->phase >= PH_BACK && f->phase < PH_STOP ? 1u : 0u;
  const unsigned ph = f->phase == PH_STOP ? PH_RAMP : f->phase - PH_BACK * dir_k;
  const float target = f->phase == PH_STOP ? 0.0f : (dir_k == 0u ? w_id : -w_id);
  const float acc = flux_acc(c, su->machine->lambda_m, i);
  f->n_all++;
  f->n++;
  if (ph == PH_RAMP) {
    const float dw = acc * c->ts;
    f->w_ref = f->w_ref < target ? fminf(f->w_ref + dw, target) : fmaxf(f->w_ref - dw, target);
    if (!(fabsf(f->w_ref - target) > 0.0f) && fabsf(wm - target) < 0.1f * w_id + 1e-3f) {
      if (f->phase == PH_STOP) {
        out->apply = false;
        return PROC_DONE;
      }
      f->phase++;
      f->n = 0u;
    }
  } else if (ph == PH_SETTLE) {
    if ((float)f->n * c->ts >= PROC_FLUX_SETTLE) {
      f->phase++;
      f->n = 0u;
      f->th0 = th;
      f->sum[0] = f->sum[1] = f->sum[2] = f->sum[3] = 0.0f;
      f->sum_n = 0u;
    }
  } else { /* PH_MEAS: the voltage asked last period acted over it, in its frame */
    f->sum[0] += f->v_prev.d;
    f->sum[1] += f->v_prev.q;
    f->sum[2] += idq.d;
    f->sum[3] += idq.q;
    f->sum_n++;
    f->limited |= (uint8_t)(f->cc.limited != 0);
    const float turn_t = PROC_FLUX_TURNS * 2.0f * FRAMES_PI / (c->pole_pairs * w_id);
    const float t_win = fminf(fmaxf(PROC_FLUX_WIN, turn_t), 2.0f);
    if ((float)f->n * c->ts >= t_win) {
      const float inv = 1.0f / (float)f->sum_n;
      const float mean[4] = {f->sum[0] * inv, f->sum[1] * inv, f->sum[2] * inv, f->sum[3] * inv};
      /* the electrical speed over the window: the encoder's change */
      const float w = c->pole_pairs * (th - f->th0) / ((float)f->sum_n * c->ts);
      f->lam[dir_k] = flux_lambda(su->machine, mean, w);
      f->w[dir_k] = w;
      f->n = 0u;
      f->phase++; /* the ramp back, or to standstill */
    }
  }
  if ((float)f->n * c->ts > PROC_FLUX_TIMEOUT) {
    out->fault = DRIVE_FAULT_LOST_CONTROL; /* the speed was not reached */
    return PROC_FAILED;
  }
  /* the speed loop (P, the parameters' inertia and the machine's torque
   * constant: a flux map's lambda_m at zero current) */
  const float kt = 1.5f * c->pole_pairs * su->machine->lambda_m;
  const float iq_max = PROC_FLUX_ID * i;
  const float iq =
      kt > 0.0f ? fd_clampf(c->inertia * PROC_FLUX_BW * (f->w_ref - wm) / kt, -iq_max, iq_max)
                : 0.0f;
  const dq_t v = current_ctrl_update(&f->cc, (dq_t){PROC_FLUX_ID * i, iq}, idq, we, in->v_max);
  f->v_prev = v;
  /* the voltage acts over the next period: the angle at its centre */
  const sincos_t sc_out = frames_sincos(frames_wrap_pi(in->pos->theta + we * 1.5f * c->ts));
  out->v_ab = frames_park_inv(v, sc_out);
  return PROC_RUNNING;
}

/* result: [0] lambda_m [Vs] (the mean of both directions), [1], [2] forward
 * and back, [3], [4] their electrical speeds [rad/s], [5] the speed
 * reference [rad/s mechanical], [6] 1 when the voltage limit was met in a
 * window (the current not at its reference: lower id_speed) */
FD_COLD static void flux_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_flux_t *f = &st->flux;
  tm->phase = f->phase;
  tm->n = f->n_all;
  const bool both = f->phase >= PH_STOP;
  tm->result[0] = both ? 0.5f * (f->lam[0] + f->lam[1]) : f->lam[0];
  tm->result[1] = f->lam[0];
  tm->result[2] = f->lam[1];
  tm->result[3] = f->w[0];
  tm->result[4] = f->w[1];
  tm->result[5] = f->w_ref;
  tm->result[6] = (float)f->limited;
}

FD_COLD static const char *flux_check(const proc_setup_t *su, const char **field) {
  const char *why = proc_id_encoder_check(su, field);
  if (why == NULL && !(proc_id_speed(su->cfg) > 0.0f)) {
    *field = "id_speed";
    why = "needs a speed (id_speed, or speed_max > 0)";
  }
  return why;
}

const proc_row_t proc_flux = {
    .name = "flux",
    .id = PROC_FLUX,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = flux_check,
    .wanted = NULL,
    .init = flux_init,
    .step = flux_step,
    .abort = NULL,
    .publish = flux_publish,
};
