/*
 * test_high_speed.c - the plant at extreme speed (issue 22 point 10).
 *
 * The active short circuit (gates on, every low side on) of Rubino's SPM
 * (p = 21, R 7.1 Ohm, L 57 mH, psi 0.19 Vs) on a dynamometer: the steady
 * short-circuit current of a linear PM machine at electrical speed w_e is
 *   |i_sc| = psi w_e / sqrt(R^2 + (w_e L)^2)  (-> psi / L = 3.333 A),
 * a constant vector in the rotor frame; the flux's transient, which turns
 * at w_e in the rotor frame, decays with L/R = 8 ms. At 16 kHz one step
 * per period is |w_e| Ts = 2.69 rad at 19,564 rpm: RK4's stability ends at
 * 2.83, its accuracy long before; the plant raises its steps with the
 * speed (plant.h: PLANT_HW_MAX). Also a free rotor that a 5x rated load
 * (100 N m) drives backwards through 19,564 rpm, both inverter models, and
 * a speed beyond what PLANT_STEPS_SPEED_MAX steps cover (the plant stops
 * advancing, finite, and says so).
 */
#include "plant_test_util.h"

#define RPM (T_PI / 30.0)

static plant_params_t rubino(plant_inverter_model_t model) {
  plant_params_t p = test_params();
  p.machine.pole_pairs = 21;
  p.machine.rs = 7.1;
  p.machine.ld = 0.057;
  p.machine.lq = 0.057;
  p.machine.lambda_m = 0.19;
  p.inverter.model = model;
  p.inverter.substeps = 1; /* the scenario's choice for this machine (h R / L = 0.008) */
  p.dclink.v_source = 310.0;
  p.sensors.i_full_scale = 100.0;
  p.sensors.v_full_scale = 1000.0;
  p.mech.j = 0.021;
  p.mech.b = 1e-3;
  return p;
}

static double i_sc(const plant_params_t *p, double w_m) {
  const double we = fabs(w_m) * p->machine.pole_pairs;
  const double r = p->machine.rs, x = we * p->machine.ld;
  return p->machine.lambda_m * we / sqrt(r * r + x * x);
}

/* The short for `periods`; returns the largest deviation of |i_dq| from the
 * steady short over the last 10 ms (relative) and the steps used. */
static double run_short(plant_t *pl, int periods, int *steps) {
  const double d[3] = {0.0, 0.0, 0.0}; /* every low side on */
  double dev = 0.0;
  *steps = 0;
  for (int n = 0; n < periods; n++) {
    plant_step(pl, d, true);
    plant_state_t s;
    plant_get_state(pl, &s);
    *steps = plant_steps_last(pl) > *steps ? plant_steps_last(pl) : *steps;
    if (n >= periods - 160) {
      const double want = i_sc(&pl->p, s.omega_m);
      const double got = hypot(s.i_dq[0], s.i_dq[1]);
      dev = fmax(dev, isfinite(got) ? fabs(got - want) / want : INFINITY);
    }
  }
  return dev;
}

static void short_current_at_speed(void **state) {
  (void)state;
  static const double rpm[] = {1200.0, 1485.0, -19564.0, 40000.0, -200000.0};
  for (int m = 0; m < 2; m++) {
    for (size_t r = 0; r < sizeof rpm / sizeof rpm[0]; r++) {
      plant_params_t p = rubino(m == 0 ? PLANT_INV_AVERAGE : PLANT_INV_SWITCHING);
      test_const_speed(&p, rpm[r] * RPM);
      plant_t pl;
      test_init(&pl, &p);
      int steps = 0;
      const double dev = run_short(&pl, 1600, &steps); /* 0.1 s: 12 L/R */
      plant_state_t s;
      plant_get_state(&pl, &s);
      print_message("%s, %.0f rpm (w_e Ts %.3f rad): |i_dq| %.4f A, short %.4f A (psi/L %.4f A), "
                    "deviation %.2e, %d steps per period\n",
                    m == 0 ? "average" : "switching", rpm[r],
                    fabs(rpm[r]) * RPM * p.machine.pole_pairs * p.ts, hypot(s.i_dq[0], s.i_dq[1]),
                    i_sc(&p, s.omega_m), p.machine.lambda_m / p.machine.ld, dev, steps);
      assert_true(dev < 0.02);
      assert_true(steps >= (int)ceil(fabs(rpm[r]) * RPM * p.machine.pole_pairs * p.ts / 0.5));
    }
  }
}

