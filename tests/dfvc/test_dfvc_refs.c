/*
 * test_dfvc_refs.c - references of Rubino 2020, Fig. 5, eqs. (22)-(26):
 * MTPA flux, voltage-limited flux, current and load-angle limits and the
 * torque limits, against the analytic values (double).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "control/dfvc_refs.h"

#define RS   7.1
#define LS   0.057
#define LM   0.19
#define P    21.0
#define IMAX 3.5355339
#define DMAX (80.0 * 0.017453292519943295)

static machine_t machine; /* the references hold a pointer to it */

static dfvc_refs_t make(void) {
  dfvc_refs_t r;
  assert_int_equal(
      machine_init_linear(&machine, (float)P, (float)RS, (float)LS, (float)LS, (float)LM), 0);
  const dfvc_refs_cfg_t cfg = {&machine, (float)IMAX, (float)DMAX, (float)(0.2 * LM), 0.95f};
  assert_int_equal(dfvc_refs_init(&r, &cfg), 0);
  return r;
}

static void near_rel(double got, double want, double rel) {
  if (fabs(got - want) > rel * fabs(want) + 1e-9) {
    fail_msg("got %.9g want %.9g", got, want);
  }
}

static double w_of_rpm(double rpm) {
  return rpm / 60.0 * 6.283185307179586 * P;
}

/* Hand values (Python): 0.19, 0.21253304398276637 (10 N m),
 * 0.21696787017745833 (11), 0.26903750507749286 (20). */
static void test_mtpa(void **state) {
  (void)state;
  dfvc_refs_t r = make();
  near_rel(dfvc_refs_lambda_mtpa(&r, 0.0f), 0.19, 1e-6);
  near_rel(dfvc_refs_lambda_mtpa(&r, 10.0f), 0.21253304398276637, 1e-6);
  near_rel(dfvc_refs_lambda_mtpa(&r, -11.0f), 0.21696787017745833, 1e-6);
  near_rel(dfvc_refs_lambda_mtpa(&r, 20.0f), 0.26903750507749286, 1e-6);
  /* beyond the MTPA torque at I_max (1.5 p LM IMAX = 21.16 N m) it saturates */
  const double tmax = 1.5 * P * LM * IMAX;
  const double x = LS * tmax / (P * LM * LM);
  near_rel(dfvc_refs_lambda_mtpa(&r, 100.0f), LM * sqrt(1.0 + 4.0 / 9.0 * x * x), 1e-6);
}

