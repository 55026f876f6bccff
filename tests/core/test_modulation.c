/*
 * test_modulation.c - min-max modulation: known duties, applied vector,
 * linear limit, overmodulation, bad DC-link voltage.
 */
#include "core_test_util.h"

#include "control/modulation.h"

static const float VDC = 400.0f;

/* Independent reconstruction in double: pole voltages duty*Vdc minus their
 * common mode, then amplitude-invariant Clarke. */
static void reconstruct(const modulation_out_t *o, double vdc, double *al, double *be) {
  const double va = o->duty[0] * vdc, vb = o->duty[1] * vdc, vc = o->duty[2] * vdc;
  const double cm = (va + vb + vc) / 3.0;
  *al = (2.0 * (va - cm) - (vb - cm) - (vc - cm)) / 3.0;
  *be = ((vb - cm) - (vc - cm)) / sqrt(3.0);
}

static void test_v_max(void **state) {
  (void)state;
  ASSERT_NEAR(modulation_v_max(VDC, 0.0f, 1.0f), 400.0 / sqrt(3.0), 1e-4);
  ASSERT_NEAR(modulation_v_max(-1.0f, 0.0f, 1.0f), 0.0, 0.0);
  ASSERT_NEAR(modulation_v_max(NAN, 0.0f, 1.0f), 0.0, 0.0);
}

/* v = 100 V along a: va = 100, vb = vc = -50, v0 = -25:
 * duty_a = 0.5 + 75/400 = 0.6875, duty_b = duty_c = 0.3125. */
static void test_known_vectors(void **state) {
  (void)state;
  modulation_out_t o = modulation_minmax((ab_t){100.0f, 0.0f}, VDC, 0.0f, 1.0f);
  ASSERT_NEAR(o.duty[0], 0.6875, 1e-6);
  ASSERT_NEAR(o.duty[1], 0.3125, 1e-6);
  ASSERT_NEAR(o.duty[2], 0.3125, 1e-6);
  assert_int_equal(o.saturated, 0);
  /* v = 100 V along +beta: va = 0, vb = 86.6, vc = -86.6, v0 = 0 */
  o = modulation_minmax((ab_t){0.0f, 100.0f}, VDC, 0.0f, 1.0f);
  ASSERT_NEAR(o.duty[0], 0.5, 1e-6);
  ASSERT_NEAR(o.duty[1], 0.5 + 50.0 * sqrt(3.0) / 400.0, 1e-6);
  ASSERT_NEAR(o.duty[2], 0.5 - 50.0 * sqrt(3.0) / 400.0, 1e-6);
  o = modulation_minmax((ab_t){0.0f, 0.0f}, VDC, 0.0f, 1.0f);
  for (int x = 0; x < 3; x++) {
    ASSERT_NEAR(o.duty[x], 0.5, 0.0);
  }
}

static void test_linear_range_applied(void **state) {
  (void)state;
  const double vmax = 400.0 / sqrt(3.0);
  for (int k = 0; k < 360; k++) {
    const double th = k * T_PI / 180.0;
    const double amp = vmax * (0.05 + 0.94 * (k % 10) / 9.0);
    const ab_t v = {(float)(amp * cos(th)), (float)(amp * sin(th))};
    const modulation_out_t o = modulation_minmax(v, VDC, 0.0f, 1.0f);
    assert_int_equal(o.saturated, 0);
    double al, be;
    reconstruct(&o, VDC, &al, &be);
    ASSERT_NEAR(al, v.alpha, 1e-3); /* 1 mV of 231 V: float rounding of duties */
    ASSERT_NEAR(be, v.beta, 1e-3);
    ASSERT_NEAR(o.v_applied.alpha, v.alpha, 1e-3);
    ASSERT_NEAR(o.v_applied.beta, v.beta, 1e-3);
    for (int x = 0; x < 3; x++) {
      ASSERT_IN(o.duty[x], 0.0, 1.0);
    }
    /* min-max centring: the largest and smallest duties are symmetric about 1/2 */
    const double dmax = fmax(o.duty[0], fmax(o.duty[1], o.duty[2]));
    const double dmin = fmin(o.duty[0], fmin(o.duty[1], o.duty[2]));
    ASSERT_NEAR(dmax + dmin, 1.0, 1e-6);
  }
}

