/*
 * proc_enc.c - identification of the encoder's offset and direction
 * (issue 25 e): the rotor held by a current vector of amplitude
 * i = id_i_test at PROC_ENC_POINTS electrical angles theta_k = 2 pi k / N
 * turning forward, then at the same angles turning back; at each the
 * encoder's electrical reading p (theta_m + half a count) is compared with
 * the vector's angle: the direction from the sign of the encoder's change
 * when the vector steps forward, the offset (pos_encoder.c: theta_e = p
 * (theta_m + half) - offset) the circular mean of the differences
 * e_k = p (theta_m + half) - theta_k over both passes. As ODrive's encoder
 * offset calibration (Encoder::run_offset_calibration: the vector turned a
 * few electrical turns forward and back, the offset the mean of both
 * passes, the direction from the encoder's change) and moteus's calibrate,
 * learnt from, not copied.
 *
 * Loads (the rest angle is the vector's angle minus the load angle
 * delta = asin(T_L / (1.5 p lambda_m i)) electrical, the "bias by load /
 * stiffness"):
 *  - a light free rotor (friction only): it swings about the vector; the
 *    vector's angle is led against the encoder's speed (-k_d omega_e, the
 *    alignment's damping, proc_align_timing) and the reading is the mean
 *    over a window after it settled: right;
 *  - Coulomb friction (any holding friction below the vector's torque):
 *    the rotor stops short of the vector, behind it in the direction it
 *    came from: +delta forward, -delta back; the mean of the two passes
 *    cancels it (result[4] shows delta);
 *  - a constant load torque (gravity, a spring) biases both passes the
 *    same way: not cancelled, the offset errs by delta (raise id_i_test:
 *    delta ~ T_L / (1.5 p lambda_m i)).
 * The damping and the settling come from the machine's lambda_m (a flux
 * map's at zero current, which its parameter set's lambda_m, 0, does not
 * hold: with that 0 ipm_sat's rotor swung undamped, 23 deg off).
 * Bounds: the current i (PROC_ID_TRIP i + 5 % i_max, proc_poles.c), the
 * voltage v_max; the rotor turns one electrical turn forward and back
 * (1 / p mechanical turn).
 */
#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"
#include "proc.h"

#define PROC_ENC_POINTS 6u    /* per pass: one electrical turn */
#define PROC_ENC_MOVE   0.05f /* from one angle to the next [s] */
#define PROC_ENC_TRIP   1.3f  /* the current's bound: x the test current (+ 5 % i_max) */

/* periods to settle, and to average, at a point: 2.5 the alignment's calm
 * span (2 / w_n, proc_align_timing), at least 0.05 s, at most 0.5 s */
FD_COLD static uint32_t enc_n_settle(const drive_config_t *c, float lambda_m) {
  proc_align_timing_t t;
  proc_align_timing(c, lambda_m, &t);
  const uint32_t lo = (uint32_t)(0.05f / c->ts), hi = (uint32_t)(0.5f / c->ts);
  const uint32_t n = 5u * t.calm_need / 2u;
  return n < lo ? lo : (n > hi ? hi : n);
}

FD_COLD static void enc_init(proc_state_t *st, const proc_setup_t *su) {
  proc_enc_t *e = &st->enc;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&e->cc, &ccfg);
  proc_enc_unwrap_reset(&e->u);
  e->n = 0u;
  e->n_all = 0u;
  e->point = 0u;
  e->theta_v = 0.0f;
  e->th_start = 0.0f;
  e->move = 0.0f;
  for (unsigned k = 0; k < 2u; ++k) {
    e->s[k][0] = e->s[k][1] = 0.0f;
    e->e[k] = 0.0f;
  }
  e->acc_c = e->acc_s = 0.0f;
  e->acc_n = 0u;
  e->dir = 0.0f;
}

/* The target of point k: 0 (the start, k = 0), then 1 .. N forward, then
 * N - 1 .. 0 back [rad electrical, unwrapped]. */
FD_COLD static float enc_target(unsigned k) {
  const float step = 2.0f * FRAMES_PI / (float)PROC_ENC_POINTS;
  const unsigned j = k <= PROC_ENC_POINTS ? k : 2u * PROC_ENC_POINTS - k;
  return (float)j * step;
}

