/*
 * SIL: power-stage faults injected into the switching inverter model
 * (scenario inject.gate_driver, switch_open, switch_closed, phase_lost,
 * phase_open, phase_short, ground_short; docs/faults.md "Injected in the
 * SIL"). Base: the Rubino 2020
 * SPM (p = 21, Rs = 7.1 Ohm, Ls = 57 mH, lambda_m = 0.19 Vs, 310 V) in
 * torque mode on a dynamometer at 300 rpm, a 10 N m step at 50 ms, the
 * fault from 150 ms. At 300 rpm w_e = 659.7 rad/s: the line-to-line
 * back-EMF peak sqrt(3) lambda_m w_e = 217 V is below the 310 V link (below
 * the rectifier speed, 429 rpm), so with the gates off the diodes block.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "sil_test_util.h"

#define PI    3.14159265358979323846
#define T_INJ 0.15
#define T_REF 10.0 /* N m */
#define P     21.0
#define RS    7.1
#define LS    0.057
#define LM    0.19
#define VDC   310.0
#define W_E   (P * 300.0 * 2.0 * PI / 60.0)
#define KT    (1.5 * P * LM)                     /* N m per A of current amplitude */
#define Z_ABS sqrt(RS *RS + W_E * LS * W_E * LS) /* phase impedance at w_e */
#define I_SC  (LM * W_E / Z_ABS)                 /* three-phase short-circuit current */

/* The true currents of phases a and b and the phase-balance check's
 * requests beside the common trace. */
static double *g_ia, *g_ib;
static unsigned *g_ph_trips;
static float *g_vdef;      /* the phase check's last judged voltage deficit |D| / v_dc */
static float g_vdef_ab[2]; /* its D / v_dc at the end of the run (alpha, beta) */
/* Energy over [E_T0, E_T1): from the shaft, into the link, into copper
 * (true states, period averages where the plant keeps them) [J] */
#define E_T0 0.2
#define E_T1 0.3
static double g_e_shaft, g_e_link, g_e_cu;

static void observer(void *user, const sil_step_t *st) {
  trace_t *tr = user;
  const plant_state_t *p = st->plant;
  const double ts = 1.0 / 16000.0;
  if (p->t >= E_T0 && p->t < E_T1) {
    g_e_shaft -= p->torque_avg * p->omega_m * ts;
    g_e_link -= p->v_dc * p->i_dc * ts;
    g_e_cu += RS *
              (p->i_abc[0] * p->i_abc[0] + p->i_abc[1] * p->i_abc[1] + p->i_abc[2] * p->i_abc[2]) *
              ts;
  }
  if (tr->n < tr->cap) {
    g_ia[tr->n] = st->plant->i_abc[0];
    g_ib[tr->n] = st->plant->i_abc[1];
    g_ph_trips[tr->n] = st->drive->host.ph.trips;
    g_vdef[tr->n] = st->drive->host.ph.vdef;
    g_vdef_ab[0] = st->drive->host.ph.vdef_ab[0];
    g_vdef_ab[1] = st->drive->host.ph.vdef_ab[1];
  }
  trace_observer(user, st);
}

/* rpm: the speed from 160 ms on (300 rpm before, a ramp over 20 ms);
 * torque: the step at 50 ms [N m]. */
