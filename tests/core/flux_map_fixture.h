/*
 * flux_map_fixture.h - a .fdmap blob built in the test from a closed-form
 * saturated machine (double precision), for the core's flux-map tests.
 *
 * Co-energy (fluxdrive frame, reciprocal by construction):
 *   W'(i_d, i_q) = lm i_d + Ld/2 i_d^2 + Lq0 a^2 ln cosh(i_q / a) g(i_d),
 *   g(i_d) = 1 / (1 + k i_d^2)
 *   lambda_d = dW'/di_d = lm + Ld i_d + Lq0 a^2 ln cosh(i_q/a) g'(i_d)
 *   lambda_q = dW'/di_q = Lq0 a tanh(i_q/a) g(i_d)
 * q saturates (tanh), the d current desaturates q less (g: cross-
 * saturation), and d lambda_d / d i_q = d lambda_q / d i_d.
 * Grid: i_d, i_q in [-FX_I, FX_I], FX_N points each; tables of FX_NL points
 * by brute force (MTPA: the best current angle at each amplitude; MTPV:
 * the best load angle at each flux amplitude).
 */
#ifndef FLUX_MAP_FIXTURE_H
#define FLUX_MAP_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "model/flux_map.h"

#define FX_N     25
#define FX_NL    64
#define FX_I     6.0
#define FX_WORDS (12 + 2 * FX_N * FX_N + 1 + 3 * FX_NL + 1 + FX_NL + 1)

typedef struct {
  double lm, ld, lq0, a, k, p;
} fx_model_t;

static const fx_model_t FX_SYR = {0.0, 0.1, 0.4, 3.0, 0.003, 2.0};
static const fx_model_t FX_PM = {0.3, 0.1, 0.4, 3.0, 0.003, 2.0};

static inline void fx_flux(const fx_model_t *m, double id, double iq, double *ld, double *lq) {
  const double g = 1.0 / (1.0 + m->k * id * id);
  const double dg = -2.0 * m->k * id * g * g;
  *ld = m->lm + m->ld * id + m->lq0 * m->a * m->a * log(cosh(iq / m->a)) * dg;
  *lq = m->lq0 * m->a * tanh(iq / m->a) * g;
}

static inline double fx_torque(const fx_model_t *m, double id, double iq) {
  double ld, lq;
  fx_flux(m, id, iq, &ld, &lq);
  return 1.5 * m->p * (ld * iq - lq * id);
}

static inline void fx_put_f(uint32_t *w, int i, double v) {
  const float f = (float)v;
  memcpy(&w[i], &f, sizeof f);
}

/* Best torque and its current at amplitude amp (angle sweep, motoring). */
static inline double fx_mtpa(const fx_model_t *m, double amp, double *id, double *iq) {
  double best = -1e300;
  for (int n = 0; n <= 4000; ++n) {
    const double b = 3.14159265358979 * n / 4000.0; /* from +q towards -d... all of it */
    const double d = -amp * sin(b), q = amp * cos(b);
    const double t = fx_torque(m, d, q);
    if (t > best && q >= 0.0) {
      best = t;
      *id = d;
      *iq = q;
    }
  }
  return best;
}

