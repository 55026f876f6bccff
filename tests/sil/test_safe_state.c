/*
 * SIL: the safe state after a trip at top speed with an active load
 * (issue 13 item 5; firmware/app/protect/drive_safe.c, docs/faults.md).
 *
 * A dynamometer (imposed speed: an active load of any strength) turns the
 * machine at its top speed on a diode-rectifier link (braking energy stays
 * in the capacitor); the main loop posts a fault. Above the rectifier speed
 * (line back-EMF peak sqrt(3) psi_pm w_e > v_dc) all switches off would let
 * the diodes pump the link far beyond v_dc_max; the active short circuit
 * keeps the link where it is and the current at the short-circuit value.
 * Below it, all off is the safe state. Bounds come from the plant's
 * machine (the physics of the short), not from the drive's settings.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "sil_test_util.h"

#define PI 3.14159265358979323846

/* Rubino's SPM machine at 1200 rpm (its top speed, Table I) on a 310 V
 * rectifier link; the fault at 0.5 s. */
#define RUBINO(asc, extra)                                                                         \
  "{\"duration\": 0.8, \"machine\": {\"preset\": \"rubino2020_spm\"},"                             \
  "\"dc_link\": {\"kind\": \"rectifier\", \"voltage\": 310, \"r\": 0.5, \"c\": 200e-6},"           \
  "\"controller\": {\"law\": \"db_dfvc\", \"mode\": \"torque\", \"asc_speed\": " asc "},"          \
  "\"references\": {\"torque\": 3}, \"log\": {\"decimation\": 1}," extra "}"
#define TOP_SPEED                                                                                  \
  "\"mechanics\": {\"mode\": \"imposed\", \"speed\": [{\"type\": \"ramp\", \"t0\": 0.05, \"t1\": " \
  "0.35, \"value\": 125.66}]}"
#define TRIP "\"inject\": {\"trip_at\": 0.5, \"trip_cause\": \"control\"}"

/* Steady short circuit of a linear PM machine at electrical speed w:
 * 0 = R i + j w (L i + psi)  ->  i_d = -psi w^2 L / (R^2 + w^2 L^2),
 * i_q = -psi w R / (R^2 + w^2 L^2), torque 1.5 p psi i_q. */
static double asc_torque(const plant_machine_t *m, double w_e) {
  const double z2 = m->rs * m->rs + w_e * w_e * m->ld * m->ld;
  return 1.5 * m->pole_pairs * m->lambda_m * (-m->lambda_m * w_e * m->rs / z2);
}

static double asc_current(const plant_machine_t *m, double w_e) {
  return m->lambda_m * w_e / sqrt(m->rs * m->rs + w_e * w_e * m->ld * m->ld);
}

/* The short engages in the ISR of the trip and holds; the link stays at
 * the source; the current is the short's, the braking torque the short's. */
static void rubino_short_at_top_speed(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(RUBINO("0.9", TOP_SPEED "," TRIP), &sc, &tr, &res);
  const plant_machine_t *m = &sc.plant.machine;
  const size_t k = first_fault(&tr);
  const double w_e = 125.66 * m->pole_pairs;
  const double rect = sc.plant.dclink.v_source / (sqrt(3.0) * m->lambda_m);
  printf("trip at %.4f s, w_e %.0f rad/s = %.2f x the rectifier speed\n", tr.t[k], w_e, w_e / rect);
  assert_true(w_e > 2.0 * rect);
  assert_true(tr.t[k] >= 0.5 && tr.t[k] < 0.5 + 2e-3);
  for (size_t j = k; j < tr.n; ++j) {
    assert_int_equal(tr.gates[j], 0);
    assert_int_equal(tr.asc[j], 1);
  }
  const double v_max = trace_max(tr.v_dc, k, tr.n);
  const double i_pk = trace_max(tr.imax_abs, k, tr.n);
  const size_t k_ss = k + (size_t)(0.1 / sc.plant.ts); /* 12 L/R after the trip */
  const double t_ss = trace_mean(tr.torque, k_ss, tr.n);
  const double i_ss = trace_max(tr.imax_abs, k_ss, tr.n);
  printf("after the trip: v_dc max %.2f V (v_dc_max %.1f), peak current %.3f A, steady %.3f A "
         "(short %.3f A), torque %.4f N m (short %.4f N m)\n",
         v_max, (double)sc.drive.v_dc_max, i_pk, i_ss, asc_current(m, w_e), t_ss,
         asc_torque(m, w_e));
  assert_true(v_max <= sc.plant.dclink.v_source + 1.0 && v_max >= sc.plant.dclink.v_source - 5.0);
  /* the transient peak is below twice the short-circuit current psi/L */
  assert_true(i_pk < 2.0 * m->lambda_m / m->ld);
  assert_true(fabs(i_ss - asc_current(m, w_e)) < 0.02 * asc_current(m, w_e));
  assert_true(fabs(t_ss - asc_torque(m, w_e)) < 0.03 * fabs(asc_torque(m, w_e)));
  trace_free(&tr);
}

