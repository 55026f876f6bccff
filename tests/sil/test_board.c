/*
 * SIL: the board the drive runs on.
 *  - Duty limits: on the NUCLEO-G474 board the low-side shunts need the
 *    low side on around the valley (duty <= 0.95, its board header). The
 *    modulator works inside that range (hal_caps_t) and the observer
 *    integrates the voltage the pattern really applies: through flux
 *    weakening the observed flux stays within 1 % of the true flux.
 *  - Watchdog: refreshed only by the main loop's background service and
 *    only when the ISR advanced (drive.h). A hung main loop and a stuck
 *    interrupt each let it expire after the board's timeout (50 ms): the
 *    MCU resets (gates off at once) and the drive starts in fault with the
 *    cause latched. A normal run never resets.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "sil_test_util.h"

/* Rated torque while the dynamometer ramps 100 -> 1200 rpm in 0.8 s
 * (Rubino 2020, Fig. 14 faster), on the default board (g474_nucleo). */
static const char *const FW_RAMP =
    "{\"duration\": 0.9, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"log\": {\"decimation\": "
    "1}, \"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": "
    "[{\"type\": \"const\", \"value\": 100}, {\"type\": \"ramp\", \"t0\": 0.05, \"t1\": 0.85, "
    "\"value\": 1100}]}},"
    "\"controller\": {\"law\": \"db_dfvc\", \"mode\": \"torque\"}, \"references\": {\"torque\": "
    "20}}";

static void observer_sees_the_board_voltage(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(FW_RAMP, &sc, &tr, &res);
  assert_float_equal(sc.board.duty_max, 0.95f, 0.0f);
  assert_int_equal(res.faults_seen, 0);
  double worst = 0.0, duty = 0.0, flux_min = 1.0;
  for (size_t k = idx_at(&tr, 0.05); k < tr.n; ++k) {
    worst = fmax(worst, fabs(tr.flux_est[k] / tr.flux[k] - 1.0));
    duty = fmax(duty, tr.duty_max[k]);
    flux_min = fmin(flux_min, tr.flux[k]);
  }
  printf("g474 board: largest duty %.4f, flux down to %.4f Vs, observed flux within %.3f %% of "
         "the true flux\n",
         duty, flux_min, 100.0 * worst);
  assert_true(duty <= 0.95 + 1e-6);
  assert_true(duty > 0.94);     /* the range was used: flux weakening */
  assert_true(flux_min < 0.06); /* deep flux weakening (0.19 Vs at rest) */
  assert_true(worst < 0.01);
  /* the modulator kept to the board's range: the HAL never had to clamp */
  assert_int_equal(res.pwm_clamped, 0u);
  trace_free(&tr);
}

static const char *const RUNNING =
    "{\"duration\": 0.4, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"log\": {\"decimation\": "
    "1}, \"mechanics\": {\"mode\": \"imposed\", \"speed\": 10},"
    "\"controller\": {\"law\": \"foc\", \"mode\": \"torque\"}, \"references\": {\"torque\": 5}";

static void watchdog_resets(const char *inject, const char *what) {
  char json[1024];
  snprintf(json, sizeof json, "%s%s}", RUNNING, inject);
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(json, &sc, &tr, &res);
  const double t_stall = 0.2, timeout = 1e-3 * sc.board.watchdog_ms;
  printf("%s: watchdog resets %u, first at %.4f s (stall at %.2f s, timeout %.0f ms)\n", what,
         (unsigned)res.watchdog_resets, res.first_watchdog_t, t_stall, 1e3 * timeout);
  if (inject[0] == '\0') {
    assert_int_equal(res.watchdog_resets, 0);
    assert_int_equal(tr.state[tr.n - 1], DRIVE_STATE_RUN);
    trace_free(&tr);
    return;
  }
  assert_true(res.watchdog_resets >= 1u);
  /* the last refresh came at most one main-loop period (1 ms) before */
  assert_true(res.first_watchdog_t >= t_stall + timeout - 1.1e-3);
  assert_true(res.first_watchdog_t <= t_stall + timeout + 1e-4);
  const size_t k = idx_at(&tr, res.first_watchdog_t);
  for (size_t j = k; j < tr.n; ++j) {
    assert_int_equal(tr.gates[j], 0);
  }
  assert_true((tr.faults[tr.n - 1] & DRIVE_FAULT_WATCHDOG) != 0u || tr.state[tr.n - 1] == 0u);
  trace_free(&tr);
}

static void watchdog_quiet_in_a_normal_run(void **state) {
  (void)state;
  watchdog_resets("", "normal run");
}

static void watchdog_catches_a_hung_main_loop(void **state) {
  (void)state;
  watchdog_resets(
      ", \"inject\": {\"main_stall\": [{\"type\": \"step\", \"t\": 0.2, \"value\": 1}]}",
      "main loop hung");
}

static void watchdog_catches_a_stuck_interrupt(void **state) {
  (void)state;
  watchdog_resets(", \"inject\": {\"isr_stall\": [{\"type\": \"step\", \"t\": 0.2, \"value\": 1}]}",
                  "interrupt stuck");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(observer_sees_the_board_voltage),
                                     cmocka_unit_test(watchdog_quiet_in_a_normal_run),
                                     cmocka_unit_test(watchdog_catches_a_hung_main_loop),
                                     cmocka_unit_test(watchdog_catches_a_stuck_interrupt)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
