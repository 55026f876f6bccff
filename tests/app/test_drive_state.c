/*
 * The drive state machine and its concurrency contract against the SIL HAL
 * with hand-made samples: idle -> offset calibration -> [align] -> run;
 * offsets measured; commands clamped and taken by the next ISR; faults
 * disable the gates at once, latch, and clear only on request; fault
 * requests and clears keep their order; a law change waits for the gates
 * to be off; a law the machine cannot run is refused with its reason;
 * parameter requests are applied by the ISR (LIVE ones while running, the
 * rest when the gates are off); the watchdog is refreshed only while the
 * ISR runs; the position source must be valid; bad configs are named.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "drive_params.h"
#include "hal_sil.h"

static hal_sil_t hal;
static drive_t drv;

static void sample(float ia, float ib, float ic, float vdc) {
  memset(&hal.sample, 0, sizeof hal.sample);
  hal.sample.i_abc[0] = ia;
  hal.sample.i_abc[1] = ib;
  hal.sample.i_abc[2] = ic;
  hal.sample.v_dc = vdc;
  hal.sample.enc_valid = true;
  hal.sample.valid = true;
}

static void setup_with(const drive_config_t *cfg) {
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 50u, false, 0.0f, 0.0f, 0.0f};
  hal_sil_init(&hal, &board);
  hal_sil_bind(&hal);
  drive_config_err_t err;
  assert_int_equal(drive_init(&drv, cfg, &err), 0);
}

static void setup_drive(void) {
  drive_config_t cfg;
  drive_config_default(&cfg);
  setup_with(&cfg);
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
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
}

static float duty(int x) {
  return hal.pwm.off[x] - hal.pwm.on[x];
}

static void calibrates_offsets_then_runs(void **state) {
  (void)state;
  setup_drive();
  sample(0.10f, -0.05f, 0.02f, 310.0f);
  run_isrs(10);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(hal.gates_on);
  drive_cmd_enable(&drv, true);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE); /* posted: the next ISR takes it */
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
  assert_float_equal(duty(0), 0.5f, 0.02f);
  /* disable: gates off in the next ISR, back to idle */
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(hal.gates_on);
}

static void offset_out_of_range_faults(void **state) {
  (void)state;
  setup_drive();
  sample(0.9f, 0.0f, 0.0f, 310.0f); /* offset_max is 0.5 A */
  drive_cmd_enable(&drv, true);
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
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  drive_cmd_enable(&drv, true);
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_false(hal.gates_on);
  /* clear: back to idle, and the enable in force before it does not count */
  drive_cmd_clear_fault(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(drv.faults, 0);
  run_isrs(10);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
}

/* A clear that meets a new trip in the same ISR: the clear takes the old
 * faults, the new one latches again (never idle with faults latched, never
 * re-enabled by the old enable). */
static void clear_racing_a_trip_stays_safe(void **state) {
  (void)state;
  start_running();
  sample(drv.cfg.i_trip + 1.0f, 0.0f, -(drv.cfg.i_trip + 1.0f), 310.0f);
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_OVERCURRENT);
  drive_cmd_clear_fault(&drv); /* the cause persists */
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_OVERCURRENT);
  assert_false(hal.gates_on);
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_cmd_enable(&drv, true); /* the operator re-arms, cause gone, but no clear */
  run_isrs(50);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
}

/* STATUS.cmd_enabled as the main loop would send it now. */
static int enabled_in_force(void) {
  return drive_enable_in_force(&drv.tm, &drv.cmd) ? 1 : 0;
}

/* A clear clears only the faults latched before it: a request the ISR has
 * not seen latches, whether posted before or after the clear in the same
 * period (issue 22, point 3: a flood of clears swallowed the main loop's
 * fault requests). Every fault bit. */
static void clear_never_voids_an_unseen_request(void **state) {
  (void)state;
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    const uint32_t bit = 1u << b;
    setup_drive();
    sample(0.0f, 0.0f, 0.0f, 310.0f);
    /* request, then clear, before the ISR: the request stands */
    drive_request_fault(&drv, bit);
    drive_cmd_clear_fault(&drv);
    drive_isr(&drv);
    assert_int_equal(drv.faults, bit);
    assert_int_equal(drv.state, DRIVE_STATE_FAULT);
    /* clear, then request: the old fault goes, the new request stands */
    drive_cmd_clear_fault(&drv);
    drive_request_fault(&drv, bit);
    drive_isr(&drv);
    assert_int_equal(drv.faults, bit);
    /* a clear alone clears it; nothing is applied twice */
    drive_cmd_clear_fault(&drv);
    run_isrs(3);
    assert_int_equal(drv.faults, 0);
    assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  }
  /* two requests between ISRs: one fault, none lost, none applied twice */
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_request_fault(&drv, DRIVE_FAULT_CMD_TIMEOUT);
  drive_request_fault(&drv, DRIVE_FAULT_CMD_TIMEOUT);
  run_isrs(3);
  assert_int_equal(drv.faults, DRIVE_FAULT_CMD_TIMEOUT);
  drive_cmd_clear_fault(&drv);
  run_isrs(3);
  assert_int_equal(drv.faults, 0);
}