/* Builds the blob of model m into w (FX_WORDS words); returns its bytes. */
static inline uint32_t fx_build(const fx_model_t *m, uint32_t *w) {
  const double step = 2.0 * FX_I / (FX_N - 1);
  w[0] = FLUX_MAP_MAGIC;
  w[1] = FLUX_MAP_VERSION;
  w[2] = 4u * FX_WORDS;
  w[3] = FX_N;
  w[4] = FX_N;
  w[5] = FX_NL;
  w[6] = m->lm > 0.0 ? FLUX_MAP_FLAG_PM : 0u;
  fx_put_f(w, 7, m->p);
  fx_put_f(w, 8, -FX_I);
  fx_put_f(w, 9, step);
  fx_put_f(w, 10, -FX_I);
  fx_put_f(w, 11, step);
  for (int k = 0; k < FX_N; ++k) {
    for (int j = 0; j < FX_N; ++j) {
      double ld, lq;
      fx_flux(m, -FX_I + j * step, -FX_I + k * step, &ld, &lq);
      fx_put_f(w, 12 + k * FX_N + j, ld);
      fx_put_f(w, 12 + FX_N * FX_N + k * FX_N + j, lq);
    }
  }
  int o = 12 + 2 * FX_N * FX_N;
  /* MTPA: T(I) on a fine amplitude grid, then resampled at uniform torque */
  enum { NA = 400 };
  static double ta[NA + 1], da[NA + 1], qa[NA + 1];
  const double amax = FX_I;
  for (int n = 0; n <= NA; ++n) {
    ta[n] = fx_mtpa(m, amax * n / NA, &da[n], &qa[n]);
    ta[n] = n > 0 && ta[n] < ta[n - 1] ? ta[n - 1] : ta[n];
  }
  const double tmax = ta[NA];
  fx_put_f(w, o, tmax);
  int a = 0;
  for (int n = 0; n < FX_NL; ++n) {
    const double t = tmax * n / (FX_NL - 1);
    while (a < NA - 1 && ta[a + 1] < t) {
      ++a;
    }
    const double f = ta[a + 1] > ta[a] ? (t - ta[a]) / (ta[a + 1] - ta[a]) : 0.0;
    const double d = da[a] + f * (da[a + 1] - da[a]), q = qa[a] + f * (qa[a + 1] - qa[a]);
    double ld, lq;
    fx_flux(m, d, q, &ld, &lq);
    fx_put_f(w, o + 1 + n, d);
    fx_put_f(w, o + 1 + FX_NL + n, q);
    fx_put_f(w, o + 1 + 2 * FX_NL + n, sqrt(ld * ld + lq * lq));
  }
  o += 1 + 3 * FX_NL;
  /* MTPV: the largest torque on the current grid at each flux amplitude
   * (the flux amplitude bins of a dense current sweep) */
  double fmax = 0.0;
  for (int k = 0; k < FX_N; ++k) {
    for (int j = 0; j < FX_N; ++j) {
      double ld, lq;
      fx_flux(m, -FX_I + j * step, -FX_I + k * step, &ld, &lq);
      fmax = fmax > sqrt(ld * ld + lq * lq) ? fmax : sqrt(ld * ld + lq * lq);
    }
  }
  fx_put_f(w, o, fmax);
  double tv[FX_NL] = {0};
  for (int k = 0; k <= 240; ++k) {
    for (int j = 0; j <= 240; ++j) {
      const double id = -FX_I + 2.0 * FX_I * j / 240, iq = -FX_I + 2.0 * FX_I * k / 240;
      double ld, lq;
      fx_flux(m, id, iq, &ld, &lq);
      const int bin = (int)ceil(sqrt(ld * ld + lq * lq) / fmax * (FX_NL - 1));
      const double t = fx_torque(m, id, iq);
      if (bin < FX_NL && t > tv[bin]) {
        tv[bin] = t;
      }
    }
  }
  for (int n = 0; n < FX_NL; ++n) {
    tv[n] = n > 0 && tv[n] < tv[n - 1] ? tv[n - 1] : tv[n];
    fx_put_f(w, o + 1 + n, tv[n]);
  }
  w[FX_WORDS - 1] = flux_map_crc32(w, 4u * (FX_WORDS - 1));
  return 4u * FX_WORDS;
}

/* Re-seals a blob after a test changed it (a new CRC). */
static inline void fx_reseal(uint32_t *w) {
  w[FX_WORDS - 1] = flux_map_crc32(w, 4u * (FX_WORDS - 1));
}

/* A strong one-way cross term d lambda_d / d i_q from the row i_q index 12
 * on (a blob built by fx_build): the self-inductances stay positive, the
 * incremental matrix is not positive definite from cell (0, 12); resealed. */
static inline void fx_break_pd(uint32_t *w) {
  for (int k = 13; k < FX_N; ++k) {
    for (int j = 0; j < FX_N; ++j) {
      float f;
      memcpy(&f, &w[12 + k * FX_N + j], sizeof f);
      fx_put_f(w, 12 + k * FX_N + j, (double)f + 3.0 * (k - 12));
    }
  }
  fx_reseal(w);
}

#endif
