/*
 * core_test_util.h - shared helpers for the core unit tests (cmocka).
 */
#ifndef CORE_TEST_UTIL_H
#define CORE_TEST_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>

#define T_PI 3.14159265358979323846

/* |a - b| <= tol, with the values printed on failure */
#define ASSERT_NEAR(a, b, tol)                                                                     \
  do {                                                                                             \
    const double a_ = (double)(a), b_ = (double)(b), t_ = (double)(tol);                           \
    if (!(fabs(a_ - b_) <= t_)) {                                                                  \
      fail_msg("%s = %.9g, expected %s = %.9g (tol %.3g, diff %.3g)", #a, a_, #b, b_, t_,          \
               fabs(a_ - b_));                                                                     \
    }                                                                                              \
  } while (0)

/* lo <= x <= hi */
#define ASSERT_IN(x, lo, hi)                                                                       \
  do {                                                                                             \
    const double x_ = (double)(x), l_ = (double)(lo), h_ = (double)(hi);                           \
    if (!(x_ >= l_ && x_ <= h_)) {                                                                 \
      fail_msg("%s = %.9g not in [%.9g, %.9g]", #x, x_, l_, h_);                                   \
    }                                                                                              \
  } while (0)

#endif
