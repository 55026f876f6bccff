/*
 * test_fluxmap.c - the plant's flux-map machine against an independent
 * closed form: the Hinkkanen et al. 2017 current-from-flux model (IEEE TIA
 * 53(3)) with the syr_1k1 preset's parameters, written here in C (the tool
 * has its own, in Python). The plant gets the map as a grid (65 x 65 over
 * +-8 A, 0.25 A steps; the preset's blob has 0.5 A) and inverts it; the
 * closed form i(psi) is exact, so every check measures the plant's
 * interpolation and inversion:
 *   1. steady states at locked rotor (v = Rs i*) reproduce the map
 *      lambda(i*) within 0.1 % at its grid points (saturated,
 *      cross-saturated, both signs); between them the interpolation's own
 *      error against the model is printed and bounded (0.3 %);
 *   2. a small voltage step at locked rotor gives the incremental
 *      inductances of the model within 1 % (the hardest place: next to
 *      i_d = 0, where the model's d-axis term |psi|^1 makes its curvature
 *      jump, which no C2 interpolant follows exactly);
 *   3. energy over a closed current cycle at constant speed: electrical
 *      energy in = copper losses + mechanical work within 0.5 %;
 *   4. both inverter models run the map machine and agree;
 *   5. bad grids refused with the cell; the inversion's extrapolated and
 *      non-unique nodes reported; halving the step changes little (RK4).
 */
#include "plant_test_util.h"

#include "plant_fluxmap.h"

#define NG 65
#define IG 8.0

/* syr_1k1 (tools/src/fluxdrive/fluxmap/presets.py): k, c, r */
static const double K = 0.137396, C = 2.0, R = 3.0;

/* Hinkkanen model, SyR convention, i(psi). */
static void model_current_syr(double pd, double pq, double *id, double *iq) {
  const double ad0 = K * 17.4 / C, add = K * 373.0 / pow(C, 6), aq0 = R * K * 52.1 / C;
  const double aqq = R * K * 658.0 / (C * C), adq = K * 1120.0 / pow(C, 4);
  const double d = fabs(pd), q = fabs(pq);
  *id = (ad0 + add * pow(d, 5) + adq / 2.0 * d * q * q) * pd;
  *iq = (aq0 + aqq * q + adq / 3.0 * d * d * d) * pq;
}

/* fluxdrive frame: x_d = -x_q(SyR), x_q = x_d(SyR). */
static void model_current(double ld, double lq, double *id, double *iq) {
  double sd, sq;
  model_current_syr(lq, -ld, &sd, &sq);
  *id = -sq;
  *iq = sd;
}

/* lambda(i) by Newton on the closed form (numerical Jacobian). */
static void model_flux(double id, double iq, double *ld, double *lq) {
  double x = id * 0.07, y = iq * 0.8;
  for (int it = 0; it < 100; ++it) {
    double a, b, a1, b1, a2, b2;
    const double h = 1e-7;
    model_current(x, y, &a, &b);
    model_current(x + h, y, &a1, &b1);
    model_current(x, y + h, &a2, &b2);
    const double g00 = (a1 - a) / h, g10 = (b1 - b) / h, g01 = (a2 - a) / h, g11 = (b2 - b) / h;
    const double det = g00 * g11 - g01 * g10, rd = id - a, rq = iq - b;
    const double sx = (g11 * rd - g01 * rq) / det, sy = (g00 * rq - g10 * rd) / det;
    const double n = hypot(sx, sy), lim = 0.5 * hypot(x, y) + 0.05;
    const double f = n > lim ? lim / n : 1.0;
    x += f * sx;
    y += f * sy;
    if (fabs(rd) + fabs(rq) < 1e-13) {
      break;
    }
  }
  *ld = x;
  *lq = y;
}

static double pd_g[NG * NG], pq_g[NG * NG];

static plant_fluxmap_t *make_map(void) {
  const double step = 2.0 * IG / (NG - 1);
  for (int k = 0; k < NG; ++k) {
    for (int j = 0; j < NG; ++j) {
      model_flux(-IG + j * step, -IG + k * step, &pd_g[k * NG + j], &pq_g[k * NG + j]);
    }
  }
  const plant_fluxmap_grid_t g = {NG, NG, -IG, step, -IG, step, pd_g, pq_g};
  plant_fluxmap_t *m = NULL;
  char err[256];
  const int rc = plant_fluxmap_create(&g, &m, err, sizeof err);
  if (rc != 0) {
    print_error("%s\n", err);
  }
  assert_int_equal(rc, 0);
  return m;
}

