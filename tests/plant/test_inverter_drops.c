/*
 * test_inverter_drops.c - the inverter's device voltage drops (switch and
 * diode threshold and resistance, plant_inverter_sw.c, plant_inverter_avg.c)
 * with the dead time, on a locked rotor with DC currents along alpha
 * (i_a = I, i_b = i_c = -I/2, |I| well above the ripple and i_band).
 *  - switching model against the analytic period-average leg error
 *      i > 0: err = -(td/Ts) v_dc - (e V_sw(i) + (1 - e) V_d(i)),  e = d - td/Ts
 *      i < 0: err = +(td/Ts) v_dc - (e V_d(i) + (1 - e) V_sw(i)),  e = d + td/Ts
 *    V_sw(i) = v_th_sw sgn(i) + r_on_sw i, V_d(i) = v_f_diode sgn(i) + r_diode i,
 *    measured as the phase voltage's error v_an - v_an* = (2/3)(err_a - err_b)
 *    (legs b, c alike), at several currents of both signs and at three
 *    common-mode offsets of the duties (which move e and so weigh switch
 *    against diode: the ideal inverter's phase voltage does not see them);
 *    bound on both sides: |measured - analytic| within 0.5 % of the drop
 *    part plus 1 mV (measured: < 2e-4 V; the residual is the current's
 *    ripple about its sampled value);
 *  - the drops alone (dead time 0), the same bound;
 *  - the average model against the switching one at the same points: the
 *    error and the steady current; and against the formula; the error
 *    curve through zero current;
 * Each term broken (the drop's sign flipped, r_on_sw or r_diode dropped,
 * switch and diode swapped) breaks a bound: tests/mutation/mutants.json
 * holds such mutants of both models (scripts/mutation_check.py --only
 * sw_drop_sign ...: all killed).
 */
#include "plant_test_util.h"

#define VTH 1.0   /* [V] */
#define RON 0.05  /* [Ohm] */
#define VF  0.7   /* [V] */
#define RD  0.025 /* [Ohm] */

static double sgn(double x) {
  return x > 0.0 ? 1.0 : -1.0;
}

/* The analytic period-average error of a leg of duty d at current i. */
static double leg_err(double d, double kdt, double vdc, double i) {
  const double vsw = VTH * sgn(i) + RON * i, vd = VF * sgn(i) + RD * i;
  if (i > 0.0) {
    const double e = d - kdt;
    return -kdt * vdc - (e * vsw + (1.0 - e) * vd);
  }
  const double e = d + kdt;
  return kdt * vdc - (e * vd + (1.0 - e) * vsw);
}

typedef struct {
  double i_a;   /* steady phase-a current [A] */
  double err;   /* measured error of v_an [V] */
  double ref;   /* analytic [V] */
  double drops; /* the drops' part of ref [V] */
} point_t;

static point_t run_point(int model, double td, double valpha, double cm) {
  plant_params_t p = test_params();
  p.inverter.model = (plant_inverter_model_t)model;
  p.inverter.dead_time = td;
  p.inverter.substeps = 4;
  p.inverter.v_th_sw = VTH;
  p.inverter.r_on_sw = RON;
  p.inverter.v_f_diode = VF;
  p.inverter.r_diode = RD;
  test_const_speed(&p, 0.0);
  plant_t pl;
  test_init(&pl, &p);
  const double vdc = p.dclink.v_source, kdt = td / p.ts;
  double d[3];
  test_duties_ab(valpha, 0.0, vdc, d);
  for (int j = 0; j < 3; j++) {
    d[j] += cm;
  }
  for (int k = 0; k < 1600; k++) { /* 50 time constants */
    plant_step(&pl, d, true);
  }
  plant_state_t s;
  plant_get_state(&pl, &s);
  point_t r;
  r.i_a = s.i_abc[0];
  const double ib = s.i_abc[1];
  const double van_cmd = (2.0 * d[0] - d[1] - d[2]) / 3.0 * vdc;
  r.err = s.v_abc[0] - van_cmd;
  r.ref = 2.0 / 3.0 * (leg_err(d[0], kdt, vdc, r.i_a) - leg_err(d[1], kdt, vdc, ib));
  const double dt_only = 2.0 / 3.0 * (-kdt * vdc * sgn(r.i_a) - kdt * vdc * sgn(r.i_a));
  r.drops = r.ref - dt_only;
  return r;
}

static const double V_ALPHA[] = {-7.0, -5.0, -3.5, 3.5, 5.0, 7.0};
static const double CM[] = {-0.15, 0.0, 0.15}; /* no duty clamped */
#define N_V  (int)(sizeof V_ALPHA / sizeof V_ALPHA[0])
#define N_CM (int)(sizeof CM / sizeof CM[0])

