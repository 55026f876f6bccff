/*
 * hal_pattern.h - what a timer does with a requested PWM pattern, shared
 * by the HAL implementations that model a timer (hal/sil, pil): every leg
 * limited to the board's duty range and, without HAL_CAP_ASYM_EDGES,
 * centred; edges rounded to the timer's compare steps (counts per period,
 * 0 = exact). A NaN request gives the middle of the range (no voltage).
 * The STM32G4 HAL does the same with its registers (hal/stm32g4/pwm_tim1.c).
 *
 * The timer is taken once (hal_pattern_init: the range's middle, the
 * counts as floats, the features), not at every write: the write is the
 * PIL's stand-in for the board's register HAL, counted in the ISR's
 * instructions (docs/pil.md), and the SIL's every period.
 */
#ifndef FLUXDRIVE_HAL_PATTERN_H
#define FLUXDRIVE_HAL_PATTERN_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"

/* -Os would call the leg's helpers three times: inline, as one pattern */
#if defined(__GNUC__)
#define HAL_PATTERN_INLINE static inline __attribute__((always_inline))
#else
#define HAL_PATTERN_INLINE static inline
#endif

/* A timer as the write sees it (hal_pattern_init). */
typedef struct {
  float lo, hi;    /* the duty range the write limits to */
  float mid;       /* a NaN request's duty */
  uint32_t counts; /* compare steps per period; 0: exact */
  float n;         /* counts as a float: the duty's steps */
  float n2;        /* 2 counts: the edges' steps (centre-aligned timer) */
  bool asym;       /* HAL_CAP_ASYM_EDGES: the edges as asked */
  bool star;       /* HAL_CAP_STAR_POINT: star-point samples kept */
} hal_pattern_t;

/* The board's duty range and its middle; with rounding, both from 0 up: a
 * duty below 0 rounds to count 0, so limiting it to 0 first gives the same
 * pattern and the rounding needs no test of its sign. */
static inline void hal_pattern_init(hal_pattern_t *m, const hal_caps_t *caps, uint32_t counts) {
  const float mid = 0.5f * (caps->duty_min + caps->duty_max);
  m->lo = caps->duty_min;
  m->hi = caps->duty_max;
  m->mid = mid;
  if (counts != 0u) {
    m->lo = m->lo > 0.0f ? m->lo : 0.0f;
    m->mid = mid > 0.0f ? mid : 0.0f;
  }
  m->counts = counts;
  m->n = (float)counts;
  m->n2 = (float)(2u * counts);
  m->asym = (caps->features & HAL_CAP_ASYM_EDGES) != 0u;
  m->star = (caps->features & HAL_CAP_STAR_POINT) != 0u;
}

/* To the nearest of n steps (n > 0), as the board's duty_to_ccr, for x >=
 * 0 (a duty limited by hal_pattern_duty, an edge inside the period; no
 * libm call in the ISR). The step count divides (not a reciprocal's
 * product): the same float as the board's count over its period. */
HAL_PATTERN_INLINE float hal_pattern_round(float x, float n) {
  return (float)(uint32_t)(x * n + 0.5f) / n;
}

/* A leg's duty limited to the range (a NaN request: the middle). */
HAL_PATTERN_INLINE float hal_pattern_limit(const hal_pattern_t *m, float on, float off) {
  const float x = off - on;
  if (!(x >= m->lo)) {
    return x < m->lo ? m->lo : m->mid; /* NaN: the middle */
  }
  return x > m->hi ? m->hi : x;
}

/* A leg's duty as the timer makes it: limited to the range, rounded. */
HAL_PATTERN_INLINE float hal_pattern_duty(const hal_pattern_t *m, float on, float off) {
  const float d = hal_pattern_limit(m, on, off);
  return m->counts != 0u ? hal_pattern_round(d, m->n) : d;
}

/* A leg of a timer with asymmetric edges: the edges as asked, the pulse
 * limited from its end (2 counts per compare step of a centre-aligned
 * timer); a pulse out of the period, centred. `rounded` is a constant at
 * each call (m->counts != 0): two straight-through loops, not a test per
 * leg. */
HAL_PATTERN_INLINE void hal_pattern_asym_leg(const hal_pattern_t *m, float on, float off,
                                             float *e_on, float *e_off, bool rounded) {
  const float dl = hal_pattern_limit(m, on, off);
  const float d = rounded ? hal_pattern_round(dl, m->n) : dl;
  if (on >= 0.0f && off <= 1.0f) {
    const float e = rounded ? hal_pattern_round(on, m->n2) : on;
    *e_on = e;
    *e_off = e + d;
  } else {
    *e_on = 0.5f * (1.0f - d);
    *e_off = 0.5f * (1.0f + d);
  }
}

/* The asymmetric edges' pattern: the timer and the request's edges in
 * locals first (a store to *out could alias either, which would read them
 * again per leg), then the legs straight through. */
HAL_PATTERN_INLINE void hal_pattern_asym(const hal_pattern_t *m, const hal_pwm_t *p, hal_pwm_t *out,
                                         bool rounded) {
  const hal_pattern_t t = *m;
  float on[3];
  float off[3];
#pragma GCC unroll 3
  for (int x = 0; x < 3; ++x) {
    on[x] = p->on[x];
    off[x] = p->off[x];
  }
#pragma GCC unroll 3
  for (int x = 0; x < 3; ++x) {
    hal_pattern_asym_leg(&t, on[x], off[x], &on[x], &off[x], rounded);
  }
#pragma GCC unroll 3
  for (int x = 0; x < 3; ++x) {
    out->on[x] = on[x];
    out->off[x] = off[x];
  }
}

/* Every field of *out written; each leg of p read before its store. */
static inline void hal_pattern_apply(const hal_pattern_t *m, const hal_pwm_t *p, hal_pwm_t *out) {
  out->test_vector = p->test_vector;
  out->n_star = m->star ? p->n_star : 0u;
  for (int k = 0; k < HAL_STAR_MAX; ++k) {
    out->t_star_req[k] = p->t_star_req[k];
  }
  if (!m->asym) {
    /* centred pulses (the usual timer): the legs straight through */
#pragma GCC unroll 3
    for (int x = 0; x < 3; ++x) {
      /* 0.5 -+ 0.5 d: the same floats as 0.5 (1 -+ d) (halving is exact) */
      const float h = 0.5f * hal_pattern_duty(m, p->on[x], p->off[x]);
      out->on[x] = 0.5f - h;
      out->off[x] = 0.5f + h;
    }
    return;
  }
  /* asymmetric edges (the DFC window's timer): rounded or exact */
  if (m->counts != 0u) {
    hal_pattern_asym(m, p, out, true);
  } else {
    hal_pattern_asym(m, p, out, false);
  }
}

#endif
