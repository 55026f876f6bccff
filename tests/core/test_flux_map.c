/*
 * test_flux_map.c - the core's flux map (model/flux_map.h) against the
 * closed-form machine it was built from (flux_map_fixture.h, double
 * precision): blob validation (each refusal), bilinear flux, incremental
 * inductance (25), inverse, torque (4), MTPA and MTPV tables, and the
 * machine_t dispatch.
 */
#include "core_test_util.h"

#include "flux_map_fixture.h"
#include "model/machine.h"

static uint32_t blob[FX_WORDS];

static flux_map_t parsed(const fx_model_t *m) {
  flux_map_t fm;
  flux_map_status_t st;
  const uint32_t n = fx_build(m, blob);
  assert_int_equal(flux_map_parse(&fm, blob, n, &st), 0);
  assert_int_equal(st.code, FLUX_MAP_OK);
  return fm;
}

/* CRC-32 of "123456789" is 0xCBF43926 (the standard check value). */
static void test_crc(void **state) {
  (void)state;
  const uint32_t w[3] = {0x34333231u, 0x38373635u, 0x39u};
  assert_int_equal(flux_map_crc32(w, 9u), 0xCBF43926u);
}

/* One corruption per refusal; each names its check (and the cell). */
static void expect(flux_map_err_t code, uint32_t size, int j, int k) {
  flux_map_t fm;
  flux_map_status_t st;
  assert_int_equal(flux_map_parse(&fm, blob, size, &st), -1);
  if (st.code != code) {
    fail_msg("got \"%s\", expected \"%s\"", flux_map_err_str(st.code), flux_map_err_str(code));
  }
  if (j >= 0) {
    assert_int_equal(st.j, j);
    assert_int_equal(st.k, k);
  }
}