FD_COLD static int enc_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                            proc_out_t *out) {
  proc_enc_t *e = &st->enc;
  const drive_config_t *c = su->cfg;
  const float i = proc_id_current(c);
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  if (!in->s->enc_valid || !fd_isfinite(in->s->enc_angle)) {
    out->fault = DRIVE_FAULT_POSITION;
    return PROC_FAILED;
  }
  const float lim = PROC_ENC_TRIP * i + 0.05f * c->i_max;
  if (!(in->i_ab.alpha * in->i_ab.alpha + in->i_ab.beta * in->i_ab.beta <= lim * lim)) {
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  const float th = proc_enc_unwrap(&e->u, in->s->enc_angle);
  const uint32_t n_move = (uint32_t)(PROC_ENC_MOVE / c->ts) + 1u;
  /* the machine's lambda_m, a flux map's too (the header) */
  /* mut: enc_timing_map_flux_ignored */
  const float lam = su->machine->lambda_m;
  const uint32_t n_settle = enc_n_settle(c, lam);
  const uint32_t n_point = n_move + 2u * n_settle; /* move, settle, average */
  const unsigned last = 2u * PROC_ENC_POINTS;
  e->n_all++;
  const uint32_t n = e->n++;
  const float tgt = enc_target(e->point);
  const float from = e->point > 0u ? enc_target(e->point - 1u) : 0.0f;
  e->theta_v = n < n_move ? from + (tgt - from) * (float)n / (float)n_move : tgt;
  if (e->point == 1u && n == 0u) {
    e->th_start = th; /* the forward pass's start (at rest at 0) */
  }
  if (e->point == 1u && n == n_move + n_settle) {
    /* mut: enc_direction_sign */
    e->dir = th - e->th_start >= 0.0f ? 1.0f : -1.0f; /* the first step forward */
  }
  if (e->point >= 1u && n >= n_move + n_settle) {
    const float half = c->enc_cpr > 0u ? FRAMES_PI / (float)c->enc_cpr : 0.0f;
    /* the reading (pos_encoder.c, the direction applied) minus the vector */
    const float d = e->dir * c->pole_pairs * (in->s->enc_angle + half) - tgt;
    const sincos_t sc = frames_sincos(frames_wrap_pi(d));
    e->acc_c += sc.c;
    e->acc_s += sc.s;
    e->acc_n++;
  }
  if (e->n >= n_point) {
    if (e->point >= 1u) {
      const unsigned pass = e->point <= PROC_ENC_POINTS ? 0u : 1u;
      const float r = sqrtf(e->acc_c * e->acc_c + e->acc_s * e->acc_s);
      if (r > 0.0f) { /* each point weighs the same */
        e->s[pass][0] += e->acc_c / r;
        e->s[pass][1] += e->acc_s / r;
      }
      if (e->point == PROC_ENC_POINTS) {
        e->move = th - e->th_start;
      }
    }
    e->acc_c = e->acc_s = 0.0f;
    e->acc_n = 0u;
    e->n = 0u;
    e->point++;
    if (e->point > last) {
      out->apply = false;
      e->e[0] = atan2f(e->s[0][1], e->s[0][0]);
      e->e[1] = atan2f(e->s[1][1], e->s[1][0]);
      /* the forward pass turned the rotor about one electrical turn */
      const float turn = e->dir * e->move * c->pole_pairs / (2.0f * FRAMES_PI);
      if (!(turn > 0.5f && turn < 1.5f)) {
        out->fault = DRIVE_FAULT_POSITION; /* stuck, slipped, or the wrong pole pairs */
        return PROC_FAILED;
      }
      return PROC_DONE;
    }
  }
  /* the alignment's damping: the vector led against the encoder's speed */
  proc_align_timing_t tmg;
  proc_align_timing(c, lam, &tmg);
  const float w = e->dir * in->pos->omega; /* 0 until the direction is known */
  const float phi = e->theta_v + fd_clampf(-tmg.kd * w, -0.25f * FRAMES_PI, 0.25f * FRAMES_PI);
  const sincos_t sc = frames_sincos(frames_wrap_pi(phi));
  const dq_t v = current_ctrl_update(&e->cc, (dq_t){i * sc.c, i * sc.s},
                                     (dq_t){in->i_ab.alpha, in->i_ab.beta}, 0.0f, in->v_max);
  out->v_ab = (ab_t){v.d, v.q};
  return PROC_RUNNING;
}

/* result: [0] the offset (enc_offset) [rad electrical]: the circular mean of
 * both passes; [1] the direction (+1: the encoder counts up as the
 * electrical angle grows; -1: against, the offset then for theta_e = -p
 * (theta_m + half) - offset); [2], [3] the offset of the forward and the
 * backward pass; [4] half their difference (the holding load's bias
 * delta); [5] the forward pass's movement [rad mechanical] */
FD_COLD static void enc_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_enc_t *e = &st->enc;
  tm->phase = e->point;
  tm->n = e->n_all;
  const float c = e->s[0][0] + e->s[1][0], s = e->s[0][1] + e->s[1][1];
  tm->result[0] = atan2f(s, c); /* 0 before any point */
  tm->result[1] = e->dir;
  tm->result[2] = e->e[0];
  tm->result[3] = e->e[1];
  tm->result[4] = 0.5f * frames_wrap_pi(e->e[0] - e->e[1]);
  tm->result[5] = e->move;
}

FD_COLD static const char *enc_check(const proc_setup_t *su, const char **field) {
  return proc_id_encoder_check(su, field);
}

const proc_row_t proc_enc = {
    .name = "enc",
    .id = PROC_ENC,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = enc_check,
    .wanted = NULL,
    .init = enc_init,
    .step = enc_step,
    .abort = NULL,
    .publish = enc_publish,
};
