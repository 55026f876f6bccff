/*
 * test_star_point.c - the star point of the (3.3) inductance matrix in the
 * switching-level plant (plant_star.c): the DFC signal (2.101) emerges from
 * two samples around the test-vector edge, equal to the static divider
 * G_c of (2.90) and to (3.6)-(3.7); none without anisotropy; the
 * measurement circuit's first-order settling and the channel's gain.
 */
#include "plant_test_util.h"

#include <stdio.h>

/* |a - b| <= tol, printed on failure */
#define ASSERT_NEAR_D(a, b, tol)                                                                   \
  do {                                                                                             \
    const double a_ = (a), b_ = (b);                                                               \
    if (!(fabs(a_ - b_) <= (tol))) {                                                               \
      fail_msg("%s = %.9g, expected %.9g (tol %.3g)", #a, a_, b_, (double)(tol));                  \
    }                                                                                              \
  } while (0)

/* The Table 5.1 motor with the star-point split of its preset; R_s ~ 0:
 * the resistive drop of the current change over the test vector is the
 * one thing the two samples do not cancel ((2.92) holds for continuous
 * terms of constant value), tested apart below */
static plant_params_t star_params(double theta_e, double tau, double dead) {
  plant_params_t p = test_params();
  p.machine.pole_pairs = 8;
  p.machine.rs = 1e-6;
  p.machine.ld = 394e-6;
  p.machine.lq = 475e-6;
  p.machine.lambda_m = 0.1186 / 8.0;
  p.machine.aniso = (plant_aniso_t){1, 20e-6, -48.54e-6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  p.inverter.model = PLANT_INV_SWITCHING;
  p.inverter.dead_time = dead;
  p.sensors.adc_bits = 24;
  p.sensors.star_full_scale = 13.0;
  p.sensors.star_tau = tau;
  p.mech.theta0 = theta_e / 8.0;
  test_const_speed(&p, 0.0);
  return p;
}

#define T0  (1.5e-6 / 62.5e-6) /* window start [periods] */
#define TW  (3.0e-6 / 62.5e-6)
#define T_B 0.75e-6 /* samples [s] */
#define T_A 4.0e-6

/* One period with leg x's test vector; Gamma_x / v_dc of the two samples */
static double gamma_of(plant_t *pl, int x) {
  double on[3], off[3];
  for (int j = 0; j < 3; ++j) {
    on[j] = j == x ? T0 : T0 + TW;
    off[j] = on[j] + 0.3;
  }
  const double t[2] = {T_B, T_A};
  plant_star_request(pl, 2, t);
  plant_step_pattern(pl, on, off, true);
  double v[PLANT_STAR_MAX];
  assert_int_equal(plant_star_read(pl, v), 2);
  return (v[1] - v[0]) / pl->v_dc - 1.0 / 3.0;
}

static void warm_up(plant_t *pl) {
  const double d[3] = {0.5, 0.5, 0.5};
  for (int k = 0; k < 4; ++k) {
    plant_step(pl, d, true);
  }
}

/* The worst |Gamma_x - (G_c,x - 1/3)| of v_dc over 24 angles, with the
 * phase resistance rs */
static double worst_vs_divider(double rs) {
  double worst = 0.0;
  for (int i = 0; i < 24; ++i) {
    const double th = -T_PI + 2.0 * T_PI * i / 24.0;
    plant_params_t p = star_params(th, 0.0, 0.0);
    p.machine.rs = rs;
    plant_t pl;
    test_init(&pl, &p);
    warm_up(&pl);
    double g[3];
    plant_star_gain(&pl, th, 0.0, g);
    for (int x = 0; x < 3; ++x) {
      const double e = fabs(gamma_of(&pl, x) - (g[x] - 1.0 / 3.0)); /* (2.101) */
      worst = e > worst ? e : worst;
    }
  }
  return worst;
}

static void test_gamma_is_the_static_divider(void **state) {
  (void)state;
  const double worst = worst_vs_divider(1e-6);
  printf("Gamma vs G_c - 1/3: worst %.3g of v_dc\n", worst);
  assert_true(worst < 2e-6);
}

/* With the Table 5.1 resistance the current change over the test vector
 * (about 0.1 A in 2.5 us) leaves its resistive drop through the divider's
 * anisotropic part: below 1e-3 of v_dc (2 % of a), more than 1e-4. */
static void test_resistive_drop_is_what_remains(void **state) {
  (void)state;
  const double worst = worst_vs_divider(2.2);
  printf("with R_s = 2.2 Ohm: worst %.3g of v_dc\n", worst);
  assert_true(worst > 1e-4 && worst < 1e-3);
}

/* The three components over three periods at standstill against
 * (3.6) with a, b of (3.7): Gamma_alpha = -a cos 2th + b cos 4th ... */
static void test_gamma_is_3_6(void **state) {
  (void)state;
  plant_params_t p0 = star_params(0.0, 0.0, 0.0);
  double a, b;
  plant_aniso_ab(&p0.machine, &a, &b);
  ASSERT_NEAR_D(b / a, (394e-6 - 475e-6) / (394e-6 + 475e-6), 1e-12); /* p of the preset */
  for (int i = 0; i < 12; ++i) {
    const double th = 2.0 * T_PI * i / 12.0 + 0.1;
    plant_params_t p = star_params(th, 0.0, 0.0);
    plant_t pl;
    test_init(&pl, &p);
    warm_up(&pl);
    double gm[3];
    for (int x = 0; x < 3; ++x) {
      gm[x] = gamma_of(&pl, x);
    }
    const double al = (2.0 * gm[0] - gm[1] - gm[2]) / 3.0, be = (gm[1] - gm[2]) / sqrt(3.0);
    ASSERT_NEAR_D(al, -a * cos(2.0 * th) + b * cos(4.0 * th), 2e-6);
    ASSERT_NEAR_D(be, a * sin(2.0 * th) + b * sin(4.0 * th), 2e-6);
  }
}

/* Issue 23, point 6: the self and mutual terms turned apart with the load
 * (phi_self, phi_mut) and scaled (amp_iq). The divider's signal is (3.97)
 * exactly: its 2theta and 4theta terms (a DFT over a turn of 2 theta_e)
 * are turned from the unloaded ones by phi_a, phi_b and their ratio is p,
 * as plant_aniso_load says ((3.7) with L2, M2 as phasors), to 1e-9. */
static void test_gamma_is_3_97_with_independent_shifts(void **state) {
  (void)state;
  static const double cases[][4] = {/* phi_self, phi_mut [rad/A], amp_iq [1/A], i_q [A] */
                                    {0.1, 0.1, 0.0, 1.5},
                                    {0.3, -0.05, 0.0, 1.2},
                                    {0.0, 0.2, 0.1, -1.0},
                                    {0.25, 0.02, -0.1, 2.0}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    double A[2][2] = {{0.0, 0.0}, {0.0, 0.0}}, B[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    plant_params_t p = star_params(0.0, 0.0, 0.0);
    p.machine.aniso.phi_self = cases[c][0];
    p.machine.aniso.phi_mut = cases[c][1];
    p.machine.aniso.amp_iq = cases[c][2];
    plant_t pl;
    test_init(&pl, &p);
    enum { N = 36 };
    for (int u = 0; u < 2; ++u) { /* unloaded, loaded */
      const double i_q = u ? cases[c][3] : 0.0;
      for (int i = 0; i < N; ++i) {
        const double th = T_PI * i / N;
        double g[3];
        plant_star_gain(&pl, th, i_q, g);
        const double al = (2.0 * g[0] - g[1] - g[2]) / 3.0, be = (g[1] - g[2]) / sqrt(3.0);
        const double zr = -al, zi = be; /* a e^{j(2th + phi_a)} - b e^{-j(4th + phi_b)} */
        A[u][0] += (zr * cos(2.0 * th) + zi * sin(2.0 * th)) / N;
        A[u][1] += (zi * cos(2.0 * th) - zr * sin(2.0 * th)) / N;
        B[u][0] += (zr * cos(4.0 * th) - zi * sin(4.0 * th)) / N;
        B[u][1] += (zi * cos(4.0 * th) + zr * sin(4.0 * th)) / N;
      }
    }
    double pa, pb, pp;
    plant_aniso_load(&p.machine, cases[c][3], &pa, &pb, &pp);
    const double arg_a = atan2(A[1][1], A[1][0]) - atan2(A[0][1], A[0][0]);
    const double arg_b = atan2(B[1][1], B[1][0]) - atan2(B[0][1], B[0][0]);
    printf("case %zu: phi_a %.6f (model %.6f), phi_b %.6f (model %.6f), p %.6f (model %.6f)\n", c,
           arg_a, pa, -arg_b, pb, -hypot(B[1][0], B[1][1]) / hypot(A[1][0], A[1][1]), pp);
    ASSERT_NEAR_D(arg_a, pa, 1e-9);
    ASSERT_NEAR_D(-arg_b, pb, 1e-9);
    /* b/a with the sign of (3.7): -B / A for a real a, b */
    ASSERT_NEAR_D(-hypot(B[1][0], B[1][1]) / hypot(A[1][0], A[1][1]), pp, 1e-9);
  }
}

static void test_isotropic_star_point_carries_nothing(void **state) {
  (void)state;
  plant_params_t p = star_params(0.7, 0.0, 0.0);
  p.machine.aniso.enabled = 0;
  plant_t pl;
  test_init(&pl, &p);
  warm_up(&pl);
  for (int x = 0; x < 3; ++x) {
    ASSERT_NEAR_D(gamma_of(&pl, x), 0.0, 1e-6);
  }
}

/* tau = 0.5 us, no dead time: the after-sample 2.5 us after the edge sees
 * 1 - e^-5 of the step; a +10 % channel gain scales the difference. */
static void test_circuit_and_channel(void **state) {
  (void)state;
  const double th = 0.4;
  double ref[3];
  {
    plant_params_t p = star_params(th, 0.0, 0.0);
    plant_t pl;
    test_init(&pl, &p);
    warm_up(&pl);
    for (int x = 0; x < 3; ++x) {
      ref[x] = gamma_of(&pl, x) + 1.0 / 3.0;
    }
  }
  plant_params_t p = star_params(th, 0.5e-6, 0.0);
  plant_t pl;
  test_init(&pl, &p);
  warm_up(&pl);
  const double settle = 1.0 - exp(-(T_A - T0 * 62.5e-6) / 0.5e-6);
  for (int x = 0; x < 3; ++x) {
    ASSERT_NEAR_D(gamma_of(&pl, x) + 1.0 / 3.0, settle * ref[x], 2e-6);
  }
  p = star_params(th, 0.0, 0.0);
  p.sensors.star_gain_error = 0.1;
  p.sensors.star_full_scale = 16.0; /* 1.1 x 12 V inside the range */
  test_init(&pl, &p);
  warm_up(&pl);
  for (int x = 0; x < 3; ++x) {
    ASSERT_NEAR_D(gamma_of(&pl, x) + 1.0 / 3.0, 1.1 * ref[x], 2e-6);
  }
}

/* Bad matrices are refused: not positive definite, or L2 = M2 (no
 * position in the signals, first condition of (3.7)). */
static void test_matrix_checked(void **state) {
  (void)state;
  plant_params_t p = star_params(0.0, 0.0, 0.0);
  const char *f = NULL;
  assert_int_equal(plant_check(&p, &f), 0);
  p.machine.aniso.m0 = -300e-6; /* zero-sequence inductance L0 + 2 M0 < 0 */
  assert_int_not_equal(plant_check(&p, &f), 0);
  assert_string_equal(f, "machine.star_m0");
  p = star_params(0.0, 0.0, 0.0);
  p.machine.aniso.m2 = (p.machine.ld - p.machine.lq) / 3.0; /* L2 = M2 */
  assert_int_not_equal(plant_check(&p, &f), 0);
  /* and a channel at its rail clips: 13 V range, 1.1 x 12 V */
  p = star_params(0.4, 0.0, 0.0);
  p.sensors.star_gain_error = 0.1;
  plant_t pl;
  test_init(&pl, &p);
  warm_up(&pl);
  const double t[2] = {T_B, T_A};
  const double on[3] = {T0, T0 + TW, T0 + TW}, off[3] = {T0 + 0.3, T0 + TW + 0.3, T0 + TW + 0.3};
  plant_star_request(&pl, 2, t);
  plant_step_pattern(&pl, on, off, true);
  double v[PLANT_STAR_MAX];
  assert_int_equal(plant_star_read(&pl, v), 2);
  ASSERT_NEAR_D(v[0], -13.0, 1e-5);
  p = star_params(0.0, 0.0, 0.0);
  p.sensors.star_tau = -1.0;
  assert_int_not_equal(plant_check(&p, &f), 0);
  assert_string_equal(f, "sensors.star_tau");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_gamma_is_the_static_divider),
      cmocka_unit_test(test_resistive_drop_is_what_remains),
      cmocka_unit_test(test_gamma_is_3_6),
      cmocka_unit_test(test_gamma_is_3_97_with_independent_shifts),
      cmocka_unit_test(test_isotropic_star_point_carries_nothing),
      cmocka_unit_test(test_circuit_and_channel),
      cmocka_unit_test(test_matrix_checked),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