/* The same trip with the short disabled (asc_speed 0): the diodes pump the
 * link far beyond v_dc_max - what the short prevents. */
static void rubino_all_off_pumps_the_link(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(RUBINO("0", TOP_SPEED "," TRIP), &sc, &tr, &res);
  const size_t k = first_fault(&tr);
  const double v_max = trace_max(tr.v_dc, k, tr.n);
  const double emf = sqrt(3.0) * sc.plant.machine.lambda_m * 125.66 * sc.plant.machine.pole_pairs;
  printf("all off: v_dc max %.1f V (line back-EMF peak %.1f V, v_dc_max %.1f V)\n", v_max, emf,
         (double)sc.drive.v_dc_max);
  assert_true(v_max > 1.5 * (double)sc.drive.v_dc_max);
  assert_true(v_max < emf);
  for (size_t j = k; j < tr.n; ++j) {
    assert_int_equal(tr.asc[j], 0);
  }
  trace_free(&tr);
}

/* Position lost at top speed (the encoder reports an error): the speed is
 * not known, the short engages; the dynamometer then slows down and the
 * short ends on the rotation of its own current vector, between the exit
 * and the entry speeds, after asc_hold. */
static void short_ends_below_the_rectifier_speed(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(RUBINO("0.9", "\"mechanics\": {\"mode\": \"imposed\", \"speed\": [{\"type\": \"ramp\", "
                         "\"t0\": 0.05, \"t1\": 0.35, \"value\": 125.66}, {\"type\": \"ramp\", "
                         "\"t0\": 0.55, \"t1\": 0.75, \"value\": -125.66}]},"
                         "\"inject\": {\"encoder_invalid\": [{\"type\": \"step\", \"t\": 0.5, "
                         "\"value\": 1}]}"),
           &sc, &tr, &res);
  const size_t k = first_fault(&tr);
  assert_true((tr.faults[k] & DRIVE_FAULT_POSITION) != 0u);
  assert_int_equal(tr.asc[k], 1);
  size_t k_end = k;
  while (k_end < tr.n && tr.asc[k_end] == 1u) {
    ++k_end;
  }
  assert_true(k_end < tr.n);
  const plant_machine_t *m = &sc.plant.machine;
  const double rect_m = sc.plant.dclink.v_source / (sqrt(3.0) * m->lambda_m * m->pole_pairs);
  const double ratio = tr.speed[k_end] / rect_m;
  printf("short from %.4f s to %.4f s, ended at %.1f rpm = %.3f x the rectifier speed\n", tr.t[k],
         tr.t[k_end], tr.speed[k_end] * 30.0 / PI, ratio);
  /* exit speed 0.7 x 0.9 of the rectifier speed, judged over EXIT_N
   * periods on a filtered estimate while the speed falls */
  assert_true(ratio > 0.45 && ratio < 0.63);
  for (size_t j = k_end; j < tr.n; ++j) {
    assert_int_equal(tr.asc[j], 0);
    assert_int_equal(tr.gates[j], 0);
  }
  /* ending the short hands the windings' energy 0.75 L |i|^2 to the
   * capacitor (the diodes take the current): one such step at most */
  const double v0 = sc.plant.dclink.v_source;
  const double i_sc = m->lambda_m / m->ld;
  const double v_dump = sqrt(v0 * v0 + 1.5 * m->ld * i_sc * i_sc / sc.plant.dclink.c);
  const double v_max = trace_max(tr.v_dc, k, tr.n);
  printf("v_dc max after the trip %.2f V (the short's energy on %.0f V: %.2f V)\n", v_max, v0,
         v_dump);
  assert_true(v_max <= v_dump + 0.5 && v_max > v0 + 0.5 * (v_dump - v0));
  trace_free(&tr);
}

/* A free rotor with an active load (a hanging weight that turns it
 * backwards once the drive lets go), held at standstill by the speed loop
 * until the trip. 2 N m: the short engages when the encoder's speed
 * passes the entry speed, its drag (above the load there) slows the rotor
 * to the exit speed, and so on: the rotor stays below the rectifier speed,
 * the link is never pumped. 5 N m: more than the short's drag at the
 * entry speed; the short holds the link and the current while the load
 * runs the rotor away (only a mechanical brake stops that), where all off
 * pumps the link. */