static void run_fault_tq(const char *inject, double rpm, double torque, trace_t *tr,
                         scenario_t *sc) {
  sil_result_t res;
  char err[512];
  char js[2048];
  snprintf(js, sizeof js,
           "{\"duration\": 0.3, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"inverter\": "
           "{\"model\": \"switching\"}, \"sensors\": {\"i_noise\": 0.005}, \"mechanics\": "
           "{\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": [{\"type\": "
           "\"const\", \"value\": 300}, {\"type\": \"ramp\", \"t0\": 0.16, \"t1\": 0.18, "
           "\"value\": %g}]}}, \"controller\": {\"mode\": \"torque\"}, "
           "\"references\": {\"torque\": [{\"type\": \"step\", \"t\": 0.05, \"value\": %g}]}, "
           "\"inject\": {%s}}",
           rpm - 300.0, torque, inject);
  g_e_shaft = 0.0;
  g_e_link = 0.0;
  g_e_cu = 0.0;
  int r = scenario_parse(js, "test", sc, err, sizeof err);
  if (r != 0) {
    fprintf(stderr, "%s\n", err);
  }
  assert_int_equal(r, 0);
  const size_t cap = (size_t)(sc->duration / sc->plant.ts) + 2;
  trace_alloc(tr, cap);
  free(g_ia);
  free(g_ib);
  free(g_ph_trips);
  free(g_vdef);
  g_vdef = calloc(cap, sizeof(float));
  g_ia = calloc(cap, sizeof(double));
  g_ib = calloc(cap, sizeof(double));
  g_ph_trips = calloc(cap, sizeof(unsigned));
  r = sil_run(sc, observer, tr, &res, err, sizeof err);
  assert_int_equal(r, 0);
  assert_true(fabs(sc->plant.ts - 1.0 / 16000.0) < 1e-15); /* the observer's step */
}

static void run_fault_at(const char *inject, double rpm, trace_t *tr, scenario_t *sc) {
  run_fault_tq(inject, rpm, T_REF, tr, sc);
}

static void run_fault(const char *inject, trace_t *tr, scenario_t *sc) {
  run_fault_at(inject, 300.0, tr, sc);
}

#define ACTIVE_FROM_INJ "\"active\": [{\"type\": \"step\", \"t\": 0.15, \"value\": 1}]"

/* The trip: gate_driver alone, reported by the ISR after the period in
 * which the break latched (at most two periods after t_from), gates off
 * and the cause latched to the end. */
static size_t check_gate_driver_trip(const trace_t *tr, const scenario_t *sc, double t_from,
                                     const char *what) {
  const size_t k = first_fault(tr);
  assert_true(k < tr->n);
  printf("%s: injected at %.6f s, gate_driver reported at %.6f s (%.2f periods), faults 0x%x\n",
         what, t_from, tr->t[k], (tr->t[k] - t_from) / sc->plant.ts, tr->faults[k]);
  assert_true(tr->t[k] >= t_from);
  assert_true(tr->t[k] <= t_from + 2.0 * sc->plant.ts + 1e-9);
  assert_int_equal(tr->faults[k], DRIVE_FAULT_GATE_DRIVER);
  for (size_t j = k; j < tr->n; ++j) {
    assert_int_equal(tr->gates[j], 0);
    assert_int_equal(tr->state[j], DRIVE_STATE_FAULT);
    assert_int_equal(tr->faults[j], DRIVE_FAULT_GATE_DRIVER);
  }
  return k;
}

/* nFAULT asserted for 1 ms: gates off in hardware at once, gate_driver
 * reported by the next ISR and latched after the input is released; below
 * the rectifier speed the currents die out (the diodes block once the
 * inductances have emptied into the link: L I / (v_dc - e) < 1 ms). */
static void gate_driver_input(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault("\"gate_driver\": [{\"type\": \"step\", \"t\": 0.15, \"value\": 1}, {\"type\": "
            "\"step\", \"t\": 0.151, \"value\": -1}]",
            &tr, &sc);
  const size_t k = check_gate_driver_trip(&tr, &sc, T_INJ, "gate driver nFAULT");
  /* the break acts on the period starting at the injection: the next ISR
   * is the first that can see it */
  assert_true(fabs(tr.t[k] - (T_INJ + sc.plant.ts)) < 1e-9);
  const double i_late = trace_max(tr.imax_abs, idx_at(&tr, T_INJ + 0.005), idx_at(&tr, 0.3));
  printf("gate driver nFAULT: largest phase current from 5 ms after: %.3g A\n", i_late);
  assert_true(i_late < 1e-6);
  trace_free(&tr);
}

/* A leg tied to one rail whatever its gates (a switch stuck closed, a
 * lead shorted to earth): the other switch's next turn-on is a
 * shoot-through, which the gate driver's desaturation detection ends
 * (gate_driver within two periods). With the gates off the tie and the
 * diodes keep a rectifier path: braking torque, currents between half the
 * three-phase short-circuit current and twice the largest the six-step
 * voltage and the back-EMF drive through the phase impedance. */
static void check_tied_leg(const char *inject, const char *what) {
  trace_t tr;
  scenario_t sc;
  run_fault(inject, &tr, &sc);
  check_gate_driver_trip(&tr, &sc, T_INJ, what);
  const double torque = trace_mean(tr.torque, idx_at(&tr, 0.2), idx_at(&tr, 0.3));
  const double i_pk = trace_max(tr.imax_abs, idx_at(&tr, T_INJ), idx_at(&tr, 0.3));
  const double i_hi = 2.0 * (2.0 * VDC / PI + LM * W_E) / Z_ABS;
  printf("%s: mean torque 0.2-0.3 s %.3f N m, peak current %.3f A (bounds %.3f, %.3f A)\n", what,
         torque, i_pk, 0.5 * I_SC, i_hi);
  assert_true(torque < 0.0 && torque > -T_REF * 2.0);
  assert_true(i_pk > 0.5 * I_SC && i_pk < i_hi);
  trace_free(&tr);
}

static void switch_stuck_closed(void **state) {
  (void)state;
  check_tied_leg("\"switch_closed\": {\"switch\": \"a_high\", " ACTIVE_FROM_INJ "}",
                 "a_high stuck closed");
}

/* Leads a and b shorted together (bolted): the first period in which legs
 * a and b are commanded apart shoots through the short, which the gate
 * driver's desaturation detection ends (gate_driver within two periods).
 * Then the gates are off and the machine works into its own line-to-line
 * short: below the rectifier speed of the node (a, b) against c (the
 * back-EMF 1.5 lambda_m w_e = 188 V < v_dc) phase c's diodes block once
 * the trip's transient has died out (L / R = 8 ms), and the loop a-b alone
 * carries the current the line-to-line back-EMF sqrt(3) lambda_m w_e drives
 * through 2 Z: sqrt(3) / 2 of I_SC, dissipating 2 R I^2 / 2 in copper, all
 * of it from the shaft: the mean torque is -R I^2 / w_m. Both to 2 %
 * over 0.2-0.3 s (five time constants after the trip). */
static void phase_to_phase_short(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault("\"phase_short\": {\"phases\": \"ab\", " ACTIVE_FROM_INJ "}", &tr, &sc);
  check_gate_driver_trip(&tr, &sc, T_INJ, "a-b short");
  const size_t k0 = idx_at(&tr, 0.2), k1 = idx_at(&tr, 0.3);
  const double torque = trace_mean(tr.torque, k0, k1);
  double ia = 0.0, ic = 0.0;
  for (size_t k = k0; k < k1; ++k) {
    ia = fmax(ia, fabs(g_ia[k]));
    ic = fmax(ic, fabs(g_ia[k] + g_ib[k]));
  }
  const double i_ll = 0.5 * sqrt(3.0) * I_SC;
  const double t_ll = -RS * i_ll * i_ll / (W_E / P);
  printf("a-b short: 0.2-0.3 s peak |i_a| %.4f A (line-to-line short %.4f A), peak |i_c| %.3g A, "
         "mean torque %.4f N m (expected %.4f)\n",
         ia, i_ll, ic, torque, t_ll);
  assert_true(fabs(ia - i_ll) < 0.02 * i_ll);
  assert_true(ic < 1e-6);
  assert_true(fabs(torque - t_ll) < 0.02 * fabs(t_ll));
  trace_free(&tr);
}

/* The same short, the dynamometer then at 600 rpm: the node (a, b) against c now rectifies
 * (1.5 lambda_m w_e = 376 V > v_dc): phase c's diodes conduct and the
 * ideal link takes power. The circuit's energy balance checks the
 * shorted pair's diode node (plant_inverter_sw.c): over 0.2-0.3 s the
 * shaft's energy equals the link's plus the copper's to 1 %, the link's
 * share above a tenth, and the phase current stays below twice the
 * line-to-line short's. */
static void phase_to_phase_short_rectifying(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault_at("\"phase_short\": {\"phases\": \"ab\", " ACTIVE_FROM_INJ "}", 600.0, &tr, &sc);
  check_gate_driver_trip(&tr, &sc, T_INJ, "a-b short at 600 rpm");
  double ic = 0.0;
  for (size_t k = idx_at(&tr, E_T0); k < idx_at(&tr, E_T1); ++k) {
    ic = fmax(ic, fabs(g_ia[k] + g_ib[k]));
  }
  const double w_e = 2.0 * W_E, z = sqrt(RS * RS + w_e * LS * w_e * LS);
  const double i_ll = 0.5 * sqrt(3.0) * LM * w_e / z;
  const double i_pk = trace_max(tr.imax_abs, idx_at(&tr, E_T0), idx_at(&tr, E_T1));
  const double bal = g_e_shaft - g_e_link - g_e_cu;
  printf("a-b short at 600 rpm, 0.2-0.3 s: shaft %.4f J, link %.4f J, copper %.4f J, balance "
         "%.2e J (%.3f %%); peak |i_c| %.3f A; peak current %.3f A (line-to-line short %.3f "
         "A)\n",
         g_e_shaft, g_e_link, g_e_cu, bal, 100.0 * bal / g_e_shaft, ic, i_pk, i_ll);
  assert_true(g_e_shaft > 0.0);
  assert_true(fabs(bal) < 0.01 * g_e_shaft);
  assert_true(g_e_link > 0.1 * g_e_shaft);
  assert_true(ic > 0.05 * i_ll);
  assert_true(i_pk < 2.0 * i_ll);
  trace_free(&tr);
}

/* Lead a shorted to earth, the link's negative rail (bolted): phase a
 * tied to that rail, the circuit of a stuck-closed low side, braking
 * through the low diodes of b and c. */
static void phase_to_ground_short(void **state) {
  (void)state;
  check_tied_leg("\"ground_short\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", "a-earth short");
}

/* The drive's phase-balance check (drive_phase_check.h, main loop)
 * requests lost_control after two unbalanced electrical revolutions in a
 * row: not before one whole revolution with the fault (T_E after the
 * injection), at most three revolutions and two main-loop periods after it
 * (the revolution under way when the fault came may still look balanced;
 * the request is taken by the next ISR). */
#define T_E (2.0 * PI / W_E)
static void check_phase_trip(const trace_t *tr, const char *what) {
  const size_t k = first_fault(tr);
  assert_true(k < tr->n);
  printf("%s: lost_control at %.4f s, %.2f electrical revolutions (%.2f ms) after the injection, "
         "faults 0x%x, phase-check requests %u, lc_cause 0x%x\n",
         what, tr->t[k], (tr->t[k] - T_INJ) / T_E, 1e3 * (tr->t[k] - T_INJ), tr->faults[k],
         g_ph_trips[k], tr->lc_cause[k]);
  assert_true(tr->t[k] >= T_INJ + T_E);
  assert_true(tr->t[k] <= T_INJ + 3.0 * T_E + 2e-3);
  assert_int_equal(tr->faults[k], DRIVE_FAULT_LOST_CONTROL);
  assert_int_equal(g_ph_trips[k], 1);
  assert_int_equal(tr->lc_cause[k], 0); /* none of the ISR's own conditions */
  for (size_t j = k + 1; j < tr->n; ++j) {
    assert_int_equal(tr->gates[j], 0);
    assert_int_equal(tr->faults[j], DRIVE_FAULT_LOST_CONTROL);
  }
}

/* The largest |i_a| from 1 ms after the injection to the trip. */
static double ia_until_trip(const trace_t *tr) {
  double ia = 0.0;
  for (size_t k = idx_at(tr, T_INJ + 1e-3); k < first_fault(tr); ++k) {
    ia = fmax(ia, fabs(g_ia[k]));
  }
  return ia;
}

/* The same run without a fault (the injection after the end) does not
 * trip: the torque step at 50 ms and the steady 10 N m are balanced. */
static void healthy_does_not_trip(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault("\"phase_open\": {\"phase\": \"a\", \"active\": [{\"type\": \"step\", \"t\": 1, "
            "\"value\": 1}]}",
            &tr, &sc);
  const double torque = trace_mean(tr.torque, idx_at(&tr, 0.2), idx_at(&tr, 0.3));
  float vdef = 0.0f;
  for (size_t k = idx_at(&tr, 0.1); k < tr.n; ++k) {
    vdef = fmaxf(vdef, g_vdef[k]);
  }
  printf("healthy: faults 0x%x, mean torque 0.2-0.3 s %.3f N m, largest voltage deficit from 0.1 "
         "s %.5f v_dc (trips above %.2f)\n",
         tr.faults[tr.n - 1], torque, (double)vdef, (double)DRIVE_PH_VDEF);
  assert_true(first_fault(&tr) >= tr.n);
  assert_true(vdef < 0.25f * DRIVE_PH_VDEF);
  assert_true(fabs(torque - T_REF) < 0.02 * T_REF);
  trace_free(&tr);
}

/* A switch stuck open: its phase never reaches that rail while its
 * current would need it (a_high: the leg stays at 0 V in the positive
 * half-wave), so the voltage the drive believes it applied is missing
 * there: the phase check's stationary voltage deficit (drive_phase_check.h)
 * exceeds DRIVE_PH_VDEF and it trips as for a dead phase (check_phase_trip's
 * time bounds), the deficit then at least DRIVE_PH_VDEF and along the
 * phase's own axis, outwards for a high side (the believed voltage above
 * the one applied), inwards for a low side, within 15 deg; the current
 * stays below i_trip meanwhile (the healthy amplitude). */
static void check_stuck_open(const char *sw, double torque) {
  trace_t tr;
  scenario_t sc;
  char inj[256];
  snprintf(inj, sizeof inj, "\"switch_open\": {\"switch\": \"%s\", " ACTIVE_FROM_INJ "}", sw);
  run_fault_tq(inj, 300.0, torque, &tr, &sc);
  char what[64];
  snprintf(what, sizeof what, "%s stuck open at %g N m", sw, torque);
  check_phase_trip(&tr, what);
  const size_t k = first_fault(&tr);
  const double i_pk = trace_max(tr.imax_abs, idx_at(&tr, T_INJ), k);
  printf("%s: voltage deficit at the trip %.4f v_dc (trips above %.2f), peak current until the "
         "trip %.3f A (i_trip %.2f)\n",
         what, (double)g_vdef[k], (double)DRIVE_PH_VDEF, i_pk, sc.drive.i_trip);
  assert_true(g_vdef[k] > DRIVE_PH_VDEF);
  assert_true(i_pk < sc.drive.i_trip);
  /* the phase's axis (a 0, b 120, c 240 deg), reversed for a low side */
  const int leg = sw[0] - 'a';
  const double axis = 2.0 * PI / 3.0 * leg + (strstr(sw, "low") != NULL ? PI : 0.0);
  const double ang = atan2(g_vdef_ab[1], g_vdef_ab[0]);
  const double off = fabs(remainder(ang - axis, 2.0 * PI));
  printf("%s: deficit direction %.1f deg, the stuck switch's phase axis %.1f deg (off by %.1f)\n",
         what, ang * 180.0 / PI, remainder(axis, 2.0 * PI) * 180.0 / PI, off * 180.0 / PI);
  assert_true(off < 15.0 * PI / 180.0);
  trace_free(&tr);
}

static void switch_stuck_open(void **state) {
  (void)state;
  check_stuck_open("a_high", T_REF);
  check_stuck_open("b_low", T_REF);
  check_stuck_open("c_high", T_REF);
  check_stuck_open("a_high", 0.2 * T_REF); /* light load */
}

/* Phase a without current (lead open: exactly zero) or without drive
 * (both switches of leg a off: only its diodes conduct, when the floating
 * terminal would leave [0, v_dc]: at most 5 % of the healthy amplitude
 * T_REF / KT): the phase-balance check trips. */
static void phase_lost(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault("\"phase_lost\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", &tr, &sc);
  check_phase_trip(&tr, "phase a lost");
  const double ia = ia_until_trip(&tr);
  printf("phase a lost: max |i_a| until the trip %.3g A\n", ia);
  assert_true(ia <= 0.05 * T_REF / KT);
  trace_free(&tr);
}

static void phase_open(void **state) {
  (void)state;
  trace_t tr;
  scenario_t sc;
  run_fault("\"phase_open\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", &tr, &sc);
  check_phase_trip(&tr, "phase a open");
  const double ia = ia_until_trip(&tr);
  printf("phase a open: max |i_a| until the trip %.3g A\n", ia);
  assert_true(ia <= 1e-9);
  trace_free(&tr);
}

/* Refused: the faults of the switch-level circuit on the average model,
 * unknown switches, missing fields; each error names the field. */
static void bad_injections_named(void **state) {
  (void)state;
  static const struct {
    const char *inject, *inverter, *expect;
  } cases[] = {
      {"\"phase_open\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", "average",
       "inject.phase_open: needs inverter.model: switching"},
      {"\"switch_closed\": {\"switch\": \"a_hi\", " ACTIVE_FROM_INJ "}", "switching",
       "inject.switch_closed.switch: "},
      {"\"switch_open\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", "switching",
       "inject.switch_open.phase: unknown field"},
      {"\"phase_lost\": {\"phase\": \"d\", " ACTIVE_FROM_INJ "}", "switching",
       "inject.phase_lost.phase: "},
      {"\"phase_lost\": {\"phase\": \"a\"}", "switching", "inject.phase_lost.active: required"},
      {"\"switch_open\": {" ACTIVE_FROM_INJ "}", "switching",
       "inject.switch_open.switch: required"},
      {"\"gate_driver\": \"on\"", "switching", "inject.gate_driver"},
      {"\"phase_short\": {\"phases\": \"ac\", " ACTIVE_FROM_INJ "}", "switching",
       "inject.phase_short.phases: "},
      {"\"phase_short\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", "switching",
       "inject.phase_short.phase: unknown field"},
      {"\"ground_short\": {\"phase\": \"a\", " ACTIVE_FROM_INJ "}", "average",
       "inject.ground_short: needs inverter.model: switching"},
      {"\"phase_short\": {\"phases\": \"ca\", " ACTIVE_FROM_INJ "}, \"phase_open\": "
       "{\"phase\": \"a\", " ACTIVE_FROM_INJ "}",
       "switching", "inject.phase_short: shares a lead with inject.phase_open"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    char js[1024], err[512] = "";
    scenario_t sc;
    snprintf(js, sizeof js,
             "{\"duration\": 0.1, \"inverter\": {\"model\": \"%s\"}, \"inject\": {%s}}",
             cases[i].inverter, cases[i].inject);
    const int r = scenario_parse(js, "t", &sc, err, sizeof err);
    printf("%s\n", err);
    assert_int_equal(r, -1);
    assert_non_null(strstr(err, cases[i].expect));
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(gate_driver_input),
      cmocka_unit_test(switch_stuck_closed),
      cmocka_unit_test(phase_to_phase_short),
      cmocka_unit_test(phase_to_phase_short_rectifying),
      cmocka_unit_test(phase_to_ground_short),
      cmocka_unit_test(healthy_does_not_trip),
      cmocka_unit_test(switch_stuck_open),
      cmocka_unit_test(phase_lost),
      cmocka_unit_test(phase_open),
      cmocka_unit_test(bad_injections_named),
  };
  const int r = cmocka_run_group_tests(tests, NULL, NULL);
  free(g_ia);
  free(g_ib);
  free(g_ph_trips);
  free(g_vdef);
  return r;
}
