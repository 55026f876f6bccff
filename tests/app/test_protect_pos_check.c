/*
 * The position plausibility check as a part (protect/drive_pos_check.h),
 * without the SIL: the applied voltage of a machine in the source's frame
 * passes, the same voltage half a turn off trips after POS_TRIP_S worth of
 * checks (and not one check earlier), a residual just inside the
 * tolerance does not, the leaky count, the restart when it does not apply,
 * nothing in a slow period that is not one of its own.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "drive_enums.h"
#include "protect/drive_pos_check.h"

static machine_t m;

/* 4 pole pairs, 0.1 Ohm, 1 mH, 0.1 Vs; 100 rad/s electrical, i = (0, 10) A:
 * psi = (0.1, 0.01) Vs, v = R i + w J psi = (-1, 11) V at theta 0. Ts
 * 1/16384 s (binary-exact), 32 periods between checks: 8.192 checks' worth
 * of POS_TRIP_S, the trip at the 9th. Tolerance 0.3 (11 + 1) + 0.05 * 48 =
 * 6 V. */
static protect_pos_view_t view(float dv_d) {
  const protect_pos_view_t v = {true,
                                true,
                                32u,
                                100.0f,
                                0.0f,
                                (dq_t){0.0f, 10.0f},
                                (ab_t){-1.0f + dv_d, 11.0f},
                                48.0f,
                                0.0f,
                                1.0f / 16384.0f,
                                0.1f,
                                0.3f,
                                &m,
                                (dq_t){0.1f, 0.0f},
                                0.1f};
  return v;
}

static int setup(void **state) {
  (void)state;
  return machine_init_linear(&m, 4.0f, 0.1f, 1e-3f, 1e-3f, 0.1f);
}

static int checks_to_trip(protect_pos_t *p, const protect_pos_view_t *v, int n) {
  for (int k = 1; k <= n; ++k) {
    if (protect_pos_step(p, v) != 0u) {
      return k;
    }
  }
  return 0;
}

static void the_machine_passes(void **state) {
  (void)state;
  protect_pos_t p = {0};
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(checks_to_trip(&p, &v, 100), 0);
  assert_true(p.res < 0.01f);
}

static void half_a_turn_off_trips(void **state) {
  (void)state;
  protect_pos_t p = {0};
  protect_pos_view_t v = view(0.0f);
  v.v_ab = (ab_t){1.0f, -11.0f}; /* the source's angle off by pi */
  assert_int_equal(checks_to_trip(&p, &v, 100), 9);
  assert_true(p.res > 3.0f);
}

static void just_inside_the_tolerance(void **state) {
  (void)state;
  protect_pos_t p = {0};
  protect_pos_view_t v = view(5.9f);
  assert_int_equal(checks_to_trip(&p, &v, 100), 0);
  v = view(6.1f);
  p = (protect_pos_t){0};
  assert_int_equal(checks_to_trip(&p, &v, 100), 9);
}

static void leaky_count_restart_and_due(void **state) {
  (void)state;
  protect_pos_t p = {0};
  const protect_pos_view_t bad = view(10.0f);
  const protect_pos_view_t good = view(0.0f);
  for (int k = 0; k < 50; ++k) { /* one over, one under: never */
    assert_int_equal(protect_pos_step(&p, &bad), 0u);
    assert_int_equal(protect_pos_step(&p, &good), 0u);
  }
  assert_int_equal(checks_to_trip(&p, &bad, 8), 0);
  assert_int_equal(p.n, 8);
  protect_pos_view_t off = bad;
  off.due = false; /* not one of its slow periods: nothing */
  assert_int_equal(checks_to_trip(&p, &off, 10), 0);
  assert_int_equal(p.n, 8);
  off.active = false; /* out of run, a star-point source ...: restart */
  off.due = false;
  assert_int_equal(protect_pos_step(&p, &off), 0u);
  assert_int_equal(p.n, 0);
  assert_false(p.psi_ok);
  assert_int_equal(checks_to_trip(&p, &bad, 100), 9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(the_machine_passes),
      cmocka_unit_test(half_a_turn_off_trips),
      cmocka_unit_test(just_inside_the_tolerance),
      cmocka_unit_test(leaky_count_restart_and_due),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