static void active_load_after_a_trip_at_standstill(void **state) {
  (void)state;
  static const char *const loads[] = {"2", "5", "5"};
  static const char *const asc[] = {"0.9", "0.9", "0"};
  for (int r = 0; r < 3; ++r) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"duration\": 1.2, \"machine\": {\"preset\": \"rubino2020_spm\"},"
             "\"dc_link\": {\"kind\": \"rectifier\", \"voltage\": 310, \"r\": 0.5, \"c\": 200e-6},"
             "\"controller\": {\"law\": \"db_dfvc\", \"mode\": \"speed\", \"asc_speed\": %s},"
             "\"references\": {\"speed\": 0}, \"log\": {\"decimation\": 1},"
             "\"mechanics\": {\"mode\": \"free\", \"load_torque\": %s},"
             "\"inject\": {\"trip_at\": 0.2, \"trip_cause\": \"control\"}}",
             asc[r], loads[r]);
    scenario_t sc;
    trace_t tr;
    sil_result_t res;
    run_json(json, &sc, &tr, &res);
    const size_t k = first_fault(&tr);
    const plant_machine_t *m = &sc.plant.machine;
    const double rect_m = sc.plant.dclink.v_source / (sqrt(3.0) * m->lambda_m * m->pole_pairs);
    double w_min = 0.0;
    unsigned shorts = 0u;
    for (size_t j = k; j < tr.n; ++j) {
      w_min = fmin(w_min, tr.speed[j]);
      shorts += j > k && tr.asc[j] == 1u && tr.asc[j - 1] == 0u;
    }
    const double v_max = trace_max(tr.v_dc, k, tr.n);
    const double i_pk = trace_max(tr.imax_abs, k, tr.n);
    printf("load %s N m, asc_speed %s: speed at the trip %.1f rpm, fastest backwards %.1f rpm "
           "(rectifier %.1f rpm), %u shorts, v_dc max %.2f V, peak current %.3f A\n",
           loads[r], asc[r], tr.speed[k] * 30.0 / PI, w_min * 30.0 / PI, rect_m * 30.0 / PI, shorts,
           v_max, i_pk);
    assert_true(fabs(tr.speed[k]) < 0.02 * rect_m);
    if (r == 2) { /* all off: pumped */
      assert_true(v_max > (double)sc.drive.v_dc_max);
      trace_free(&tr);
      continue;
    }
    assert_true(v_max < (double)sc.drive.v_dc_max);
    assert_true(i_pk < 2.0 * m->lambda_m / m->ld);
    assert_true(shorts >= 1u);
    if (r == 0) {
      assert_true(w_min < -0.5 * rect_m && w_min > -rect_m);
      assert_true(shorts >= 2u); /* it cycles between the exit and entry speeds */
    } else {
      assert_true(w_min < -2.0 * rect_m);
    }
    trace_free(&tr);
  }
}

/* Machines whose rectifier speed is above their top speed, or whose
 * short-circuit current exceeds their rating: all off, the link stays
 * below v_dc_max, the current dies out. */
