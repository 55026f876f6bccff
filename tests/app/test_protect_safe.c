/*
 * The safe state as a part (protect/drive_safe.h), without the SIL: at a
 * trip above the rectifier speed the short, below it all off; the short
 * held, and ended only after asc_hold with the speed below the exit speed;
 * with all off the short engages on overvoltage or after ENTRY_N periods
 * above the entry speed (not before); never with the hardware break
 * latched, never on a machine whose short-circuit current exceeds i_max.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "protect/drive_safe.h"

static machine_t m;
static const float zero[3] = {0.0f, 0.0f, 0.0f};

/* 0.1 Vs, 1 mH: i_sc 100 A, the rectifier speed 300 V / (sqrt(3) 0.1 Vs)
 * = 1732 rad/s electrical; i_max 150 A, i_trip 300 A. */
static protect_safe_t configured(void) {
  protect_safe_t z = {0};
  protect_safe_configure(&z, &m, 0.1f, 100.0f, 0.2f, 300.0f);
  return z;
}

static protect_safe_view_t view(drive_state_t st, float w_e) {
  const protect_safe_view_t v = {zero,   300.0f,
                                 st,     DRIVE_FAULT_OVERCURRENT,
                                 false,  true,
                                 false,  w_e,
                                 true,   (dq_t){0.0f, 0.0f},
                                 0.0f,   false,
                                 &m,     1.0f,
                                 150.0f, 400.0f,
                                 1e-4f,  0.01f};
  return v;
}

static int setup(void **state) {
  (void)state;
  return machine_init_linear(&m, 4.0f, 0.1f, 1e-3f, 1e-3f, 0.1f);
}

static void configured_limits(void **state) {
  (void)state;
  const protect_safe_t z = configured();
  /* the trapped flux's ring within i_trip: (psi + 0.1) / 1 mH <= 300 A */
  assert_float_equal(z.psi_max, 0.2f, 1e-3f);
  assert_float_equal(z.i_sc, 100.0f, 0.0f);
}

static void a_trip_chooses_by_the_speed(void **state) {
  (void)state;
  protect_safe_t z = configured();
  protect_safe_leave_gates(&z);
  protect_safe_view_t v = view(DRIVE_STATE_FAULT, 2000.0f);
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
  assert_true(z.asc);
  z = configured();
  protect_safe_leave_gates(&z);
  v = view(DRIVE_STATE_FAULT, 1500.0f); /* below the rectifier speed */
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_DISABLE);
  assert_false(z.asc);
}

static void the_short_ends_after_asc_hold_below_the_exit_speed(void **state) {
  (void)state;
  protect_safe_t z = configured();
  protect_safe_leave_gates(&z);
  protect_safe_view_t v = view(DRIVE_STATE_FAULT, 2000.0f);
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
  v = view(DRIVE_STATE_IDLE, 1300.0f); /* below the entry, above the exit speed (0.7) */
  for (int k = 0; k < 500; ++k) {
    assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
  }
  v.pos_omega = 1000.0f; /* below the exit speed: EXIT_N periods, and asc_hold is over */
  for (int k = 0; k < 15; ++k) {
    assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
  }
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_DISABLE);
  assert_false(z.asc);
}

static void gates_off_entry_after_entry_n_or_on_overvoltage(void **state) {
  (void)state;
  protect_safe_t z = configured();
  protect_safe_view_t v = view(DRIVE_STATE_IDLE, 2000.0f);
  v.faults = 0u;
  for (int k = 0; k < 15; ++k) {
    assert_int_equal(protect_safe_step(&z, &v), 0u);
  }
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT); /* the 16th */
  z = configured();
  v = view(DRIVE_STATE_IDLE, 0.0f);
  v.faults = 0u;
  v.v_dc = 379.0f; /* at most 0.95 v_dc_max (380 V): nothing */
  assert_int_equal(protect_safe_step(&z, &v), 0u);
  v.v_dc = 381.0f;
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
}

static void never_with_the_break_or_a_large_short_circuit_current(void **state) {
  (void)state;
  protect_safe_t z = configured();
  protect_safe_leave_gates(&z);
  protect_safe_view_t v = view(DRIVE_STATE_FAULT, 2000.0f);
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_SHORT);
  v.hw_tripped = true; /* the break: the short ends, all off */
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_DISABLE);
  assert_false(z.asc);
  z = configured();
  protect_safe_leave_gates(&z);
  v = view(DRIVE_STATE_FAULT, 2000.0f);
  v.i_max = 90.0f; /* i_sc 100 A not below i_max */
  assert_int_equal(protect_safe_step(&z, &v), PROTECT_SAFE_DISABLE);
  assert_false(z.asc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(configured_limits),
      cmocka_unit_test(a_trip_chooses_by_the_speed),
      cmocka_unit_test(the_short_ends_after_asc_hold_below_the_exit_speed),
      cmocka_unit_test(gates_off_entry_after_entry_n_or_on_overvoltage),
      cmocka_unit_test(never_with_the_break_or_a_large_short_circuit_current),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
