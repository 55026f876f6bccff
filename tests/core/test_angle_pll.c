/*
 * test_angle_pll.c - type-2 angle PLL: ramp tracking with zero steady-state
 * error, wrap through +-pi, speed accuracy with a 4096 counts/rev encoder.
 * Ts = 62.5 us, wn = 200 rad/s (kp = 400, ki = 40000).
 */
#include "core_test_util.h"

#include "estimation/angle_pll.h"

#define TS 62.5e-6
#define WN 200.0f

static double wrap(double x) {
  return atan2(sin(x), cos(x));
}

typedef struct {
  double max_angle_err; /* over the last half */
  double max_speed_rel_err;
  double mean_speed;
  int wraps;         /* jumps of the estimate from +pi to -pi (or back), last half */
  double max_domega; /* largest step of the speed estimate (last half) */
} pll_run_t;

/* counts = 0: exact angle; otherwise quantised to 2 pi / counts (floor, as an encoder). */
static pll_run_t run(double w, int counts, int n) {
  angle_pll_t p;
  angle_pll_init(&p, WN, (float)TS);
  pll_run_t r = {0.0, 0.0, 0.0, 0, 0.0};
  double th = 0.3, prev_est = 0.0, prev_om = 0.0, sum = 0.0;
  int m = 0;
  for (int k = 0; k < n; k++) {
    double meas = wrap(th);
    if (counts > 0) {
      const double q = 2.0 * T_PI / counts;
      meas = wrap(floor(wrap(th) / q) * q);
    }
    angle_pll_update(&p, (float)meas);
    assert_true(p.theta >= (float)-T_PI && p.theta < (float)T_PI);
    if (k > n / 2 && fabs(p.theta - prev_est) > T_PI) {
      r.wraps++;
    }
    if (k >= n / 2) {
      /* the PLL estimate after update k refers to the next sample's angle
       * only through its integrator; compare with the angle it was given */
      const double e = fabs(wrap(p.theta - (th + w * TS)));
      if (e > r.max_angle_err) {
        r.max_angle_err = e;
      }
      const double se = fabs(p.omega - w) / fabs(w);
      if (se > r.max_speed_rel_err) {
        r.max_speed_rel_err = se;
      }
      if (fabs(p.omega - prev_om) > r.max_domega) {
        r.max_domega = fabs(p.omega - prev_om);
      }
      sum += p.omega;
      m++;
    }
    prev_est = p.theta;
    prev_om = p.omega;
    th += w * TS;
  }
  r.mean_speed = sum / m;
  return r;
}

/* Exact ramp: after the transient the estimate equals the (one-step-ahead)
 * angle to float rounding and the speed is exact; every revolution wraps once. */
static void test_ramp_zero_error(void **state) {
  (void)state;
  const double speeds[] = {2.0 * T_PI * 50.0, -2.0 * T_PI * 120.0, 2.0 * T_PI * 400.0};
  for (int s = 0; s < 3; s++) {
    const int n = 16000; /* 1 s = 200/wn time constants */
    const pll_run_t r = run(speeds[s], 0, n);
    printf("  exact ramp w=%.1f: max angle err %.2e rad, max speed err %.2e\n", speeds[s],
           r.max_angle_err, r.max_speed_rel_err);
    ASSERT_NEAR(r.max_angle_err, 0.0, 5e-5); /* float ulp of pi is 2.4e-7 */
    ASSERT_NEAR(r.max_speed_rel_err, 0.0, 1e-4);
    /* the pull-in from omega = 0 may slip cycles; count after it */
    const int expected_wraps = (int)floor(fabs(speeds[s]) * (n / 2) * TS / (2.0 * T_PI));
    assert_in_range(r.wraps, expected_wraps - 1, expected_wraps + 1);
  }
}

/* 4096 counts/rev, floor quantisation: speed within 0.5 % at every sample of
 * the second half, mean within 0.01 %, angle within 1 count (floor biases by
 * half a count). 5 Hz is 0.2 counts per sample. */
static void test_quantised_speed(void **state) {
  (void)state;
  const double speeds[] = {2.0 * T_PI * 5.0, 2.0 * T_PI * 20.0, 2.0 * T_PI * 100.0,
                           -2.0 * T_PI * 300.0};
  for (int s = 0; s < 4; s++) {
    const pll_run_t r = run(speeds[s], 4096, 32000);
    printf("  4096 cpr w=%.1f: max speed err %.3f %%, mean err %.4f %%, angle err %.2f counts\n",
           speeds[s], 100.0 * r.max_speed_rel_err,
           100.0 * fabs(r.mean_speed - speeds[s]) / fabs(speeds[s]),
           r.max_angle_err / (2.0 * T_PI / 4096.0));
    assert_true(r.max_speed_rel_err < 0.005);
    assert_true(r.max_angle_err < 2.0 * T_PI / 4096.0);
    ASSERT_NEAR(r.mean_speed, speeds[s], 1e-4 * fabs(speeds[s]));
  }
}

/* Through the +-pi edge the speed estimate does not jump (the error is wrapped). */
static void test_wrap_no_glitch(void **state) {
  (void)state;
  const double w = 2.0 * T_PI * 200.0;
  const pll_run_t r = run(w, 0, 16000);
  assert_in_range(r.wraps, 99, 101); /* 200 Hz over the last 0.5 s */
  /* in steady state the speed estimate is constant to float rounding */
  assert_true(r.max_domega < 1e-3 * w);
}

static void test_reset_and_coast(void **state) {
  (void)state;
  angle_pll_t p;
  angle_pll_init(&p, WN, (float)TS);
  ASSERT_NEAR(p.kp, 400.0, 1e-4);
  ASSERT_NEAR(p.ki, 40000.0, 1e-2);
  angle_pll_reset(&p, (float)(3.0 * T_PI), 100.0f);
  ASSERT_NEAR(p.theta, -T_PI, 1e-5);
  ASSERT_NEAR(p.omega, 100.0, 0.0);
  /* non-finite measurement: coast at the estimated speed */
  angle_pll_reset(&p, 1.0f, 100.0f);
  angle_pll_update(&p, NAN);
  ASSERT_NEAR(p.theta, 1.0 + 100.0 * TS, 1e-6);
  ASSERT_NEAR(p.omega, 100.0, 0.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ramp_zero_error),
      cmocka_unit_test(test_quantised_speed),
      cmocka_unit_test(test_wrap_no_glitch),
      cmocka_unit_test(test_reset_and_coast),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