static void presets_below_the_rectifier_speed_go_all_off(void **state) {
  (void)state;
  static const char *const runs[] = {
      /* saturated IPM (flux map), 3000 rpm, 300 V */
      "{\"duration\": 0.7, \"machine\": {\"preset\": \"ipm_sat\"},"
      "\"dc_link\": {\"kind\": \"rectifier\", \"voltage\": 300, \"r\": 0.5, \"c\": 200e-6},"
      "\"mechanics\": {\"mode\": \"imposed\", \"speed\": [{\"type\": \"ramp\", \"t0\": 0.05, "
      "\"t1\": 0.35, \"value\": 314.16}]},"
      "\"controller\": {\"law\": \"dfvc_decoupled\", \"mode\": \"torque\", \"flux_min\": 0.01},"
      "\"references\": {\"torque\": 3}," TRIP "}",
      /* synchronous reluctance (flux map, no magnet), 1800 rpm, 340 V */
      "{\"duration\": 0.7, \"machine\": {\"preset\": \"syr_1k1\"},"
      "\"dc_link\": {\"kind\": \"rectifier\", \"voltage\": 340, \"r\": 0.5, \"c\": 200e-6},"
      "\"mechanics\": {\"mode\": \"imposed\", \"speed\": [{\"type\": \"ramp\", \"t0\": 0.05, "
      "\"t1\": 0.35, \"value\": 188.5}]},"
      "\"controller\": {\"law\": \"dfvc_decoupled\", \"mode\": \"torque\", \"flux_min\": 0.2},"
      "\"references\": {\"torque\": 3}," TRIP "}",
      /* sensorless (star point, IVD + Kalman filter), 800 rpm, 24 V */
      "{\"duration\": 0.9, \"machine\": {\"preset\": \"fabbri2022_t51\"},"
      "\"inverter\": {\"model\": \"switching\", \"dead_time\": 5e-7},"
      "\"sensors\": {\"encoder_cpr\": 65536, \"i_noise\": 0.005, \"star_full_scale\": 13.0,"
      "\"star_noise\": 0.002, \"star_tau\": 2e-7},"
      "\"board\": {\"preset\": \"g474_nucleo\", \"asym_edges\": 1},"
      "\"dc_link\": {\"kind\": \"rectifier\", \"voltage\": 24, \"r\": 0.05, \"c\": 470e-6},"
      "\"mechanics\": {\"mode\": \"imposed\", \"speed\": [{\"type\": \"ramp\", \"t0\": 0.2, "
      "\"t1\": 0.45, \"value\": 83.78}]},"
      "\"controller\": {\"law\": \"foc\", \"mode\": \"torque\", \"pos_source\": \"ivd+kf\","
      "\"align_time\": 0.1, \"align_current\": 1.0},"
      "\"references\": {\"torque\": 0.1}, \"inject\": {\"trip_at\": 0.6, \"trip_cause\": "
      "\"control\"}}"};
  for (size_t r = 0; r < sizeof runs / sizeof runs[0]; ++r) {
    scenario_t sc;
    trace_t tr;
    sil_result_t res;
    run_json(runs[r], &sc, &tr, &res);
    const size_t k = first_fault(&tr);
    const double t_trip = sc.trip_at;
    assert_true(tr.t[k] >= t_trip && tr.t[k] < t_trip + 2e-3);
    assert_int_equal(tr.faults[k], DRIVE_FAULT_CONTROL);
    for (size_t j = k; j < tr.n; ++j) {
      assert_int_equal(tr.gates[j], 0);
      assert_int_equal(tr.asc[j], 0);
    }
    const double v_max = trace_max(tr.v_dc, k, tr.n);
    const size_t k_late = k + (size_t)(0.05 / sc.plant.ts);
    const double i_late = trace_max(tr.imax_abs, k_late, tr.n);
    printf("%s: speed at the trip %.0f rpm, v_dc max %.2f V (v_dc_max %.1f), current 50 ms "
           "later %.2e A\n",
           sc.plant.machine.map != NULL ? "flux map" : "linear", tr.speed[k] * 30.0 / PI, v_max,
           (double)sc.drive.v_dc_max, i_late);
    assert_true(v_max < (double)sc.drive.v_dc_max);
    assert_true(v_max <= sc.plant.dclink.v_source * 1.02);
    assert_true(i_late < 1e-3);
    trace_free(&tr);
  }
}

/* Issue 22 point 11: what the board must bound. Rubino's SPM on the
 * dynamometer at 1200 rpm (its top speed) and 1485 rpm (just below
 * speed_trip, 1500 rpm), the same 310 V diode-rectifier link of 200 uF.
 * (i) A trip: the active short circuit holds the link at the source. (ii)
 * The gate driver's nFAULT (a desaturation, its supply's undervoltage):
 * every switch off in hardware, no short possible (the break input clears
 * MOE): the diodes rectify the line back-EMF (peak sqrt(3) psi w_e) into
 * the link. Printed: the peak, the energy the capacitor took,
 * C (v_max^2 - v_0^2) / 2, and the power it took while passing v_dc_max
 * (C (v_2^2 - v_1^2) / 2 / (t_2 - t_1) between 0.95 and 1.05 v_dc_max):
 * what a chopper must burn to hold the link at v_dc_max, or a TVS /
 * the capacitor and switches must take. */
#define GATE_DRIVER                                                                                \
  "\"inject\": {\"gate_driver\": [{\"type\": \"step\", \"t\": 0.5, \"value\": 1}]}"