/* The state machine of enable, clear and keep (docs/can.md, "Enable and
 * clear"), every transition: a clear on a running drive changes nothing;
 * after a trip only an enable posted after the trip and after the clear
 * starts the drive, the clear's own frame included; telemetry's
 * cmd_enabled says whether the enable is in force (issue 22, point 6). */
static void enable_clear_keep_transitions(void **state) {
  (void)state;
  /* running + clear (enable kept): still running */
  start_running();
  drive_cmd_clear_fault(&drv);
  run_isrs(5);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  assert_true(hal.gates_on);
  assert_int_equal(enabled_in_force(), 1);
  /* trip: the enable level stays 1 but is no longer in force */
  drive_request_fault(&drv, DRIVE_FAULT_CONTROL);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(enabled_in_force(), 0);
  /* clear alone: idle, and it stays idle (the enable was posted before) */
  drive_cmd_clear_fault(&drv);
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(enabled_in_force(), 0);
  assert_false(hal.gates_on);
  /* a later enable = 1 (without a 0 first) starts it */
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  assert_int_equal(enabled_in_force(), 1);
  /* trip, then clear and enable in one step (one CMD_STATE frame): restarts */
  drive_request_fault(&drv, DRIVE_FAULT_CONTROL);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  drive_cmd_clear_fault(&drv);
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  /* trip, enable without a clear: stays in fault; then a clear alone does
   * not start it (that enable came before the clear) */
  drive_request_fault(&drv, DRIVE_FAULT_CONTROL);
  drive_isr(&drv);
  drive_cmd_enable(&drv, true);
  run_isrs(20);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_false(hal.gates_on);
  drive_cmd_clear_fault(&drv);
  run_isrs(100);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  /* disable, then enable: starts */
  drive_cmd_enable(&drv, false);
  run_isrs(3);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(enabled_in_force(), 0);
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  /* disable while running: idle at the next ISR */
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(hal.gates_on);
}

/* A parameter set written in a fault waits for the clear: the safe state
 * is held with the set in force at the trip (issue 22, point 1). */
static void write_in_fault_waits_for_the_clear(void **state) {
  (void)state;
  start_running();
  const float asc = drv.cfg.asc_speed, i_max = drv.cfg.i_max;
  drive_request_fault(&drv, DRIVE_FAULT_CONTROL);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drive_params_set(&drv, drive_params_by_name("asc_speed")->id, 0.0f, NULL),
                   DRIVE_PARAM_OK);
  assert_int_equal(drive_params_set(&drv, drive_params_by_name("i_max")->id, 1.0f, NULL),
                   DRIVE_PARAM_OK);
  run_isrs(50);
  assert_float_equal(drv.cfg.asc_speed, asc, 0.0f);
  assert_float_equal(drv.cfg.i_max, i_max, 0.0f);
  assert_true(drv.cfg_pending);
  drive_cmd_clear_fault(&drv);
  run_isrs(2);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_float_equal(drv.cfg.asc_speed, 0.0f, 0.0f);
  assert_float_equal(drv.cfg.i_max, 1.0f, 0.0f);
  assert_false(drv.cfg_pending);
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

/* The break's source names the cause: the comparator, the gate driver's
 * nFAULT, both; a board that cannot tell reports the comparator's. */
static void hw_break_source_names_the_cause(void **state) {
  (void)state;
  static const struct {
    uint32_t source, faults;
  } cases[] = {
      {0u, DRIVE_FAULT_HW_OVERCURRENT},
      {HAL_BREAK_OVERCURRENT, DRIVE_FAULT_HW_OVERCURRENT},
      {HAL_BREAK_GATE_DRIVER, DRIVE_FAULT_GATE_DRIVER},
      {HAL_BREAK_OVERCURRENT | HAL_BREAK_GATE_DRIVER,
       DRIVE_FAULT_HW_OVERCURRENT | DRIVE_FAULT_GATE_DRIVER},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    setup_drive();
    sample(0.0f, 0.0f, 0.0f, 310.0f);
    hal.hw_tripped = true;
    hal.hw_source = cases[i].source;
    drive_isr(&drv);
    assert_int_equal(drv.faults, cases[i].faults);
    hal_pwm_enable();
    assert_false(hal.gates_on);
    hal.hw_tripped = false;
    hal.hw_source = 0u;
  }
}

