/*
 * The ISR overrun check as a part (protect/overrun.h), without the SIL:
 * overruns in overrun_k of the last overrun_n slow periods trip, k - 1 do
 * not, old ones leave the window, the board's count at start-up is not
 * this run's.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "drive_enums.h"
#include "protect/overrun.h"

/* Feeds slow periods; an overrun in a period when late[j] != 0. */
static uint32_t feed(protect_overrun_t *p, uint32_t *count, const int *late, int n) {
  uint32_t f = 0u;
  for (int j = 0; j < n; ++j) {
    *count += late[j] != 0 ? 1u : 0u;
    const protect_overrun_view_t v = {*count, 16u, 4u};
    f = protect_overrun_step(p, &v);
  }
  return f;
}

static void k_of_n_trips(void **state) {
  (void)state;
  protect_overrun_t p;
  uint32_t count = 7u; /* earlier overruns (another run) */
  protect_overrun_init(&p, count);
  const int late[8] = {1, 0, 1, 0, 0, 1, 0, 0};
  assert_int_equal(feed(&p, &count, late, 8), 0u); /* 3 of 16: no */
  const int one[1] = {1};
  assert_int_equal(feed(&p, &count, one, 1), DRIVE_FAULT_OVERRUN); /* the 4th */
}

static void old_overruns_leave_the_window(void **state) {
  (void)state;
  const int late[3] = {1, 1, 1};
  const int one[1] = {1};
  const int calm[13] = {0};
  for (int wait = 12; wait <= 13; ++wait) {
    protect_overrun_t p;
    uint32_t count = 0u;
    protect_overrun_init(&p, count);
    assert_int_equal(feed(&p, &count, late, 3), 0u);
    assert_int_equal(feed(&p, &count, calm, wait), 0u);
    /* the 4th in period 16 trips (all in the window of 16); in period 17
     * the first has left it */
    assert_int_equal(feed(&p, &count, one, 1), wait == 12 ? DRIVE_FAULT_OVERRUN : 0u);
  }
  protect_overrun_t p;
  uint32_t count = 0u;
  protect_overrun_init(&p, count);
  assert_int_equal(feed(&p, &count, late, 3), 0u);
  const int many[32] = {0};
  assert_int_equal(feed(&p, &count, many, 32), 0u); /* all left: the usual case again */
  assert_int_equal(p.hist, 0u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(k_of_n_trips),
      cmocka_unit_test(old_overruns_leave_the_window),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
