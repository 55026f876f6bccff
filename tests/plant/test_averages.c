/*
 * test_averages.c - plant_set_averages: the average model integrates the
 * period averages (v_abc, i_dc, torque, i_dq) only when asked; the state
 * evolves the same either way, bit for bit, and the averages read NaN when
 * off (never a stale value). Average model, gates on, every specialised
 * case: ideal link with a free rotor (the usual one), an RC link, imposed
 * speed; with dead time (the smooth sign and its clamps) and duties that
 * touch the rails; a few gates-off periods (the switching model's diodes)
 * in between.
 */
#include "plant_test_util.h"

static void run_pair(const plant_params_t *p, const char *what) {
  plant_t on, off;
  test_init(&on, p);
  test_init(&off, p);
  plant_set_averages(&off, false);
  double dev = 0.0;
  for (int k = 0; k < 3000; k++) {
    const double ph = 0.013 * k;
    /* from a small vector to one saturating two legs */
    const double amp = k < 1500 ? 0.3 : 0.62;
    double d[3];
    for (int j = 0; j < 3; j++) {
      d[j] = 0.5 + amp * cos(ph - j * 2.0943951023931957);
    }
    const bool gates = (k % 500) >= 3; /* gates off for 3 periods every 500 */
    plant_step(&on, d, gates);
    plant_step(&off, d, gates);
    plant_state_t a, b;
    plant_get_state(&on, &a);
    plant_get_state(&off, &b);
    assert_memory_equal(a.lambda_dq, b.lambda_dq, sizeof a.lambda_dq);
    assert_memory_equal(&a.theta_m, &b.theta_m, sizeof a.theta_m);
    assert_memory_equal(&a.omega_m, &b.omega_m, sizeof a.omega_m);
    assert_memory_equal(&a.v_dc, &b.v_dc, sizeof a.v_dc);
    assert_memory_equal(a.i_abc, b.i_abc, sizeof a.i_abc);
    plant_adc_t sa, sb;
    plant_sample(&on, &sa);
    plant_sample(&off, &sb);
    assert_memory_equal(&sa, &sb, sizeof sa); /* the star point's average included */
    assert_true(isfinite(a.v_abc[0]) && isfinite(a.i_dc) && isfinite(a.torque_avg) &&
                isfinite(a.i_dq_avg[1]));
    assert_true(isnan(b.v_abc[0]) && isnan(b.v_abc[2]) && isnan(b.i_dc) && isnan(b.torque_avg) &&
                isnan(b.i_dq_avg[0]) && isnan(b.i_dq_avg[1]));
    dev = fmax(dev, fabs(a.i_dq[1]));
  }
  print_message("%s: 3000 periods, the same state; max |i_q| %.2f A\n", what, dev);
  assert_true(dev > 0.5); /* the runs did drive a current */
}

static void test_ideal_free(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.inverter.dead_time = 1e-6;
  p.mech.mode = PLANT_MECH_FREE;
  p.mech.j = 1e-3;
  run_pair(&p, "ideal link, free rotor");
}

static void test_rc_link(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.inverter.dead_time = 1e-6;
  p.dclink.kind = PLANT_DC_RC;
  p.mech.mode = PLANT_MECH_FREE;
  p.mech.j = 1e-3;
  run_pair(&p, "RC link, free rotor");
}

static void test_imposed_speed(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.inverter.dead_time = 1e-6;
  test_const_speed(&p, 150.0);
  run_pair(&p, "ideal link, imposed speed");
}

/* Back on: integrated again from the next period. */
static void test_back_on(void **state) {
  (void)state;
  plant_params_t p = test_params();
  plant_t pl;
  test_init(&pl, &p);
  plant_set_averages(&pl, false);
  const double d[3] = {0.6, 0.5, 0.4};
  plant_step(&pl, d, true);
  plant_state_t s;
  plant_get_state(&pl, &s);
  assert_true(isnan(s.v_abc[0]));
  plant_set_averages(&pl, true);
  plant_step(&pl, d, true);
  plant_get_state(&pl, &s);
  assert_true(fabs(s.v_abc[0] - 0.1 * 24.0) < 1e-9); /* v_an = (d_a - mean d) v_dc */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ideal_free),
      cmocka_unit_test(test_rc_link),
      cmocka_unit_test(test_imposed_speed),
      cmocka_unit_test(test_back_on),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
