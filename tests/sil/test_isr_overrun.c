/*
 * SIL, issue 13 item 4: ISR overrun (inject.isr_overrun, sil/runner/sil_run.h):
 * while the profile is > 0.5 the PWM-period interrupt ends after the next
 * valley; its pattern misses the timer's update (the previous one acts one
 * more period) and the board counts an overrun (hal_isr_stats). The drive's
 * `overrun` fault (protect/overrun.c) trips when overruns occurred in
 * overrun_k of the last overrun_n slow periods (defaults 4 of 16, slow
 * period 1 ms).
 * Base: the Rubino 2020 SPM machine (p = 21, L = 57 mH, lambda_m = 0.19 Vs)
 * on a dynamometer at 300 rpm (omega_e = 660 rad/s), FOC, 10 N m, 310 V.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "sil_test_util.h"

#define P_P    21.0
#define L_S    0.057
#define LAMBDA 0.19
#define W_E    (300.0 / 60.0 * 2.0 * 3.14159265358979 * P_P)
#define V_DC   310.0

static void run_with(const char *law, const char *inject, scenario_t *sc, trace_t *tr,
                     sil_result_t *res) {
  static char js[4096];
  snprintf(js, sizeof js,
           "{\"duration\": 0.4, \"machine\": {\"preset\": \"rubino2020_spm\"}, \"mechanics\": "
           "{\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": [{\"type\": "
           "\"const\", \"value\": 300}]}}, \"controller\": {\"law\": \"%s\", \"mode\": "
           "\"torque\"}, \"references\": {\"torque\": [{\"type\": \"step\", \"t\": 0.05, "
           "\"value\": 10}]}, \"inject\": {%s}}",
           law, inject);
  run_json(js, sc, tr, res);
}

/* Sustained from t_o: every slow period from the one containing t_o has
 * overruns; the check at the start of each slow period sees the last one's,
 * so the k-th such check (the trip) comes (k - 1) to k slow periods after
 * t_o. Nothing else trips first. */
static void sustained(const char *law, double t_o) {
  char inj[256];
  snprintf(inj, sizeof inj, "\"isr_overrun\": [{\"type\": \"step\", \"t\": %.6f, \"value\": 1}]",
           t_o);
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_with(law, inj, &sc, &tr, &res);
  const double t_slow = sc.drive.slow_div * sc.plant.ts;
  const double k = sc.drive.overrun_k;
  const size_t kf = first_fault(&tr);
  assert_true(kf < tr.n);
  const double dt = tr.t[kf] - t_o;
  printf("%s, sustained overrun from %.5f s: faults 0x%x at +%.4f ms (limits %.1f .. %.1f ms)\n",
         law, t_o, (unsigned)res.faults_seen, 1e3 * dt, 1e3 * (k - 1.0) * t_slow, 1e3 * k * t_slow);
  assert_int_equal(res.faults_seen, DRIVE_FAULT_OVERRUN);
  assert_true(dt > (k - 1.0) * t_slow - 1e-9);
  assert_true(dt <= k * t_slow + 1e-9);
  assert_int_equal(tr.gates[kf], 0);
  trace_free(&tr);
}

static void sustained_overrun_trips(void **state) {
  (void)state;
  sustained("foc", 0.2);     /* on a slow-period boundary */
  sustained("foc", 0.20031); /* inside a slow period */
  sustained("db_dfvc", 0.20031);
}

/* One late interrupt at 300.0625 ms: the pattern of the period before acts
 * one period more. Its error is the rotation of the voltage vector over one
 * period, |dv| = 2 |v| sin(omega_e Ts / 2), which drives the current off by
 * |dv| Ts / L at the end of the late period before the loop sees it. |v| is
 * at least the back-EMF omega_e lambda_m and at most the linear range
 * v_dc / sqrt(3): the deviation from the same run without the overrun lies
 * between half the first and twice the second (the loop's reaction), and
 * the torque's within 3/2 p lambda_m times that. No fault; one overrun. */
