/*
 * SIL: FOC on the saturated 1.1 kW SyR machine `syr_1k1` (Varatharajan
 * 2022 Table I: p = 2, 2.3 A rms, 7.1 N m, 1500 rpm, J = 0.04 kg m^2)
 * through its flux map, plant and drive on the same blob.
 *  1. Rated torque at rated current: torque mode, T* = 7.1 N m (the
 *     paper's rating), i_max = the rated 2.3 sqrt(2) A: the plant's torque
 *     and current amplitude within 3 % of the rating (both sides).
 *  2. The scenario sil/scenarios/syr_1k1_speed_load.json: speed step to
 *     1500 rpm, rated load step; no fault, the speed within 1 % of the
 *     reference before and after the step, the load met; the position
 *     check's residual over its tolerance below 0.5 over the whole run
 *     (on the one-period check before issue 24 point 8 it was over 1 for
 *     7 checks in a row at the end of the ramp, 8 trip).
 *  3. The current loop keeps its design bandwidth on the saturated map:
 *     small d and q steps at a light and at the rated operating point reach
 *     63 % of the step after 1/current_bw plus the loop's delay (1.5 Ts),
 *     +-25 %. The incremental inductance at rated current is a quarter of
 *     the unsaturated one: constant gains would make the loop up to 4x
 *     faster there, gains from the wrong axis up to 7x slower.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "sil_test_util.h"

/* lo <= x <= hi, the values printed on failure */
#define ASSERT_IN(x, lo, hi)                                                                       \
  do {                                                                                             \
    const double x_ = (x), l_ = (lo), h_ = (hi);                                                   \
    if (!(x_ >= l_ && x_ <= h_)) {                                                                 \
      fail_msg("%s = %.6g not in [%.6g, %.6g]", #x, x_, l_, h_);                                   \
    }                                                                                              \
  } while (0)

#define RPM     (3.14159265358979 / 30.0)
#define T_RATED 7.1
#define I_RATED (2.3 * 1.4142135623730951)
#define W_RATED (1500.0 * RPM)

static const char *rated_json =
    "{\"name\": \"syr rated torque\", \"duration\": 0.4,"
    " \"machine\": {\"preset\": \"syr_1k1\"},"
    " \"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\", \"terms\": [{\"type\": "
    "\"const\", \"value\": 300}]}},"
    " \"sensors\": {\"i_noise\": 0.002, \"encoder_cpr\": 4096},"
    " \"controller\": {\"law\": \"foc\", \"mode\": \"torque\", \"i_max\": 3.2526912,"
    " \"torque_max\": 7.1},"
    " \"references\": {\"torque\": [{\"type\": \"step\", \"t\": 0.05, \"value\": 7.1}]}}";

static void rated_torque_at_rated_current(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(rated_json, &sc, &tr, &res);
  double t = 0.0, i = 0.0;
  const size_t k0 = idx_at(&tr, 0.3);
  for (size_t k = k0; k < tr.n; ++k) {
    t += tr.torque[k];
    i += hypot(tr.id[k], tr.iq[k]);
  }
  t /= (double)(tr.n - k0);
  i /= (double)(tr.n - k0);
  printf("syr_1k1 FOC, T* = %.2f N m: torque %.4f N m (%+.2f %%), current %.4f A (%+.2f %% of the "
         "rated %.4f A peak)\n",
         T_RATED, t, 100.0 * (t / T_RATED - 1.0), i, 100.0 * (i / I_RATED - 1.0), I_RATED);
  ASSERT_IN(t, 0.97 * T_RATED, 1.03 * T_RATED);
  ASSERT_IN(i, 0.97 * I_RATED, 1.03 * I_RATED);
  assert_int_equal(res.faults, 0);
  trace_free(&tr);
}

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  static char buf[16384];
  const size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = '\0';
  return buf;
}

