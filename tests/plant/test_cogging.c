/*
 * test_cogging.c - the cogging torque (plant_mech.c):
 * T_cog = A sin(N theta_m + phi), in both inverter models' mechanics.
 *  - at standstill with zero current (zero voltage vector, no dead time;
 *    gates off: the diodes block), one period from rest at angles over two
 *    cogging periods: J dw/Ts against A sin(N theta + phi) (the angle moves
 *    by < 1e-6 rad in the period: the torque is constant to 1e-5 A);
 *    amplitude (the largest over the angles) within 0.5 % of A, period
 *    2 pi / N (T(theta + 2 pi / N) = T(theta));
 *  - none by default: the rotor at rest stays at rest;
 *  - out-of-range values are refused, naming the parameter.
 */
#include "plant_test_util.h"

#define COG_A     0.02 /* [N m] */
#define COG_N     24
#define COG_PHI   0.3 /* [rad] */
#define COG_STEPS 48  /* angles over two cogging periods */

/* The mean torque on the rotor over one period from rest at theta. */
static double torque_at(int model, int gates, double theta, double amp) {
  plant_params_t p = test_params();
  p.inverter.model = (plant_inverter_model_t)model;
  p.mech.mode = PLANT_MECH_FREE;
  p.mech.b = 0.0;
  p.mech.j = 1e-3;
  p.mech.theta0 = theta;
  p.mech.cog_amp = amp;
  p.mech.cog_order = COG_N;
  p.mech.cog_phase = COG_PHI;
  plant_t pl;
  test_init(&pl, &p);
  const double d[3] = {0.5, 0.5, 0.5};
  plant_step(&pl, d, gates != 0);
  return p.mech.j * pl.omega_m / p.ts;
}

static void test_amplitude_and_period(void **state) {
  (void)state;
  for (int model = 0; model < 2; model++) {
    for (int gates = 0; gates < 2; gates++) {
      double t_max = 0.0, err_max = 0.0, per_max = 0.0;
      for (int k = 0; k < COG_STEPS; k++) {
        const double th = 1.0 + k * (2.0 * T_TWO_PI / COG_N) / COG_STEPS;
        const double te = torque_at(model, gates, th, COG_A);
        const double ref = COG_A * sin(COG_N * th + COG_PHI);
        const double te_next = torque_at(model, gates, th + T_TWO_PI / COG_N, COG_A);
        t_max = fmax(t_max, fabs(te));
        err_max = fmax(err_max, fabs(te - ref));
        per_max = fmax(per_max, fabs(te_next - te));
      }
      print_message("model %d, gates %d: largest torque %.6f N m (A %.3f), worst error %.2e N m, "
                    "worst T(theta + 2pi/N) - T(theta) %.2e N m\n",
                    model, gates, t_max, COG_A, err_max, per_max);
      assert_true(err_max < 1e-3 * COG_A);
      assert_true(fabs(t_max - COG_A) < 5e-3 * COG_A);
      assert_true(per_max < 1e-3 * COG_A);
    }
  }
}

static void test_none_by_default(void **state) {
  (void)state;
  for (int model = 0; model < 2; model++) {
    assert_true(torque_at(model, 1, 1.234, 0.0) == 0.0);
  }
}

static void test_check(void **state) {
  (void)state;
  static const char *const names[] = {"mech.cog_amp", "mech.cog_order", "mech.cog_phase"};
  for (int k = 0; k < 3; k++) {
    plant_params_t p = test_params();
    p.mech.mode = PLANT_MECH_FREE;
    p.mech.cog_amp = COG_A;
    p.mech.cog_order = COG_N;
    if (k == 0) {
      p.mech.cog_amp = NAN;
    } else if (k == 1) {
      p.mech.cog_order = 0;
    } else {
      p.mech.cog_phase = 100.0;
    }
    const char *field = NULL;
    assert_int_not_equal(plant_check(&p, &field), 0);
    assert_string_equal(field, names[k]);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_amplitude_and_period),
      cmocka_unit_test(test_none_by_default),
      cmocka_unit_test(test_check),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
