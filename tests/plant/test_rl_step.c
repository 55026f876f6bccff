/*
 * test_rl_step.c - locked rotor (imposed speed 0, theta_e = 0 so the d axis
 * is phase a): a voltage step along d gives i_d(t) = V/R (1 - exp(-t R/Ld)),
 * i_q = 0. Checked at every period for 8 time constants, both inverter
 * models, dead time 0.
 */
#include "plant_test_util.h"

#define V_STEP 5.0 /* -> 10 A final */

static double run_rl(plant_inverter_model_t model, int substeps, double *max_iq) {
  plant_params_t p = test_params();
  p.inverter.model = model;
  p.inverter.substeps = substeps;
  test_const_speed(&p, 0.0);
  plant_t pl;
  test_init(&pl, &p);
  double d[3];
  test_duties_ab(V_STEP, 0.0, p.dclink.v_source, d);
  const double tau = p.machine.ld / p.machine.rs, i_fin = V_STEP / p.machine.rs;
  const int n = (int)(8.0 * tau / p.ts);
  double err = 0.0;
  *max_iq = 0.0;
  for (int k = 0; k < n; k++) {
    plant_step(&pl, d, true);
    plant_state_t s;
    plant_get_state(&pl, &s);
    const double ref = i_fin * (1.0 - exp(-s.t / tau));
    err = fmax(err, fabs(s.i_dq[0] - ref));
    *max_iq = fmax(*max_iq, fabs(s.i_dq[1]));
  }
  print_message("model %d substeps %d: max |i_d - analytic| = %.3e A (%.4f %% of final), "
                "max |i_q| = %.2e A\n",
                (int)model, substeps, err, 100.0 * err / i_fin, *max_iq);
  return err / i_fin;
}

/* Average model: RK4 with h = Ts/substeps, h/tau = 0.03: the local error
 * (h/tau)^5/120 is ~1e-10, so 0.1 % is a loose bound; we demand 1e-6. */
static void test_average(void **state) {
  (void)state;
  double iq;
  assert_true(run_rl(PLANT_INV_AVERAGE, 1, &iq) < 1e-6);
  assert_true(iq < 1e-9);
  assert_true(run_rl(PLANT_INV_AVERAGE, 2, &iq) < 1e-6);
}

/* Switching model sampled at the valley: the valley is the centre of the
 * zero vector where the (antisymmetric) ripple crosses its mean, so the
 * sample equals the period mean up to O(ripple * Ts/tau): requirement
 * 0.1 % of final; we hold it to 0.01 %. */
static void test_switching(void **state) {
  (void)state;
  double iq;
  assert_true(run_rl(PLANT_INV_SWITCHING, 4, &iq) < 1e-4); /* measured 2.5e-6 */
  assert_true(iq < 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_average),
      cmocka_unit_test(test_switching),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
