/*
 * test_kf_mech.c - the Kalman filter on the rotor's mechanics
 * (estimation/kf_mech.h): a simulated rotor with a load step, measured
 * through a noisy angle; the filter tracks speed and angle, estimates the
 * load (4.46)-(4.49), keeps its covariance symmetric and positive, follows
 * the angle across +-pi, and refuses bad configurations and measurements.
 */
#include "core_test_util.h"

#include "estimation/kf_mech.h"

static double wrapd(double x) {
  return remainder(x, 2.0 * T_PI);
}

static kf_mech_cfg_t cfg_t51(void) {
  kf_mech_cfg_t c = {62.5e-6f, 8.0f, 2e-4f, 1e-5f, {1.0f, 0.0f, 1e-6f}}; /* Q of (5.1) */
  return c;
}

/* deterministic normal numbers (Box-Muller on a LCG) */
static double gauss(unsigned *s) {
  *s = *s * 1664525u + 1013904223u;
  const double u1 = ((*s >> 8) + 0.5) / 16777216.0;
  *s = *s * 1664525u + 1013904223u;
  const double u2 = ((*s >> 8) + 0.5) / 16777216.0;
  return sqrt(-2.0 * log(u1)) * cos(2.0 * T_PI * u2);
}

static void test_tracks_speed_angle_and_load(void **state) {
  (void)state;
  const kf_mech_cfg_t c = cfg_t51();
  kf_mech_t k;
  assert_true(kf_mech_init(&k, &c));
  const float p0[3] = {100.0f, 0.1f, 1.0f};
  kf_mech_reset(&k, 0.0f, 0.0f, p0);
  double w = 0.0, th = 0.0, tl = 0.0;
  const double T = c.ts, p = c.pole_pairs, J = c.inertia, B = c.friction, r = 1e-4;
  unsigned seed = 7u;
  double e_w = 0.0, e_th = 0.0, tl_sum = 0.0;
  int n_e = 0;
  for (int n = 0; n < 64000; ++n) { /* 4 s */
    /* torque: accelerate, then hold ~ 500 rpm against a 0.02 N m load from 2 s */
    tl = n >= 32000 ? 0.02 : 0.0;
    const double w_ref = 500.0 * T_PI / 30.0 * p;
    const double te = fmin(0.05, fmax(-0.05, 1e-3 * (w_ref - w))) + tl;
    const double y = wrapd(th + sqrt(r) * gauss(&seed));
    assert_true(kf_mech_update(&k, (float)y, (float)r));
    kf_mech_predict(&k, (float)te);
    w += T * (p / J * (te - tl) - B / J * w);
    th = wrapd(th + T * w);
    if (n > 56000) { /* the last half second */
      e_w += fabs(k.x[0] - w);
      e_th += fabs(wrapd(k.x[1] - th));
      tl_sum += k.x[2];
      ++n_e;
    }
    /* the covariance stays positive: diagonal and 2x2 minors */
    if (n % 997 == 0) {
      assert_true(k.p[0] > 0.0f && k.p[3] > 0.0f && k.p[5] > 0.0f);
      assert_true(k.p[0] * k.p[3] - k.p[1] * k.p[1] > 0.0f);
    }
  }
  /* speed within 1 % of 500 rpm electrical on average, angle within 5 mrad,
   * the load estimate's mean within 5 % of the 0.02 N m step */
  ASSERT_IN(e_w / n_e, 0.0, 0.01 * 500.0 * T_PI / 30.0 * 8.0);
  ASSERT_IN(e_th / n_e, 0.0, 5e-3);
  ASSERT_NEAR(tl_sum / n_e, 0.02, 0.001);
}

static void test_refusals_and_wrap(void **state) {
  (void)state;
  kf_mech_cfg_t c = cfg_t51();
  kf_mech_t k;
  c.inertia = 0.0f;
  assert_false(kf_mech_init(&k, &c));
  c = cfg_t51();
  c.q[2] = -1.0f;
  assert_false(kf_mech_init(&k, &c));
  c = cfg_t51();
  c.ts = NAN;
  assert_false(kf_mech_init(&k, &c));
  c = cfg_t51();
  assert_true(kf_mech_init(&k, &c));
  const float p0[3] = {1.0f, 0.01f, 0.0f};
  kf_mech_reset(&k, 3.1f, 0.0f, p0);
  assert_false(kf_mech_update(&k, NAN, 1e-4f));
  assert_false(kf_mech_update(&k, 0.0f, 0.0f));
  ASSERT_NEAR(k.x[1], 3.1, 1e-6); /* nothing changed */
  /* a measurement just across -pi pulls the angle forward, not by 2 pi */
  assert_true(kf_mech_update(&k, -3.1f, 1e-4f));
  ASSERT_IN(fabs(wrapd(k.x[1] - (-3.1))), 0.0, 0.1);
  ASSERT_IN(k.x[0], 0.0, 1e9); /* moved the right way (positive speed) */
  ASSERT_NEAR(kf_mech_r_speed(1e-4f, 1e-6f, 100.0f, 1e-9f, 300.0f),
              1e-4 + 1e-6 * 200.0 + 1e-9 * 9e4, 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tracks_speed_angle_and_load),
      cmocka_unit_test(test_refusals_and_wrap),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
