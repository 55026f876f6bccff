/*
 * SIL: the loss-of-control monitor (firmware/app/drive.c, drive_monitor).
 * Each condition is provoked by a physical cause, with the other
 * conditions' thresholds at their widest so that the one under test is the
 * one that trips; the test finds, from what the ISR saw (its telemetry),
 * the sample from which the condition held without a break, and requires
 * the lost_control trip exactly lc_time (current, load angle) or
 * lc_track_time (torque, flux, observer) later, to one ISR, the gates off
 * from then on and the cause named.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "sil_test_util.h"

typedef bool (*cond_fn)(const trace_t *tr, size_t k, const scenario_t *sc);

static bool over_current(const trace_t *tr, size_t k, const scenario_t *sc) {
  return tr->iamp_meas[k] > sc->drive.lc_current * sc->drive.i_max;
}

static bool over_delta(const trace_t *tr, size_t k, const scenario_t *sc) {
  return fabs(tr->delta_est[k]) > sc->drive.delta_max + sc->drive.lc_delta;
}

static bool flux_off(const trace_t *tr, size_t k, const scenario_t *sc) {
  return fabs(tr->flux_est[k] - tr->flux_ref[k]) > sc->drive.lc_track * tr->flux_ref[k];
}

/* flux scale: |lambda| on MTPA at i_max of the Rubino machine */
static bool observer_off(const trace_t *tr, size_t k, const scenario_t *sc) {
  const double scale = hypot(0.19, 0.057 * 3.5355339);
  return tr->obs_err[k] > sc->drive.lc_track * scale;
}

/* Runs the scenario, finds the trip and checks its timing and cause. */
static void check_lost_control(const char *json, uint32_t cause, cond_fn cond, bool fast,
                               const char *what) {
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(json, &sc, &tr, &res);
  const size_t k_trip = first_fault(&tr);
  assert_true(k_trip < tr.n);
  /* onset: the condition holds from k_on to the trip without a break */
  size_t k_on = k_trip;
  while (k_on > 0 && cond(&tr, k_on - 1, &sc)) {
    --k_on;
  }
  const double n_max = (fast ? sc.drive.lc_time : sc.drive.lc_track_time) / sc.drive.ts;
  printf("%s: condition from ISR %zu (t %.4f s), trip at ISR %zu (%zu ISRs, %.1f expected), "
         "faults 0x%x, cause 0x%x\n",
         what, k_on, tr.t[k_on], k_trip, k_trip - k_on, n_max - 1.0, tr.faults[k_trip],
         tr.lc_cause[k_trip]);
  assert_true(cond(&tr, k_trip, &sc));
  assert_int_equal(tr.faults[k_trip], DRIVE_FAULT_LOST_CONTROL);
  assert_true((tr.lc_cause[k_trip] & cause) != 0u);
  assert_true(fabs((double)(k_trip - k_on) - (n_max - 1.0)) <= 1.0);
  for (size_t k = k_trip + 1; k < tr.n; ++k) {
    assert_int_equal(tr.gates[k], 0);
    assert_int_equal(tr.state[k], DRIVE_STATE_FAULT);
  }
  trace_free(&tr);
}

/* The widest thresholds of the conditions not under test. */
#define WIDE_TRACK "\"lc_track\": 10"
#define WIDE_CUR   "\"lc_current\": 3.0"
#define WIDE_DELTA "\"lc_delta\": 1.5"

/* The low-inductance Fabbri 2022 Table 5.1 machine driven past its voltage
 * limit by the dynamometer while FOC asks for zero torque: the current
 * grows with the speed (tests/sil/test_faults.c, the overcurrent case). */
