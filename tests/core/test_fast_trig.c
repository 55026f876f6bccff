/*
 * test_fast_trig.c - fd_sincosf / fd_atan2f / fd_asinf against
 * double-precision libm on dense grids (the error bounds of fast_trig.h),
 * and their edge cases.
 */
#include "core_test_util.h"

#include <float.h>
#include <string.h>

#include "math/fast_trig.h"

/* Every float in [lo, hi] visited with a step of about `step` plus a jitter
 * of a few ulp, so that both round and odd arguments are covered. */
#define GRID_N 2000000

static void sincos_max_err(float lo, float hi, double *es, double *ec) {
  *es = 0.0;
  *ec = 0.0;
  const double step = ((double)hi - (double)lo) / GRID_N;
  for (int k = 0; k <= GRID_N; ++k) {
    const float th = (float)((double)lo + step * k);
    float s;
    float c;
    fd_sincosf(th, &s, &c);
    const double ds = fabs((double)s - sin((double)th));
    const double dc = fabs((double)c - cos((double)th));
    *es = ds > *es ? ds : *es;
    *ec = dc > *ec ? dc : *ec;
  }
}

static void test_sincos_accuracy(void **state) {
  (void)state;
  double es;
  double ec;
  sincos_max_err((float)(-4.0 * T_PI), (float)(4.0 * T_PI), &es, &ec);
  print_message("fd_sincosf on [-4pi, 4pi]: max |err| sin %.3g cos %.3g\n", es, ec);
  ASSERT_IN(es, 0.0, 2e-7);
  ASSERT_IN(ec, 0.0, 2e-7);
  /* the neighbourhood of the quadrant boundaries, every float */
  for (int q = -8; q <= 8; ++q) {
    const float b = (float)(q * T_PI / 4.0);
    float th = b;
    for (int k = 0; k < 200; ++k) {
      th = nextafterf(th, -FLT_MAX);
    }
    for (int k = 0; k < 400; ++k) {
      float s;
      float c;
      fd_sincosf(th, &s, &c);
      ASSERT_NEAR(s, sin((double)th), 2e-7);
      ASSERT_NEAR(c, cos((double)th), 2e-7);
      th = nextafterf(th, FLT_MAX);
    }
  }
  /* exact reduction range: the error stays at the polynomial's */
  sincos_max_err(-12000.0f, 12000.0f, &es, &ec);
  print_message("fd_sincosf on [-12000, 12000]: max |err| sin %.3g cos %.3g\n", es, ec);
  ASSERT_IN(es, 0.0, 2e-7);
  ASSERT_IN(ec, 0.0, 2e-7);
}

static void test_sincos_edges(void **state) {
  (void)state;
  float s = 9.0f;
  float c = 9.0f;
  fd_sincosf(0.0f, &s, &c);
  ASSERT_NEAR(s, 0.0, 0.0);
  ASSERT_NEAR(c, 1.0, 0.0);
  const float bad[] = {NAN, -NAN, INFINITY, -INFINITY, 1.5e6f, -1.5e6f, FLT_MAX, -FLT_MAX};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    s = 9.0f;
    c = 9.0f;
    fd_sincosf(bad[k], &s, &c);
    ASSERT_NEAR(s, 0.0, 0.0);
    ASSERT_NEAR(c, 1.0, 0.0);
  }
  /* any finite argument up to the limit: a unit vector, bounded error */
  for (float th = 1.0e4f; th <= FD_TRIG_ARG_MAX; th *= 1.37f) {
    for (int sg = -1; sg <= 1; sg += 2) {
      const float x = (float)sg * th;
      fd_sincosf(x, &s, &c);
      ASSERT_NEAR((double)s * s + (double)c * c, 1.0, 1e-6);
      /* the float spacing of x bounds what any float sin can resolve */
      const double tol = 2e-7 + 4.0 * (double)(nextafterf(th, FLT_MAX) - th);
      ASSERT_NEAR(s, sin((double)x), tol);
      ASSERT_NEAR(c, cos((double)x), tol);
    }
  }
  /* odd / even symmetry */
  for (int k = 0; k < 1000; ++k) {
    const float th = 0.0123f * (float)k;
    float s1;
    float c1;
    float s2;
    float c2;
    fd_sincosf(th, &s1, &c1);
    fd_sincosf(-th, &s2, &c2);
    ASSERT_NEAR(s1, -s2, 0.0);
    ASSERT_NEAR(c1, c2, 0.0);
  }
}