static void bad_samples_fault(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.sample.i_abc[1] = NAN;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_SAMPLE);
  /* an incomplete sample set (the board's ADC timeout) */
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.sample.valid = false;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_SAMPLE);
}

/* A board without a usable encoder: the drive refuses to turn the gates on
 * (position fault), and an encoder that fails while running trips. */
static void invalid_position_faults(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.sample.enc_valid = false;
  run_isrs(10);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE); /* idle: no fault yet */
  drive_cmd_enable(&drv, true);
  run_isrs(2);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_POSITION);
  assert_false(hal.gates_on);

  start_running();
  hal.sample.enc_valid = false;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_POSITION);
  assert_false(hal.gates_on);
  /* implausible: a jump of the encoder by half a turn electrical */
  start_running();
  hal.sample.enc_angle = 3.14159f / drv.cfg.pole_pairs;
  drive_isr(&drv);
  assert_int_equal(drv.faults, DRIVE_FAULT_POSITION);
}

static void commands_are_clamped_and_posted(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_cmd_torque(&drv, 1e9f);
  assert_float_equal(drv.cmd.torque, 0.0f, 0.0f); /* posted, not yet in force */
  drive_isr(&drv);
  assert_float_equal(drv.cmd.torque, drv.cfg.torque_max, 0.0f);
  drive_cmd_speed(&drv, -1e9f);
  drive_cmd_current(&drv, 100.0f, 100.0f);
  drive_cmd_torque(&drv, NAN);
  drive_isr(&drv);
  assert_float_equal(drv.cmd.speed, -drv.cfg.speed_max, 0.0f);
  assert_float_equal(drv.cmd.id * drv.cmd.id + drv.cmd.iq * drv.cmd.iq,
                     drv.cfg.i_max * drv.cfg.i_max, 1e-3f);
  assert_float_equal(drv.cmd.torque, 0.0f, 0.0f);
  assert_non_null(drive_cmd_set_law(&drv, (drive_law_t)7));
  assert_non_null(drive_cmd_set_mode(&drv, (drive_mode_t)-1));
  /* current mode only with a law that has it */
  assert_null(drive_cmd_set_law(&drv, DRIVE_LAW_DB_DFVC));
  assert_non_null(drive_cmd_set_mode(&drv, DRIVE_MODE_CURRENT));
}

/* Issue 13, defect 8: a LIVE limit written while running re-clamps the
 * references in force at once (and a command block taken later cannot
 * bring an old reference back); the speed reference then follows at
 * accel_max. */
static void live_limits_reclamp_the_references(void **state) {
  (void)state;
  start_running();
  const drive_param_t *tmax = drive_params_by_name("torque_max");
  const drive_param_t *wmax = drive_params_by_name("speed_max");
  /* no machine behind these samples: the position check (rightly) finds
   * the applied voltage unexplained within 16 ms; off for this test */
  assert_int_equal(drive_params_set(&drv, drive_params_by_name("pos_emf_tol")->id, 0.0f, NULL),
                   DRIVE_PARAM_OK);
  drive_cmd_torque(&drv, 15.0f);
  run_isrs(2);
  assert_float_equal(drv.tm.torque_ref, 15.0f, 0.0f);
  assert_int_equal(drive_params_set(&drv, tmax->id, 5.0f, NULL), DRIVE_PARAM_OK);
  drive_isr(&drv);
  assert_float_equal(drv.cmd.torque, 5.0f, 0.0f);
  assert_float_equal(drv.tm.torque_ref, 5.0f, 0.0f);
  drive_cmd_flux(&drv, 0.0f); /* another command: the block is taken again */
  run_isrs(2);
  assert_float_equal(drv.cmd.torque, 5.0f, 0.0f);
  /* speed: 100 rad/s, then the limit to 50 */
  assert_null(drive_cmd_set_mode(&drv, DRIVE_MODE_SPEED));
  drive_cmd_speed(&drv, 100.0f);
  run_isrs(16 * 1000); /* 1 s: the ramp (accel_max 125.7 rad/s^2) reaches 100 */
  assert_float_equal(drv.tm.speed_ref, 100.0f, 1e-3f);
  assert_int_equal(drive_params_set(&drv, wmax->id, 50.0f, NULL), DRIVE_PARAM_OK);
  drive_isr(&drv);
  assert_float_equal(drv.cmd.speed, 50.0f, 0.0f);
  run_isrs(16 * 500); /* 0.5 s > 50 / 125.7 */
  assert_float_equal(drv.tm.speed_ref, 50.0f, 1e-3f);
}

