/*
 * proc_ldq.c - L_d and L_q at standstill, zero average torque (issue 25,
 * procedure b; docs/commissioning.md, "ldq").
 *
 * A d bias current i_b (the current loop, current_ctrl.h) along pi/2 for
 * id_rs_align / 2, turned to 0 in PROC_LDQ_TURN and held there for
 * id_rs_align (proc_ident_align_angle) aligns a PM rotor's d axis at
 * theta = 0 from anywhere (a reluctance rotor's high-inductance axis);
 * over the alignment the loop damps the free rotor's swing as rs does
 * (i_y = -v_y / R_app across the current: proc_rs.c; without it the
 * rotor's d axis swings under the injection, and the d injection sees
 * L_d + (L_q - L_d) <sin^2 delta>: L_d up to +15 % on drawn IPMs);
 * its voltage is then held (v_hold, trimmed once an injection
 * period on the period's mean current) and a square wave of +-v_h, a half
 * period of M PWM periods (M = 1 / (2 f_h ts), id_ldq_freq; 2 .. 16), is added
 * along d, then along q. The axis' current deviation from the bias
 * follows L di/dt = u - R i (the bias' constant terms, R i_b and the
 * inverter's error, cancel against v_hold); its exact zero-order-hold
 * response, with the voltage asked at k acting over one PWM period that
 * ends one or two samples later (the timer's preload: the SIL's ISR k
 * acts over [t_{k+1}, t_{k+2}); a board's sampling point may split it), is
 *   i_{k+1} = alpha i_k + beta_1 u_k + beta_2 u_{k-1} + c,
 *   alpha = exp(-R ts / L), beta_1 + beta_2 = beta = (1 - alpha) / R    (5)
 * (the modified z-transform of the delayed zero-order hold: the split of
 * beta depends on the delay, the sum does not).
 * The samples are averaged at each of the wave's 2M positions over the
 * waves measured (w_j: the noise down by the square root of their count,
 * so the least squares of (5) on w_j, cyclic in j, is not biased by noise
 * in its regressor), and
 *   L = ts (1 - alpha) / (beta (-ln alpha))   (ts / beta when alpha -> 1) (6)
 * exact for any R / (w L), any delay from one to two periods and the
 * inverter's error below its knee, which acts as a resistance (it enters
 * alpha and beta alike). The bias
 * keeps every phase current's sign through the ripple (d: i_b +- ripple /
 * 2, q: the b, c phases at -i_b / 2 +- 0.87 i_q), so the error stays on its
 * plateau (in c). This is the pulse method L = v dt / di (VESC's and
 * ODrive's inductance measurements with square voltages), on a bias and
 * over many periods: on a saturated machine it gives the
 * incremental inductances at (i_b, 0), dpsi_d/di_d and dpsi_q/di_q.
 *
 * The amplitude: from the parameter set's inductance, a quarter of the
 * ripple wanted (PROC_LDQ_RIPPLE i_b peak to peak), then scaled to the
 * ripple measured over PROC_LDQ_TRY injection periods (a quarter at once
 * when the current leaves 1.5 times the band wanted), up to
 * PROC_LDQ_TRIES times, within the voltage left by v_hold.
 *
 * Bounds: the current stays below 1.5 i_b (the ripple PROC_LDQ_RIPPLE i_b
 * peak to peak about it), i_b = id_ldq_current (0: i_max / 3) clamped to
 * i_max / 2; a measured current above 2 i_b fails it (overcurrent). The q
 * injection's torque averages zero over each period: the rotor wiggles by
 * 1.5 p lambda_m (i_q ripple / 2) / (J (2 pi f_h)^2) (mechanical) about the
 * alignment, which itself turns it by at most 1.5 pi electrical: the bound
 * is one electrical turn, 2 pi / p mechanical.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"

#define PROC_LDQ_RIPPLE 0.5f   /* the ripple wanted, peak to peak, times i_b */
#define PROC_LDQ_TRIP   2.0f   /* a measured current above this times i_b fails it */
#define PROC_LDQ_TRY    4u     /* injection periods of an amplitude trial */
#define PROC_LDQ_TRIES  8u     /* amplitude trials at most */
#define PROC_LDQ_RAMP   0.005f /* the bias is ramped over this [s] */
#define PROC_LDQ_TURN   0.2f   /* the alignment's turn from pi/2 to 0 [s] */
#define PROC_LDQ_DAMP   0.3f   /* the alignment's damping current: at most this times i_b */
#define PROC_LDQ_TRIM   0.25f  /* the bias voltage's trim a period, of the apparent resistance */