#define OVERDRIVEN_AT(extra, torque)                                                               \
  "{\"duration\": 0.3, \"machine\": {\"preset\": \"fabbri2022_t51\"}, \"log\": {\"decimation\": "  \
  "1}, \"sensors\": {\"i_noise\": 0.005},"                                                         \
  "\"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": "              \
  "[{\"type\": \"ramp\", \"t0\": 0.02, \"t1\": 0.5, \"value\": 6000}]}},"                          \
  "\"controller\": {\"mode\": \"torque\", \"speed_trip\": 900, " extra                             \
  "}, \"references\": {\"torque\": " torque "}}"
#define OVERDRIVEN(extra) OVERDRIVEN_AT(extra, "0")

static void current_above_limit(void **state) {
  (void)state;
  check_lost_control(OVERDRIVEN(WIDE_TRACK), DRIVE_LC_CURRENT, over_current, true, "current");
}

/* The overdriven machine's braking torque against the reference `json`
 * asks for. */
static void check_torque_off(const char *json, const char *what) {
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(json, &sc, &tr, &res);
  const size_t k_trip = first_fault(&tr);
  assert_true(k_trip < tr.n);
  /* the monitor's scale: the torque on MTPA at i_max */
  machine_t m;
  assert_int_equal(machine_init_linear(&m, sc.drive.pole_pairs, sc.drive.rs, sc.drive.ld,
                                       sc.drive.lq, sc.drive.lambda_m),
                   0);
  const double bound = sc.drive.lc_track * machine_mtpa_torque(&m, sc.drive.i_max);
  size_t k_on = k_trip;
  while (k_on > 0 && fabs(tr.torque_est[k_on - 1]) > bound) {
    --k_on;
  }
  printf("%s: |T_est| above the bound from ISR %zu, trip at ISR %zu (%zu ISRs), cause 0x%x\n", what,
         k_on, k_trip, k_trip - k_on, tr.lc_cause[k_trip]);
  assert_int_equal(tr.faults[k_trip], DRIVE_FAULT_LOST_CONTROL);
  assert_int_equal(tr.lc_cause[k_trip], DRIVE_LC_TORQUE);
  const double n_max = sc.drive.lc_track_time / sc.drive.ts;
  assert_true(fabs((double)(k_trip - k_on) - (n_max - 1.0)) <= 1.0);
  for (size_t k = k_trip + 1; k < tr.n; ++k) {
    assert_int_equal(tr.gates[k], 0);
  }
  trace_free(&tr);
}

static void torque_off_reference(void **state) {
  (void)state;
  /* the braking torque of the overdriven machine against a zero reference */
  check_torque_off(OVERDRIVEN(WIDE_CUR), "torque");
}

/* FOC on its voltage limit may deliver less than the reference (law_foc.c:
 * between zero and the reference, not a loss of control:
 * test_foc_voltage_limit.c), never a torque against it: the overdriven
 * machine brakes against a motoring reference of a third of torque_max. */
static void torque_against_reference(void **state) {
  (void)state;
  check_torque_off(OVERDRIVEN_AT(WIDE_CUR, "0.1"), "torque against the reference");
}

/* DB-DFVC at 600 rpm, 10 N m; the encoder error grows slowly (a slipping
 * coupling: no jump, so no position fault) to 120 deg electrical behind: the
 * load angle the drive computes from the observer's flux and the wrong rotor
 * angle leaves its limit. */
#define SLIPPING(extra)                                                                            \
  "{\"duration\": 0.3, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"log\": {\"decimation\": "  \
  "1}, \"board\": {\"preset\": \"ideal\"},"                                                        \
  "\"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": "              \
  "[{\"type\": \"const\", \"value\": 600}]}},"                                                     \
  "\"inject\": {\"encoder_error\": [{\"type\": \"ramp\", \"t0\": 0.1, \"t1\": 0.2, \"value\": "    \
  "-0.0997}]},"                                                                                    \
  "\"controller\": {\"law\": \"db_dfvc\", \"mode\": \"torque\", " extra "},"                       \
  "\"references\": {\"torque\": 10}}"

static void load_angle_beyond_limit(void **state) {
  (void)state;
  check_lost_control(SLIPPING(WIDE_TRACK ", " WIDE_CUR), DRIVE_LC_DELTA, over_delta, true,
                     "load angle");
}

static void observer_off_current_model(void **state) {
  (void)state;
  /* the same slip: the observer follows the true flux (back-EMF above its
   * crossover), its current model the wrong angle */
  check_lost_control(SLIPPING(WIDE_DELTA ", " WIDE_CUR), DRIVE_LC_OBSERVER, observer_off, false,
                     "observer");
}

/* DB-DFVC at 100 rpm; the flux reference steps 0.19 -> 0.30 Vs while the
 * flux-axis voltage is limited to 1 V: the flux needs 110 ms to follow. */
static void flux_off_reference(void **state) {
  (void)state;
  check_lost_control(
      "{\"duration\": 0.3, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"log\": "
      "{\"decimation\": 1}, \"board\": {\"preset\": \"ideal\"},"
      "\"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": "
      "[{\"type\": \"const\", \"value\": 100}]}},"
      "\"controller\": {\"law\": \"db_dfvc\", \"mode\": \"torque\", \"vsd_max\": 1, "
      "\"lc_track\": 0.2, " WIDE_CUR ", " WIDE_DELTA "},"
      "\"references\": {\"torque\": 5, \"flux\": [{\"type\": \"step\", \"t\": 0.1, \"value\": "
      "0.30}]}}",
      DRIVE_LC_FLUX, flux_off, false, "flux");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(current_above_limit),        cmocka_unit_test(torque_off_reference),
      cmocka_unit_test(torque_against_reference),   cmocka_unit_test(load_angle_beyond_limit),
      cmocka_unit_test(observer_off_current_model), cmocka_unit_test(flux_off_reference),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