/* Shown by tests/fuzz fuzz_can (its current-limit invariant, on the input
 * corpus/fuzz_can/regress-imax-lowered): an i_max lowered with the gates off
 * re-clamps the current references in force as torque_max and speed_max
 * do; before, a current-mode reference of 3 A stayed in force (and was
 * taken into the run) under an i_max of 1.77 A. */
static void lowered_i_max_reclamps_the_currents(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  const drive_param_t *imax = drive_params_by_name("i_max");
  const float lim = 0.5f * drv.cfg.i_max;
  drive_cmd_current(&drv, -1.0f, 3.0f);
  drive_isr(&drv);
  assert_float_equal(drv.cmd.iq, 3.0f, 0.0f);
  assert_int_equal(drive_params_set(&drv, imax->id, lim, NULL), DRIVE_PARAM_OK);
  drive_isr(&drv);
  assert_float_equal(drv.cfg.i_max, lim, 0.0f);
  /* as drive_cmd_current clamps: each axis to the limit (i_q 3 -> lim),
   * then onto the circle of radius lim */
  assert_float_equal(hypotf(drv.cmd.id, drv.cmd.iq), lim, 1e-5f * lim);
  assert_float_equal(drv.cmd.iq / drv.cmd.id, -lim, 1e-4f);
}

/* Issue 13, item 1: a trip the board's ADC cannot see is refused, at
 * start-up and as a parameter write (a current beyond the ADC's range reads
 * as the full scale and would never reach i_trip). */
static void protections_must_fit_the_adc_ranges(void **state) {
  (void)state;
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 50u, false, 8.0f, 500.0f, 0.0f};
  hal_sil_init(&hal, &board);
  hal_sil_bind(&hal);
  drive_config_t cfg;
  drive_config_default(&cfg); /* i_trip 7.07 A, v_dc_max 400 V: fit */
  drive_config_err_t err;
  assert_int_equal(drive_init(&drv, &cfg, &err), 0);
  const drive_param_t *itrip = drive_params_by_name("i_trip");
  const drive_param_t *vmax = drive_params_by_name("v_dc_max");
  assert_int_equal(drive_params_set(&drv, itrip->id, 8.0f, &err), DRIVE_PARAM_INCONSISTENT);
  assert_string_equal(err.field, "i_trip");
  assert_int_equal(drive_params_set(&drv, vmax->id, 600.0f, &err), DRIVE_PARAM_INCONSISTENT);
  assert_string_equal(err.field, "v_dc_max");
  assert_int_equal(drive_params_set(&drv, itrip->id, 7.9f, &err), DRIVE_PARAM_OK);
  cfg.i_trip = 9.0f;
  assert_int_equal(drive_init(&drv, &cfg, &err), -1);
  assert_string_equal(err.field, "i_trip");
}

static void law_change_waits_for_gates_off(void **state) {
  (void)state;
  start_running();
  assert_null(drive_cmd_set_law(&drv, DRIVE_LAW_PI_DFVC));
  run_isrs(5);
  assert_int_equal(drv.ctrl.law, DRIVE_LAW_FOC);
  drive_cmd_enable(&drv, false);
  run_isrs(2);
  assert_int_equal(drv.ctrl.law, DRIVE_LAW_PI_DFVC);
}

/* A law switch validated against a set that waits (written in a fault or
 * under the short) is made with that set, not the one in force: it is never
 * refused later (issue 22, point 4). */