static void test_refusals(void **state) {
  (void)state;
  const uint32_t n = fx_build(&FX_SYR, blob);
  flux_map_t fm;
  assert_int_equal(flux_map_parse(&fm, NULL, n, NULL), -1);
  expect(FLUX_MAP_E_SIZE, n - 4u, -1, -1); /* truncated */
  expect(FLUX_MAP_E_SIZE, 8u, -1, -1);
  blob[0] ^= 1u;
  expect(FLUX_MAP_E_MAGIC, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[1] = 2u;
  expect(FLUX_MAP_E_VERSION, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[3] = 65u;
  expect(FLUX_MAP_E_GRID, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[5] = 1u;
  expect(FLUX_MAP_E_LUT, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[6] = 4u;
  expect(FLUX_MAP_E_FLAGS, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[4] = FX_N - 1; /* header and size disagree */
  expect(FLUX_MAP_E_SIZE, n, -1, -1);
  fx_build(&FX_SYR, blob);
  blob[100] ^= 0x10u; /* one bit of one flux value */
  expect(FLUX_MAP_E_CRC, n, -1, -1);
  fx_build(&FX_SYR, blob);
  fx_put_f(blob, 9, -0.5);
  fx_reseal(blob);
  expect(FLUX_MAP_E_AXES, n, -1, -1);
  fx_build(&FX_SYR, blob);
  fx_put_f(blob, 10, 0.0); /* i_q from 0: no negative torque */
  fx_reseal(blob);
  expect(FLUX_MAP_E_IQ_SIGNS, n, -1, -1);
  fx_build(&FX_SYR, blob);
  fx_put_f(blob, 12 + 3 * FX_N + 7, NAN);
  fx_reseal(blob);
  expect(FLUX_MAP_E_FINITE, n, 7, 3);
  /* lambda_d falling along i_d at node (11, 4): a negative l_d */
  fx_build(&FX_SYR, blob);
  fx_put_f(blob, 12 + 4 * FX_N + 11, -5.0);
  fx_put_f(blob, 12 + 5 * FX_N + 11, -5.0);
  fx_reseal(blob);
  expect(FLUX_MAP_E_SELF_L, n, 10, 3); /* the first cell with the corner */
  /* a strong one-way cross term in cell (12, 12): self-inductances stay
   * positive, the matrix is not positive definite */
  fx_build(&FX_SYR, blob);
  fx_break_pd(blob);
  expect(FLUX_MAP_E_NOT_PD, n, 0, 12);
  fx_build(&FX_SYR, blob);
  fx_put_f(blob, 12 + 2 * FX_N * FX_N + 1 + FX_NL + 5, -1.0); /* mtpa_iq < 0 */
  fx_reseal(blob);
  expect(FLUX_MAP_E_TABLES, n, 5, -1);
  for (int e = 0; e <= (int)FLUX_MAP_E_COUNT; ++e) {
    assert_non_null(flux_map_err_str((flux_map_err_t)e));
  }
}

/* Bilinear: exact at the nodes, within the interpolation error
 * h^2/8 max|f''| between them (h = 0.5 A: a few 1e-3 Vs at most here). */
static void test_flux(void **state) {
  (void)state;
  const flux_map_t fm = parsed(&FX_PM);
  double worst_node = 0.0, worst_mid = 0.0;
  for (int k = 0; k < FX_N; ++k) {
    for (int j = 0; j < FX_N; ++j) {
      const double id = -FX_I + j * 0.5, iq = -FX_I + k * 0.5;
      double ld, lq;
      fx_flux(&FX_PM, id, iq, &ld, &lq);
      const dq_t f = flux_map_flux(&fm, (dq_t){(float)id, (float)iq});
      worst_node = fmax(worst_node, fmax(fabs(f.d - ld), fabs(f.q - lq)));
      fx_flux(&FX_PM, id + 0.25, iq + 0.25, &ld, &lq);
      const dq_t g = flux_map_flux(&fm, (dq_t){(float)(id + 0.25), (float)(iq + 0.25)});
      if (j < FX_N - 1 && k < FX_N - 1) {
        worst_mid = fmax(worst_mid, fmax(fabs(g.d - ld), fabs(g.q - lq)));
      }
    }
  }
  printf("flux map: node error %.3g Vs, cell-centre error %.3g Vs\n", worst_node, worst_mid);
  assert_true(worst_node < 2e-6);
  assert_true(worst_mid < 5e-3);
  assert_true(worst_mid > 1e-5); /* it is an interpolation, not the model */
  /* outside the grid: the edge cell's plane continues (no clamp) */
  const dq_t e1 = flux_map_flux(&fm, (dq_t){7.0f, 0.0f});
  const dq_t e0 = flux_map_flux(&fm, (dq_t){6.0f, 0.0f});
  const dq_t e2 = flux_map_flux(&fm, (dq_t){5.5f, 0.0f});
  ASSERT_NEAR(e1.d - e0.d, 2.0 * (e0.d - e2.d), 1e-5);
}

/* (25) centred over one step against the analytic derivatives; the map is
 * reciprocal, so l_dq = l_qd within the interpolation error. */
static void test_inductance(void **state) {
  (void)state;
  const flux_map_t fm = parsed(&FX_SYR);
  const double pts[][2] = {{0.0, 0.0}, {-3.0, 3.0}, {-1.2, 4.4}, {2.1, -5.2}, {-4.7, -1.3}};
  const double h = 1e-6;
  for (size_t n = 0; n < sizeof pts / sizeof pts[0]; ++n) {
    const double id = pts[n][0], iq = pts[n][1];
    double a, b, c, d, e, f;
    fx_flux(&FX_SYR, id + h, iq, &a, &b);
    fx_flux(&FX_SYR, id - h, iq, &c, &d);
    const double ldd = (a - c) / (2 * h), lqd = (b - d) / (2 * h);
    fx_flux(&FX_SYR, id, iq + h, &a, &b);
    fx_flux(&FX_SYR, id, iq - h, &e, &f);
    const double ldq = (a - e) / (2 * h), lqq = (b - f) / (2 * h);
    const flux_map_ldq_t l = flux_map_inductance(&fm, (dq_t){(float)id, (float)iq});
    const double scale = fabs(ldd) + fabs(lqq);
    ASSERT_NEAR(l.dd, ldd, 0.02 * scale);
    ASSERT_NEAR(l.qq, lqq, 0.02 * scale);
    ASSERT_NEAR(l.dq, ldq, 0.02 * scale);
    ASSERT_NEAR(l.qd, lqd, 0.02 * scale);
    ASSERT_NEAR(l.dq, l.qd, 0.02 * scale);
  }
  /* saturation is seen: l_qq at i_q = 5 A well below its value at 0 */
  const flux_map_ldq_t l0 = flux_map_inductance(&fm, (dq_t){0.0f, 0.0f});
  const flux_map_ldq_t l5 = flux_map_inductance(&fm, (dq_t){0.0f, 5.0f});
  assert_true(l5.qq < 0.5f * l0.qq);
}

/* flux_map_flux_inductance (one cell and its neighbours) is the flux
 * lookup and the centred (25) of flux_map_inductance, on a dense sweep over
 * the grid, its edges and beyond (extrapolation), including points on cell
 * edges and at the half-step where the window changes cell. */
static void test_flux_inductance_combined(void **state) {
  (void)state;
  const flux_map_t fm = parsed(&FX_PM);
  float worst_l = 0.0f;
  float worst_f = 0.0f;
  const float q = (float)(0.25 * 2.0 * FX_I / (FX_N - 1)); /* a quarter of a grid step */
  for (int a = -56; a <= 56; ++a) {                        /* +-7 A: the grid's +-6 A and beyond */
    for (int b = -56; b <= 56; ++b) {                      /* edges and half-steps included */
      const dq_t i = {q * (float)a, q * (float)b};
      flux_map_ldq_t l;
      const dq_t f = flux_map_flux_inductance(&fm, i, &l);
      const dq_t f0 = flux_map_flux(&fm, i);
      const flux_map_ldq_t l0 = flux_map_inductance(&fm, i);
      const float sc = fabsf(l0.dd) + fabsf(l0.qq);
      worst_f = fmaxf(worst_f, fmaxf(fabsf(f.d - f0.d), fabsf(f.q - f0.q)));
      worst_l = fmaxf(worst_l, fmaxf(fmaxf(fabsf(l.dd - l0.dd), fabsf(l.qq - l0.qq)),
                                     fmaxf(fabsf(l.dq - l0.dq), fabsf(l.qd - l0.qd))) /
                                   sc);
    }
  }
  print_message("combined lookup: flux %.2e Vs, inductance %.2e (relative) from the five lookups\n",
                (double)worst_f, (double)worst_l);
  assert_true(worst_f == 0.0f);
  assert_true(worst_l < 3e-5f); /* float rounding of two summation orders */
}

/* The inverse: flux(current(lambda)) = lambda to float resolution over the
 * grid, including strongly saturated points. */
static void test_inverse(void **state) {
  (void)state;
  const flux_map_t fm = parsed(&FX_PM);
  double worst = 0.0;
  for (int k = 0; k <= 20; ++k) {
    for (int j = 0; j <= 20; ++j) {
      const dq_t i = {(float)(-5.5 + 11.0 * j / 20), (float)(-5.5 + 11.0 * k / 20)};
      const dq_t l = flux_map_flux(&fm, i);
      const dq_t back = flux_map_current(&fm, l);
      worst = fmax(worst, fmax(fabs(back.d - i.d), fabs(back.q - i.q)));
    }
  }
  printf("flux map inverse: worst current error %.3g A\n", worst);
  assert_true(worst < 1e-3);
}

static void test_torque_mtpa_mtpv(void **state) {
  (void)state;
  const flux_map_t fm = parsed(&FX_SYR);
  /* (4) against the model at a node */
  ASSERT_NEAR(flux_map_torque(&fm, 2.0f, (dq_t){-3.0f, 3.0f}), fx_torque(&FX_SYR, -3.0, 3.0), 1e-4);
  /* MTPA: the table's current gives the torque asked for, and no current
   * angle of the same amplitude gives more (model, 0.5 % interpolation) */
  for (int n = 1; n <= 10; ++n) {
    const float t = fm.mtpa_t_max * (float)n / 10.5f;
    const dq_t i = flux_map_mtpa_current(&fm, t);
    ASSERT_NEAR(fx_torque(&FX_SYR, i.d, i.q), t, 0.01 * t);
    double bd, bq;
    const double best = fx_mtpa(&FX_SYR, sqrt(i.d * i.d + i.q * i.q), &bd, &bq);
    ASSERT_IN(fx_torque(&FX_SYR, i.d, i.q), 0.995 * best, 1.000001 * best);
    const dq_t in = flux_map_mtpa_current(&fm, -t);
    ASSERT_NEAR(in.q, -i.q, 0.0);
    ASSERT_NEAR(flux_map_mtpa_torque(&fm, sqrtf(i.d * i.d + i.q * i.q)), t, 0.01 * t);
    const dq_t l = flux_map_flux(&fm, i);
    ASSERT_NEAR(flux_map_mtpa_flux(&fm, t), sqrtf(l.d * l.d + l.q * l.q), 0.01);
  }
  assert_true(flux_map_mtpa_current(&fm, 0.0f).q == 0.0f);
  ASSERT_NEAR(flux_map_mtpa_current(&fm, 1e9f).q, flux_map_mtpa_current(&fm, fm.mtpa_t_max).q, 0.0);
  /* MTPV: rising with the flux, 0 at zero flux */
  ASSERT_NEAR(flux_map_mtpv_torque(&fm, 0.0f), 0.0, 1e-6);
  assert_true(flux_map_mtpv_torque(&fm, 0.5f * fm.mtpv_flux_max) > 0.0f);
}

static void test_machine_dispatch(void **state) {
  (void)state;
  static flux_map_t fm;
  fm = parsed(&FX_PM);
  machine_t m;
  assert_int_equal(machine_init_map(&m, 0.0f, &fm), -1);
  assert_int_equal(machine_init_map(&m, 1.0f, NULL), -1);
  assert_int_equal(machine_init_map(&m, 1.5f, &fm), 0);
  assert_int_equal(m.kind, MACHINE_FLUX_MAP);
  ASSERT_NEAR(m.pole_pairs, 2.0, 0.0);
  ASSERT_NEAR(machine_pm_flux(&m), 0.3, 1e-6);
  assert_false(machine_is_isotropic(&m, 10.0f));
  const dq_t i = {-2.0f, 3.0f};
  const dq_t l = machine_flux(&m, i);
  const dq_t lf = flux_map_flux(&fm, i);
  ASSERT_NEAR(l.d, lf.d, 0.0);
  ASSERT_NEAR(l.q, lf.q, 0.0);
  const dq_t back = machine_current(&m, l);
  ASSERT_NEAR(back.d, i.d, 1e-3);
  ASSERT_NEAR(machine_torque(&m, i), flux_map_torque(&fm, 2.0f, i), 0.0);
  const machine_ldq_t L = machine_inductance(&m, i);
  const flux_map_ldq_t Lf = flux_map_inductance(&fm, i);
  ASSERT_NEAR(L.dq, Lf.dq, 0.0);
  const dq_t v = machine_voltage_ss(&m, i, 100.0f);
  ASSERT_NEAR(v.q, 1.5f * i.q + 100.0f * l.d, 1e-3);
  const dq_t mt = machine_mtpa_current(&m, 5.0f);
  ASSERT_NEAR(machine_torque(&m, mt), 5.0, 0.05);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_crc),
      cmocka_unit_test(test_refusals),
      cmocka_unit_test(test_flux),
      cmocka_unit_test(test_inductance),
      cmocka_unit_test(test_flux_inductance_combined),
      cmocka_unit_test(test_inverse),
      cmocka_unit_test(test_torque_mtpa_mtpv),
      cmocka_unit_test(test_machine_dispatch),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
