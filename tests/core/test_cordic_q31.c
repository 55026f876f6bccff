/*
 * test_cordic_q31.c - the portable Q31 CORDIC (math/cordic_q31.h) against
 * double-precision libm: its angle table, atan2 over a dense grid of
 * directions and magnitudes (the axes, tiny, subnormal and huge vectors,
 * both signs of zero), the magnitude, and the integer entry point.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>

#include "math/cordic_q31.h"

static void test_table(void **state) {
  (void)state;
  for (int i = 0; i < FD_CORDIC_ITER; ++i) {
    const double ref = atan(ldexp(1.0, -i)) * 2147483648.0 / 3.14159265358979323846;
    assert_true(fabs((double)fd_cordic_atan_q31[i] - ref) <= 0.5);
  }
}

/* atan2 error against libm, the angle difference wrapped */
static double ang_err(float y, float x) {
  const double ref = atan2((double)y, (double)x);
  double e = (double)fd_cordic_atan2f(y, x) - ref;
  e = remainder(e, 2.0 * 3.14159265358979323846);
  return fabs(e);
}

static void test_atan2_dense(void **state) {
  (void)state;
  double worst = 0.0;
  const double scales[] = {1e-44, 1e-38, 1e-20, 1e-6, 1.0, 7.3, 1e6, 1e20, 3e38};
  for (size_t s = 0; s < sizeof scales / sizeof scales[0]; ++s) {
    for (int k = 0; k < 20000; ++k) {
      const double th = -3.14159265358979323846 + 6.283185307179586 * k / 20000.0;
      const float x = (float)(scales[s] * cos(th));
      const float y = (float)(scales[s] * sin(th));
      if (x == 0.0f && y == 0.0f) {
        continue;
      }
      worst = fmax(worst, ang_err(y, x));
    }
  }
  /* the axes and the diagonals, exactly */
  const float axes[][2] = {{0.0f, 1.0f}, {1.0f, 0.0f},  {0.0f, -1.0f},  {-1.0f, 0.0f},
                           {1.0f, 1.0f}, {-1.0f, 1.0f}, {-1.0f, -1.0f}, {1.0f, -1.0f}};
  for (size_t n = 0; n < 8; ++n) {
    worst = fmax(worst, ang_err(axes[n][0], axes[n][1]));
  }
  printf("CORDIC Q31 atan2 vs libm: worst %.3g rad over 180000 directions x 9 magnitudes\n", worst);
  /* the Q31 angle within 1e-7 rad, then rounded to a float: its spacing
   * near pi is 2.4e-7 rad */
  assert_true(worst < 4e-7);
  /* the conventions of fd_atan2f */
  assert_true(fd_cordic_atan2f(0.0f, -1.0f) == 3.14159265358979f);
  assert_true(fd_cordic_atan2f(-0.0f, -1.0f) == 3.14159265358979f);
  assert_true(fd_cordic_atan2f(0.0f, 0.0f) == 0.0f);
  assert_true(fd_cordic_atan2f(NAN, 1.0f) == 0.0f);
  assert_true(fd_cordic_atan2f(1.0f, INFINITY) == 0.0f);
  assert_true(fd_cordic_atan2f(-1e-30f, -1.0f) < -3.14159f); /* below the -x axis: -pi */
}

static void test_q31_entry_and_magnitude(void **state) {
  (void)state;
  double worst_m = 0.0;
  double worst_a = 0.0;
  for (int k = 0; k < 3600; ++k) {
    const double th = 6.283185307179586 * k / 3600.0;
    const double r = 4.0e8; /* in [2^28, 2^29) */
    const int32_t x = (int32_t)lround(r * cos(th));
    const int32_t y = (int32_t)lround(r * sin(th));
    int32_t mag = 0;
    const int32_t a = fd_cordic_atan2_q31(y, x, &mag);
    const double ref = remainder(atan2((double)y, (double)x), 6.283185307179586);
    double e =
        remainder((double)a * 3.14159265358979323846 / 2147483648.0 - ref, 6.283185307179586);
    worst_a = fmax(worst_a, fabs(e));
    worst_m = fmax(worst_m, fabs((double)mag / (1.6467602581210656 * hypot(x, y)) - 1.0));
  }
  printf("CORDIC Q31 angle vs libm: worst %.3g rad; magnitude / (gain |v|) - 1: worst %.3g\n",
         worst_a, worst_m);
  assert_true(worst_a < 1e-7);
  assert_true(worst_m < 1e-7);
  int32_t mag = 5;
  assert_int_equal(fd_cordic_atan2_q31(0, 0, &mag), 0);
  assert_int_equal(mag, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_table),
      cmocka_unit_test(test_atan2_dense),
      cmocka_unit_test(test_q31_entry_and_magnitude),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