static void law_switch_waits_for_the_pending_set(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.law = DRIVE_LAW_FOC;
  cfg.vsd_max = 0.0f; /* FOC runs it; the DFVC laws refuse it */
  setup_with(&cfg);
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  run_isrs(2);
  drive_request_fault(&drv, DRIVE_FAULT_CONTROL);
  run_isrs(2);
  assert_int_equal(drive_params_set(&drv, drive_params_by_name("vsd_max")->id, 60.0f, NULL),
                   DRIVE_PARAM_OK);
  assert_null(drive_cmd_set_law(&drv, DRIVE_LAW_DB_DFVC)); /* valid with the set requested */
  drv.safe.asc = true; /* the short still holds after the clear (a spinning rotor) */
  drive_cmd_clear_fault(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_true(drv.cfg_pending);
  assert_int_equal(drv.faults, 0u);
  assert_int_equal(drv.ctrl.law, DRIVE_LAW_FOC); /* waits with the set */
  drv.safe.asc = false;                          /* the short ends */
  run_isrs(2);
  assert_int_equal(drv.faults, 0u);
  assert_false(drv.cfg_pending);
  assert_int_equal(drv.ctrl.law, DRIVE_LAW_DB_DFVC);
  assert_float_equal(drv.cfg.vsd_max, 60.0f, 0.0f);
}

/* Posts a law in the command block without the main loop's validation
 * (what a torn or unvalidated path would hand the ISR). */
static void post_law_unchecked(drive_law_t law) {
  drv.req.seq++;
  drv.req.cmd.law = law;
  drv.req.cmd.seq++;
  drv.req.seq++;
}

/* A law switch the target law refuses leaves the law in force exactly as it
 * was, for every pair of laws with a set the target refuses and the source
 * runs (issue 22, point 2: the decoupled DFVC's init overwrote the running
 * law's state, then a null machine was dereferenced on enable). FOC
 * refuses no valid set; PI and deadbeat DFVC share their check and init,
 * so no set separates them. */
static void refused_law_switch_leaves_the_law_as_it_was(void **state) {
  (void)state;
  static const struct {
    drive_law_t to;
    const char *param;
    float value;
  } refusals[] = {{DRIVE_LAW_PI_DFVC, "vsd_max", 0.0f},
                  {DRIVE_LAW_DB_DFVC, "vsd_max", 0.0f},
                  {DRIVE_LAW_DFVC_DECOUPLED, "flux_min", 1.76f}};
  static ctrl_t before;
  unsigned pairs = 0;
  for (unsigned f = 0; f < (unsigned)DRIVE_LAW_COUNT; ++f) {
    for (size_t r = 0; r < sizeof refusals / sizeof refusals[0]; ++r) {
      const drive_law_t from = (drive_law_t)f, to = refusals[r].to;
      drive_config_t cfg;
      drive_config_default(&cfg);
      cfg.law = from;
      drive_param_set(&cfg, drive_params_by_name(refusals[r].param), refusals[r].value);
      drive_config_err_t err;
      machine_t m;
      flux_map_t map;
      if (from == to || drive_config_validate(&cfg, from, hal_caps(), &m, &map, &err) != 0) {
        continue; /* the source cannot run this set either */
      }
      pairs++;
      setup_with(&cfg);
      sample(0.0f, 0.0f, 0.0f, 310.0f);
      drive_cmd_enable(&drv, true);
      run_isrs(drv.cfg.offset_samples + 4); /* the law's state moves (or it trips: no machine
                                               behind these samples) */
      drive_cmd_enable(&drv, false);
      drive_cmd_clear_fault(&drv);
      run_isrs(2);
      assert_int_equal(drv.state, DRIVE_STATE_IDLE);
      /* the main loop refuses it, with the reason */
      const char *why = drive_cmd_set_law(&drv, to);
      assert_non_null(why);
      assert_int_equal(drv.req.cmd.law, from);
      /* the ISR refuses it too, touching nothing of the law in force */
      before = drv.ctrl;
      post_law_unchecked(to);
      run_isrs(3);
      assert_int_equal(drv.ctrl.law, from);
      assert_memory_equal(&drv.ctrl, &before, sizeof before);
      assert_int_equal(drv.faults, DRIVE_FAULT_CONFIG);
      /* back to the source law, cleared and enabled: it runs */
      post_law_unchecked(from);
      drive_cmd_clear_fault(&drv);
      drive_cmd_enable(&drv, true);
      run_isrs(drv.cfg.offset_samples + 4);
      assert_int_not_equal(drv.state, DRIVE_STATE_IDLE); /* started (runs, or its law trips) */
      assert_true((drv.faults & DRIVE_FAULT_CONFIG) == 0u);
      assert_int_equal(drv.tm.law, from);
      assert_ptr_equal(drv.ctrl.impl, ctrl_law(from));
    }
  }
  printf("refused law switches: %u pairs\n", pairs);
  assert_int_equal(pairs, 7); /* foc, pi, db, decoupled -> the three refusing targets */

  /* the init refused after the check passed (the set changed under the
   * cached availability): the law in force, its state and row unchanged */
  drive_config_t cfg;
  drive_config_default(&cfg);
  static ctrl_t c;
  machine_t m;
  assert_int_equal(machine_init_linear(&m, cfg.pole_pairs, cfg.rs, cfg.ld, cfg.lq, cfg.lambda_m),
                   0);
  const char *reason = "";
  assert_int_equal(ctrl_init(&c, &cfg, &m, 1.5f * cfg.ts, DRIVE_LAW_FOC, &reason), 0);
  assert_null(ctrl_unavailable(&c, DRIVE_LAW_DB_DFVC));
  cfg.vsd_max = 0.0f; /* the deadbeat's init refuses it */
  before = c;
  assert_int_equal(ctrl_select(&c, DRIVE_LAW_DB_DFVC), -1);
  assert_memory_equal(&c, &before, sizeof before);
  assert_non_null(ctrl_law_refusal(DRIVE_LAW_DB_DFVC, &c.su));
}

/* A reluctance machine (no magnet, Lq > Ld) under FOC. */
static void syr_config(drive_config_t *cfg) {
  drive_config_default(cfg);
  cfg->pole_pairs = 2.0f;
  cfg->rs = 6.8f;
  cfg->ld = 0.05f;
  cfg->lq = 0.25f;
  cfg->lambda_m = 0.0f;
  cfg->flux_min = 0.0f;
  cfg->law = DRIVE_LAW_FOC;
}

/* A reluctance machine (no magnet, Lq > Ld): FOC runs it, the SPM laws
 * are unavailable with their reason instead of failing the whole drive. */
static void syr_machine_runs_foc_only(void **state) {
  (void)state;
  drive_config_t cfg;
  syr_config(&cfg);
  setup_with(&cfg);
  const char *why = drive_cmd_set_law(&drv, DRIVE_LAW_DB_DFVC);
  assert_non_null(why);
  assert_non_null(strstr(why, "lambda_m"));
  assert_non_null(ctrl_unavailable(&drv.ctrl, DRIVE_LAW_PI_DFVC));
  assert_null(ctrl_unavailable(&drv.ctrl, DRIVE_LAW_FOC));
  /* and the start-up law must be available: named with the reason */
  cfg.law = DRIVE_LAW_DB_DFVC;
  drive_config_err_t err;
  assert_int_not_equal(drive_init(&drv, &cfg, &err), 0);
  assert_string_equal(err.field, "law");
  assert_non_null(strstr(err.reason, "PM machine"));
}

/* The short's flux bound of a reluctance machine (no magnet) at start-up:
 * the same as from a second configuration of the same set, and not 0 (it
 * was 0 at start-up: the bisection took the previous set's flux scale, and
 * every short was refused until a second set was taken). */
static void syr_short_bound_from_its_own_set(void **state) {
  (void)state;
  drive_config_t cfg;
  syr_config(&cfg);
  setup_with(&cfg);
  const float first = drv.safe.psi_max;
  assert_true(first > 0.1f * drv.flux_scale);
  drive_config_err_t err;
  cfg.speed_max *= 0.99f; /* a new set of the same machine, taken with the gates off */
  assert_int_equal(drive_request_config(&drv, &cfg, &err), 0);
  run_isrs(2);
  assert_float_equal(drv.cfg.speed_max, cfg.speed_max, 0.0f);
  assert_float_equal(drv.safe.psi_max, first, 1e-6f * first);
}

/* Parameter requests: applied by the ISR; an IDLE parameter is refused
 * while running, a LIVE one applied at the next ISR. */
static void parameter_requests_are_applied_by_the_isr(void **state) {
  (void)state;
  start_running();
  const drive_param_t *itrip = drive_params_by_name("i_trip");
  const drive_param_t *rs = drive_params_by_name("rs");
  assert_int_equal(drive_params_set(&drv, itrip->id, 6.0f, NULL), DRIVE_PARAM_OK);
  assert_float_equal(drv.cfg.i_trip, 7.0710678f, 1e-6f); /* not yet */
  drive_isr(&drv);
  assert_float_equal(drv.cfg.i_trip, 6.0f, 0.0f);
  assert_int_equal(drive_params_set(&drv, rs->id, 8.0f, NULL), DRIVE_PARAM_RUNNING);
  drive_config_err_t err;
  assert_int_equal(drive_params_set(&drv, itrip->id, 1.0f, &err), DRIVE_PARAM_INCONSISTENT);
  assert_string_equal(err.field, "i_trip"); /* below i_max */
  float v;
  assert_int_equal(drive_params_get(&drv, itrip->id, &v), DRIVE_PARAM_OK);
  assert_float_equal(v, 6.0f, 0.0f);
  /* with the gates off the whole set, and the law re-initialised */
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_int_equal(drive_params_set(&drv, rs->id, 8.0f, NULL), DRIVE_PARAM_OK);
  drive_isr(&drv);
  assert_float_equal(drv.cfg.rs, 8.0f, 0.0f);
  assert_float_equal(drv.machine.rs, 8.0f, 0.0f);
}

/* The watchdog is refreshed by the main loop's background service, and only
 * when the ISR has run since the last refresh. */
static void watchdog_needs_both_contexts(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  const uint32_t k0 = hal.watchdog_kicks;
  run_isrs(16); /* the ISR alone never refreshes it */
  assert_int_equal(hal.watchdog_kicks, k0);
  drive_background(&drv);
  assert_int_equal(hal.watchdog_kicks, k0 + 1u);
  drive_background(&drv); /* no ISR since: no refresh */
  assert_int_equal(hal.watchdog_kicks, k0 + 1u);
  drive_isr(&drv);
  drive_background(&drv);
  assert_int_equal(hal.watchdog_kicks, k0 + 2u);
  /* after a watchdog reset the drive starts in fault, cause latched */
  hal.reset_by_watchdog = true;
  drive_config_t cfg;
  drive_config_default(&cfg);
  assert_int_equal(drive_init(&drv, &cfg, NULL), 0);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_WATCHDOG);
  hal.reset_by_watchdog = false;
}

