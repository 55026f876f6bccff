/*
 * test_dfc.c - the star-point position algorithms (estimation/dfc.h) and
 * the DFC window of the pattern (control/dfc_window.h):
 *  - the IVD on unit vectors against (3.76) and (3.100) written as the
 *    thesis prints them (atan2, sin, cos in double), every iteration;
 *  - the standard DFC's error against (3.13), the inverse DFC exact for a
 *    diagonal inductance matrix ((3.15)-(3.16), section 3.1.2);
 *  - Theorem 1 in the configuration check (|p| >= 1/2 refused);
 *  - the signals (2.96)-(2.101) and the sequentiality compensation;
 *  - the window: leg X alone from t0, the others after t0 + tw, every
 *    pulse width kept.
 */
#include "core_test_util.h"

#include <string.h>

#include "control/dfc_window.h"
#include "estimation/dfc.h"

static double wrapd(double x) {
  return remainder(x, 2.0 * T_PI);
}

/* Gamma / v_dc of (3.6): Gamma_a, Gamma_b, Gamma_c from the alpha-beta
 * model with phase shifts (3.97) */
static void model_g(double a, double b, double th, double pa, double pb, float g[3]) {
  const double al = -a * cos(2.0 * th + pa) + b * cos(4.0 * th + pb);
  const double be = a * sin(2.0 * th + pa) + b * sin(4.0 * th + pb);
  g[0] = (float)al;
  g[1] = (float)(-0.5 * al + 0.8660254037844386 * be);
  g[2] = (float)(-0.5 * al - 0.8660254037844386 * be);
}

/* (3.76) / (3.100) as printed, with the quadrant of -conj(Gamma) (the
 * atan2 of section 3.1.1), in double: 2theta_k for k = 0..n */
static void ref_ivd(double a, double b, const float g[3], double pa, double pb, int n,
                    double *out) {
  const double al = (2.0 * g[0] - g[1] - g[2]) / 3.0, be = (g[1] - g[2]) / sqrt(3.0);
  double t2 = atan2(be, -al) - pa; /* (3.98) */
  out[0] = t2;
  for (int k = 1; k <= n; ++k) {
    const double x = 2.0 * t2 + pb; /* 4 theta_{k-1} + phi_b */
    t2 = atan2((be - b * sin(x)) / a, -(al - b * cos(x)) / a) - pa;
    out[k] = t2;
  }
}

static void test_ivd_equals_the_printed_iteration(void **state) {
  (void)state;
  const double ps[] = {-0.45, -0.3, -0.0932, 0.15, 0.3, 0.45};
  const double a = 0.05;
  double worst = 0.0;
  for (size_t ip = 0; ip < sizeof ps / sizeof ps[0]; ++ip) {
    for (int full = 0; full < 2; ++full) {
      const double pa = full ? 0.09 : 0.0, pb = full ? 0.18 : 0.0;
      const dfc_cfg_t c = {full ? DFC_FULL_IVD : DFC_IVD, (float)a,
                           (float)(ps[ip] * a),           full ? 0.06f : 0.0f,
                           full ? 0.12f : 0.0f,           8u};
      assert_int_equal(dfc_check(&c), DFC_OK);
      for (int i = 0; i < 720; ++i) {
        const double th = -T_PI + 2.0 * T_PI * i / 720.0;
        float g[3], tr[2 * (DFC_ITER_MAX + 1u)], c2, s2;
        model_g(a, ps[ip] * a, th, pa, pb, g);
        dfc_vec_t v;
        dfc_vec_plain(g, &v);
        assert_true(dfc_vector2(&c, g, &v, 1.5f, &c2, &s2, tr));
        double ref[DFC_ITER_MAX + 1u];
        ref_ivd(a, ps[ip] * a, g, pa, pb, (int)DFC_ITER_MAX, ref);
        for (unsigned k = 0; k <= DFC_ITER_MAX; ++k) {
          const double e = fabs(wrapd(atan2((double)tr[2 * k + 1], (double)tr[2 * k]) - ref[k]));
          worst = e > worst ? e : worst;
        }
        /* with the phase shifts known the Full IVD converges to 2 theta */
        if (fabs(ps[ip]) < 0.35) {
          ASSERT_NEAR(wrapd(atan2((double)s2, (double)c2) - 2.0 * th), 0.0, 2e-3);
        }
      }
    }
  }
  /* float arithmetic against double: 8 iterations within 2e-5 rad */
  ASSERT_IN(worst, 0.0, 2e-5);
}

