/*
 * The drive state machine against the SIL HAL with hand-made samples:
 * idle -> offset calibration -> run; offsets measured; commands clamped;
 * faults disable the gates at once, latch, and clear only on command;
 * a law change waits for the gates to be off; bad configs are named.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "hal_sil.h"

static hal_sil_t hal;
static drive_t drv;

static void sample(float ia, float ib, float ic, float vdc) {
  hal.sample = (hal_adc_sample_t){{ia, ib, ic}, vdc, 0.0f, 0.0f, true};
}

static void setup_drive(void) {
  hal_sil_init(&hal);
  hal_sil_bind(&hal);
  drive_config_t cfg;
  drive_config_default(&cfg);
  const char *field = NULL;
  assert_int_equal(drive_init(&drv, &cfg, &field), 0);
}

static void run_isrs(int n) {
  for (int i = 0; i < n; ++i) {
    drive_isr(&drv);
  }
}

/* A fresh drive, enabled with zero currents, through calibration to run. */
static void start_running(void) {
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_cmd_enable(&drv, true);
  drive_slow_loop(&drv);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
}

static void calibrates_offsets_then_runs(void **state) {
  (void)state;
  setup_drive();
  sample(0.10f, -0.05f, 0.02f, 310.0f);
  run_isrs(10);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(hal.gates_on);
  drive_cmd_enable(&drv, true);
  drive_slow_loop(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  run_isrs(drv.cfg.offset_samples - 1);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  assert_false(hal.gates_on);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  assert_true(hal.gates_on);
  assert_float_equal(drv.offset[0], 0.10f, 1e-5);
  assert_float_equal(drv.offset[1], -0.05f, 1e-5);
  assert_float_equal(drv.offset[2], 0.02f, 1e-5);
  /* zero current after offset removal -> duties stay near 50 % at zero ref */
  drive_isr(&drv);
  assert_float_equal(hal.duty[0], 0.5f, 0.01f);
  /* disable: gates off in the next ISR, back to idle */
  drive_cmd_enable(&drv, false);
  drive_slow_loop(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(hal.gates_on);
}

static void offset_out_of_range_faults(void **state) {
  (void)state;
  setup_drive();
  sample(0.9f, 0.0f, 0.0f, 310.0f); /* offset_max is 0.5 A */
  drive_cmd_enable(&drv, true);
  drive_slow_loop(&drv);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_OFFSET);
  assert_false(hal.gates_on);
}

static void fault_latches_until_cleared(void **state) {
  (void)state;
  start_running();
  /* one sample above the trip level */
  sample(drv.cfg.i_trip + 0.01f, 0.0f, -(drv.cfg.i_trip + 0.01f), 310.0f);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_false(hal.gates_on);
  assert_int_equal(drv.faults, DRIVE_FAULT_OVERCURRENT);
  assert_string_equal(drive_fault_name(drv.faults), "overcurrent");
  /* the cause is gone: still latched, enable is refused */
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_slow_loop(&drv);
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_false(hal.gates_on);
  drive_cmd_enable(&drv, true);
  drive_slow_loop(&drv);
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  /* clear: back to idle, needs a fresh enable */
  drive_cmd_clear_fault(&drv);
  drive_slow_loop(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(drv.faults, 0);
  drive_cmd_enable(&drv, true);
  drive_slow_loop(&drv);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
}

static void hw_break_cannot_be_overridden(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.hw_tripped = true;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_HW_OVERCURRENT);
  hal_pwm_enable(); /* like MOE with the break latched: refused */
  assert_false(hal.gates_on);
}

static void non_finite_sample_faults(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.sample.i_abc[1] = 0.0f / 0.0f;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_SAMPLE);
}

static void commands_are_clamped_and_staged(void **state) {
  (void)state;
  setup_drive();
  drive_cmd_torque(&drv, 1e9f);
  assert_float_equal(drv.ref.torque, 0.0f, 0.0f); /* staged, not yet in force */
  drive_slow_loop(&drv);
  assert_float_equal(drv.ref.torque, drv.cfg.torque_max, 0.0f);
  drive_cmd_speed(&drv, -1e9f);
  drive_cmd_current(&drv, 100.0f, 100.0f);
  drive_cmd_torque(&drv, 0.0f / 0.0f);
  drive_slow_loop(&drv);
  assert_float_equal(drv.ref.speed, -drv.cfg.speed_max, 0.0f);
  assert_float_equal(drv.ref.id * drv.ref.id + drv.ref.iq * drv.ref.iq,
                     drv.cfg.i_max * drv.cfg.i_max, 1e-3f);
  assert_float_equal(drv.ref.torque, 0.0f, 0.0f);
  assert_false(drive_cmd_set_law(&drv, (drive_law_t)7));
  assert_false(drive_cmd_set_mode(&drv, (drive_mode_t)-1));
}

static void law_change_waits_for_gates_off(void **state) {
  (void)state;
  start_running();
  assert_true(drive_cmd_set_law(&drv, DRIVE_LAW_PI_DFVC));
  drive_slow_loop(&drv);
  assert_int_equal(drv.ref.law, DRIVE_LAW_FOC);
  drive_cmd_enable(&drv, false);
  drive_slow_loop(&drv);
  drive_isr(&drv);
  drive_slow_loop(&drv);
  assert_int_equal(drv.ref.law, DRIVE_LAW_PI_DFVC);
}

static void bad_config_is_named(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  const char *field = NULL;
  cfg.lq = -1.0f;
  assert_int_not_equal(drive_init(&drv, &cfg, &field), 0);
  assert_string_equal(field, "lq");
  drive_config_default(&cfg);
  cfg.pole_pairs = 2.5f;
  assert_int_not_equal(drive_config_check(&cfg, &field), 0);
  assert_string_equal(field, "pole_pairs");
  drive_config_default(&cfg);
  cfg.v_dc_min = cfg.v_dc_max + 1.0f;
  assert_int_not_equal(drive_config_check(&cfg, &field), 0);
  assert_string_equal(field, "v_dc_min");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(calibrates_offsets_then_runs),
                                     cmocka_unit_test(offset_out_of_range_faults),
                                     cmocka_unit_test(fault_latches_until_cleared),
                                     cmocka_unit_test(hw_break_cannot_be_overridden),
                                     cmocka_unit_test(non_finite_sample_faults),
                                     cmocka_unit_test(commands_are_clamped_and_staged),
                                     cmocka_unit_test(law_change_waits_for_gates_off),
                                     cmocka_unit_test(bad_config_is_named)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
