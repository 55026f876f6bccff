/*
 * The run-away check as a part (protect/runaway.h), without the SIL: a
 * speed that runs away from its reference against the loop's torque trips
 * after the window, one held at a constant offset, one at the margin, one
 * the torque does not push back, or one that comes back does not; a break
 * starts the window again.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "protect/lc_monitor.h"
#include "protect/runaway.h"

/* speed_max 500 rad/s (floor 10 rad/s), 1 ms loop: a 20-period window,
 * quarters of 5 */
static protect_ra_t configured(void) {
  protect_ra_t p = {0};
  protect_ra_configure(&p, 500.0f, 0.001f);
  return p;
}

static void window_of_the_parameters(void **state) {
  (void)state;
  const protect_ra_t p = configured();
  assert_int_equal(p.n_win, 20u);
  assert_int_equal(p.q, 5u);
  assert_float_equal(p.floor, 10.0f, 1e-6f);
}

/* Periods to the trip of a speed w0 + slope k (0: none within n). */
static int run(protect_ra_t *p, float w0, float slope, float w_ref, float torque, int n) {
  for (int k = 1; k <= n; ++k) {
    const protect_ra_view_t v = {w0 + slope * (float)k, w_ref, torque};
    if (protect_ra_step(p, &v) != 0u) {
      return k;
    }
  }
  return 0;
}

static void running_away_trips_after_the_window(void **state) {
  (void)state;
  protect_ra_t p = configured();
  /* 100 rad/s: 50 above a reference of 50 (margin 0.2 * 50 + 10 = 20),
   * torque negative (braking), the speed rising 1 rad/s per period: the
   * last quarter's mean 15 above the first's (> 10) */
  assert_int_equal(run(&p, 100.0f, 1.0f, 50.0f, -1.0f, 100), 20);
  assert_int_equal(p.n, 0u); /* a new window */
  protect_ra_t q = configured();
  assert_int_equal(run(&q, -100.0f, -1.0f, -50.0f, 1.0f, 100), 20); /* mirrored */
}

static void no_trip_without_growth_or_push_back(void **state) {
  (void)state;
  protect_ra_t p = configured();
  assert_int_equal(run(&p, 100.0f, 0.0f, 50.0f, -1.0f, 200), 0); /* held off, not away */
  p = configured();
  assert_int_equal(run(&p, 100.0f, -1.0f, 0.0f, -1.0f, 60), 0); /* coming back */
  p = configured();
  assert_int_equal(run(&p, 100.0f, 1.0f, 50.0f, 1.0f, 200), 0); /* torque along: no push back */
  /* the last quarter's mean exactly 10 (the floor) above the first's: at
   * the bound, no trip; a little more trips at the window's end */
  for (int more = 0; more < 2; ++more) {
    p = configured();
    uint32_t t = 0u;
    for (int k = 1; k <= 20; ++k) {
      const protect_ra_view_t v = {k > 15 ? (more != 0 ? 110.5f : 110.0f) : 100.0f, 50.0f, -1.0f};
      t |= protect_ra_step(&p, &v);
    }
    assert_int_equal(t, more != 0 ? DRIVE_LC_RUNAWAY : 0u);
  }
}

static void at_the_margin_and_a_break_restart(void **state) {
  (void)state;
  protect_ra_t p = configured();
  /* 20 rad/s off a reference of 50 with the floor 10: 0.2 * 50 + 10 = 20,
   * at the margin: the condition does not hold */
  assert_int_equal(run(&p, 70.0f, 0.0f, 50.0f, -1.0f, 1), 0);
  assert_int_equal(p.n, 0u);
  assert_int_equal(run(&p, 100.0f, 1.0f, 50.0f, -1.0f, 19), 0);
  assert_int_equal(p.n, 19u);
  const protect_ra_view_t ok = {50.0f, 50.0f, -1.0f};
  assert_int_equal(protect_ra_step(&p, &ok), 0u); /* a break */
  assert_int_equal(p.n, 0u);
  assert_int_equal(run(&p, 100.0f, 1.0f, 50.0f, -1.0f, 100), 20);
  protect_ra_reset(&p);
  assert_int_equal(p.n, 0u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(window_of_the_parameters),
      cmocka_unit_test(running_away_trips_after_the_window),
      cmocka_unit_test(no_trip_without_growth_or_push_back),
      cmocka_unit_test(at_the_margin_and_a_break_restart),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
