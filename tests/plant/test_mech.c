/*
 * test_mech.c - mechanics.
 *  - free rotor, no current (gates off below the rectifier threshold, so
 *    T_e = 0), constant load torque T_L (signed, subtracted):
 *      w(t) = w_inf + (w0 - w_inf) exp(-t B/J), w_inf = -T_L/B,
 *      theta(t) = theta0 + w_inf t + (w0 - w_inf) (J/B) (1 - exp(-t B/J)).
 *  - imposed speed (ramp + sine): w equals the profile exactly at every
 *    period, theta equals its analytic integral.
 */
#include "plant_test_util.h"

static void test_free_constant_torque(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.mech.mode = PLANT_MECH_FREE;
  p.mech.j = 2e-4;
  p.mech.b = 1e-3;
  p.mech.omega0 = 20.0;
  p.mech.theta0 = 1.0;
  p.machine.lambda_m = 0.001; /* keep the back-EMF far below the rectifier threshold */
  const double tl = -0.2;     /* drives the rotor forward: w_inf = 200 rad/s */
  profile_term_t k = {PROFILE_CONST, tl, 0, 0, 0, 0};
  assert_int_equal(profile_add(&p.mech.load_torque, k), 0);
  plant_t pl;
  test_init(&pl, &p);
  const double winf = -tl / p.mech.b, tm = p.mech.j / p.mech.b;
  double werr = 0.0, therr = 0.0;
  const double d[3] = {0.5, 0.5, 0.5};
  for (int n = 0; n < 16000; n++) { /* 1 s = 5 time constants */
    plant_step(&pl, d, false);
    plant_state_t s;
    plant_get_state(&pl, &s);
    const double e = exp(-s.t / tm);
    const double w = winf + (p.mech.omega0 - winf) * e;
    const double th = p.mech.theta0 + winf * s.t + (p.mech.omega0 - winf) * tm * (1.0 - e);
    werr = fmax(werr, fabs(s.omega_m - w));
    therr = fmax(therr, fabs(test_wrap_diff(s.theta_m, th)));
    assert_true(s.torque == 0.0);
    assert_true(s.load_torque == tl);
  }
  print_message("free rotor: max |w - analytic| = %.2e rad/s, max |theta - analytic| = %.2e rad\n",
                werr, therr);
  /* RK4, h/tm = 2e-4: truncation ~1e-16; what remains is rounding of the
   * theta accumulation and of the analytic expression at theta ~ 170 rad */
  assert_true(werr < 1e-9 * winf);
  assert_true(therr < 1e-9);
}

static void test_imposed_profile(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.mech.theta0 = 0.3;
  profile_term_t ramp = {PROFILE_RAMP, 150.0, 0.0, 0.2, 0, 0};
  profile_term_t sine = {PROFILE_SINE, 10.0, 0.0, 0.0, 7.0, 0.5};
  assert_int_equal(profile_add(&p.mech.speed, ramp), 0);
  assert_int_equal(profile_add(&p.mech.speed, sine), 0);
  plant_t pl;
  test_init(&pl, &p);
  const double d[3] = {0.5, 0.5, 0.5};
  double therr = 0.0;
  for (int n = 0; n < 8000; n++) {
    plant_step(&pl, d, true);
    plant_state_t s;
    plant_get_state(&pl, &s);
    assert_true(s.omega_m == profile_eval(&p.mech.speed, s.t)); /* exact */
    const double t = s.t, a = T_TWO_PI * 7.0;
    const double th_ramp = t < 0.2 ? 150.0 * t * t / (2 * 0.2) : 150.0 * (0.1 + (t - 0.2));
    const double th = 0.3 + th_ramp + 10.0 * (cos(0.5) - cos(a * t + 0.5)) / a;
    therr = fmax(therr, fabs(test_wrap_diff(s.theta_m, th)));
  }
  print_message("imposed: max |theta - analytic| = %.2e rad\n", therr);
  /* RK4 quadrature: exact for the ramp (corner at a period boundary),
   * (a h)^4-order for the sine */
  assert_true(therr < 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_free_constant_torque),
      cmocka_unit_test(test_imposed_profile),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
