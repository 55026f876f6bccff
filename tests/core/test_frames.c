/*
 * test_frames.c - Clarke / Park transforms and angle wraps.
 */
#include "core_test_util.h"

#include "math/frames.h"

static abc_t balanced(double amp, double th) {
  abc_t x;
  x.a = (float)(amp * cos(th));
  x.b = (float)(amp * cos(th - 2.0 * T_PI / 3.0));
  x.c = (float)(amp * cos(th + 2.0 * T_PI / 3.0));
  return x;
}

/* A balanced set of peak X at angle th maps to X e^{j th}: amplitude invariant. */
static void test_clarke_balanced(void **state) {
  (void)state;
  for (int k = 0; k < 24; k++) {
    const double th = -T_PI + k * (2.0 * T_PI / 24.0) + 0.1;
    const double amp = 7.5;
    const ab_t y = frames_clarke(balanced(amp, th));
    ASSERT_NEAR(y.alpha, amp * cos(th), 1e-5);
    ASSERT_NEAR(y.beta, amp * sin(th), 1e-5);
    ASSERT_NEAR(sqrt((double)y.alpha * y.alpha + (double)y.beta * y.beta), amp, 1e-5);
    const ab_t y2 = frames_clarke2(balanced(amp, th).a, balanced(amp, th).b);
    ASSERT_NEAR(y2.alpha, y.alpha, 1e-5);
    ASSERT_NEAR(y2.beta, y.beta, 1e-5);
  }
}

/* Hand values: (1, 0, 0) -> (2/3, 0); (0, 1, -1) -> (0, 2/sqrt3); zero sequence dropped. */
static void test_clarke_known(void **state) {
  (void)state;
  ab_t y = frames_clarke((abc_t){1.0f, 0.0f, 0.0f});
  ASSERT_NEAR(y.alpha, 2.0 / 3.0, 1e-7);
  ASSERT_NEAR(y.beta, 0.0, 1e-7);
  y = frames_clarke((abc_t){0.0f, 1.0f, -1.0f});
  ASSERT_NEAR(y.alpha, 0.0, 1e-7);
  ASSERT_NEAR(y.beta, 2.0 / sqrt(3.0), 1e-6);
  y = frames_clarke((abc_t){5.0f, 5.0f, 5.0f});
  ASSERT_NEAR(y.alpha, 0.0, 1e-7);
  ASSERT_NEAR(y.beta, 0.0, 1e-7);
  y = frames_clarke2(1.0f, 0.0f); /* a = 1, b = 0, c = -1 */
  ASSERT_NEAR(y.alpha, 1.0, 1e-7);
  ASSERT_NEAR(y.beta, 1.0 / sqrt(3.0), 1e-7);
}

static void test_clarke_round_trip(void **state) {
  (void)state;
  for (int k = 0; k < 50; k++) {
    const ab_t x = {(float)(0.9 * cos(0.37 * k)), (float)(1.1 * sin(0.53 * k + 0.2))};
    const abc_t p = frames_clarke_inv(x);
    ASSERT_NEAR(p.a + p.b + p.c, 0.0, 1e-6);
    const ab_t y = frames_clarke(p);
    ASSERT_NEAR(y.alpha, x.alpha, 1e-6);
    ASSERT_NEAR(y.beta, x.beta, 1e-6);
    const abc_t s = balanced(1.0, 0.3 * k);
    const abc_t r = frames_clarke_inv(frames_clarke(s));
    ASSERT_NEAR(r.a, s.a, 1e-6);
    ASSERT_NEAR(r.b, s.b, 1e-6);
    ASSERT_NEAR(r.c, s.c, 1e-6);
  }
}

/* Park by +90 deg: alpha -> -q, beta -> d; by 30 deg: (1,0) -> (cos30, -sin30). */
static void test_park_known_angles(void **state) {
  (void)state;
  sincos_t sc = frames_sincos((float)(T_PI / 2.0));
  dq_t y = frames_park((ab_t){1.0f, 0.0f}, sc);
  ASSERT_NEAR(y.d, 0.0, 1e-7);
  ASSERT_NEAR(y.q, -1.0, 1e-7);
  y = frames_park((ab_t){0.0f, 1.0f}, sc);
  ASSERT_NEAR(y.d, 1.0, 1e-7);
  ASSERT_NEAR(y.q, 0.0, 1e-7);
  sc = frames_sincos((float)(T_PI / 6.0));
  y = frames_park((ab_t){1.0f, 0.0f}, sc);
  ASSERT_NEAR(y.d, sqrt(3.0) / 2.0, 1e-7);
  ASSERT_NEAR(y.q, -0.5, 1e-7);
  /* a balanced set at angle th is a pure d vector in the frame at th */
  for (int k = 0; k < 16; k++) {
    const double th = 0.41 * k - 3.0;
    const dq_t z = frames_park(frames_clarke(balanced(2.0, th)), frames_sincos((float)th));
    ASSERT_NEAR(z.d, 2.0, 2e-6);
    ASSERT_NEAR(z.q, 0.0, 2e-6);
  }
  /* non-finite angle: identity, no NaN */
  sc = frames_sincos(NAN);
  ASSERT_NEAR(sc.s, 0.0, 0.0);
  ASSERT_NEAR(sc.c, 1.0, 0.0);
}