/* Alignment: gates on with d current along theta = 0 for align_time and
 * until the encoder's speed has stayed calm: a rotor that never moved for
 * still_need periods (1 / w_n: 13 ms with the default machine, w_n =
 * 77 rad/s at 1 A), then the encoder's offset is what it reads there. */
static void alignment_sets_the_encoder_offset(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.align_time = 0.01f;
  cfg.align_current = 1.0f;
  setup_with(&cfg);
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  hal.sample.enc_angle = 0.5f; /* the rotor's d axis sits here */
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 1);
  assert_int_equal(drv.state, DRIVE_STATE_ALIGN);
  assert_true(hal.gates_on);
  proc_align_timing_t tmg; /* the alignment procedure's (proc_align.c) */
  proc_align_timing(&drv.cfg, drv.cfg.lambda_m, &tmg);
  const int need = (int)tmg.still_need;
  assert_true(need > (int)(0.01f / drv.cfg.ts) + 1); /* the calm outlasts align_time here */
  run_isrs(need - 2);
  assert_int_equal(drv.state, DRIVE_STATE_ALIGN); /* not yet settled */
  run_isrs(2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  const float half = 3.14159265f / (float)drv.cfg.enc_cpr;
  const float want = remainderf(drv.cfg.pole_pairs * (0.5f + half), 6.2831853f);
  assert_float_equal(drv.pos_st.enc.offset, want, 1e-4f);
}

