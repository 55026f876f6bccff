/*
 * spm_plant_ref.h - test-side reference SPM machine in double precision:
 * the exact solution of the continuous model (Rubino 2020, eqs. (1)-(3))
 * over one period with the voltage held constant in (alpha, beta) (what an
 * average-value inverter applies) and constant rotor speed:
 *   L di/dt = v - R i - j w lambda_m e^{j theta(t)}
 *   i(Ts) = k i0 + (1-k)/R v - j w lambda_m e^{j theta0} (e^{j w Ts} - k) / (L (f + j w))
 * Independent of the firmware code (complex double arithmetic), plus an RK4
 * integrator for a second, method-independent check.
 */
#ifndef DFVC_TEST_SPM_PLANT_REF_H
#define DFVC_TEST_SPM_PLANT_REF_H

#include <complex.h>
#include <math.h>

typedef struct {
  double r, l, lm, p, ts;
  double complex i; /* stator current, alpha + j beta [A] */
  double theta;     /* electrical angle [rad] */
  double w;         /* electrical speed [rad/s] */
} spm_plant_t;

static inline void spm_plant_init(spm_plant_t *m, double r, double l, double lm, double p,
                                  double ts, double w) {
  m->r = r;
  m->l = l;
  m->lm = lm;
  m->p = p;
  m->ts = ts;
  m->i = 0.0;
  m->theta = 0.0;
  m->w = w;
}

/* Exact one-period solution from (i0, theta0) under v, speed w. */
static inline double complex spm_plant_exact(double r, double l, double lm, double ts, double w,
                                             double complex i0, double theta0, double complex v) {
  const double f = r / l;
  const double k = exp(-f * ts);
  const double complex emf =
      -I * w * lm * cexp(I * theta0) * (cexp(I * w * ts) - k) / (l * (f + I * w));
  return k * i0 + (1.0 - k) / r * v + emf;
}

/* RK4 with n sub-steps of the same ODE (method-independent check). */
static inline double complex spm_plant_rk4(double r, double l, double lm, double ts, double w,
                                           double complex i0, double theta0, double complex v,
                                           int n) {
  const double h = ts / n;
  double complex i = i0;
  for (int s = 0; s < n; ++s) {
    const double t = s * h;
#define SPM_DI(ii, tt) ((v - r * (ii)-I * w * lm * cexp(I * (theta0 + w * (tt)))) / l)
    const double complex k1 = SPM_DI(i, t);
    const double complex k2 = SPM_DI(i + 0.5 * h * k1, t + 0.5 * h);
    const double complex k3 = SPM_DI(i + 0.5 * h * k2, t + 0.5 * h);
    const double complex k4 = SPM_DI(i + h * k3, t + h);
#undef SPM_DI
    i += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return i;
}

static inline void spm_plant_step(spm_plant_t *m, double complex v) {
  m->i = spm_plant_exact(m->r, m->l, m->lm, m->ts, m->w, m->i, m->theta, v);
  m->theta = remainder(m->theta + m->w * m->ts, 6.283185307179586);
}

static inline double complex spm_plant_flux(const spm_plant_t *m) {
  return m->l * m->i + m->lm * cexp(I * m->theta);
}

/* i_qs = (lambda x i) / |lambda| */
static inline double spm_plant_iqs(const spm_plant_t *m) {
  const double complex lam = spm_plant_flux(m);
  return cimag(conj(lam) * m->i) / cabs(lam);
}

static inline double spm_plant_torque(const spm_plant_t *m) {
  const double complex lam = spm_plant_flux(m);
  return 1.5 * m->p * cimag(conj(lam) * m->i);
}

#endif