enum { PH_ALIGN = 0, PH_D_TRY = 1, PH_D = 2, PH_Q_TRY = 3, PH_Q = 4, PH_DONE = 5 };

FD_COLD static float ldq_bias(const drive_config_t *c) {
  const float i = c->id_ldq_current > 0.0f ? c->id_ldq_current : c->i_max / 3.0f;
  return fminf(i, 0.5f * c->i_max);
}

/* PWM periods of a half injection period (at least 1). */
FD_COLD static uint32_t ldq_half(const drive_config_t *c) {
  const float m = 0.5f / (c->id_ldq_freq * c->ts);
  return m < 2.0f ? 2u : m > (float)PROC_LDQ_M_MAX ? PROC_LDQ_M_MAX : (uint32_t)(m + 0.5f);
}

FD_COLD static bool ldq_wanted(const proc_setup_t *su) {
  (void)su;
  return false; /* never in the start: the host runs it (drive_cmd_identify) */
}

FD_COLD static const char *ldq_check(const proc_setup_t *su, const char **field) {
  const drive_config_t *c = su->cfg;
  if (!(ldq_bias(c) > 0.0f)) {
    *field = "id_ldq_current";
    return "the bias current must be positive";
  }
  const float m = 0.5f / (c->id_ldq_freq * c->ts);
  if (m < 1.5f || m > (float)PROC_LDQ_M_MAX + 0.5f) {
    *field = "id_ldq_freq";
    return "a half wave of 2 .. PROC_LDQ_M_MAX PWM periods";
  }
  return NULL;
}

FD_COLD static void ldq_reset_sums(proc_ldq_t *q) {
  /* the wave of an axis being solved is kept (q's trials leave it alone;
   * the measurement that follows them clears it once the solve is done) */
  for (unsigned j = 0; j < 2u * PROC_LDQ_M_MAX && !q->solving; ++j) {
    q->w[j] = 0.0f;
  }
  q->sn = 0u;
  q->i_lo = q->o_lo = 1e30f;
  q->i_hi = q->o_hi = -1e30f;
  q->acc_d = 0.0f;
}

FD_COLD static void ldq_init(proc_state_t *st, const proc_setup_t *su) {
  proc_ldq_t *q = &st->ldq;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&q->cc, &ccfg);
  q->phase = PH_ALIGN;
  q->axis = 0u;
  q->tries = 0u;
  q->n = 0u;
  q->n_all = 0u;
  q->i_ref = 0.0f;
  proc_swing_reset(&q->swing);
  q->v_hold[0] = q->v_hold[1] = 0.0f;
  q->v_h = 0.0f;
  q->i_peak = 0.0f;
  q->l[0] = q->l[1] = 0.0f;
  q->ripple[0] = q->ripple[1] = 0.0f;
  q->cross[0] = q->cross[1] = 0.0f;
  q->solving = false; /* before the sums: they keep a wave being solved */
  ldq_reset_sums(q);
}

/* The first amplitude of an axis: a quarter of the ripple wanted on the
 * parameter set's inductance (v_h M ts / L = ripple / 4). */
FD_COLD static float ldq_v_first(const drive_config_t *c, uint8_t axis, float ib) {
  const float l = axis == 0u ? c->ld : c->lq;
  return 0.25f * PROC_LDQ_RIPPLE * ib * l / ((float)ldq_half(c) * c->ts);
}

/* The least squares of (5) on the averaged wave w_j (2m positions,
 * cyclic: w_{j+1} on w_j, u_j and u_{j-1}, centred by the constant c),
 * spread over the periods after the measurement so that no ISR carries
 * it whole (the PIL's worst ISR of ldq: 4477 instructions in one period
 * before): ldq_solve_begin (the wave's mean), ldq_solve_step
 * (PROC_LDQ_SOLVE positions a period into the normal equations),
 * ldq_solve_end (Cramer's rule, then (6)). */
#define PROC_LDQ_SOLVE 8u

FD_COLD static void ldq_solve_begin(proc_ldq_t *q, uint32_t m) {
  const uint32_t n2 = 2u * m;
  float mw = 0.0f;
  for (uint32_t j = 0; j < n2; ++j) {
    mw += q->w[j];
  }
  q->sns = q->sn;
  q->s_axis = q->axis;
  q->v_hs = q->v_h;
  q->mw = q->sn > 0u ? mw / ((float)n2 * (float)q->sn) : 0.0f;
  for (unsigned a = 0; a < 6u; ++a) {
    q->g[a] = 0.0f;
  }
  q->h[0] = q->h[1] = q->h[2] = 0.0f;
  q->sj = 0u;
  q->solving = true;
}