static void isolated_overrun_ridden_through(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr, base;
  sil_result_t res, res0;
  run_with("foc", "", &sc, &base, &res0);
  run_with("foc",
           "\"isr_overrun\": [{\"type\": \"step\", \"t\": 0.30003, \"value\": 1}, {\"type\": "
           "\"step\", \"t\": 0.30009, \"value\": -1}]",
           &sc, &tr, &res);
  const double ts = sc.plant.ts;
  const double rot = 2.0 * sin(0.5 * W_E * ts);
  const double di_lo = 0.5 * rot * W_E * LAMBDA * ts / L_S;
  const double di_hi = 2.0 * rot * V_DC / sqrt(3.0) * ts / L_S;
  const double dt_hi = 1.5 * P_P * LAMBDA * di_hi;
  double di = 0.0, dtq = 0.0, di_before = 0.0;
  for (size_t k = idx_at(&tr, 0.25); k < tr.n; ++k) {
    const double e = hypot(tr.id[k] - base.id[k], tr.iq[k] - base.iq[k]);
    if (tr.t[k] < 0.3) {
      di_before = fmax(di_before, e);
    } else {
      di = fmax(di, e);
      dtq = fmax(dtq, fabs(tr.torque[k] - base.torque[k]));
    }
  }
  hal_isr_stats_t st;
  hal_isr_stats(&st);
  printf("isolated overrun: %u counted, faults 0x%x; current off by %.5f A (limits %.5f .. "
         "%.5f), torque by %.4f N m (limit %.4f); before it %.2g A\n",
         (unsigned)st.overruns, (unsigned)res.faults_seen, di, di_lo, di_hi, dtq, dt_hi, di_before);
  assert_int_equal(st.overruns, 1u);
  assert_int_equal(res.faults_seen, 0u);
  assert_true(di_before < 1e-9); /* the runs are identical until then */
  assert_true(di >= di_lo && di <= di_hi);
  assert_true(dtq <= dt_hi);
  trace_free(&tr);
  trace_free(&base);
}

/* Single overruns 3 ms apart: k - 1 of them in the window ride through, the
 * k-th trips at the check after it. */
static void k_of_n(int count, unsigned expect) {
  char inj[1024] = "\"isr_overrun\": [";
  for (int j = 0; j < count; ++j) {
    char term[160];
    const double t = 0.3 + 0.003 * j;
    snprintf(term, sizeof term,
             "%s{\"type\": \"step\", \"t\": %.5f, \"value\": 1}, {\"type\": \"step\", \"t\": "
             "%.5f, \"value\": -1}",
             j > 0 ? ", " : "", t + 3e-5, t + 9e-5);
    strncat(inj, term, sizeof inj - strlen(inj) - 1);
  }
  strncat(inj, "]", sizeof inj - strlen(inj) - 1);
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_with("foc", inj, &sc, &tr, &res);
  const size_t kf = first_fault(&tr);
  printf("%d single overruns 3 ms apart: faults 0x%x", count, (unsigned)res.faults_seen);
  if (kf < tr.n) {
    printf(" at %.4f s (the last overrun at %.5f s)", tr.t[kf], 0.3 + 0.003 * (count - 1) + 6e-5);
  }
  printf("\n");
  assert_int_equal(res.faults_seen, expect);
  if (expect != 0u) {
    const double t_last = 0.3 + 0.003 * (count - 1) + 6.25e-5;
    const double t_slow = sc.drive.slow_div * sc.plant.ts;
    assert_true(tr.t[kf] > t_last && tr.t[kf] <= t_last + t_slow + 1e-9);
  }
  trace_free(&tr);
}

static void overruns_counted_over_the_window(void **state) {
  (void)state;
  k_of_n(3, 0u);
  k_of_n(4, DRIVE_FAULT_OVERRUN);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(sustained_overrun_trips),
                                     cmocka_unit_test(isolated_overrun_ridden_through),
                                     cmocka_unit_test(overruns_counted_over_the_window)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
