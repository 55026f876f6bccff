/*
 * SIL: FOC speed control of the Rubino 2020 machine (free rotor, J = 0.021
 * kg m^2): speed step 0 -> 200 rpm with the 1200 rpm/s slew limit, then a
 * 10 N m load step. Speed PI: bandwidth 60 rad/s, zero at 15 rad/s.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "sil_test_util.h"

#define RPM (3.14159265358979 / 30.0)

static const char *scenario_json =
    "{\"name\": \"speed and load step\", \"duration\": 1.6,"
    " \"machine\": {\"preset\": \"rubino2020_spm\"},"
    " \"mechanics\": {\"mode\": \"free\", \"load_torque\": [{\"type\": \"step\", \"t\": 1.0, "
    "\"value\": 10}]},"
    " \"sensors\": {\"i_noise\": 0.005, \"encoder_cpr\": 4096},"
    " \"controller\": {\"law\": \"foc\", \"mode\": \"speed\", \"speed_bw\": 60, "
    "\"accel_max\": 125.66},"
    " \"references\": {\"speed\": {\"unit\": \"rpm\", \"terms\": [{\"type\": \"step\", \"t\": "
    "0.05, \"value\": 200}]}}}";

static void speed_step_and_load_step(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(scenario_json, &sc, &tr, &res);
  const double w_ref = 200.0 * RPM;
  /* Speed step: slew-limited ramp (0.167 s at 1200 rpm/s), then settles. */
  double overshoot = 0.0;
  size_t k_settle = 0;
  for (size_t k = idx_at(&tr, 0.05); k < idx_at(&tr, 1.0); ++k) {
    overshoot = fmax(overshoot, (tr.speed[k] - w_ref) / w_ref);
    if (fabs(tr.speed[k] - w_ref) > 0.01 * w_ref) {
      k_settle = k + 1;
    }
  }
  double t_settle = tr.t[k_settle] - 0.05;
  printf("speed step: overshoot %.2f %%, within 1 %% after %.3f s (ramp alone 0.167 s)\n",
         overshoot * 100.0, t_settle);
  assert_true(overshoot < 0.02);
  assert_true(t_settle < 0.45);

  /* Load step: the dip recovers, zero steady-state error (integral action). */
  double dip = 0.0;
  size_t k_rec = 0;
  for (size_t k = idx_at(&tr, 1.0); k < tr.n; ++k) {
    dip = fmax(dip, (w_ref - tr.speed[k]) / w_ref);
    if (fabs(tr.speed[k] - w_ref) > 0.01 * w_ref) {
      k_rec = k + 1;
    }
  }
  double t_rec = tr.t[k_rec] - 1.0;
  double mean_err = 0.0;
  size_t k1 = idx_at(&tr, 1.5);
  for (size_t k = k1; k < tr.n; ++k) {
    mean_err += (tr.speed[k] - w_ref) / w_ref;
  }
  mean_err /= (double)(tr.n - k1);
  printf("load step: dip %.2f %%, back within 1 %% after %.3f s, mean error %.3f %%\n", dip * 100.0,
         t_rec, mean_err * 100.0);
  /* Dip bound from the loop: dT/(J wb) ~ 10/(0.021*60) = 7.9 rad/s = 38 %;
   * the PI zero makes it smaller; anything beyond 40 % is a broken loop. */
  assert_true(dip > 0.01 && dip < 0.40);
  assert_true(t_rec < 0.35);
  assert_true(fabs(mean_err) < 0.002);
  /* torque met: the mean electromagnetic torque balances the load + friction */
  assert_true(fabs(res.final_torque - (10.0 + 1e-3 * w_ref)) < 0.2);
  assert_int_equal(res.faults, 0);
  trace_free(&tr);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(speed_step_and_load_step)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