/* The standard DFC's error is (3.13): Delta = atan(p sin 6th / (1 - p cos 6th)) */
static void test_standard_dfc_error_is_3_13(void **state) {
  (void)state;
  const double a = 0.05, p = 0.3;
  const dfc_cfg_t c = {DFC_STANDARD, (float)a, (float)(p * a), 0.0f, 0.0f, 0u};
  for (int i = 0; i < 360; ++i) {
    const double th = 2.0 * T_PI * i / 360.0;
    float g[3];
    model_g(a, p * a, th, 0.0, 0.0, g);
    bool ok;
    const double t2 = (double)dfc_angle2(&c, g, 0.0f, &ok);
    assert_true(ok);
    const double d = atan2(p * sin(6.0 * th), 1.0 - p * cos(6.0 * th));
    ASSERT_NEAR(wrapd(t2 - 2.0 * th - d), 0.0, 1e-5);
  }
}

/* Inverse DFC: kappa_x = sum L_Sigma / L_Sigma,x; for a diagonal matrix
 * (M0 = M2 = 0) L_Sigma,x is the product of the other two self
 * inductances and the estimate is exact (section 3.1.2). */
static void test_inverse_dfc_exact_for_a_diagonal_matrix(void **state) {
  (void)state;
  const double l0 = 400e-6, l2 = 60e-6;
  const dfc_cfg_t c = {DFC_INVERSE, 0.05f, 0.0f, 0.0f, 0.0f, 0u};
  for (int i = 0; i < 360; ++i) {
    const double th = 2.0 * T_PI * i / 360.0;
    double l[3], s[3], sum = 0.0;
    for (int x = 0; x < 3; ++x) {
      l[x] = l0 + l2 * cos(2.0 * th + x * 2.0 * T_PI / 3.0);
    }
    for (int x = 0; x < 3; ++x) {
      s[x] = l[(x + 1) % 3] * l[(x + 2) % 3]; /* column sums of the adjugate */
      sum += s[x];
    }
    float g[3];
    for (int x = 0; x < 3; ++x) {
      g[x] = (float)(s[x] / sum - 1.0 / 3.0); /* (2.101) */
    }
    bool ok;
    const double t2 = (double)dfc_angle2(&c, g, 0.0f, &ok);
    assert_true(ok);
    ASSERT_NEAR(wrapd(t2 - 2.0 * th), 0.0, 2e-4);
  }
}

static void test_check_theorem1(void **state) {
  (void)state;
  dfc_cfg_t c = {DFC_IVD, 0.05f, 0.0249f, 0.0f, 0.0f, 1u};
  assert_int_equal(dfc_check(&c), DFC_OK);
  c.b = 0.025f; /* p = 1/2 */
  assert_int_equal(dfc_check(&c), DFC_ERR_P);
  c.b = -0.03f;
  assert_int_equal(dfc_check(&c), DFC_ERR_P);
  c.method = DFC_FULL_IVD;
  assert_int_equal(dfc_check(&c), DFC_ERR_P);
  c.method = DFC_STANDARD; /* no iteration: no convergence condition */
  assert_int_equal(dfc_check(&c), DFC_OK);
  c.a = 0.0f;
  assert_int_equal(dfc_check(&c), DFC_ERR_A);
  c.a = NAN;
  assert_int_equal(dfc_check(&c), DFC_ERR_A);
  c = (dfc_cfg_t){DFC_IVD, 0.05f, 0.0f, 0.0f, 0.0f, DFC_ITER_MAX + 1u};
  assert_int_equal(dfc_check(&c), DFC_ERR_ITER);
  c.iterations = 1u;
  c.phi_a = 1.5f;
  assert_int_equal(dfc_check(&c), DFC_ERR_PHI);
  c.phi_a = 0.0f;
  c.method = (dfc_method_t)7;
  assert_int_equal(dfc_check(&c), DFC_ERR_METHOD);
  assert_non_null(strstr(dfc_strerror(DFC_ERR_P), "1/2"));
}

