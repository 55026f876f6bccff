/*
 * The loss-of-control monitor as a part (protect/lc_monitor.h), without
 * the SIL: each condition trips after its time (lc_time for the current
 * and the load angle, lc_track_time for the tracking ones) and not a
 * period earlier, a break restarts its count, the conditions apply only
 * where the law and the mode have them, the reset of a start.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "protect/lc_monitor.h"

/* Ts 0.25 s (binary-exact counts): lc_time 4 periods, lc_track_time 10;
 * i_max 10 A, lc_current 1.5 (15 A); torque 2 N m at i_max, flux 0.5 Vs;
 * lc_track 0.5; delta_max + lc_delta 1.25 rad. */
static protect_lc_t configured(void) {
  protect_lc_t p = {0};
  const protect_lc_cfg_t c = {1.5f, 10.0f, 0.5f, 1.0f, 0.25f, 1.0f, 2.5f, 0.25f, 2.0f, 0.5f};
  protect_lc_configure(&p, &c);
  return p;
}

/* healthy: 5 A, torque on its reference, flux on its reference */
static protect_lc_view_t healthy(void) {
  const protect_lc_view_t v = {0.0f,
                               5.0f,
                               1.0f,
                               1.0f,
                               -2.0f,
                               2.0f,
                               0.5f,
                               0.3f,
                               0.3f,
                               0.0f,
                               PROTECT_LC_CHECK_TORQUE | PROTECT_LC_CHECK_FLUX |
                                   PROTECT_LC_CHECK_DELTA};
  return v;
}

/* Periods until the first trip (0: none within n). */
static int periods_to_trip(protect_lc_t *p, const protect_lc_view_t *v, int n, uint32_t *cause) {
  for (int k = 1; k <= n; ++k) {
    const uint32_t t = protect_lc_step(p, v);
    if (t != 0u) {
      *cause = t;
      return k;
    }
  }
  return 0;
}

static void each_condition_after_its_time(void **state) {
  (void)state;
  uint32_t cause = 0u;
  protect_lc_view_t v = healthy();
  protect_lc_t p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 0);

  v = healthy();
  v.i_q = 15.5f; /* above 15 A */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 4);
  assert_int_equal(cause, DRIVE_LC_CURRENT);

  v = healthy();
  v.delta = 1.3f; /* beyond 1.25 rad */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 4);
  assert_int_equal(cause, DRIVE_LC_DELTA);

  v = healthy();
  v.torque = 2.1f; /* 1.1 N m off a tolerance of 1 N m */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 10);
  assert_int_equal(cause, DRIVE_LC_TORQUE);

  v = healthy();
  v.flux = 0.5f; /* 0.2 Vs off a tolerance of 0.15 Vs */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 10);
  assert_int_equal(cause, DRIVE_LC_FLUX);

  v = healthy();
  v.obs_err = 0.3f; /* above 0.25 Vs */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 10);
  assert_int_equal(cause, DRIVE_LC_OBSERVER);
}

static void no_trip_at_the_bound(void **state) {
  (void)state;
  uint32_t cause = 0u;
  protect_lc_view_t v = healthy();
  v.i_q = 15.0f;       /* at 15 A */
  v.delta = 1.25f;     /* at delta_max + lc_delta */
  v.torque = 1.0f;     /* the reference clamped to what the law can deliver ... */
  v.torque_ref = 3.0f; /* ... 2 N m: 1 N m off, at the tolerance */
  v.obs_err = 0.25f;   /* at the tolerance */
  protect_lc_t p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 0);
}

static void a_break_restarts_the_count(void **state) {
  (void)state;
  uint32_t cause = 0u;
  protect_lc_view_t bad = healthy();
  bad.i_q = 16.0f;
  const protect_lc_view_t good = healthy();
  protect_lc_t p = configured();
  for (int k = 0; k < 3; ++k) {
    assert_int_equal(protect_lc_step(&p, &bad), 0u);
  }
  assert_int_equal(protect_lc_step(&p, &good), 0u);
  assert_int_equal(p.n[0], 0u);
  assert_int_equal(p.held, 0u);
  assert_int_equal(periods_to_trip(&p, &bad, 100, &cause), 4);
  protect_lc_reset(&p); /* a start */
  assert_int_equal(p.n[0], 0u);
  assert_int_equal(periods_to_trip(&p, &bad, 100, &cause), 4);
}

static void conditions_apply_where_the_law_has_them(void **state) {
  (void)state;
  uint32_t cause = 0u;
  protect_lc_view_t v = healthy();
  v.torque = 5.0f;  /* off, but current mode */
  v.delta = 3.0f;   /* off, but no load-angle limit */
  v.flux = 1.0f;    /* off, but a law without a flux */
  v.obs_err = 1.0f; /* ditto */
  v.checks = 0u;
  protect_lc_t p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 0);
  v.checks = PROTECT_LC_CHECK_FLUX; /* the decoupled DFVC: no load-angle limit */
  p = configured();
  assert_int_equal(periods_to_trip(&p, &v, 100, &cause), 10);
  assert_int_equal(cause, DRIVE_LC_FLUX | DRIVE_LC_OBSERVER);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(each_condition_after_its_time),
      cmocka_unit_test(no_trip_at_the_bound),
      cmocka_unit_test(a_break_restarts_the_count),
      cmocka_unit_test(conditions_apply_where_the_law_has_them),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
