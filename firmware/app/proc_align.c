/*
 * proc_align.c - the alignment as a procedure (proc.h): d current along
 * theta = 0 for align_time, then the position source takes the current's
 * angle as its reference. A star-point source reads the polarity from the
 * motion (pos_dfc.c). An encoder's offset is taken only once the rotor
 * rests (issue 23, point 18: a light free rotor swung through the offset,
 * -57.5 deg): the current's angle leads against the encoder's speed,
 * -k_d omega_e (at most 45 deg), which damps the swing (proc_align_timing),
 * and the alignment ends when the rotor has settled (|omega_e| < w_calm for
 * calm_need periods, or from the start for still_need), or fails with the
 * position fault after PROC_ALIGN_SWINGS swings more. Bounded: the current
 * is align_current, the voltage the current loop's limit v_max.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"

/* The encoder's alignment: damping ratio, the swing left when it is taken
 * as settled [rad electrical], and the swings after align_time it may take
 * to settle before the position fault. */
#define PROC_ALIGN_ZETA   0.7f
#define PROC_ALIGN_CALM   0.01f
#define PROC_ALIGN_SWINGS 10.0f

FD_COLD void proc_align_timing(const drive_config_t *c, float lambda_m, proc_align_timing_t *t) {
  /* the rotor swings about the current's axis at w_n = p sqrt(1.5 lambda_m
   * i_align / J) (electrical), the PM torque 1.5 p lambda_m i_q (lambda_m
   * the machine's: a flux map's at zero current, which the parameter
   * set's lambda_m does not hold; issue 25, ipm_sat's enc); the
   * current's angle led by -k_d omega_e damps it (theta'' = -w_n^2 (theta
   * + k_d theta'): zeta = k_d w_n / 2) */
  const float wn2 = 1.5f * c->pole_pairs * c->pole_pairs * lambda_m * c->align_current / c->inertia;
  const float wn = wn2 > 0.0f ? sqrtf(wn2) : 0.0f;
  t->kd = wn > 0.0f ? 2.0f * PROC_ALIGN_ZETA / wn : 0.0f;
  /* settled: |omega_e| < PROC_ALIGN_CALM w_n for 2 / w_n (over a quarter
   * swing: a swing left would show its speed peak), i.e. a swing of at most
   * PROC_ALIGN_CALM rad electrical left */
  t->w_calm = PROC_ALIGN_CALM * wn;
  t->calm_need = wn > 0.0f ? (uint32_t)(2.0f / (wn * c->ts)) + 1u : 0u;
  /* a rotor calm from the alignment's start for 1 / w_n started within
   * PROC_ALIGN_CALM rad of the axis (from rest at theta_0 its speed passes
   * PROC_ALIGN_CALM w_n after PROC_ALIGN_CALM / (w_n theta_0)) */
  t->still_need = wn > 0.0f ? (uint32_t)(1.0f / (wn * c->ts)) + 1u : 0u;
  const float t_out =
      c->align_time + (wn > 0.0f ? PROC_ALIGN_SWINGS * 2.0f * FRAMES_PI / wn : 0.0f);
  t->n_timeout = (uint32_t)(t_out / c->ts) + 1u;
}

/* Wanted with align_time > 0 by a source that aligns, unless it starts
 * held (start_mode 1: proc_hold.c). */
FD_COLD static bool align_wanted(const proc_setup_t *su) {
  const drive_config_t *c = su->cfg;
  return c->start_mode != 1u && c->align_time > 0.0f && (su->pos_src->caps & POS_CAP_ALIGN) != 0u;
}

FD_COLD static void align_init(proc_state_t *st, const proc_setup_t *su) {
  proc_align_t *a = &st->align;
  const current_ctrl_cfg_t acfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&a->cc, &acfg);
  a->n = 0u;
  a->calm_n = 0u;
  a->phi = 0.0f;
}

FD_COLD static int align_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                              proc_out_t *out) {
  proc_align_t *a = &st->align;
  const drive_config_t *c = su->cfg;
  proc_align_timing_t tmg;
  proc_align_timing(c, su->machine->lambda_m, &tmg);
  /* mut: encoder_alignment_undamped */
  const bool enc = !su->gated && tmg.kd > 0.0f;
  const float w = in->pos->omega;
  const float phi = enc ? fd_clampf(-tmg.kd * w, -0.25f * FRAMES_PI, 0.25f * FRAMES_PI) : 0.0f;
  a->phi = phi;
  const sincos_t sc = frames_sincos(phi);
  const dq_t v =
      current_ctrl_update(&a->cc, (dq_t){c->align_current * sc.c, c->align_current * sc.s},
                          (dq_t){in->i_ab.alpha, in->i_ab.beta}, 0.0f, in->v_max);
  *out = (proc_out_t){{v.d, v.q}, true, false, 0u};
  a->calm_n = fabsf(w) < tmg.w_calm ? a->calm_n + 1u : 0u;
  const uint32_t n = ++a->n;
  /* calm for 2 / w_n, or from the start on for 1 / w_n (a rotor that never
   * moved: started at the axis, or held) */
  const bool settled =
      !enc || a->calm_n >= tmg.calm_need || (a->calm_n == n && n >= tmg.still_need);
  if ((float)n * c->ts >= c->align_time && settled) {
    su->pos_src->align(su->pos_st, c, in->s, phi);
    return PROC_DONE;
  }
  if (enc && a->n >= tmg.n_timeout) {
    out->fault = DRIVE_FAULT_POSITION; /* the rotor did not settle */
    return PROC_FAILED;
  }
  return PROC_RUNNING;
}

FD_COLD static void align_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_align_t *a = &st->align;
  tm->phase = 0u;
  tm->n = a->n;
  tm->result[0] = a->phi;
  tm->result[1] = (float)a->calm_n;
  tm->result[2] = 0.0f;
}

const proc_row_t proc_align = {
    .name = "align",
    .id = PROC_ALIGN,
    .state = DRIVE_STATE_ALIGN,
    .caps = PROC_CAP_GATES,
    .check = NULL,
    .wanted = align_wanted,
    .init = align_init,
    .step = align_step,
    .abort = NULL,
    .publish = align_publish,
};