static void link_bound_short_vs_gate_driver(void **state) {
  (void)state;
  static const struct {
    double rpm;
    const char *inject;
  } runs[] = {
      {1200.0, TRIP},
      {1485.0, TRIP},
      {1485.0, GATE_DRIVER},
      {1485.0, GATE_DRIVER}, /* with the chopper the third run sizes */
  };
  double p_pass = 0.0;
  for (size_t r = 0; r < sizeof runs / sizeof runs[0]; ++r) {
    char json[1024];
    snprintf(json, sizeof json,
             RUBINO("0.9", "\"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": "
                           "\"rpm\", \"terms\": [{\"type\": \"ramp\", \"t0\": 0.05, \"t1\": "
                           "0.35, \"value\": %.1f}]}}, %s"),
             runs[r].rpm, runs[r].inject);
    if (r == 3) { /* the chopper: on at 0.95 v_dc_max, off at 0.9 (403 V: the preset's) */
      char *at = strstr(json, "\"c\": 200e-6");
      assert_non_null(at);
      char tail[1024];
      snprintf(tail, sizeof tail, "%s", at + strlen("\"c\": 200e-6"));
      snprintf(at, sizeof json - (size_t)(at - json),
               "\"c\": 200e-6, \"chopper_r\": %.3f, \"chopper_on\": 382.85, \"chopper_off\": "
               "362.7%s",
               pow(0.9 * 403.0, 2) / p_pass, tail);
    }
    scenario_t sc;
    trace_t tr;
    sil_result_t res;
    run_json(json, &sc, &tr, &res);
    const plant_machine_t *m = &sc.plant.machine;
    const size_t k = first_fault(&tr);
    assert_true(k < tr.n);
    const double w_e = runs[r].rpm * PI / 30.0 * m->pole_pairs;
    const double emf = sqrt(3.0) * m->lambda_m * w_e;
    const double c = sc.plant.dclink.c, v0 = sc.plant.dclink.v_source;
    const double vmax_drive = (double)sc.drive.v_dc_max;
    const double v_max = trace_max(tr.v_dc, k, tr.n);
    const double energy = 0.5 * c * (v_max * v_max - v0 * v0);
    const bool all_off = r >= 2;
    if (r == 3) {
      printf("with a chopper of %.1f Ohm on at %.1f V, off at %.1f V: ", sc.plant.dclink.r_chop,
             sc.plant.dclink.v_chop_on, sc.plant.dclink.v_chop_off);
    }
    printf("%s at %.0f rpm (line back-EMF peak %.1f V = %.2f x the %.0f V link), %.0f uF: faults "
           "0x%x, short %s; v_dc max %.1f V (v_dc_max %.1f V), the capacitor took %.2f J",
           all_off ? "gate driver nFAULT (all off)" : "trip (active short circuit)", runs[r].rpm,
           emf, emf / v0, v0, c * 1e6, tr.faults[k], tr.asc[k] ? "on" : "off", v_max, vmax_drive,
           energy);
    if (r == 2) {
      const size_t k1 = first_above(tr.v_dc, tr.n, 0.95 * vmax_drive);
      const size_t k2 = first_above(tr.v_dc, tr.n, 1.05 * vmax_drive);
      assert_true(k1 < k2 && k2 < tr.n);
      const double v1 = tr.v_dc[k1], v2 = tr.v_dc[k2];
      const double p = 0.5 * c * (v2 * v2 - v1 * v1) / (tr.t[k2] - tr.t[k1]);
      p_pass = p;
      printf(", %.0f W passing v_dc_max (%.2f ms from %.0f to %.0f V): a chopper of %.1f Ohm "
             "burns it at 0.9 v_dc_max",
             p, (tr.t[k2] - tr.t[k1]) * 1e3, v1, v2, pow(0.9 * vmax_drive, 2) / p);
      assert_true((tr.faults[k] & DRIVE_FAULT_GATE_DRIVER) != 0u);
      for (size_t j = k; j < tr.n; ++j) {
        assert_int_equal(tr.asc[j], 0);
        assert_int_equal(tr.gates[j], 0);
      }
      /* pumped towards the back-EMF's peak, never beyond it */
      assert_true(v_max > 0.9 * emf && v_max < emf);
      assert_true(p > 0.0);
    } else if (r == 3) { /* the same with that chopper: bounded below v_dc_max */
      assert_true((tr.faults[k] & DRIVE_FAULT_GATE_DRIVER) != 0u);
      assert_true(v_max < vmax_drive && v_max > 0.9 * vmax_drive);
    } else {
      assert_int_equal(tr.asc[k], 1);
      assert_true(v_max <= v0 + 1.0);
    }
    printf("\n");
    trace_free(&tr);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(rubino_short_at_top_speed),
      cmocka_unit_test(rubino_all_off_pumps_the_link),
      cmocka_unit_test(short_ends_below_the_rectifier_speed),
      cmocka_unit_test(active_load_after_a_trip_at_standstill),
      cmocka_unit_test(presets_below_the_rectifier_speed_go_all_off),
      cmocka_unit_test(link_bound_short_vs_gate_driver),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