static plant_params_t map_params(const plant_fluxmap_t *m) {
  plant_params_t p = test_params();
  p.machine.pole_pairs = 2;
  p.machine.rs = 6.8;
  p.machine.map = m;
  p.dclink.v_source = 650.0;
  p.inverter.substeps = 1;
  return p;
}

/* 1. Steady states at locked rotor (theta_e = 0: dq = alpha beta). */
static void test_steady_states(void **state) {
  (void)state;
  plant_fluxmap_t *m = make_map();
  /* grid points (multiples of 0.5 A), then points between them */
  const double pts[][2] = {{-3.0, 6.0}, {-2.5, 1.5},  {2.5, -1.0}, {-6.0, 0.5},     {0.5, -7.0},
                           {5.0, 5.0},  {-4.5, -2.0}, {-1.0, 1.0}, {-2.797, 1.660}, {2.5, -1.25},
                           {-6.2, 0.4}, {0.3, -7.1},  {-4.4, -2.2}};
  const size_t n_grid = 8;
  double worst = 0.0, worst_off = 0.0;
  for (size_t n = 0; n < sizeof pts / sizeof pts[0]; ++n) {
    plant_params_t p = map_params(m);
    test_const_speed(&p, 0.0);
    plant_t pl;
    test_init(&pl, &p);
    double d[3];
    test_duties_ab(6.8 * pts[n][0], 6.8 * pts[n][1], p.dclink.v_source, d);
    for (int k = 0; k < 32000; ++k) { /* 2 s: > 10 L/R at the largest inductance */
      plant_step(&pl, d, true);
    }
    plant_state_t s;
    plant_get_state(&pl, &s);
    double ld, lq;
    model_flux(pts[n][0], pts[n][1], &ld, &lq);
    const double e = hypot(s.lambda_dq[0] - ld, s.lambda_dq[1] - lq) / hypot(ld, lq + 1e-3);
    const double ei = hypot(s.i_dq[0] - pts[n][0], s.i_dq[1] - pts[n][1]);
    print_message("steady state i* = (%5.2f, %5.2f) A: lambda (%.5f, %.5f) Vs, model (%.5f, "
                  "%.5f), error %.4f %%; current error %.2e A\n",
                  pts[n][0], pts[n][1], s.lambda_dq[0], s.lambda_dq[1], ld, lq, 100.0 * e, ei);
    if (n < n_grid) {
      worst = fmax(worst, e);
    } else {
      worst_off = fmax(worst_off, e);
    }
    assert_true(ei < 1e-6);
  }
  print_message("steady states: worst flux error %.4f %% at grid points (bound 0.1 %%), %.4f %% "
                "between them (bound 0.3 %%)\n",
                100.0 * worst, 100.0 * worst_off);
  assert_true(worst < 1e-3);
  assert_true(worst_off < 3e-3);
  plant_fluxmap_free(m);
}

/* 2. Small voltage steps from a bias point: d lambda / d i from the plant's
 * response (its flux state and currents) against the model's Jacobian. */