/* On the circle |v| = Vdc/sqrt3 the peak line-to-line voltage equals Vdc at
 * th = pi/6 + k pi/3: there max duty = 1 and min duty = 0. */
static void test_linear_limit(void **state) {
  (void)state;
  const double vmax = 400.0 / sqrt(3.0);
  for (int k = 0; k < 6; k++) {
    const double th = T_PI / 6.0 + k * T_PI / 3.0;
    const modulation_out_t o = modulation_minmax(
        (ab_t){(float)(vmax * cos(th)), (float)(vmax * sin(th))}, VDC, 0.0f, 1.0f);
    const double dmax = fmax(o.duty[0], fmax(o.duty[1], o.duty[2]));
    const double dmin = fmin(o.duty[0], fmin(o.duty[1], o.duty[2]));
    ASSERT_NEAR(dmax, 1.0, 1e-6);
    ASSERT_NEAR(dmin, 0.0, 1e-6);
  }
  for (int k = 0; k < 720; k++) {
    const double th = k * T_PI / 360.0;
    const modulation_out_t o = modulation_minmax(
        (ab_t){(float)(vmax * cos(th)), (float)(vmax * sin(th))}, VDC, 0.0f, 1.0f);
    const double dmax = fmax(o.duty[0], fmax(o.duty[1], o.duty[2]));
    const double dmin = fmin(o.duty[0], fmin(o.duty[1], o.duty[2]));
    assert_true(dmax - dmin <= 1.0 + 1e-6);
  }
}

static void test_overmodulation(void **state) {
  (void)state;
  const double vmax = 400.0 / sqrt(3.0);
  for (int k = 0; k < 36; k++) {
    const double th = 0.7 + k * T_PI / 18.0;
    const double amp = vmax * (1.05 + 0.5 * k);
    const modulation_out_t o =
        modulation_minmax((ab_t){(float)(amp * cos(th)), (float)(amp * sin(th))}, VDC, 0.0f, 1.0f);
    assert_int_equal(o.saturated, 1);
    const double mag = hypot(o.v_applied.alpha, o.v_applied.beta);
    ASSERT_NEAR(mag, vmax, 1e-4 * vmax);
    const double dang = atan2(sin(atan2(o.v_applied.beta, o.v_applied.alpha) - th),
                              cos(atan2(o.v_applied.beta, o.v_applied.alpha) - th));
    ASSERT_NEAR(dang, 0.0, 1e-5);
    for (int x = 0; x < 3; x++) {
      ASSERT_IN(o.duty[x], 0.0, 1.0);
    }
  }
  /* huge but finite components overflow |v|: safe output, flagged */
  const modulation_out_t o = modulation_minmax((ab_t){3e38f, 3e38f}, VDC, 0.0f, 1.0f);
  assert_int_equal(o.saturated, 1);
  for (int x = 0; x < 3; x++) {
    ASSERT_IN(o.duty[x], 0.0, 1.0);
  }
}

static void test_bad_inputs(void **state) {
  (void)state;
  const float bad_vdc[] = {0.0f, -10.0f, NAN, INFINITY};
  for (int k = 0; k < 4; k++) {
    const modulation_out_t o = modulation_minmax((ab_t){50.0f, 20.0f}, bad_vdc[k], 0.0f, 1.0f);
    assert_int_equal(o.saturated, 1);
    for (int x = 0; x < 3; x++) {
      ASSERT_NEAR(o.duty[x], 0.5, 0.0);
    }
    ASSERT_NEAR(o.v_applied.alpha, 0.0, 0.0);
    ASSERT_NEAR(o.v_applied.beta, 0.0, 0.0);
  }
  const modulation_out_t o = modulation_minmax((ab_t){NAN, 20.0f}, VDC, 0.0f, 1.0f);
  assert_int_equal(o.saturated, 1);
  for (int x = 0; x < 3; x++) {
    ASSERT_NEAR(o.duty[x], 0.5, 0.0);
  }
}