/* The normal equations G p = h of the regressors (x, u_j, u_{j-1}),
 * scaled by v_h (u = +-1) for their conditioning: PROC_LDQ_SOLVE more
 * positions; true when all 2m are in. */
FD_COLD static bool ldq_solve_step(proc_ldq_t *q, uint32_t m) {
  const uint32_t n2 = 2u * m;
  const float inv_sn = q->sns > 0u ? 1.0f / (float)q->sns : 0.0f;
  for (uint32_t c = 0; c < PROC_LDQ_SOLVE && q->sj < n2; ++c, ++q->sj) {
    const uint32_t j = q->sj;
    const float r0 = q->w[j] * inv_sn - q->mw;
    const float r1 = (j < m) ? 1.0f : -1.0f;
    const float r2 = (((j + n2 - 1u) % n2) < m) ? 1.0f : -1.0f;
    const float y = q->w[(j + 1u) % n2] * inv_sn - q->mw;
    q->g[0] += r0 * r0;
    q->g[1] += r0 * r1;
    q->g[2] += r0 * r2;
    q->g[3] += r1 * r1;
    q->g[4] += r1 * r2;
    q->g[5] += r2 * r2;
    q->h[0] += r0 * y;
    q->h[1] += r1 * y;
    q->h[2] += r2 * y;
  }
  return q->sj >= n2;
}

/* Cramer's rule on G p = h, then (6) with beta = beta_1 + beta_2: L [H],
 * 0 when it has no solution. */
FD_COLD static float ldq_solve_end(const proc_ldq_t *q, float v_h, float ts) {
  if (q->sns == 0u || !(v_h > 0.0f)) {
    return 0.0f;
  }
  const float g00 = q->g[0], g01 = q->g[1], g02 = q->g[2];
  const float g11 = q->g[3], g12 = q->g[4], g22 = q->g[5];
  const float h0 = q->h[0], h1 = q->h[1], h2 = q->h[2];
  const float det =
      g00 * (g11 * g22 - g12 * g12) - g01 * (g01 * g22 - g12 * g02) + g02 * (g01 * g12 - g11 * g02);
  if (!(fabsf(det) > 0.0f)) {
    return 0.0f;
  }
  const float alpha =
      (h0 * (g11 * g22 - g12 * g12) - g01 * (h1 * g22 - g12 * h2) + g02 * (h1 * g12 - g11 * h2)) /
      det;
  const float b1 =
      (g00 * (h1 * g22 - g12 * h2) - h0 * (g01 * g22 - g12 * g02) + g02 * (g01 * h2 - h1 * g02)) /
      det;
  const float b2 =
      (g00 * (g11 * h2 - h1 * g12) - g01 * (g01 * h2 - h1 * g02) + h0 * (g01 * g12 - g11 * g02)) /
      det;
  const float beta = (b1 + b2) / v_h;
  if (!(beta > 0.0f) || !(alpha > 0.0f) || !isfinite(alpha)) {
    return 0.0f;
  }
  /* (6); ts / beta within 1e-3 when 1 - alpha < 2e-3 (the series 1 + x / 2) */
  const float x = 1.0f - alpha;
  const float gl = x > 2e-3f ? x / -logf(alpha) : 1.0f - 0.5f * x;
  return ts * gl / beta;
}

/* The least squares in progress: PROC_LDQ_SOLVE more positions; all in,
 * the axis' inductance (6) kept, or a fault when it has no solution (no
 * response: an open phase, or no voltage left for the injection). */
FD_COLD static void ldq_solve_run(proc_ldq_t *q, uint32_t m, float ts, proc_out_t *out) {
  if (!ldq_solve_step(q, m)) {
    return;
  }
  q->solving = false;
  const float l = ldq_solve_end(q, q->v_hs, ts);
  if (!(l > 0.0f) || !isfinite(l)) {
    out->fault = DRIVE_FAULT_CONTROL;
    return;
  }
  q->l[q->s_axis] = l;
}

/* The voltage (d, q at theta = 0: alpha, beta) scaled into v_max. */
FD_COLD static ab_t ldq_within(float vd, float vq, float v_max) {
  const float vm = sqrtf(vd * vd + vq * vq);
  const float sc = vm > v_max ? v_max / vm : 1.0f;
  return (ab_t){sc * vd, sc * vq};
}