/* A rotor that keeps swinging through the encoder's alignment (issue 23,
 * point 18): no offset is taken; the position fault after
 * PROC_ALIGN_SWINGS swings more (n_timeout), gates off. */
static void swinging_rotor_never_aligns(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.align_time = 0.01f;
  cfg.align_current = 1.0f;
  setup_with(&cfg);
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_cmd_enable(&drv, true);
  const float off0 = drv.pos_st.enc.offset;
  proc_align_timing_t tmg; /* the alignment procedure's (proc_align.c) */
  proc_align_timing(&drv.cfg, drv.cfg.lambda_m, &tmg);
  for (int k = 0; k < (int)drv.cfg.offset_samples + (int)tmg.n_timeout + 2; ++k) {
    /* 0.1 rad mechanical at 5 Hz: 2 x 10 x 2 pi rad/s electrical peak */
    hal.sample.enc_angle = 1.0f + 0.1f * sinf(31.4159f * (float)k * drv.cfg.ts);
    drive_isr(&drv);
    if (drv.state == DRIVE_STATE_FAULT) {
      break;
    }
    assert_true(drv.state != DRIVE_STATE_RUN);
  }
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_POSITION);
  assert_false(hal.gates_on);
  assert_float_equal(drv.pos_st.enc.offset, off0, 0.0f);
}

/* The angle the law uses is the position source's, extrapolated from the
 * encoder's sampling instant to the currents' (hal_sample_t timestamps). */
static void angle_extrapolated_from_timestamps(void **state) {
  (void)state;
  start_running();
  const float w_m = 20.0f, t_enc = 20e-6f, ts = drv.cfg.ts;
  const float p = drv.cfg.pole_pairs, half = 3.14159265f / (float)drv.cfg.enc_cpr;
  float th = 0.0f;
  for (int k = 0; k < 4000; ++k) { /* the PLL locks on the speed */
    th = remainderf(w_m * (float)k * ts, 6.2831853f);
    hal.sample.enc_angle = th < 0.0f ? th + 6.2831853f : th;
    hal.sample.t_enc = t_enc;
    hal.sample.t_i = 0.0f;
    drive_isr(&drv);
  }
  const float want = remainderf(
      p * (hal.sample.enc_angle + half) - drv.cfg.enc_offset - p * w_m * t_enc, 6.2831853f);
  assert_float_equal(remainderf(drv.tm.theta_e - want, 6.2831853f), 0.0f, 2e-4f);
  assert_float_equal(drv.pos.out.omega, p * w_m, 0.01f * p * w_m);
}