static void check_switching(double td) {
  for (int v = 0; v < N_V; v++) {
    for (int c = 0; c < N_CM; c++) {
      const point_t r = run_point(PLANT_INV_SWITCHING, td, V_ALPHA[v], CM[c]);
      const double tol = 0.005 * fabs(r.drops) + 1e-3;
      print_message("switching, td %.1e, cm %+.2f: i_a %+7.3f A, v_an error %+.5f V, analytic "
                    "%+.5f V (drops %+.5f V), diff %+.2e V (bound %.2e)\n",
                    td, CM[c], r.i_a, r.err, r.ref, r.drops, r.err - r.ref, tol);
      assert_true(fabs(r.i_a) > 2.0); /* well above the ripple */
      assert_true(r.err >= r.ref - tol && r.err <= r.ref + tol);
    }
  }
}

static void test_switching_dead_time_and_drops(void **state) {
  (void)state;
  check_switching(1.0e-6);
}

static void test_switching_drops_alone(void **state) {
  (void)state;
  check_switching(0.0);
}

/* Average model against the switching one: the same error (0.2 % of the
 * drops' part plus 1 mV; measured < 1e-5 V) and the same steady current
 * (0.1 %; measured < 0.05 %). */
static void test_average_vs_switching(void **state) {
  (void)state;
  for (int v = 0; v < N_V; v++) {
    for (int c = 0; c < N_CM; c++) {
      const point_t sw = run_point(PLANT_INV_SWITCHING, 1.0e-6, V_ALPHA[v], CM[c]);
      const point_t av = run_point(PLANT_INV_AVERAGE, 1.0e-6, V_ALPHA[v], CM[c]);
      const double tol = 0.002 * fabs(sw.drops) + 1e-3;
      print_message("cm %+.2f: i_a avg %+7.4f sw %+7.4f A; error avg %+.5f sw %+.5f V, diff "
                    "%+.2e V (bound %.2e)\n",
                    CM[c], av.i_a, sw.i_a, av.err, sw.err, av.err - sw.err, tol);
      assert_true(fabs(av.err - sw.err) <= tol);
      assert_true(fabs(av.i_a - sw.i_a) <= 1e-3 * fabs(sw.i_a));
      /* and the average model against the formula itself */
      assert_true(fabs(av.err - av.ref) <= 0.002 * fabs(av.drops) + 1e-3);
    }
  }
}

/* The voltage-error curve through zero current: the average model's
 * smooth sign over i_band against the switching model, whose current stays
 * clamped at zero below the error (the dead time alone does the same: the
 * floating legs follow the zero current), at the same commanded voltage:
 * within 12 mV everywhere (measured: 8.6 mV at 0.5 V; 11 mV with the dead
 * time alone, which the average model has always had), 1e-6 V once the
 * current flows (>= 2 V here). */
static void test_curve_near_zero(void **state) {
  (void)state;
  static const double vs[] = {0.05, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0};
  for (unsigned k = 0; k < sizeof vs / sizeof vs[0]; k++) {
    for (int sg = -1; sg <= 1; sg += 2) {
      const point_t sw = run_point(PLANT_INV_SWITCHING, 1.0e-6, sg * vs[k], 0.0);
      const point_t av = run_point(PLANT_INV_AVERAGE, 1.0e-6, sg * vs[k], 0.0);
      print_message("v_alpha %+5.2f V: i_a avg %+8.4f sw %+8.4f A; error avg %+.4f sw %+.4f V, "
                    "diff %+.2e V\n",
                    sg * vs[k], av.i_a, sw.i_a, av.err, sw.err, av.err - sw.err);
      assert_true(fabs(av.err - sw.err) <= 12e-3);
    }
  }
}

/* Out-of-range drops are refused, naming the parameter. */
static void test_check(void **state) {
  (void)state;
  static const char *const names[] = {"inverter.v_th_sw", "inverter.r_on_sw", "inverter.v_f_diode",
                                      "inverter.r_diode"};
  for (int k = 0; k < 4; k++) {
    for (int bad = 0; bad < 3; bad++) {
      plant_params_t p = test_params();
      test_const_speed(&p, 0.0);
      const double v = bad == 0 ? -1e-3 : (bad == 1 ? 1e3 : NAN);
      double *f[4] = {&p.inverter.v_th_sw, &p.inverter.r_on_sw, &p.inverter.v_f_diode,
                      &p.inverter.r_diode};
      *f[k] = v;
      const char *field = NULL;
      assert_int_not_equal(plant_check(&p, &field), 0);
      assert_string_equal(field, names[k]);
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_switching_dead_time_and_drops),
      cmocka_unit_test(test_switching_drops_alone),
      cmocka_unit_test(test_average_vs_switching),
      cmocka_unit_test(test_curve_near_zero),
      cmocka_unit_test(test_check),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
