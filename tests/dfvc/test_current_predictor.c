/*
 * test_current_predictor.c - MPE, Rubino 2020, eq. (21), against the exact
 * solution of the continuous SPM equations over one period (double, closed
 * form and RK4), at 0, 100 and 1200 rpm, both forms.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>

#include "estimation/current_predictor.h"
#include "spm_plant_ref.h"

#define RS 7.1
#define LS 0.057
#define LM 0.19
#define TS 62.5e-6
#define P  21.0

static double rpm_to_we(double rpm) {
  return rpm * 6.283185307179586 / 60.0 * P;
}

/* worst error of the predictor over a set of states and voltages */
static machine_t machine; /* the predictor holds a pointer to it */

static double worst_error(current_predictor_mode_t mode, double we) {
  current_predictor_t p;
  assert_int_equal(
      machine_init_linear(&machine, (float)P, (float)RS, (float)LS, (float)LS, (float)LM), 0);
  const current_predictor_cfg_t cfg = {&machine, (float)TS, mode};
  assert_int_equal(current_predictor_init(&p, &cfg), 0);
  double worst = 0.0;
  for (int n = 0; n < 64; ++n) {
    const double th = -3.1 + 0.097 * n;
    const double complex i0 = 3.0 * cexp(I * (0.3 + 0.41 * n));
    const double complex v = 150.0 * cexp(I * (1.1 - 0.23 * n));
    const double complex want = spm_plant_exact(RS, LS, LM, TS, we, i0, th, v);
    const double complex rk = spm_plant_rk4(RS, LS, LM, TS, we, i0, th, v, 200);
    assert_true(cabs(want - rk) < 1e-9); /* the closed form is the ODE solution */
    const ab_t got =
        current_predictor_step(&p, (ab_t){(float)creal(i0), (float)cimag(i0)},
                               (ab_t){(float)creal(v), (float)cimag(v)}, (float)th, (float)we);
    const double e = cabs((got.alpha + I * got.beta) - want);
    worst = (e > worst) ? e : worst;
  }
  return worst;
}

/* Exact form: float rounding only (|i| ~ 3 A, |v| ~ 150 V). */
static void test_exact_form_matches_continuous(void **state) {
  (void)state;
  const double rpm[4] = {0.0, 100.0, -600.0, 1200.0};
  for (int n = 0; n < 4; ++n) {
    const double e = worst_error(CURRENT_PREDICTOR_EXACT, rpm_to_we(rpm[n]));
    printf("  exact MPE, %6.0f rpm: worst |error| %.3g A\n", rpm[n], e);
    assert_true(e < 5e-6);
  }
}

/* Printed (21): the back-EMF is held at tau. Its error is first order in
 * w Ts: about (Ts/Ls) w lambda_m (w Ts / 2). Check it stays within 1.2x that
 * bound and that the exact form is far better at high speed. */
static void test_eq21_error_bound(void **state) {
  (void)state;
  const double rpm[3] = {0.0, 100.0, 1200.0};
  for (int n = 0; n < 3; ++n) {
    const double we = rpm_to_we(rpm[n]);
    const double e = worst_error(CURRENT_PREDICTOR_EQ21, we);
    const double bound = TS / LS * fabs(we) * LM * fabs(we) * TS / 2.0;
    printf("  eq. (21) MPE, %5.0f rpm: worst |error| %.3g A (bound %.3g A)\n", rpm[n], e, bound);
    assert_true(e <= 1.2 * bound + 5e-6);
    if (rpm[n] > 1000.0) {
      assert_true(e > 0.5 * bound); /* the held EMF really is an approximation */
      assert_true(e > 100.0 * worst_error(CURRENT_PREDICTOR_EXACT, we));
    }
  }
}

static void test_init_rejects_bad(void **state) {
  (void)state;
  current_predictor_t p;
  current_predictor_cfg_t cfg = {NULL, 62.5e-6f, CURRENT_PREDICTOR_EXACT};
  assert_int_equal(current_predictor_init(&p, &cfg), -1); /* no machine */
  assert_int_equal(machine_init_linear(&machine, 21.0f, 7.1f, 0.057f, 0.057f, 0.19f), 0);
  cfg.machine = &machine;
  cfg.ts = 0.0f;
  assert_int_equal(current_predictor_init(&p, &cfg), -1);
  cfg.ts = 62.5e-6f;
  cfg.mode = (current_predictor_mode_t)7;
  assert_int_equal(current_predictor_init(&p, &cfg), -1);
  cfg.mode = CURRENT_PREDICTOR_EQ21;
  assert_int_equal(current_predictor_init(&p, &cfg), 0);
  current_predictor_reset(&p);
  assert_true(fabsf(p.disc.ks - 0.99224514f) < 1e-6f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_exact_form_matches_continuous),
      cmocka_unit_test(test_eq21_error_bound),
      cmocka_unit_test(test_init_rejects_bad),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