/* The case: a free rotor driven backwards by 5x its rated torque,
 * shorted as it passes 19,564 rpm; 0.1 s later it turns ~23 % faster,
 * where the short's current is still psi / L within 0.1 %. */
static void short_on_a_runaway_rotor(void **state) {
  (void)state;
  for (int m = 0; m < 2; m++) {
    plant_params_t p = rubino(m == 0 ? PLANT_INV_AVERAGE : PLANT_INV_SWITCHING);
    p.mech.mode = PLANT_MECH_FREE;
    p.mech.omega0 = -19564.0 * RPM;
    profile_term_t k = {PROFILE_CONST, 100.0, 0, 0, 0, 0}; /* 5 x 20 N m */
    assert_int_equal(profile_add(&p.mech.load_torque, k), 0);
    plant_t pl;
    test_init(&pl, &p);
    int steps = 0;
    const double dev = run_short(&pl, 1600, &steps);
    plant_state_t s;
    plant_get_state(&pl, &s);
    print_message("%s, free rotor, 100 N m load: %.0f rpm after 0.1 s, |i_dq| %.4f A (short "
                  "%.4f A), deviation %.2e, up to %d steps per period\n",
                  m == 0 ? "average" : "switching", s.omega_m / RPM, hypot(s.i_dq[0], s.i_dq[1]),
                  i_sc(&p, s.omega_m), dev, steps);
    assert_true(s.omega_m < -21000.0 * RPM && s.omega_m > -26000.0 * RPM);
    assert_true(dev < 0.02);
  }
}

/* Beyond PLANT_STEPS_SPEED_MAX PLANT_HW_MAX / Ts: the plant does not
 * advance (finite state), plant_too_fast says so. */
static void beyond_the_speed_limit_stops(void **state) {
  (void)state;
  plant_params_t p = rubino(PLANT_INV_AVERAGE);
  p.mech.mode = PLANT_MECH_FREE;
  profile_term_t k = {PROFILE_CONST, -1e6, 0, 0, 0, 0}; /* drives it forwards, absurdly */
  assert_int_equal(profile_add(&p.mech.load_torque, k), 0);
  plant_t pl;
  test_init(&pl, &p);
  const double d[3] = {0.5, 0.5, 0.5};
  const double lim = plant_speed_limit_e(&pl) / p.machine.pole_pairs;
  int n = 0;
  while (!plant_too_fast(&pl) && n < 100000) {
    plant_step(&pl, d, false);
    ++n;
  }
  plant_state_t s;
  plant_get_state(&pl, &s);
  print_message("stopped after %d periods at %.4g rad/s (limit %.4g rad/s), |i| %.3g A\n", n,
                s.omega_m, lim, hypot(s.i_dq[0], s.i_dq[1]));
  assert_true(plant_too_fast(&pl));
  /* stopped where the speed, with what the load adds over a period, passes the limit */
  const double dw = 1e6 / p.mech.j * p.ts;
  assert_true(s.omega_m + dw > lim && s.omega_m < lim);
  assert_true(isfinite(s.i_dq[0]) && isfinite(s.i_dq[1]) && isfinite(s.v_dc));
  const double t = s.t;
  plant_step(&pl, d, false);
  plant_get_state(&pl, &s);
  assert_true(s.t == t); /* no further period */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(short_current_at_speed),
      cmocka_unit_test(short_on_a_runaway_rotor),
      cmocka_unit_test(beyond_the_speed_limit_stops),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