static void test_atan2_accuracy(void **state) {
  (void)state;
  /* dense in angle on circles of several radii */
  double e = 0.0;
  const int n = 1000000;
  const double radii[] = {1e-30, 1e-3, 0.19, 1.0, 310.0, 1e20};
  for (size_t r = 0; r < sizeof radii / sizeof radii[0]; ++r) {
    for (int k = 0; k < n; ++k) {
      const double th = -T_PI + (2.0 * T_PI) * (k + 0.5) / n;
      const float x = (float)(radii[r] * cos(th));
      const float y = (float)(radii[r] * sin(th));
      const double want = atan2((double)y, (double)x);
      const double d = fabs((double)fd_atan2f(y, x) - want);
      e = d > e ? d : e;
    }
  }
  print_message("fd_atan2f: max |err| %.3g rad\n", e);
  ASSERT_IN(e, 0.0, 2e-6);
  /* a grid in (x, y) including the axes and the diagonals */
  e = 0.0;
  for (int i = -400; i <= 400; ++i) {
    for (int j = -400; j <= 400; ++j) {
      const float x = 0.37f * (float)i;
      const float y = 0.37f * (float)j;
      if (i == 0 && j == 0) {
        continue;
      }
      const double d = fabs((double)fd_atan2f(y, x) - atan2((double)y, (double)x));
      e = d > e ? d : e;
    }
  }
  ASSERT_IN(e, 0.0, 2e-6);
}

static void test_atan2_edges(void **state) {
  (void)state;
  const float pi = (float)T_PI;
  ASSERT_NEAR(fd_atan2f(0.0f, 0.0f), 0.0, 0.0);
  ASSERT_NEAR(fd_atan2f(-0.0f, -0.0f), 0.0, 0.0);
  ASSERT_NEAR(fd_atan2f(0.0f, 1.0f), 0.0, 0.0);
  ASSERT_NEAR(fd_atan2f(0.0f, -1.0f), pi, 0.0);
  ASSERT_NEAR(fd_atan2f(-0.0f, -1.0f), pi, 0.0); /* (-pi, pi]: never -pi */
  ASSERT_NEAR(fd_atan2f(1.0f, 0.0f), T_PI / 2.0, 1e-7);
  ASSERT_NEAR(fd_atan2f(-1.0f, 0.0f), -T_PI / 2.0, 1e-7);
  ASSERT_NEAR(fd_atan2f(1.0f, 1.0f), T_PI / 4.0, 1e-7);
  ASSERT_NEAR(fd_atan2f(-1.0f, -1.0f), -3.0 * T_PI / 4.0, 2e-7);
  ASSERT_NEAR(fd_atan2f(FLT_MAX, FLT_MAX), T_PI / 4.0, 1e-7);
  ASSERT_NEAR(fd_atan2f(FLT_MIN, -FLT_MAX), T_PI, 2e-7);
  const float bad[] = {NAN, INFINITY, -INFINITY};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    ASSERT_NEAR(fd_atan2f(bad[k], 1.0f), 0.0, 0.0);
    ASSERT_NEAR(fd_atan2f(1.0f, bad[k]), 0.0, 0.0);
    ASSERT_NEAR(fd_atan2f(bad[k], bad[k]), 0.0, 0.0);
  }
  /* the result is always in [-pi, pi] (float pi: the angle of (-1, -tiny) rounds onto -pi) */
  for (int k = 0; k < 100000; ++k) {
    const double th = -T_PI + (2.0 * T_PI) * k / 100000.0;
    const float a = fd_atan2f((float)sin(th), (float)cos(th));
    assert_true(a >= -pi && a <= pi);
  }
}

static void test_asin(void **state) {
  (void)state;
  double e = 0.0;
  const int n = 2000000;
  for (int k = 0; k <= n; ++k) {
    const float s = (float)(-1.0 + 2.0 * k / n);
    const double d = fabs((double)fd_asinf(s) - asin((double)s));
    e = d > e ? d : e;
  }
  print_message("fd_asinf: max |err| %.3g rad\n", e);
  ASSERT_IN(e, 0.0, 2e-6);
  ASSERT_NEAR(fd_asinf(0.0f), 0.0, 0.0);
  ASSERT_NEAR(fd_asinf(1.0f), T_PI / 2.0, 1e-7);
  ASSERT_NEAR(fd_asinf(-1.0f), -T_PI / 2.0, 1e-7);
  ASSERT_NEAR(fd_asinf(1.5f), T_PI / 2.0, 1e-7); /* clamped */
  ASSERT_NEAR(fd_asinf(-7.0f), -T_PI / 2.0, 1e-7);
  ASSERT_NEAR(fd_asinf(NAN), -T_PI / 2.0, 1e-7);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sincos_accuracy),
      cmocka_unit_test(test_sincos_edges),
      cmocka_unit_test(test_atan2_accuracy),
      cmocka_unit_test(test_atan2_edges),
      cmocka_unit_test(test_asin),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
