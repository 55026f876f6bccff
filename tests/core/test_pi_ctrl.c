/*
 * test_pi_ctrl.c - discrete PI: exact step response, limits, anti-windup,
 * bumpless reset, non-finite inputs.
 */
#include "core_test_util.h"

#include "math/pi_ctrl.h"

/* u(n) = kp e + ki Ts sum_{j=1..n} e (forward Euler, integral updated first) */
static void test_step_exact(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 2.0f, 100.0f, 1e-3f, -100.0f, 100.0f);
  for (int n = 1; n <= 50; n++) {
    const float u = pi_ctrl_update(&pi, 1.0f, 0.0f);
    ASSERT_NEAR(u, 2.0 + 0.1 * n, 1e-5);
  }
  /* feed-forward adds before the limit, does not enter the integral */
  pi_ctrl_reset(&pi, 0.0f);
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.5f, 3.0f), 1.0 + 0.05 + 3.0, 1e-6);
  ASSERT_NEAR(pi.integ, 0.05, 1e-7);
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.0f, 99.0f), 99.05, 1e-4);
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.0f, 200.0f), 100.0, 0.0);
}

static void test_limits_hold(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 0.5f, 50.0f, 1e-3f, -1.0f, 2.0f);
  for (int n = 0; n < 500; n++) {
    const float e = (float)(10.0 * sin(0.01 * n));
    const float u = pi_ctrl_update(&pi, e, 0.0f);
    ASSERT_IN(u, -1.0, 2.0);
    /* documented invariant: integ in [min - max(p, 0), max - min(p, 0)] */
    const double p = 0.5 * e;
    ASSERT_IN(pi.integ, -1.0 - fmax(p, 0.0) - 1e-6, 2.0 - fmin(p, 0.0) + 1e-6);
  }
  /* limits that shrink under a running output clamp it and re-align the integral */
  pi_ctrl_reset(&pi, 1.5f);
  pi_ctrl_set_limits(&pi, -0.2f, 0.2f);
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.0f, 0.0f), 0.2f, 0.0);
  ASSERT_NEAR(pi.integ, 0.2, 1e-7);
  /* crossed limits collapse to their mean; NaN limits are ignored */
  pi_ctrl_set_limits(&pi, 1.0f, 0.0f);
  ASSERT_NEAR(pi_ctrl_update(&pi, 5.0f, 0.0f), 0.5, 0.0);
  pi_ctrl_set_limits(&pi, NAN, 3.0f);
  ASSERT_NEAR(pi.out_min, 0.5, 0.0);
  ASSERT_NEAR(pi.out_max, 0.5, 0.0);
}

/* After a long saturation the output must leave the limit on the first step
 * with the error reversed; a naive integrator (output clamp only) needs
 * thousands of steps: kp = 0.5, ki = 50, Ts = 1 ms, limits +-1, e = +2 for
 * 1 s (naive integral 100), then e = -0.5: naive leaves after
 * (100 - 0.25 - 1)/0.025 ~ 3950 steps. Ours: kp*2 = 1 saturates from the
 * first step, so the integral stays 0 and the first output after the
 * reversal is -0.25 - 0.025 = -0.275. */
static void test_anti_windup(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 0.5f, 50.0f, 1e-3f, -1.0f, 1.0f);
  double naive_integ = 0.0;
  for (int n = 0; n < 1000; n++) {
    ASSERT_NEAR(pi_ctrl_update(&pi, 2.0f, 0.0f), 1.0, 0.0);
    naive_integ += 50.0 * 1e-3 * 2.0;
  }
  ASSERT_NEAR(pi.integ, 0.0, 1e-6); /* stopped where u reached out_max: no wind-up */
  const float u = pi_ctrl_update(&pi, -0.5f, 0.0f);
  ASSERT_NEAR(u, -0.275, 1e-6);
  assert_true(u < 1.0f);
  int naive_steps = 0;
  double un = 1.0;
  while (un >= 1.0 && naive_steps < 100000) {
    naive_integ += 50.0 * 1e-3 * -0.5;
    un = fmin(1.0, fmax(-1.0, 0.5 * -0.5 + naive_integ));
    naive_steps++;
  }
  assert_in_range(naive_steps, 3900, 4000);
  /* the same holds for the lower limit */
  pi_ctrl_reset(&pi, 0.0f);
  for (int n = 0; n < 1000; n++) {
    ASSERT_NEAR(pi_ctrl_update(&pi, -2.0f, 0.0f), -1.0, 0.0);
  }
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.5f, 0.0f), 0.275, 1e-6);
}

/* Conditional integration: while the output sits on the limit with the
 * error pushing into it, the integral does not grow. */
static void test_no_growth_into_saturation(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 0.0f, 10.0f, 1e-2f, -1.0f, 1.0f); /* pure I */
  for (int n = 0; n < 100; n++) {
    const float u = pi_ctrl_update(&pi, 1.0f, 0.0f);
    ASSERT_NEAR(u, fmin(1.0, 0.1 * (n + 1)), 1e-5);
    assert_true(pi.integ <= 1.0f);
  }
  ASSERT_NEAR(pi_ctrl_update(&pi, -1.0f, 0.0f), 0.9, 1e-6); /* leaves at once */
}

static void test_bumpless_reset(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 3.0f, 7.0f, 1e-3f, -2.0f, 2.0f);
  pi_ctrl_reset(&pi, 0.3f);
  ASSERT_NEAR(pi_ctrl_update(&pi, 0.0f, 0.0f), 0.3f, 0.0);
  pi_ctrl_reset(&pi, 5.0f); /* beyond the limit: clamped */
  ASSERT_NEAR(pi.integ, 2.0, 0.0);
  pi_ctrl_reset(&pi, NAN);
  ASSERT_NEAR(pi.integ, 0.0, 0.0);
}

static void test_non_finite(void **state) {
  (void)state;
  pi_ctrl_t pi;
  pi_ctrl_init(&pi, 1.0f, 10.0f, 1e-3f, -5.0f, 5.0f);
  pi_ctrl_reset(&pi, 1.0f);
  float u = pi_ctrl_update(&pi, NAN, 0.0f);
  ASSERT_NEAR(u, 1.0, 0.0);
  u = pi_ctrl_update(&pi, INFINITY, NAN);
  ASSERT_NEAR(u, 1.0, 0.0);
  ASSERT_NEAR(pi.integ, 1.0, 0.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_step_exact),     cmocka_unit_test(test_limits_hold),
      cmocka_unit_test(test_anti_windup),    cmocka_unit_test(test_no_growth_into_saturation),
      cmocka_unit_test(test_bumpless_reset), cmocka_unit_test(test_non_finite),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