static void test_signals(void **state) {
  (void)state;
  dfc_signals_t s;
  dfc_signals_reset(&s);
  /* the virtual star point steps by v_dc / 3: a step of 9 V on 24 V */
  assert_true(dfc_signals_push(&s, 1u, -12.0f, -3.0f, 24.0f, 0.0f));
  ASSERT_NEAR(s.g[0], 9.0 / 24.0 - 1.0 / 3.0, 1e-7);
  assert_false(dfc_signals_complete(&s));
  assert_false(dfc_signals_push(&s, 2u, 0.0f, 1.0f, 24.0f, 0.0f)); /* v2: no component */
  assert_false(dfc_signals_push(&s, 3u, NAN, 1.0f, 24.0f, 0.0f));
  assert_false(dfc_signals_push(&s, 3u, 0.0f, 1.0f, 0.0f, 0.0f));
  assert_true(dfc_signals_push(&s, 3u, 0.0f, 8.0f, 24.0f, 1.0f));
  assert_true(dfc_signals_push(&s, 5u, 0.0f, 8.0f, 24.0f, 2.0f));
  assert_true(dfc_signals_complete(&s));
  assert_int_equal(s.last, 2);
  /* no anisotropy (every step v_dc / 3): no direction, reported */
  assert_true(dfc_signals_push(&s, 1u, -12.0f, -4.0f, 24.0f, 3.0f));
  const dfc_cfg_t c = {DFC_IVD, 0.05f, 0.0f, 0.0f, 0.0f, 1u};
  float c2 = 0.0f, s2 = 1.0f;
  dfc_vec_t v;
  dfc_signals_vector(&s, 0.0f, &v);
  assert_false(dfc_vector2(&c, s.g, &v, 0.0f, &c2, &s2, NULL));
  ASSERT_NEAR(c2, 1.0, 0.0);
  ASSERT_NEAR(s2, 0.0, 0.0);
}

/* Sequentiality: the components taken at three rotor angles. The plain
 * Clarke vector is off by a pattern of the order of 2 omega Ts; the
 * compensated vector with the IVD's K is within 1e-4 rad. */
static void test_sequentiality_compensation(void **state) {
  (void)state;
  const double a = 0.05, b = -0.0047, ts = 62.5e-6;
  const double we = 8.0 * 1000.0 * T_PI / 30.0;                      /* 1000 rpm, 8 pole pairs */
  const dfc_cfg_t c = {DFC_IVD, (float)a, (float)b, 0.0f, 0.0f, 6u}; /* IVD residual < 1e-5 */
  double worst_c = 0.0, worst_p = 0.0;
  for (int i = 0; i < 600; ++i) {
    dfc_signals_t s;
    dfc_signals_reset(&s);
    const double th0 = 2.0 * T_PI * i / 600.0;
    const int first = i % 3;
    double th = th0;
    for (int n = 0; n < 3; ++n) { /* components in the order first, first+1, .. */
      const int x = (first + n) % 3;
      th = th0 + we * ts * n;
      float g[3];
      model_g(a, b, th, 0.0, 0.0, g);
      const float vb = -12.0f, va = vb + 24.0f * (g[x] + 1.0f / 3.0f);
      assert_true(dfc_signals_push(&s, (uint8_t)(2 * x + 1), vb, va, 24.0f, (float)(ts * n)));
    }
    dfc_vec_t v;
    float c2, s2;
    dfc_signals_vector(&s, (float)(2.0 * we), &v);
    assert_true(dfc_vector2(&c, s.g, &v, 0.0f, &c2, &s2, NULL));
    const double ec = fabs(wrapd(atan2((double)s2, (double)c2) - 2.0 * th));
    dfc_vec_plain(s.g, &v);
    assert_true(dfc_vector2(&c, s.g, &v, 0.0f, &c2, &s2, NULL));
    const double ep = fabs(wrapd(atan2((double)s2, (double)c2) - 2.0 * th));
    worst_c = ec > worst_c ? ec : worst_c;
    worst_p = ep > worst_p ? ep : worst_p;
  }
  ASSERT_IN(worst_c, 0.0, 1e-4);
  ASSERT_IN(worst_p, 0.05, 1.0); /* without it: the newest instant is missed */
}

