/*
 * The current-sum check as a part (protect/isum.h), without the SIL: the
 * trip after PROTECT_ISUM_TRIP slow periods over more than under, none at
 * the bound, the leaky count, the restart when it does not apply.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "drive_enums.h"
#include "protect/isum.h"

static protect_isum_view_t view(const float *i) {
  const protect_isum_view_t v = {i, 0.5f, 0.1f, true};
  return v;
}

static void trips_after_the_count(void **state) {
  (void)state;
  protect_isum_t p = {0};
  const float i[3] = {10.0f, -5.0f, -3.0f}; /* sum 2 A > max(0.5, 0.1 * 10) */
  const protect_isum_view_t v = view(i);
  for (int k = 1; k < PROTECT_ISUM_TRIP; ++k) {
    assert_int_equal(protect_isum_step(&p, &v), 0u);
  }
  assert_int_equal(protect_isum_step(&p, &v), DRIVE_FAULT_CURRENT_SENSOR);
}

static void no_trip_at_the_bound(void **state) {
  (void)state;
  protect_isum_t p = {0};
  const float at[3] = {2.0f, -1.0f, -0.5f}; /* sum 0.5 A = max(0.5, 0.1 * 2): at the bound */
  const protect_isum_view_t v = view(at);
  for (int k = 0; k < 4 * PROTECT_ISUM_TRIP; ++k) {
    assert_int_equal(protect_isum_step(&p, &v), 0u);
  }
  assert_int_equal(p.n, 0);
}

static void leaky_count_and_restart(void **state) {
  (void)state;
  protect_isum_t p = {0};
  const float bad[3] = {10.0f, -5.0f, -3.0f};
  const float good[3] = {10.0f, -5.0f, -5.0f};
  protect_isum_view_t vb = view(bad);
  const protect_isum_view_t vg = view(good);
  for (int k = 0; k < PROTECT_ISUM_TRIP - 1; ++k) {
    assert_int_equal(protect_isum_step(&p, &vb), 0u);
  }
  assert_int_equal(protect_isum_step(&p, &vg), 0u); /* one under: one back */
  assert_int_equal(p.n, PROTECT_ISUM_TRIP - 2);
  assert_int_equal(protect_isum_step(&p, &vb), 0u);
  assert_int_equal(protect_isum_step(&p, &vb), DRIVE_FAULT_CURRENT_SENSOR);
  vb.active = false; /* gates off, or two sensors only: the count restarts */
  assert_int_equal(protect_isum_step(&p, &vb), 0u);
  assert_int_equal(p.n, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(trips_after_the_count),
      cmocka_unit_test(no_trip_at_the_bound),
      cmocka_unit_test(leaky_count_and_restart),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