FD_COLD static int ldq_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                            proc_out_t *out) {
  proc_ldq_t *q = &st->ldq;
  const drive_config_t *c = su->cfg;
  const float ib = ldq_bias(c);
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  ++q->n_all;
  /* theta = 0: the aligned frame is alpha-beta */
  const float i_d = in->i_ab.alpha;
  const float i_q = in->i_ab.beta;
  const float i_abs = sqrtf(i_d * i_d + i_q * i_q);
  q->i_peak = fmaxf(q->i_peak, i_abs);
  /* mut: ldq_overcurrent_bound */
  if (!(i_abs <= PROC_LDQ_TRIP * ib)) { /* also a non-finite current */
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  if (q->phase == PH_DONE) {
    out->apply = false;
    return PROC_DONE;
  }
  const uint32_t m = ldq_half(c);
  if (q->phase == PH_ALIGN) {
    const uint32_t n_hold = (uint32_t)(c->id_rs_align / c->ts) + 1u;
    const uint32_t n_turn = (uint32_t)(PROC_LDQ_TURN / c->ts) + 1u;
    const uint32_t n_align = n_hold / 2u + n_turn + n_hold;
    /* the bias from 0 over the first part (id_rs_align / 2): a rotor far
     * from the current's axis breaks away at a small current and swings
     * little (proc_rs.c) */
    const float slew = ib * c->ts / fmaxf(0.5f * c->id_rs_align, PROC_LDQ_RAMP);
    q->i_ref += fd_clampf(ib - q->i_ref, -slew, slew);
    /* the loop in the frame of the alignment's angle (proc.h) */
    const sincos_t sc = frames_sincos(proc_ident_align_angle(q->n, n_hold / 2u, n_turn));
    const dq_t i_f = {sc.c * i_d + sc.s * i_q, -sc.s * i_d + sc.c * i_q};
    /* the swing damped as rs does (proc_rs.c): across the current the
     * loop follows -v_y / R_app, a resistor across the winding */
    /* mut: ldq_swing_undamped */
    const float damp = PROC_LDQ_DAMP * ib;
    const float iy_ref = proc_swing_damping(&q->swing, q->i_ref, damp, slew, true);
    const dq_t v = current_ctrl_update(&q->cc, (dq_t){q->i_ref, iy_ref}, i_f, 0.0f, in->v_max);
    proc_swing_step(&q->swing, v.d, v.q, c->ts);
    out->v_ab = (ab_t){sc.c * v.d - sc.s * v.q, sc.s * v.d + sc.c * v.q};
    /* the bias' voltage (alpha, beta = d, q at 0): the loop's mean over
     * the last quarter (within the hold at 0) */
    if (q->n >= n_align - n_align / 4u) {
      q->v_hold[0] += out->v_ab.alpha;
      q->v_hold[1] += out->v_ab.beta;
      q->acc_d += 1.0f;
    }
    if (++q->n >= n_align) {
      const float na = q->acc_d > 0.0f ? q->acc_d : 1.0f;
      q->v_hold[0] /= na;
      q->v_hold[1] /= na;
      q->phase = PH_D_TRY;
      q->axis = 0u;
      q->n = 0u;
      q->v_h = ldq_v_first(c, 0u, ib);
      ldq_reset_sums(q);
    }
    return PROC_RUNNING;
  }
  const uint8_t ax = q->axis;
  if (q->solving) { /* an axis' least squares, a few positions a period */
    ldq_solve_run(q, m, c->ts, out);
    if (out->fault != 0u) {
      return PROC_FAILED;
    }
    if (q->phase == PH_Q) { /* q's, the last: the bias held meanwhile (within v_max) */
      out->v_ab = ldq_within(q->v_hold[0], q->v_hold[1], in->v_max);
      if (!q->solving) {
        q->phase = PH_DONE;
        out->v_ab = (ab_t){0.0f, 0.0f};
      }
      return PROC_RUNNING;
    }
  }
  /* the injection along the axis: +v_h the first half period, -v_h the second */
  const float i_x = ax == 0u ? i_d : i_q;
  const float i_o = ax == 0u ? i_q : i_d;
  /* the wave starts in the middle of its positive half: the ripple is
   * centred on the bias from the first period on */
  const uint32_t k = (q->n + m / 2u) % (2u * m);
  const bool trial = q->phase == PH_D_TRY || q->phase == PH_Q_TRY;
  const float vh_max =
      fmaxf(in->v_max - sqrtf(q->v_hold[0] * q->v_hold[0] + q->v_hold[1] * q->v_hold[1]), 0.0f);
  q->v_h = fminf(q->v_h, vh_max);
  const float u = k < m ? q->v_h : -q->v_h;
  /* mut: ldq_delay */
  if (!trial) { /* the sample at its position in the wave (5) */
    q->w[k] += i_x;
  }
  q->i_lo = fminf(q->i_lo, i_x);
  q->i_hi = fmaxf(q->i_hi, i_x);
  q->o_lo = fminf(q->o_lo, i_o);
  q->o_hi = fmaxf(q->o_hi, i_o);
  q->acc_d += i_d;
  /* an injection period's end: the bias voltage trimmed on its mean
   * current (the apparent resistance v_hold / i_b, PROC_LDQ_TRIM of it) */
  if (k == 2u * m - 1u) {
    q->sn += trial ? 0u : 1u;
    const float r_app = fabsf(q->v_hold[0]) / ib;
    q->v_hold[0] += PROC_LDQ_TRIM * r_app * (ib - q->acc_d / (float)(2u * m));
    q->acc_d = 0.0f;
  }
  const float vd = q->v_hold[0] + (ax == 0u ? u : 0.0f);
  const float vq = q->v_hold[1] + (ax == 0u ? 0.0f : u);
  /* within v_max (the trim may have moved v_hold since vh_max) */
  out->v_ab = ldq_within(vd, vq, in->v_max);
  ++q->n;
  const uint32_t n_meas = ((uint32_t)(c->id_ldq_time / c->ts) / (2u * m) + 1u) * 2u * m;
  const float want = PROC_LDQ_RIPPLE * ib;
  /* a trial ends early when the current leaves 1.5 times the ripple band
   * wanted (the parameter set's inductance far too large): a quarter of
   * the amplitude */
  const bool out_of_band = fabsf(i_x - (ax == 0u ? ib : 0.0f)) > 0.75f * want;
  if (trial && (q->n >= PROC_LDQ_TRY * 2u * m || out_of_band)) {
    const float pp = q->i_hi - q->i_lo;
    const float g = out_of_band ? 0.25f : pp > 0.0f ? fd_clampf(want / pp, 0.25f, 4.0f) : 4.0f;
    ++q->tries;
    q->v_h = fminf(q->v_h * g, vh_max);
    const bool ok = (g > 0.8f && g < 1.25f) || q->tries >= PROC_LDQ_TRIES || q->v_h >= vh_max;
    if (ok) {
      ++q->phase;          /* to the measurement */
      while (q->solving) { /* d's, if not done yet (short trials): its wave is needed now */
        ldq_solve_run(q, m, c->ts, out);
      }
      if (out->fault != 0u) {
        return PROC_FAILED;
      }
    }
    q->n = 0u;
    ldq_reset_sums(q);
    return PROC_RUNNING;
  }
  if (!trial && q->n >= n_meas) {
    /* (5) solved over the next periods, then (6): d's during q's trials */
    ldq_solve_begin(q, m);
    q->ripple[ax] = q->i_hi - q->i_lo;
    q->cross[ax] = q->ripple[ax] > 0.0f ? (q->o_hi - q->o_lo) / q->ripple[ax] : 0.0f;
    if (ax == 0u) {
      ++q->phase; /* to q's trials */
      q->n = 0u;
      q->tries = 0u;
      q->axis = 1u;
      q->v_h = ldq_v_first(c, 1u, ib);
      ldq_reset_sums(q);
    }
  }
  return PROC_RUNNING;
}

/* Phase and results (proc_telemetry_t; docs/commissioning.md, "ldq"):
 *  phase 0 the alignment (bias along theta = 0), 1 the d amplitude's
 *  trials, 2 the d measurement, 3 and 4 the same along q, 5 done.
 *   0 L_d [H] (incremental at the bias; once measured)
 *   1 L_q [H]
 *   2 the bias current i_b [A]
 *   3 the injection's amplitude v_h of the axis in force (done: q's) [V]
 *   4, 5 the d and q current ripple measured, peak to peak [A]
 *   6 the other axis' ripple over the injected one's, the larger of d and q
 *     (cross-saturation or a misaligned rotor; noise: its pp) [-]
 *   7 the largest measured current amplitude [A] */
FD_COLD static void ldq_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_ldq_t *q = &st->ldq;
  tm->phase = q->phase;
  tm->n = q->n_all;
  tm->result[0] = q->l[0];
  tm->result[1] = q->l[1];
  tm->result[2] = q->i_ref > 0.0f ? q->i_ref : 0.0f;
  tm->result[3] = q->v_h;
  tm->result[4] = q->ripple[0];
  tm->result[5] = q->ripple[1];
  tm->result[6] = fmaxf(q->cross[0], q->cross[1]);
  tm->result[7] = q->i_peak;
}

const proc_row_t proc_ldq = {
    .name = "ldq",
    .id = PROC_LDQ,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = ldq_check,
    .wanted = ldq_wanted,
    .init = ldq_init,
    .step = ldq_step,
    .abort = NULL,
    .publish = ldq_publish,
};