static void speed_step_and_rated_load(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json(read_text(FD_SYR_SCENARIO), &sc, &tr, &res);
  const double t_load = 1.8;
  /* before the load step: at 1500 rpm within 1 % */
  double err_pre = 0.0;
  for (size_t k = idx_at(&tr, 1.6); k < idx_at(&tr, t_load); ++k) {
    err_pre = fmax(err_pre, fabs(tr.speed[k] - W_RATED) / W_RATED);
  }
  /* after it: the dip, then back within 1 % and the load met */
  double dip = 0.0, t_mean = 0.0, i_max = 0.0;
  size_t k_rec = 0;
  for (size_t k = idx_at(&tr, t_load); k < tr.n; ++k) {
    dip = fmax(dip, (W_RATED - tr.speed[k]) / W_RATED);
    if (fabs(tr.speed[k] - W_RATED) > 0.01 * W_RATED) {
      k_rec = k + 1;
    }
    i_max = fmax(i_max, hypot(tr.id[k], tr.iq[k]));
  }
  const size_t k1 = idx_at(&tr, 2.4);
  for (size_t k = k1; k < tr.n; ++k) {
    t_mean += tr.torque[k];
  }
  t_mean /= (double)(tr.n - k1);
  const double t_rec = tr.t[k_rec < tr.n ? k_rec : tr.n - 1] - t_load;
  printf("syr_1k1 speed/load: speed error before the step %.3f %%, dip %.2f %%, back within 1 %% "
         "after %.3f s, torque %.3f N m (load %.1f + friction %.3f), peak current %.3f A\n",
         100.0 * err_pre, 100.0 * dip, t_rec, t_mean, T_RATED, sc.plant.mech.b * W_RATED, i_max);
  assert_true(err_pre < 0.01);
  assert_true(dip > 0.0 && dip < 0.10);
  assert_true(t_rec < 0.5);
  /* the electromagnetic torque meets the load and the friction (b w) */
  const double t_need = T_RATED + sc.plant.mech.b * W_RATED;
  ASSERT_IN(t_mean, 0.99 * t_need, 1.01 * t_need);
  assert_true(i_max <= 1.5 * I_RATED * 1.001); /* the scenario's 50 % overload limit */
  /* the position check: its largest residual / tolerance and the longest
   * run of checks over 1 (the leaky count it trips at 8) */
  double res_max = 0.0, t_res = 0.0;
  int over = 0, over_max = 0;
  for (size_t k = 1; k < tr.n; ++k) {
    if (tr.pos_res[k] != tr.pos_res[k - 1]) { /* a check */
      over = tr.pos_res[k] > 1.0 ? over + 1 : (over > 0 ? over - 1 : 0);
      over_max = over > over_max ? over : over_max;
    }
    if (tr.pos_res[k] > res_max) {
      res_max = tr.pos_res[k];
      t_res = tr.t[k];
    }
  }
  printf("syr_1k1 speed/load: position check residual / tolerance at most %.3f (at %.3f s), "
         "leaky count at most %d of the 8 that trip\n",
         res_max, t_res, over_max);
  assert_true(res_max < 0.5);
  assert_int_equal(res.faults, 0);
  trace_free(&tr);
}

/* Time from t0 until x crosses 63 % of its step from x0 to x1. */
static double t63(const trace_t *tr, const double *x, double t0, double x0, double x1) {
  const double lvl = x0 + 0.632 * (x1 - x0);
  for (size_t k = idx_at(tr, t0); k < tr->n; ++k) {
    if ((x1 > x0 && x[k] >= lvl) || (x1 < x0 && x[k] <= lvl)) {
      return tr->t[k] - t0;
    }
  }
  return 1e9;
}

static void current_loop_bandwidth(void **state) {
  (void)state;
  /* operating points (i_d, i_q): light load, rated MTPA */
  const double op[2][2] = {{-0.6, 0.4}, {-2.8, 1.66}};
  const double bw = 2000.0, ts = 62.5e-6, expect = 1.0 / bw + 1.5 * ts, step = 0.1;
  for (int n = 0; n < 2; ++n) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"name\": \"syr current steps\", \"duration\": 0.08,"
             " \"machine\": {\"preset\": \"syr_1k1\"}, \"dc_link\": {\"voltage\": 650},"
             " \"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": \"rpm\","
             " \"terms\": [{\"type\": \"const\", \"value\": 300}]}},"
             " \"sensors\": {\"v_full_scale\": 1000, \"encoder_cpr\": 4096},"
             " \"controller\": {\"law\": \"foc\", \"mode\": \"current\", \"current_bw\": %g,"
             " \"v_dc_max\": 800, \"i_max\": 4.879},"
             " \"references\": {\"id\": [{\"type\": \"const\", \"value\": %g},"
             " {\"type\": \"step\", \"t\": 0.06, \"value\": %g}],"
             " \"iq\": [{\"type\": \"const\", \"value\": %g},"
             " {\"type\": \"step\", \"t\": 0.04, \"value\": %g}]}}",
             bw, op[n][0], -step, op[n][1], step);
    scenario_t sc;
    trace_t tr;
    sil_result_t res;
    run_json(json, &sc, &tr, &res);
    const size_t kq = idx_at(&tr, 0.04), kd = idx_at(&tr, 0.06);
    const double tq = t63(&tr, tr.iq, 0.04, tr.iq[kq - 1], op[n][1] + step);
    const double td = t63(&tr, tr.id, 0.06, tr.id[kd - 1], op[n][0] - step);
    printf("syr_1k1 current loop at (%.2f, %.2f) A: 63 %% of a %.1f A step after %.3f ms (q), "
           "%.3f ms (d); design 1/bw + 1.5 Ts = %.3f ms\n",
           op[n][0], op[n][1], step, 1e3 * tq, 1e3 * td, 1e3 * expect);
    ASSERT_IN(tq, 0.75 * expect, 1.25 * expect);
    ASSERT_IN(td, 0.75 * expect, 1.25 * expect);
    assert_int_equal(res.faults, 0);
    trace_free(&tr);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(rated_torque_at_rated_current),
                                     cmocka_unit_test(speed_step_and_rated_load),
                                     cmocka_unit_test(current_loop_bandwidth)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