static void test_voltage_limit(void **state) {
  (void)state;
  dfvc_refs_t r = make();
  const double vmax = 310.0 / sqrt(3.0) * 0.95;
  const double rpm[3] = {600.0, 1200.0, -900.0};
  const double ids = -1.2, iqs = 2.1;
  for (int n = 0; n < 3; ++n) {
    const double w = w_of_rpm(rpm[n]);
    /* eq. (23) with omega_r */
    const double want =
        (sqrt(vmax * vmax - RS * ids * RS * ids) - RS * iqs * (w < 0 ? -1 : 1)) / fabs(w);
    near_rel(dfvc_refs_lambda_vlim(&r, 310.0f / sqrtf(3.0f), (float)w, (float)ids, (float)iqs),
             want, 2e-6);
  }
  /* reference = min(MTPA, voltage) >= lambda_min */
  dfvc_refs_out_t o;
  /* currents at tau+1 = at tau, delta = 0: (25) as printed */
  dfvc_refs_in_t in = {20.0f, 0.0f, (float)w_of_rpm(100.0), 310.0f / sqrtf(3.0f),
                       0.5f,  2.0f, {0.5f, 2.0f},           {0.0f, 1.0f}};
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.lambda_ref, 0.26903750507749286, 1e-6); /* 100 rpm: MTPA */
  assert_int_equal(o.limits & (DFVC_REFS_FLUX_VLIM | DFVC_REFS_FLUX_MIN), 0);
  in.omega_r = (float)w_of_rpm(1200.0);
  dfvc_refs_update(&r, &in, &o);
  assert_true(o.limits & DFVC_REFS_FLUX_VLIM);
  near_rel(o.lambda_ref, o.lambda_vlim, 1e-7);
  /* (23) at the limited i_qs* (20 N m asks ~10 A, (26) gives 3.2827 A),
   * which exceeds i_qs(tau) = 2 A: less flux than with i_qs(tau) */
  near_rel(o.lambda_ref,
           (sqrt(vmax * vmax - RS * 0.5 * RS * 0.5) - RS * 3.282692510040693) / w_of_rpm(1200.0),
           2e-6);
  near_rel(o.iqs_ref, 3.282692510040693, 1e-6);
  /* i_qs(tau) above the reference: (23) as printed, with i_qs(tau) */
  in.i_qs = 3.4f;
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.lambda_ref, (sqrt(vmax * vmax - RS * 0.5 * RS * 0.5) - RS * 3.4) / w_of_rpm(1200.0),
           2e-6);
  /* generating (T* < 0 at w > 0): i_qs* adds voltage headroom, (23) at i_qs(tau) */
  in.i_qs = 2.0f;
  in.torque_ref = -20.0f;
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.lambda_ref, (sqrt(vmax * vmax - RS * 0.5 * RS * 0.5) - RS * 2.0) / w_of_rpm(1200.0),
           2e-6);
  in.torque_ref = 20.0f;
  in.v_lin = 40.0f / sqrtf(3.0f); /* deep: lambda_min */
  dfvc_refs_update(&r, &in, &o);
  assert_true(o.limits & DFVC_REFS_FLUX_MIN);
  near_rel(o.lambda_ref, 0.2 * LM, 1e-6);
  /* override replaces MTPA, still voltage-limited */
  in.v_lin = 310.0f / sqrtf(3.0f);
  in.lambda_override = 0.15f;
  in.omega_r = (float)w_of_rpm(100.0);
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.lambda_ref, 0.15, 1e-7);
}

static void test_iqs_limits(void **state) {
  (void)state;
  dfvc_refs_t r = make();
  dfvc_refs_out_t o;
  /* 10 N m at 100 rpm: eq. (24), no limit */
  dfvc_refs_in_t in = {10.0f, 0.0f, (float)w_of_rpm(100.0), 310.0f / sqrtf(3.0f),
                       0.7f,  1.5f, {0.7f, 1.5f},           {0.0f, 1.0f}};
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.iqs_ref, 10.0 / (1.5 * P * 0.21253304398276637), 2e-6);
  assert_int_equal(o.limits, 0);
  /* current limit (25): sqrt(IMAX^2 - i_ds^2) with i_ds(tau+1) = 3 A, delta = 0 */
  in.torque_ref = -20.0f;
  in.i_ds = 3.0f;
  in.i_dqs_next.d = 3.0f;
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.iqs_max_i, sqrt(IMAX * IMAX - 3.0 * 3.0), 2e-6);
  near_rel(o.iqs_ref, -sqrt(IMAX * IMAX - 3.0 * 3.0), 2e-6);
  assert_true(o.limits & DFVC_REFS_IQS_IMAX);
  near_rel(o.torque_max, 1.5 * P * o.lambda_ref * sqrt(IMAX * IMAX - 3.0 * 3.0), 2e-6);
  near_rel(o.torque_min, -o.torque_max, 1e-7);
  /* load-angle limit (26): LM/LS sin(80 deg) = 3.282692510040693 A */
  in.torque_ref = 20.0f;
  in.i_ds = 0.0f;
  in.i_dqs_next.d = 0.0f;
  in.omega_r = (float)w_of_rpm(1200.0);
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.iqs_max_delta, 3.282692510040693, 1e-6);
  near_rel(o.iqs_ref, 3.282692510040693, 1e-6);
  assert_true(o.limits & DFVC_REFS_IQS_DELTA);
  assert_true(o.limits & DFVC_REFS_IQS_IMAX); /* 10.5 A clipped to 3.54, then 3.28 */
  /* |i_ds| > I_max: no torque current left */
  in.i_ds = 4.0f;
  in.i_dqs_next.d = 4.0f;
  dfvc_refs_update(&r, &in, &o);
  assert_true(fabsf(o.iqs_ref) < 1e-9f && fabsf(o.torque_max) < 1e-9f);
}