/* The inverse DFC at speed: the components at three rotor angles of a
 * diagonal matrix (where (3.15) is exact at standstill). On the raw held
 * components its 2theta lags by about 2 omega Ts (their mean age: one
 * period); on the compensated ones (v) it is at the newest instant. */
static void test_inverse_dfc_sequentiality(void **state) {
  (void)state;
  const double l0 = 400e-6, l2 = 60e-6, ts = 62.5e-6;
  const double we = 8.0 * 1000.0 * T_PI / 30.0; /* 1000 rpm, 8 pole pairs */
  const dfc_cfg_t c = {DFC_INVERSE, 0.05f, 0.0f, 0.0f, 0.0f, 0u};
  double sum_c = 0.0, sum_p = 0.0, worst_c = 0.0;
  const int n_th = 600;
  for (int i = 0; i < n_th; ++i) {
    dfc_signals_t s;
    dfc_signals_reset(&s);
    const double th0 = 2.0 * T_PI * i / n_th;
    const int first = i % 3;
    double th = th0;
    for (int n = 0; n < 3; ++n) {
      const int x = (first + n) % 3;
      th = th0 + we * ts * n;
      double l[3], sx[3], sum = 0.0;
      for (int y = 0; y < 3; ++y) {
        l[y] = l0 + l2 * cos(2.0 * th + y * 2.0 * T_PI / 3.0);
      }
      for (int y = 0; y < 3; ++y) {
        sx[y] = l[(y + 1) % 3] * l[(y + 2) % 3];
        sum += sx[y];
      }
      const float g = (float)(sx[x] / sum - 1.0 / 3.0);
      const float vb = -12.0f, va = vb + 24.0f * (g + 1.0f / 3.0f);
      assert_true(dfc_signals_push(&s, (uint8_t)(2 * x + 1), vb, va, 24.0f, (float)(ts * n)));
    }
    dfc_vec_t v;
    float c2, s2;
    dfc_signals_vector(&s, (float)(2.0 * we), &v);
    assert_true(dfc_vector2(&c, s.g, &v, 0.0f, &c2, &s2, NULL));
    const double ec = wrapd(atan2((double)s2, (double)c2) - 2.0 * th);
    dfc_vec_plain(s.g, &v);
    assert_true(dfc_vector2(&c, s.g, &v, 0.0f, &c2, &s2, NULL));
    const double ep = wrapd(atan2((double)s2, (double)c2) - 2.0 * th);
    sum_c += ec;
    sum_p += ep;
    worst_c = fabs(ec) > worst_c ? fabs(ec) : worst_c;
  }
  const double lag = 2.0 * we * ts; /* 2theta over the mean age, one period */
  printf("inverse DFC at %.0f rad/s: mean 2theta error %.5f rad compensated (worst %.5f), "
         "%.5f rad raw (2 w ts = %.5f)\n",
         we, sum_c / n_th, worst_c, sum_p / n_th, lag);
  ASSERT_IN(sum_c / n_th, -0.05 * lag, 0.05 * lag);
  ASSERT_IN(sum_p / n_th, -1.2 * lag, -0.8 * lag); /* the raw components' lag */
}

