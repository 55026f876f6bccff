/*
 * protect/drive_phase_check.c - phase balance on the telemetry copy (main
 * loop); drive_phase_check.h says what and why.
 */
#include "protect/drive_phase_check.h"

#include <math.h>
#include <string.h>

#include "drive_enums.h"
#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"

/* One sample into the window: x = v_applied - R_s i in (alpha, beta) at
 * the electrical angle theta, tau the fraction of a revolution swept
 * (drive_phase_check.h). */
static void window_add(drive_ph_window_t *p, const drive_phase_view_t *tm, float rs, float tau) {
  const float ia = tm->i_abc[0];
  const float ib = (tm->i_abc[0] + 2.0f * tm->i_abc[1]) * FRAMES_INV_SQRT3;
  const float xa = tm->v_ab_filt[0] - rs * ia;
  const float xb = tm->v_ab_filt[1] - rs * ib;
  float s;
  float c;
  fd_sincosf(tm->theta_e, &s, &c);
  const float ya = xa * c + xb * s; /* x e^{-j theta} */
  const float yb = xb * c - xa * s;
  p->r1[0] += xa;
  p->r1[1] += xb;
  p->r2[0] += ya;
  p->r2[1] += yb;
  p->r3[0] += tau * ya;
  p->r3[1] += tau * yb;
  p->s1[0] += c;
  p->s1[1] += s;
  p->st1[0] += tau * c;
  p->st1[1] += tau * s;
  p->st += tau;
  p->stt += tau * tau;
  for (int x = 0; x < 3; ++x) {
    p->abs[x] += fabsf(tm->i_abc[x]);
  }
  p->n++;
}

/* D of the window (drive_phase_check.h) in (alpha, beta) [V]; -1 when the
 * samples do not separate it from the fundamental's terms, else 0. */
static int window_dc(const drive_ph_window_t *p, float d[2]) {
  const float n = (float)p->n;
  const float det = n * p->stt - p->st * p->st;
  if (!(det > 1e-6f * n * p->stt)) {
    return -1;
  }
  /* w = c B^-1 (row), B^-1 = [stt, -st; -st, n] / det */
  const float w1[2] = {(p->s1[0] * p->stt - p->st1[0] * p->st) / det,
                       (p->s1[1] * p->stt - p->st1[1] * p->st) / det};
  const float w2[2] = {(p->st1[0] * n - p->s1[0] * p->st) / det,
                       (p->st1[1] * n - p->s1[1] * p->st) / det};
  /* den = n - w c^H (real), num = r1 - w rF */
  const float den =
      n - (w1[0] * p->s1[0] + w1[1] * p->s1[1] + w2[0] * p->st1[0] + w2[1] * p->st1[1]);
  if (!(den > 0.25f * n)) {
    return -1;
  }
  const float na =
      p->r1[0] - (w1[0] * p->r2[0] - w1[1] * p->r2[1]) - (w2[0] * p->r3[0] - w2[1] * p->r3[1]);
  const float nb =
      p->r1[1] - (w1[0] * p->r2[1] + w1[1] * p->r2[0]) - (w2[0] * p->r3[1] + w2[1] * p->r3[0]);
  /* mut: voltage_balance_alpha_sign */
  d[0] = na / den;
  d[1] = nb / den;
  return 0;
}

/* 1 unbalanced, 0 balanced, -1 not judged. */
static int verdict(drive_phase_check_t *p, float i_max, float v_dc) {
  const drive_ph_window_t *w = &p->w;
  const float big = fd_maxf(w->abs[0], fd_maxf(w->abs[1], w->abs[2]));
  if (w->n < DRIVE_PH_MIN_N || !(big > DRIVE_PH_FLOOR * i_max * (float)w->n)) {
    return -1;
  }
  int v = 0;
  for (int x = 0; x < 3; ++x) {
    if (w->abs[x] < DRIVE_PH_OPEN * big) {
      v = 1;
    }
  }
  float d[2];
  if (window_dc(w, d) == 0 && v_dc > 0.0f) {
    p->vdef_ab[0] = d[0] / v_dc;
    p->vdef_ab[1] = d[1] / v_dc;
    p->vdef = sqrtf(p->vdef_ab[0] * p->vdef_ab[0] + p->vdef_ab[1] * p->vdef_ab[1]);
    p->vdef_max = fd_maxf(p->vdef_max, p->vdef);
    /* mut: voltage_balance_off */
    if (p->vdef > DRIVE_PH_VDEF) {
      v = 1;
    }
  }
  return v;
}

uint32_t drive_phase_check(drive_phase_check_t *p, const drive_phase_view_t *view) {
  const drive_phase_view_t *tm = view; /* the telemetry copy's part */
  const drive_phase_view_t *c = view;  /* the parameters' */
  if (tm->isr_count == p->isr_last) {
    return 0u; /* no fresh copy */
  }
  const uint32_t isrs = tm->isr_count - p->isr_last;
  const bool first = p->isr_last == 0u;
  p->isr_last = tm->isr_count;
  if (!tm->run || first) {
    memset(&p->w, 0, sizeof p->w);
    p->bad = 0;
    return 0u;
  }
  p->w.angle += fabsf(tm->omega_m) * c->pole_pairs * (float)isrs * c->ts;
  /* mut: voltage_balance_no_resistance */
  window_add(&p->w, tm, c->rs, p->w.angle * (1.0f / FRAMES_2PI));
  if (p->w.angle < FRAMES_2PI) {
    if (p->w.n >= DRIVE_PH_MAX_N) { /* too slow: no verdict */
      memset(&p->w, 0, sizeof p->w);
      p->bad = 0;
    }
    return 0u;
  }
  /* mut: phase_check_off */
  const int v = verdict(p, c->i_max, tm->v_dc);
  p->bad = v > 0 ? p->bad + 1 : 0;
  memset(&p->w, 0, sizeof p->w);
  if (p->bad >= DRIVE_PH_TRIP) {
    p->bad = 0;
    p->trips++;
    return DRIVE_FAULT_LOST_CONTROL;
  }
  return 0u;
}