/* (25) at tau+2: i_ds follows i_qs along the constant-flux line of slope
 * tan|delta(tau+1)|; the bound is where that line meets the circle I_max,
 * the same for both torque signs, with tan capped at tan(delta_max). */
static void test_iqs_limit_next(void **state) {
  (void)state;
  dfvc_refs_t r = make();
  dfvc_refs_out_t o;
  const double d1 = 60.0 * 0.017453292519943295, ids1 = 1.9, iqs1 = 2.9;
  dfvc_refs_in_t in = {
      20.0f,       0.0f,        (float)w_of_rpm(400.0),     310.0f / sqrtf(3.0f),
      (float)ids1, (float)iqs1, {(float)ids1, (float)iqs1}, {(float)sin(d1), (float)cos(d1)}};
  dfvc_refs_update(&r, &in, &o);
  const double k = tan(d1);
  const double q = o.iqs_max_i;
  /* on the circle, along the line */
  const double id2 = ids1 + k * (q - iqs1);
  near_rel(id2 * id2 + q * q, IMAX * IMAX, 2e-6);
  /* tighter than the printed (25) at i_ds(tau+1): i_ds grows with i_qs */
  assert_true(q < sqrt(IMAX * IMAX - ids1 * ids1));
  /* even in i_qs: the same bound with i_qs(tau+1) < 0 and delta < 0 */
  in.i_dqs_next.q = (float)-iqs1;
  in.sc_delta_next.s = (float)-sin(d1);
  in.torque_ref = -20.0f;
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.iqs_max_i, q, 1e-6);
  near_rel(o.iqs_ref, -fmin(q, 3.282692510040693), 1e-6);
  /* beyond delta_max (and past 90 deg) the slope is tan(delta_max) */
  in.sc_delta_next.s = 1.0f;
  in.sc_delta_next.c = 0.0f;
  in.i_dqs_next.q = (float)iqs1;
  dfvc_refs_update(&r, &in, &o);
  const double km = tan(DMAX);
  const double id3 = ids1 + km * (o.iqs_max_i - iqs1);
  near_rel(id3 * id3 + (double)o.iqs_max_i * o.iqs_max_i, IMAX * IMAX, 2e-6);
  /* i_ds(tau+1) < 0 (deep flux weakening, |i_ds| falls as i_qs grows): the
   * printed bound at i_ds(tau+1) when it is the smaller */
  in.i_dqs_next.d = -2.2f;
  in.i_dqs_next.q = 1.0f;
  in.sc_delta_next.s = (float)sin(0.33);
  in.sc_delta_next.c = (float)cos(0.33);
  dfvc_refs_update(&r, &in, &o);
  near_rel(o.iqs_max_i, sqrt(IMAX * IMAX - 2.2 * 2.2), 2e-6);
}

static void test_init_rejects_bad(void **state) {
  (void)state;
  dfvc_refs_t r;
  assert_int_equal(machine_init_linear(&machine, 21.0f, 7.1f, 0.057f, 0.057f, 0.19f), 0);
  dfvc_refs_cfg_t cfg = {&machine, 3.5f, 1.7f, 0.04f, 0.95f};
  assert_int_equal(dfvc_refs_init(&r, &cfg), -1); /* delta_max > pi/2 */
  cfg.delta_max = 1.3f;
  cfg.v_margin = 1.2f;
  assert_int_equal(dfvc_refs_init(&r, &cfg), -1);
  cfg.v_margin = 0.9f;
  assert_int_equal(dfvc_refs_init(&r, &cfg), 0);
  r.iqs_max_delta = 0.0f;
  dfvc_refs_reset(&r);
  near_rel(r.iqs_max_delta, 0.19 / 0.057 * sin(1.3), 1e-6);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mtpa),
      cmocka_unit_test(test_voltage_limit),
      cmocka_unit_test(test_iqs_limits),
      cmocka_unit_test(test_iqs_limit_next),
      cmocka_unit_test(test_init_rejects_bad),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