static void test_park_round_trip(void **state) {
  (void)state;
  for (int k = 0; k < 50; k++) {
    const sincos_t sc = frames_sincos((float)(0.77 * k - 20.0));
    const ab_t x = {(float)cos(1.3 * k), (float)(0.5 * sin(0.7 * k))};
    const ab_t y = frames_park_inv(frames_park(x, sc), sc);
    ASSERT_NEAR(y.alpha, x.alpha, 1e-6);
    ASSERT_NEAR(y.beta, x.beta, 1e-6);
  }
}

static void test_wrap_pi(void **state) {
  (void)state;
  const float pi = (float)T_PI;
  ASSERT_NEAR(frames_wrap_pi(0.0f), 0.0, 0.0);
  ASSERT_NEAR(frames_wrap_pi(pi), -pi, 1e-6); /* half-open: +pi -> -pi */
  ASSERT_NEAR(frames_wrap_pi(-pi), -pi, 1e-6);
  ASSERT_NEAR(frames_wrap_pi(pi - 1e-3f), pi - 1e-3f, 1e-6);
  ASSERT_NEAR(frames_wrap_pi(-pi - 0.1f), pi - 0.1f, 1e-6);
  ASSERT_NEAR(frames_wrap_pi(7.0f), 7.0 - 2.0 * T_PI, 1e-6);
  ASSERT_NEAR(frames_wrap_pi(-7.0f), -7.0 + 2.0 * T_PI, 1e-6);
  ASSERT_NEAR(frames_wrap_pi(3.0f * pi), -pi, 1e-5);
  ASSERT_NEAR(frames_wrap_pi(NAN), 0.0, 0.0);
  ASSERT_NEAR(frames_wrap_pi(INFINITY), 0.0, 0.0);
  /* beyond the integer floor's range (floorf) and across it */
  ASSERT_IN(frames_wrap_pi(3e9f), -pi, pi);
  ASSERT_IN(frames_wrap_pi(-3e9f), -pi, pi);
  ASSERT_NEAR(sin((double)frames_wrap_pi(-131.5f)), sin(-131.5), 1e-5);
  /* sweep: always inside [-pi, pi) and the same direction */
  for (int k = -2000; k <= 2000; k++) {
    const float th = 0.01f * (float)k + 1e-4f;
    const float r = frames_wrap_pi(th);
    assert_true(r >= -pi && r < pi);
    ASSERT_NEAR(sin((double)r), sin((double)th), 1e-5);
    ASSERT_NEAR(cos((double)r), cos((double)th), 1e-5);
  }
}

static void test_wrap_2pi(void **state) {
  (void)state;
  const float pi = (float)T_PI;
  ASSERT_NEAR(frames_wrap_2pi(0.0f), 0.0, 0.0);
  ASSERT_NEAR(frames_wrap_2pi(2.0f * pi), 0.0, 1e-6);
  ASSERT_NEAR(frames_wrap_2pi(-0.1f), 2.0 * T_PI - 0.1, 1e-6);
  ASSERT_NEAR(frames_wrap_2pi(7.0f), 7.0 - 2.0 * T_PI, 1e-6);
  ASSERT_NEAR(frames_wrap_2pi(NAN), 0.0, 0.0);
  const float tiny = frames_wrap_2pi(-1e-9f); /* rounds onto 2 pi: must map into range */
  assert_true(tiny >= 0.0f && tiny < 2.0f * pi);
  for (int k = -2000; k <= 2000; k++) {
    const float th = 0.01f * (float)k;
    const float r = frames_wrap_2pi(th);
    assert_true(r >= 0.0f && r < 2.0f * pi);
    ASSERT_NEAR(sin((double)r), sin((double)th), 1e-5);
    ASSERT_NEAR(cos((double)r), cos((double)th), 1e-5);
  }
}

/* e^{j(a+b)} and e^{j(a-b)} as products of unit vectors agree with the
 * sin/cos of the summed angle. */
static void test_sincos_add_sub(void **state) {
  (void)state;
  for (int k = -60; k <= 60; k++) {
    const double a = 0.107 * k;
    const double b = 0.0131 * k - 0.4;
    const sincos_t sa = frames_sincos((float)a);
    const sincos_t sb = frames_sincos((float)b);
    const sincos_t p = frames_sincos_add(sa, sb);
    const sincos_t m = frames_sincos_sub(sa, sb);
    ASSERT_NEAR(p.s, sin((double)(float)a + (double)(float)b), 5e-7);
    ASSERT_NEAR(p.c, cos((double)(float)a + (double)(float)b), 5e-7);
    ASSERT_NEAR(m.s, sin((double)(float)a - (double)(float)b), 5e-7);
    ASSERT_NEAR(m.c, cos((double)(float)a - (double)(float)b), 5e-7);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_clarke_balanced),   cmocka_unit_test(test_clarke_known),
      cmocka_unit_test(test_clarke_round_trip), cmocka_unit_test(test_park_known_angles),
      cmocka_unit_test(test_park_round_trip),   cmocka_unit_test(test_wrap_pi),
      cmocka_unit_test(test_wrap_2pi),          cmocka_unit_test(test_sincos_add_sub),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
