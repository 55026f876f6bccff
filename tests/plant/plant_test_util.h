/*
 * plant_test_util.h - shared parameter sets and small analytic helpers for
 * the plant tests (header-only, static functions).
 */
#ifndef FD_TESTS_PLANT_TEST_UTIL_H
#define FD_TESTS_PLANT_TEST_UTIL_H

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "plant.h"

#define T_PI     3.14159265358979323846
#define T_TWO_PI 6.28318530717958647692

/* A small IPM test machine on a 24 V link, 16 kHz, locked at theta = 0. */
static inline plant_params_t test_params(void) {
  plant_params_t p;
  memset(&p, 0, sizeof p);
  p.machine.pole_pairs = 4;
  p.machine.rs = 0.5;
  p.machine.ld = 1.0e-3;
  p.machine.lq = 1.6e-3;
  p.machine.lambda_m = 0.01;
  p.inverter.model = PLANT_INV_AVERAGE;
  p.inverter.dead_time = 0.0;
  p.inverter.substeps = 2;
  p.dclink.kind = PLANT_DC_IDEAL;
  p.dclink.v_source = 24.0;
  p.dclink.r = 0.1;
  p.dclink.c = 1e-3;
  p.mech.mode = PLANT_MECH_IMPOSED;
  p.mech.j = 1e-4;
  p.mech.b = 1e-4;
  p.sensors.adc_bits = 12;
  p.sensors.i_full_scale = 20.0;
  p.sensors.v_full_scale = 60.0;
  p.sensors.seed = 1;
  p.ts = 62.5e-6;
  return p;
}

static inline void test_const_speed(plant_params_t *p, double w) {
  p->mech.speed.n = 0;
  profile_term_t k;
  memset(&k, 0, sizeof k);
  k.kind = PROFILE_CONST;
  k.value = w;
  assert_int_equal(profile_add(&p->mech.speed, k), 0);
}

static inline void test_init(plant_t *pl, const plant_params_t *p) {
  const char *f = NULL;
  int rc = plant_init(pl, p, &f);
  if (rc != 0) {
    print_error("plant_init failed on %s\n", f);
  }
  assert_int_equal(rc, 0);
}

/* Duties (centred on 0.5) that apply the stationary-frame vector (va, vb)
 * as phase-to-neutral voltages on a link of vdc. */
static inline void test_duties_ab(double valpha, double vbeta, double vdc, double d[3]) {
  const double va = valpha, vb = -0.5 * valpha + 0.86602540378443864676 * vbeta;
  const double vc = -va - vb;
  d[0] = 0.5 + va / vdc;
  d[1] = 0.5 + vb / vdc;
  d[2] = 0.5 + vc / vdc;
}

/* Duties applying v_dq over the coming period, with the angle advanced by
 * half a period (the rotor turns while the vector is held). */
static inline void test_duties_dq(const plant_t *pl, double vd, double vq, double d[3]) {
  const double th = pl->p.machine.pole_pairs * (pl->theta_m + 0.5 * pl->omega_m * pl->p.ts);
  const double c = cos(th), s = sin(th);
  test_duties_ab(vd * c - vq * s, vd * s + vq * c, pl->v_dc, d);
}

/* ---- n x n real matrices (n <= 6), row major, for exact LTI solutions ---- */
#define TM_N 6
typedef struct {
  int n;
  double a[TM_N][TM_N];
} tmat_t;

static inline tmat_t tm_zero(int n) {
  tmat_t m;
  memset(&m, 0, sizeof m);
  m.n = n;
  return m;
}

static inline tmat_t tm_mul(const tmat_t *x, const tmat_t *y) {
  tmat_t r = tm_zero(x->n);
  for (int i = 0; i < x->n; i++) {
    for (int j = 0; j < x->n; j++) {
      for (int k = 0; k < x->n; k++) {
        r.a[i][j] += x->a[i][k] * y->a[k][j];
      }
    }
  }
  return r;
}