static void bad_config_is_named(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  drive_config_err_t err;
  cfg.lq = -1.0f;
  assert_int_not_equal(drive_init(&drv, &cfg, &err), 0);
  assert_string_equal(err.field, "lq");
  assert_string_equal(err.reason, "outside its range");
  drive_config_default(&cfg);
  cfg.pole_pairs = 2.5f;
  assert_int_not_equal(drive_config_check(&cfg, &err), 0);
  assert_string_equal(err.field, "pole_pairs");
  drive_config_default(&cfg);
  cfg.v_dc_min = cfg.v_dc_max + 1.0f;
  assert_int_not_equal(drive_config_check(&cfg, &err), 0);
  assert_string_equal(err.field, "v_dc_min");
}

/* Issue 13: the `control` fault. DB-DFVC running; the speed reference
 * the law gets turns non-finite (a NaN through the speed loop's state,
 * written here past the checks of the command path): the law refuses its
 * input, asks for the gates off, and the drive trips `control` alone in
 * that ISR. */
static void non_finite_law_input_trips_control(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.law = DRIVE_LAW_DB_DFVC;
  setup_with(&cfg);
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  drive_cmd_enable(&drv, true);
  run_isrs(drv.cfg.offset_samples + 2);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  assert_null(drive_cmd_set_mode(&drv, DRIVE_MODE_SPEED));
  run_isrs(20);
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  drv.speed_torque = NAN; /* what the law takes as its torque reference */
  drv.isr_count = 1u;     /* the next ISR is not a speed-loop one (phase 1 of slow_div) */
  drive_isr(&drv);
  printf("control: faults 0x%x\n", (unsigned)drv.faults);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_CONTROL);
  assert_false(hal.gates_on);
}

/* Issue 13: the `config` fault. The main loop validates every set before
 * it posts it, so the ISR refusing one means a corrupted request: written
 * here past the validation (an invalid i_max in creq, a new sequence
 * number). The ISR keeps the set in force and trips `config`. */
static void refused_set_in_the_isr_trips_config(void **state) {
  (void)state;
  setup_drive();
  sample(0.0f, 0.0f, 0.0f, 310.0f);
  run_isrs(2);
  const float i_max = drv.cfg.i_max;
  drv.creq.cfg = drv.cfg;
  drv.creq.cfg.i_max = -1.0f;
  drv.creq.seq += 2u;
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(drv.faults, DRIVE_FAULT_CONFIG);
  assert_float_equal(drv.cfg.i_max, i_max, 0.0f);
  assert_false(hal.gates_on);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(calibrates_offsets_then_runs),
                                     cmocka_unit_test(offset_out_of_range_faults),
                                     cmocka_unit_test(fault_latches_until_cleared),
                                     cmocka_unit_test(clear_racing_a_trip_stays_safe),
                                     cmocka_unit_test(clear_never_voids_an_unseen_request),
                                     cmocka_unit_test(enable_clear_keep_transitions),
                                     cmocka_unit_test(write_in_fault_waits_for_the_clear),
                                     cmocka_unit_test(hw_break_cannot_be_overridden),
                                     cmocka_unit_test(hw_break_source_names_the_cause),
                                     cmocka_unit_test(bad_samples_fault),
                                     cmocka_unit_test(invalid_position_faults),
                                     cmocka_unit_test(commands_are_clamped_and_posted),
                                     cmocka_unit_test(live_limits_reclamp_the_references),
                                     cmocka_unit_test(lowered_i_max_reclamps_the_currents),
                                     cmocka_unit_test(protections_must_fit_the_adc_ranges),
                                     cmocka_unit_test(law_change_waits_for_gates_off),
                                     cmocka_unit_test(refused_law_switch_leaves_the_law_as_it_was),
                                     cmocka_unit_test(law_switch_waits_for_the_pending_set),
                                     cmocka_unit_test(syr_machine_runs_foc_only),
                                     cmocka_unit_test(syr_short_bound_from_its_own_set),
                                     cmocka_unit_test(parameter_requests_are_applied_by_the_isr),
                                     cmocka_unit_test(watchdog_needs_both_contexts),
                                     cmocka_unit_test(alignment_sets_the_encoder_offset),
                                     cmocka_unit_test(swinging_rotor_never_aligns),
                                     cmocka_unit_test(angle_extrapolated_from_timestamps),
                                     cmocka_unit_test(bad_config_is_named),
                                     cmocka_unit_test(non_finite_law_input_trips_control),
                                     cmocka_unit_test(refused_set_in_the_isr_trips_config)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
