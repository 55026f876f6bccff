/*
 * test_spm_discrete.c - Rubino 2020, eqs. (10)-(15): coefficients for the
 * Table I machine against values computed by hand (double, closed form),
 * the one-step map against the exact continuous solution, and init checks.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <complex.h>
#include <math.h>

#include "model/spm_discrete.h"

#define RS 7.1
#define LS 0.057
#define TS 62.5e-6

static void close_rel(double got, double want, double rel) {
  const double err = fabs(got - want);
  if (err > rel * fabs(want)) {
    fail_msg("got %.9g want %.9g (rel err %.3g > %.3g)", got, want, err / fabs(want), rel);
  }
}

/* Hand-computed (Python, double): f_s = 124.56140350877192,
 * k_s = 0.9922451375896806, (1-k_s)/Rs = 0.0010922341422985097;
 * omega_xy = 219.911 rad/s (100 rpm, p = 21): a_xx 0.9921514163538017,
 * a_xy 0.01363745201676027, b_xx 0.0010921998204713346, b_xy 7.496231393890948e-06;
 * omega_xy = 2638.94 rad/s (1200 rpm): 0.9787796340095781, 0.1629136001641372,
 * 0.0010872984662355922, 8.975266376021748e-05. */
static void test_coefficients_table1(void **state) {
  (void)state;
  spm_discrete_t m;
  assert_int_equal(spm_discrete_init(&m, (float)RS, (float)LS, (float)TS), 0);
  close_rel(m.fs, 124.56140350877192, 2e-7);
  close_rel(m.ks, 0.9922451375896806, 1e-7);
  close_rel(m.b_ab, 0.0010922341422985097, 2e-6);

  const double w[2] = {219.9114857512855, 2638.9378290154264};
  const double want[2][4] = {
      {0.9921514163538017, 0.01363745201676027, 0.0010921998204713346, 7.496231393890948e-06},
      {0.9787796340095781, 0.1629136001641372, 0.0010872984662355922, 8.975266376021748e-05}};
  for (int n = 0; n < 2; ++n) {
    const spm_discrete_coef_t c = spm_discrete_coef(&m, (float)w[n]);
    close_rel(c.a_xx, want[n][0], 2e-7);
    close_rel(c.a_xy, want[n][1], 2e-6);
    close_rel(c.b_xx, want[n][2], 2e-6);
    close_rel(c.b_xy, want[n][3], 2e-5);
  }
  /* omega_xy = 0: b_xy = 0, b_xx = (1 - k_s)/Rs, a = k_s */
  const spm_discrete_coef_t c0 = spm_discrete_coef(&m, 0.0f);
  close_rel(c0.a_xx, 0.9922451375896806, 1e-7);
  assert_true(fabs(c0.a_xy) < 1e-12 && fabs(c0.b_xy) < 1e-12);
  close_rel(c0.b_xx, 0.0010922341422985097, 2e-6);
  /* negative speed mirrors the cross terms */
  const spm_discrete_coef_t cn = spm_discrete_coef(&m, (float)-w[1]);
  close_rel(cn.a_xy, -want[1][1], 2e-6);
  close_rel(cn.b_xy, -want[1][3], 2e-5);
}

/* Eq. (10) in the rotor frame, where u of (8) is constant, equals the exact
 * continuous solution di/dt = (A i + u/L) (complex form) over one period. */
static void test_step_vs_exact(void **state) {
  (void)state;
  spm_discrete_t m;
  assert_int_equal(spm_discrete_init(&m, (float)RS, (float)LS, (float)TS), 0);
  const double ws[3] = {0.0, 219.9114857512855, -2638.9378290154264};
  for (int n = 0; n < 3; ++n) {
    const double w = ws[n];
    const double complex i0 = 1.3 - 0.7 * I;
    const double complex u = 40.0 + 120.0 * I;
    /* exact: i' = -(f + j w) i + u / L */
    const double complex a = -(RS / LS + I * w);
    const double complex want = cexp(a * TS) * i0 + (cexp(a * TS) - 1.0) / a * u / LS;
    const spm_discrete_coef_t c = spm_discrete_coef(&m, (float)w);
    const dq_t got = spm_discrete_step(&c, (dq_t){1.3f, -0.7f}, (dq_t){40.0f, 120.0f});
    assert_true(fabs(got.d - creal(want)) < 2e-6);
    assert_true(fabs(got.q - cimag(want)) < 2e-6);
  }
}

static void test_init_rejects_bad(void **state) {
  (void)state;
  spm_discrete_t m;
  assert_int_equal(spm_discrete_init(&m, 0.0f, 0.057f, 62.5e-6f), -1);
  assert_int_equal(spm_discrete_init(&m, 7.1f, -1.0f, 62.5e-6f), -1);
  assert_int_equal(spm_discrete_init(&m, 7.1f, 0.057f, NAN), -1);
  assert_int_equal(spm_discrete_init(&m, 7.1f, 0.057f, 62.5e-6f), 0);
  m.ks = 0.0f;
  spm_discrete_reset(&m);
  close_rel(m.ks, 0.9922451375896806, 1e-7);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_coefficients_table1),
      cmocka_unit_test(test_step_vs_exact),
      cmocka_unit_test(test_init_rejects_bad),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