static void incremental_at(plant_fluxmap_t *m, double i0d, double i0q, double *worst) {
  double L[2][2];
  for (int ax = 0; ax < 2; ++ax) {
    plant_params_t p = map_params(m);
    test_const_speed(&p, 0.0);
    plant_t pl;
    test_init(&pl, &p);
    double d[3];
    test_duties_ab(6.8 * i0d, 6.8 * i0q, p.dclink.v_source, d);
    for (int k = 0; k < 32000; ++k) {
      plant_step(&pl, d, true);
    }
    plant_state_t s0, s1;
    plant_get_state(&pl, &s0);
    const double dv = 0.2; /* V, for 40 periods: about 10 mA on d, 1 mA on q */
    test_duties_ab(6.8 * i0d + (ax == 0 ? dv : 0.0), 6.8 * i0q + (ax == 1 ? dv : 0.0),
                   p.dclink.v_source, d);
    for (int k = 0; k < 40; ++k) {
      plant_step(&pl, d, true);
    }
    plant_get_state(&pl, &s1);
    /* the step along one voltage axis moves both currents: two steps give
     * the flux changes for two current changes; solve for L */
    L[0][ax] = s1.lambda_dq[0] - s0.lambda_dq[0];
    L[1][ax] = s1.lambda_dq[1] - s0.lambda_dq[1];
    L[0][ax + 0] = L[0][ax]; /* kept: flux change column */
    static double di[2][2];
    di[0][ax] = s1.i_dq[0] - s0.i_dq[0];
    di[1][ax] = s1.i_dq[1] - s0.i_dq[1];
    if (ax == 1) {
      /* L = dLambda dI^-1 */
      const double det = di[0][0] * di[1][1] - di[0][1] * di[1][0];
      const double inv[2][2] = {{di[1][1] / det, -di[0][1] / det},
                                {-di[1][0] / det, di[0][0] / det}};
      double Lm[2][2];
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 2; ++c) {
          Lm[r][c] = L[r][0] * inv[0][c] + L[r][1] * inv[1][c];
        }
      }
      /* the model's d lambda / d i: inverse of its d i / d lambda at the bias */
      double ld, lq, a, b, a1, b1, a2, b2;
      const double h = 1e-7;
      model_flux(i0d, i0q, &ld, &lq);
      model_current(ld, lq, &a, &b);
      model_current(ld + h, lq, &a1, &b1);
      model_current(ld, lq + h, &a2, &b2);
      const double g[2][2] = {{(a1 - a) / h, (a2 - a) / h}, {(b1 - b) / h, (b2 - b) / h}};
      const double gd = g[0][0] * g[1][1] - g[0][1] * g[1][0];
      const double Lr[2][2] = {{g[1][1] / gd, -g[0][1] / gd}, {-g[1][0] / gd, g[0][0] / gd}};
      const double scale = sqrt(Lr[0][0] * Lr[1][1]);
      double e = 0.0;
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 2; ++c) {
          e = fmax(e, fabs(Lm[r][c] - Lr[r][c]) / (r == c ? Lr[r][c] : scale));
        }
      }
      print_message("incremental at (%5.2f, %5.2f) A: plant l_dd %.2f l_qq %.2f l_dq %.3f l_qd "
                    "%.3f mH; model %.2f %.2f %.3f %.3f mH; worst %.3f %%\n",
                    i0d, i0q, 1e3 * Lm[0][0], 1e3 * Lm[1][1], 1e3 * Lm[0][1], 1e3 * Lm[1][0],
                    1e3 * Lr[0][0], 1e3 * Lr[1][1], 1e3 * Lr[0][1], 1e3 * Lr[1][0], 100.0 * e);
      *worst = fmax(*worst, e);
    }
  }
}

static void test_incremental_inductance(void **state) {
  (void)state;
  plant_fluxmap_t *m = make_map();
  double worst = 0.0;
  const double pts[][2] = {{-2.797, 1.660}, {-3.0, 6.0}, {-6.0, 1.0},
                           {2.0, -3.0},     {-1.5, 3.5}, {4.5, 2.25}};
  for (size_t n = 0; n < sizeof pts / sizeof pts[0]; ++n) {
    incremental_at(m, pts[n][0], pts[n][1], &worst);
  }
  print_message("next to i_d = 0 (the model's curvature jump at zero flux):\n");
  incremental_at(m, -0.5, 0.5, &worst);
  print_message("incremental inductances: worst error %.3f %% (bound 1 %%)\n", 100.0 * worst);
  assert_true(worst < 0.01);
  plant_fluxmap_free(m);
}

/* 3. Energy over a closed cycle: at 600 rpm (imposed), dq voltages that
 * drive the currents round a loop through the saturated region (a
 * periodic steady state after some cycles); over one cycle of the loop the
 * DC-link energy (exact average-model power v_dc i_dc) equals the copper
 * losses plus the mechanical work. */
static void test_energy_balance(void **state) {
  (void)state;
  plant_fluxmap_t *m = make_map();
  plant_params_t p = map_params(m);
  const double w = 600.0 * T_PI / 30.0;
  test_const_speed(&p, w);
  plant_t pl;
  test_init(&pl, &p);
  const double f = 8.0, we = 2.0 * w;            /* loop frequency [Hz] */
  const int per = (int)lround(1.0 / (f * p.ts)); /* 2000 periods a loop */
  double e_in = 0.0, e_cu = 0.0, e_mech = 0.0, prev_cu = 0.0, prev_mech = 0.0;
  for (int k = 0; k < 6 * per; ++k) {
    const double t = k * p.ts, ph = 2.0 * T_PI * f * t;
    /* current loop centre (-2.5, 2) A, radii 2 A / 1.5 A: through saturation */
    const double id = -2.5 + 2.0 * cos(ph), iq = 2.0 + 1.5 * sin(ph);
    double ld, lq;
    model_flux(id, iq, &ld, &lq);
    /* the voltage of that trajectory (model), open loop: the plant follows
     * it up to its own small error; the state still closes its loop */
    double ld2, lq2;
    const double h = 1e-5;
    model_flux(-2.5 + 2.0 * cos(ph + 2 * T_PI * f * h), 2.0 + 1.5 * sin(ph + 2 * T_PI * f * h),
               &ld2, &lq2);
    const double vd = 6.8 * id + (ld2 - ld) / h - we * lq, vq = 6.8 * iq + (lq2 - lq) / h + we * ld;
    double d[3];
    test_duties_dq(&pl, vd, vq, d);
    plant_step(&pl, d, true);
    plant_state_t s;
    plant_get_state(&pl, &s);
    const double cu = 1.5 * 6.8 * (s.i_dq[0] * s.i_dq[0] + s.i_dq[1] * s.i_dq[1]);
    const double mech = s.torque * w;
    if (k >= 5 * per) { /* the last loop: trapezoids for the sampled powers */
      e_in += s.v_dc * s.i_dc * p.ts;
      e_cu += 0.5 * (cu + prev_cu) * p.ts;
      e_mech += 0.5 * (mech + prev_mech) * p.ts;
    }
    prev_cu = cu;
    prev_mech = mech;
  }
  const double res = (e_in - e_cu - e_mech) / e_in;
  print_message("energy over one loop: in %.4f J, copper %.4f J, mechanical %.4f J, residual "
                "%.4f %% (bound 0.5 %%)\n",
                e_in, e_cu, e_mech, 100.0 * res);
  assert_true(e_mech > 0.2 * e_in); /* the loop does work: the test can see a torque error */
  assert_true(fabs(res) < 5e-3);
  plant_fluxmap_free(m);
}