static void test_window_pattern(void **state) {
  (void)state;
  float lo, hi;
  const float t0 = 0.024f, tw = 0.048f;
  dfc_window_range(t0, tw, 0.01f, 0.98f, &lo, &hi);
  ASSERT_NEAR(lo, 0.5f - t0, 1e-7);
  ASSERT_NEAR(hi, 1.0f - t0 - tw, 1e-7);
  const float d[3][3] = {{0.7f, 0.7f, 0.7f}, {hi, lo, 0.6f}, {lo, hi, 0.8f}};
  for (int n = 0; n < 3; ++n) {
    for (unsigned leg = 0; leg < 3u; ++leg) {
      float on[3], off[3];
      dfc_window_pattern(d[n], leg, t0, tw, on, off);
      for (unsigned x = 0; x < 3u; ++x) {
        ASSERT_NEAR(off[x] - on[x], d[n][x], 1e-6); /* width (volt-seconds) kept */
        ASSERT_IN(on[x], 0.0, 0.5);                 /* rising edge in the first half */
        ASSERT_IN(off[x], 0.5, 1.0 + 1e-6);         /* falling edge in the second */
        if (x == leg) {
          ASSERT_NEAR(on[x], t0, 0.0);     /* the test vector from t0 */
          ASSERT_IN(off[x], t0 + tw, 1.0); /* ... over the whole window */
        } else {
          ASSERT_NEAR(on[x], t0 + tw, 1e-7); /* the others when it closes */
        }
      }
    }
  }
}

/* The moments of dfc_window_moments against the ripple itself: phase
 * currents of three pulses on an inductance (no resistance, no back-EMF),
 * integrated finely; the period average less half the period's change less
 * the valley value is (v_dc Ts / L) m_x (dfc_window.h). Centred pulses
 * give 0. */
static void test_window_moments_are_the_ripple(void **state) {
  (void)state;
  const double vdc = 24.0, ts = 62.5e-6, l = 434e-6;
  const float d[3] = {0.78f, 0.62f, 0.70f}, t0 = 0.024f, tw = 0.048f;
  double worst = 0.0;
  for (int leg = -1; leg < 3; ++leg) {
    float on[3], off[3], m[3];
    if (leg < 0) { /* centred */
      for (int x = 0; x < 3; ++x) {
        on[x] = 0.5f * (1.0f - d[x]);
        off[x] = 0.5f * (1.0f + d[x]);
      }
    } else {
      dfc_window_pattern(d, (unsigned)leg, t0, tw, on, off);
    }
    dfc_window_moments(on, off, m);
    enum { N = 20000 };
    double i[3] = {0.0, 0.0, 0.0}, sum[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < N; ++k) {
      const double t = (k + 0.5) / N;
      double p[3], mean = 0.0;
      for (int x = 0; x < 3; ++x) {
        p[x] = (t >= (double)on[x] && t < (double)off[x]) ? 1.0 : 0.0;
        mean += p[x] / 3.0;
      }
      for (int x = 0; x < 3; ++x) { /* midpoint rule: exact for the ramps */
        const double di = vdc * (p[x] - mean) * ts / N / l;
        sum[x] += i[x] + 0.5 * di;
        i[x] += di;
      }
    }
    for (int x = 0; x < 3; ++x) {
      const double dev = sum[x] / N - 0.5 * i[x]; /* average - change / 2 - i(0) */
      const double e = fabs(dev - vdc * ts / l * (double)m[x]);
      worst = e > worst ? e : worst;
    }
  }
  ASSERT_IN(worst, 0.0, 1e-5); /* A */
}

/* dfc_ivd_from (the warm start of ivd+kf+rls): from the raw estimate it is
 * dfc_vector2's iteration, step by step; from the true angle with the true
 * p it stays there (the fixed point); from a start off by e one step
 * leaves at most 2|p| e (Theorem 1, (3.81): the linearised step is
 * -2p e cos 6theta) plus the second-order term; other methods refused. */