/* exp(M) by scaling and squaring of a 30-term Taylor series. */
static inline tmat_t tm_expm(const tmat_t *m) {
  double nrm = 0.0;
  for (int i = 0; i < m->n; i++) {
    for (int j = 0; j < m->n; j++) {
      nrm = fmax(nrm, fabs(m->a[i][j]));
    }
  }
  int sq = 0;
  while (nrm * m->n > 0.1) {
    nrm *= 0.5;
    sq++;
  }
  tmat_t s = *m;
  for (int i = 0; i < m->n; i++) {
    for (int j = 0; j < m->n; j++) {
      s.a[i][j] = ldexp(m->a[i][j], -sq);
    }
  }
  tmat_t r = tm_zero(m->n), term = tm_zero(m->n);
  for (int i = 0; i < m->n; i++) {
    r.a[i][i] = 1.0;
    term.a[i][i] = 1.0;
  }
  for (int k = 1; k < 30; k++) {
    term = tm_mul(&term, &s);
    for (int i = 0; i < m->n; i++) {
      for (int j = 0; j < m->n; j++) {
        term.a[i][j] /= k;
        r.a[i][j] += term.a[i][j];
      }
    }
  }
  for (int k = 0; k < sq; k++) {
    r = tm_mul(&r, &r);
  }
  return r;
}

/* Exact periodic steady state, sampled at the period start, of the machine
 * in the rotor frame at constant electrical speed we with the stationary
 * voltage vector held over each period and advanced by half a period (what
 * test_duties_dq applies, no dead time): vdq(tau) = R(we Ts/2 - we tau) v*.
 * State y = (lambda_d - lambda_m, lambda_q):
 *   dy/dt = A y + u + f, A = [[-R/Ld, we], [-we, -R/Lq]], f = (0, -we lambda_m),
 *   du/dtau = -we J u. Augmented 5x5 exponential, y0 = (I - E11)^-1 (E12 u0 + E13).
 * Returns i_dq at the sample instants. */
static inline void test_periodic_dq(const plant_machine_t *mc, double we, double ts, double vd,
                                    double vq, double i_dq[2]) {
  tmat_t m = tm_zero(5);
  m.a[0][0] = -mc->rs / mc->ld;
  m.a[0][1] = we;
  m.a[1][0] = -we;
  m.a[1][1] = -mc->rs / mc->lq;
  m.a[0][2] = 1.0;
  m.a[1][3] = 1.0;
  m.a[1][4] = -we * mc->lambda_m;
  m.a[2][3] = we; /* du/dt = -we J u, J = [[0,-1],[1,0]] */
  m.a[3][2] = -we;
  for (int i = 0; i < 5; i++) {
    for (int j = 0; j < 5; j++) {
      m.a[i][j] *= ts;
    }
  }
  const tmat_t e = tm_expm(&m);
  const double x = 0.5 * we * ts;
  const double u0[2] = {cos(x) * vd - sin(x) * vq, sin(x) * vd + cos(x) * vq};
  const double r0 = e.a[0][2] * u0[0] + e.a[0][3] * u0[1] + e.a[0][4];
  const double r1 = e.a[1][2] * u0[0] + e.a[1][3] * u0[1] + e.a[1][4];
  const double m00 = 1.0 - e.a[0][0], m01 = -e.a[0][1], m10 = -e.a[1][0], m11 = 1.0 - e.a[1][1];
  const double det = m00 * m11 - m01 * m10;
  const double y0 = (m11 * r0 - m01 * r1) / det, y1 = (-m10 * r0 + m00 * r1) / det;
  i_dq[0] = y0 / mc->ld;
  i_dq[1] = y1 / mc->lq;
}

static inline double test_wrap_diff(double a, double b) {
  double d = fmod(a - b, T_TWO_PI);
  if (d > T_PI) {
    d -= T_TWO_PI;
  } else if (d < -T_PI) {
    d += T_TWO_PI;
  }
  return d;
}

#endif