/* 4. Both inverter models on the map machine, and 5. reports and refusals. */
static void test_models_and_reports(void **state) {
  (void)state;
  plant_fluxmap_t *m = make_map();
  double fin[2][2];
  for (int mod = 0; mod < 2; ++mod) {
    for (int sub = 1; sub <= 2; ++sub) {
      plant_params_t p = map_params(m);
      p.inverter.model = mod == 0 ? PLANT_INV_AVERAGE : PLANT_INV_SWITCHING;
      p.inverter.substeps = sub;
      test_const_speed(&p, 300.0 * T_PI / 30.0);
      plant_t pl;
      test_init(&pl, &p);
      for (int k = 0; k < 4000; ++k) {
        double d[3];
        test_duties_dq(&pl, 6.8 * -2.0, 6.8 * 1.5 + 2.0 * 31.4 * 0.5, d);
        plant_step(&pl, d, true);
      }
      plant_state_t s;
      plant_get_state(&pl, &s);
      if (sub == 1) {
        fin[mod][0] = s.i_dq[0];
        fin[mod][1] = s.i_dq[1];
      } else {
        print_message("model %s: i_dq (%.5f, %.5f) A, substeps 1 -> 2 changes it by %.2e A\n",
                      mod == 0 ? "average" : "switching", s.i_dq[0], s.i_dq[1],
                      hypot(s.i_dq[0] - fin[mod][0], s.i_dq[1] - fin[mod][1]));
        assert_true(hypot(s.i_dq[0] - fin[mod][0], s.i_dq[1] - fin[mod][1]) < 1e-3);
        assert_true(isfinite(s.torque));
      }
    }
  }
  print_message("average vs switching: %.4f A apart\n",
                hypot(fin[0][0] - fin[1][0], fin[0][1] - fin[1][1]));
  assert_true(hypot(fin[0][0] - fin[1][0], fin[0][1] - fin[1][1]) < 0.05);
  char msg[200];
  assert_int_equal(plant_fluxmap_nonunique(m, msg, sizeof msg), 0);
  print_message("inverse map: %d flux-grid nodes extrapolated (outside the image of the current "
                "grid), 0 not unique\n",
                plant_fluxmap_extrapolated(m));
  /* far outside the map: finite, no crash */
  double i_d, i_q;
  plant_fluxmap_current(m, 50.0, -50.0, &i_d, &i_q);
  assert_true(isfinite(i_d) && isfinite(i_q));
  plant_fluxmap_free(m);
  /* refusals: a NaN, and lambda_d falling along i_d (cell named) */
  plant_fluxmap_grid_t g = {NG, NG, -IG, 0.25, -IG, 0.25, pd_g, pq_g};
  plant_fluxmap_t *bad = NULL;
  char err[256];
  pd_g[5 * NG + 7] = NAN;
  assert_int_equal(plant_fluxmap_create(&g, &bad, err, sizeof err), -1);
  assert_non_null(strstr(err, "(7, 5)"));
  pd_g[5 * NG + 7] = pd_g[5 * NG + 6] - 0.1;
  assert_int_equal(plant_fluxmap_create(&g, &bad, err, sizeof err), -1);
  print_message("refused: %s\n", err);
  assert_non_null(strstr(err, "not positive definite in grid cell (6, 4)"));
  g.nd = 1;
  assert_int_equal(plant_fluxmap_create(&g, &bad, err, sizeof err), -1);
  assert_null(bad);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_steady_states), cmocka_unit_test(test_incremental_inductance),
      cmocka_unit_test(test_energy_balance), cmocka_unit_test(test_models_and_reports)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