/* A board range [0, 0.95] (low-side shunts need the low side on around
 * the valley): the linear range shrinks to 0.95 v_dc/sqrt(3), every duty
 * stays inside the range, and what the duties apply is the request. */
static void test_board_range(void **state) {
  (void)state;
  const double vmax = 0.95 * VDC / sqrt(3.0);
  ASSERT_NEAR(modulation_v_max(VDC, 0.0f, 0.95f), vmax, 1e-4);
  ASSERT_NEAR(modulation_v_max(VDC, 0.6f, 0.6f), 0.0, 0.0);
  for (int k = 0; k < 360; k += 7) {
    const double th = k * T_PI / 180.0;
    for (double amp = 0.2 * vmax; amp < 1.5 * vmax; amp += 0.2 * vmax) {
      const modulation_out_t o = modulation_minmax(
          (ab_t){(float)(amp * cos(th)), (float)(amp * sin(th))}, VDC, 0.0f, 0.95f);
      for (int x = 0; x < 3; x++) {
        ASSERT_IN(o.duty[x], 0.0, 0.95);
      }
      const double want = amp < vmax ? amp : vmax;
      ASSERT_NEAR(hypot(o.v_applied.alpha, o.v_applied.beta), want, 1e-4 * vmax);
      if (fabs(amp / vmax - 1.0) > 1e-3) {
        assert_int_equal(o.saturated, amp > vmax ? 1 : 0);
      }
    }
  }
  /* no voltage: duties at the middle of the range */
  const modulation_out_t z = modulation_minmax((ab_t){0.0f, 0.0f}, VDC, 0.0f, 0.95f);
  for (int x = 0; x < 3; x++) {
    ASSERT_NEAR(z.duty[x], 0.475, 1e-7);
  }
}

/* The duty-only variant the drive calls gives modulation_minmax()'s duties
 * bit for bit, and says which case it took: linear, scaled onto the circle,
 * or the safe middle of the range. */
static void test_duty_only_same(void **state) {
  (void)state;
  const double vmax = 0.95 * VDC / sqrt(3.0);
  for (int k = 0; k < 360; k += 11) {
    const double th = k * T_PI / 180.0;
    for (double amp = 0.1 * vmax; amp < 1.6 * vmax; amp += 0.3 * vmax) {
      const ab_t v = {(float)(amp * cos(th)), (float)(amp * sin(th))};
      const modulation_out_t o = modulation_minmax(v, VDC, 0.02f, 0.95f);
      float d[3];
      const int r = modulation_minmax_duty(v, VDC, 0.02f, 0.95f, d);
      for (int x = 0; x < 3; x++) {
        assert_true(d[x] == o.duty[x]);
      }
      assert_int_equal(r, o.saturated ? MODULATION_SCALED : MODULATION_LINEAR);
    }
  }
  float d[3];
  assert_int_equal(modulation_minmax_duty((ab_t){NAN, 1.0f}, VDC, 0.0f, 1.0f, d), MODULATION_SAFE);
  assert_int_equal(modulation_minmax_duty((ab_t){3e38f, 3e38f}, VDC, 0.0f, 1.0f, d),
                   MODULATION_SAFE);
  assert_int_equal(modulation_minmax_duty((ab_t){1.0f, 1.0f}, 0.0f, 0.0f, 1.0f, d),
                   MODULATION_SAFE);
  for (int x = 0; x < 3; x++) {
    ASSERT_NEAR(d[x], 0.5, 0.0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_v_max),         cmocka_unit_test(test_duty_only_same),
      cmocka_unit_test(test_known_vectors), cmocka_unit_test(test_linear_range_applied),
      cmocka_unit_test(test_linear_limit),  cmocka_unit_test(test_overmodulation),
      cmocka_unit_test(test_bad_inputs),    cmocka_unit_test(test_board_range),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