static void test_ivd_from_a_start(void **state) {
  (void)state;
  const double ps[] = {-0.45, -0.35, -0.0932, 0.15, 0.35, 0.45};
  const double a = 0.05, e = 0.05; /* rad on 2 theta */
  double worst_same = 0.0, worst_fix = 0.0, worst_ratio = 0.0;
  for (size_t ip = 0; ip < sizeof ps / sizeof ps[0]; ++ip) {
    dfc_cfg_t c = {DFC_IVD, (float)a, (float)(ps[ip] * a), 0.0f, 0.0f, DFC_ITER_MAX};
    for (int i = 0; i < 720; ++i) {
      const double th = -T_PI + 2.0 * T_PI * i / 720.0;
      float g[3], tr[2 * (DFC_ITER_MAX + 1u)], tr2[2 * (DFC_ITER_MAX + 1u)], c2, s2;
      model_g(a, ps[ip] * a, th, 0.0, 0.0, g);
      dfc_vec_t v;
      dfc_vec_plain(g, &v);
      assert_true(dfc_vector2(&c, g, &v, 0.0f, &c2, &s2, tr));
      float u0c = tr[0], u0s = tr[1];
      assert_true(dfc_ivd_from(&c, &v, 0.0f, &u0c, &u0s, tr2));
      for (unsigned k = 1; k <= DFC_ITER_MAX; ++k) {
        const double d = fabs(wrapd(atan2((double)tr2[2 * k + 1], (double)tr2[2 * k]) -
                                    atan2((double)tr[2 * k + 1], (double)tr[2 * k])));
        worst_same = d > worst_same ? d : worst_same;
      }
      c.iterations = 1u;
      float wc = (float)cos(2.0 * th), ws = (float)sin(2.0 * th);
      assert_true(dfc_ivd_from(&c, &v, 0.0f, &wc, &ws, NULL));
      const double f = fabs(wrapd(atan2((double)ws, (double)wc) - 2.0 * th));
      worst_fix = f > worst_fix ? f : worst_fix;
      wc = (float)cos(2.0 * th + e);
      ws = (float)sin(2.0 * th + e);
      assert_true(dfc_ivd_from(&c, &v, 0.0f, &wc, &ws, NULL));
      const double r = fabs(wrapd(atan2((double)ws, (double)wc) - 2.0 * th)) /
                       (2.0 * fabs(ps[ip]) * e * (1.0 + 2.0 * e));
      worst_ratio = r > worst_ratio ? r : worst_ratio;
      c.iterations = DFC_ITER_MAX;
    }
  }
  ASSERT_IN(worst_same, 0.0, 1e-6);
  ASSERT_IN(worst_fix, 0.0, 2e-6);
  ASSERT_IN(worst_ratio, 0.5, 1.0); /* reached at cos 6theta = +-1 */
  const dfc_cfg_t std = {DFC_STANDARD, 0.05f, 0.0f, 0.0f, 0.0f, 1u};
  dfc_vec_t v;
  const float g[3] = {0.01f, -0.005f, -0.005f};
  dfc_vec_plain(g, &v);
  float wc = 1.0f, ws = 0.0f;
  assert_false(dfc_ivd_from(&std, &v, 0.0f, &wc, &ws, NULL));
  ASSERT_NEAR((double)wc, 1.0, 0.0);
  ASSERT_NEAR((double)ws, 0.0, 0.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ivd_equals_the_printed_iteration),
      cmocka_unit_test(test_ivd_from_a_start),
      cmocka_unit_test(test_standard_dfc_error_is_3_13),
      cmocka_unit_test(test_inverse_dfc_exact_for_a_diagonal_matrix),
      cmocka_unit_test(test_inverse_dfc_sequentiality),
      cmocka_unit_test(test_check_theorem1),
      cmocka_unit_test(test_signals),
      cmocka_unit_test(test_sequentiality_compensation),
      cmocka_unit_test(test_window_pattern),
      cmocka_unit_test(test_window_moments_are_the_ripple),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
