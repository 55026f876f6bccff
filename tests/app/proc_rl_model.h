/*
 * proc_rl_model.h - the identification tests' R-L model (test_proc_rs.c,
 * test_proc_ldq.c): per-axis inductances (l along alpha, lq along beta),
 * the inverter's voltage error per phase (a plateau v0 beyond a knee, odd
 * in the current), noise and quantisation of the measured currents, the
 * R-L response integrated exactly over each period.
 */
#ifndef FD_TEST_PROC_RL_MODEL_H
#define FD_TEST_PROC_RL_MODEL_H

#include <math.h>
#include <stdint.h>

#include "math/frames.h"

typedef struct {
  float r, l, lq, v0, knee, noise, lsb;
  float i_a, i_b; /* alpha, beta current [A] */
  uint32_t seed;
  float i_peak; /* the largest true current amplitude [A] */
  int delay2;   /* the voltage acts a period later (the SIL's timer preload) */
  ab_t pend;    /* then: the voltage asked last period */
} model_t;

static float model_noise(model_t *m) {
  m->seed = m->seed * 1664525u + 1013904223u;
  return ((float)(m->seed >> 8) / 16777216.0f - 0.5f) * 2.0f * m->noise;
}

/* one phase's voltage error (the inverter's dead time: odd in its current) */
static float phase_err(const model_t *m, float i) {
  return fabsf(i) >= m->knee ? copysignf(m->v0, i) : m->v0 * i / m->knee;
}

/* One period with the voltage asked (alpha, beta): the phases' errors
 * subtracted (Clarke), the R-L response integrated exactly. */
static void model_step(model_t *m, ab_t v, float ts) {
  const float ia = m->i_a;
  const float ib = -0.5f * m->i_a + 0.8660254f * m->i_b;
  const float ic = -0.5f * m->i_a - 0.8660254f * m->i_b;
  const float ea = phase_err(m, ia), eb = phase_err(m, ib), ec = phase_err(m, ic);
  const float e_al = (2.0f / 3.0f) * (ea - 0.5f * eb - 0.5f * ec);
  const float e_be = (2.0f / 3.0f) * 0.8660254f * (eb - ec);
  const float k = expf(-m->r * ts / m->l);
  const float kq = expf(-m->r * ts / m->lq);
  m->i_a = m->i_a * k + (1.0f - k) * (v.alpha - e_al) / m->r;
  m->i_b = m->i_b * kq + (1.0f - kq) * (v.beta - e_be) / m->r;
  m->i_peak = fmaxf(m->i_peak, sqrtf(m->i_a * m->i_a + m->i_b * m->i_b));
}

static float model_meas(model_t *m, float i) {
  const float x = i + model_noise(m);
  return m->lsb > 0.0f ? m->lsb * roundf(x / m->lsb) : x;
}

#endif
