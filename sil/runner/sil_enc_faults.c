/*
 * sil_enc_faults.c - encoder faults of the SIL (sil_enc_faults.h).
 */
#include "sil_enc_faults.h"

#include <math.h>

#define ENC_TWO_PI 6.28318530717958647692

static uint64_t next_u64(uint64_t *s) { /* xorshift64* (Vigna 2016) */
  uint64_t x = *s;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  *s = x;
  return x * 2685821657736338717ull;
}

static double uniform(uint64_t *s) { /* (0, 1) */
  return ((double)(next_u64(s) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

static double normal(uint64_t *s) { /* Box-Muller (one of the pair) */
  return sqrt(-2.0 * log(uniform(s))) * cos(ENC_TWO_PI * uniform(s));
}

static double wrap(double a) {
  a = fmod(a, ENC_TWO_PI);
  return a < 0.0 ? a + ENC_TWO_PI : a;
}

void sil_enc_faults_reset(sil_enc_state_t *st, const sil_enc_faults_t *f) {
  *st = (sil_enc_state_t){0};
  st->rng = 0x9E3779B97F4A7C15ull ^ (uint64_t)f->seed;
  if (st->rng == 0u) {
    st->rng = 1u;
  }
}

static bool on(const profile_t *p, double t) {
  return p->n > 0 && profile_eval(p, t) > 0.5;
}

double sil_enc_faults_apply(const sil_enc_faults_t *f, sil_enc_state_t *st, double t, double angle,
                            double w_m, double step) {
  if (!st->init) {
    st->init = true;
    st->prev = angle;
  }
  /* lost edges: of the counts the shaft moved since the last sample */
  if (f->missing > 0.0 && step > 0.0) {
    const double d = remainder(angle - st->prev, ENC_TWO_PI);
    const long n = lround(fabs(d) / step);
    for (long k = 0; k < n && k < 4096; ++k) { /* bounded: 4096 counts per period */
      if (uniform(&st->rng) < f->missing) {
        st->lost += d > 0.0 ? step : -step;
      }
    }
  }
  st->prev = angle;
  double r = angle - st->lost;
  if (f->jitter > 0.0) {
    r += w_m * f->jitter * normal(&st->rng);
  }
  const bool rev = on(&f->reversed, t);
  if (rev && !st->reversed) {
    st->rev_base = r;
  }
  st->reversed = rev;
  if (rev) {
    r = 2.0 * st->rev_base - r;
  }
  r = wrap(r);
  const bool frz = on(&f->frozen, t);
  if (frz && !st->frozen) {
    st->hold = r;
  }
  st->frozen = frz;
  return frz ? st->hold : r;
}
