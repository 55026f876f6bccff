/*
 * test_speed_ctrl.c - speed PI with slew-limited reference and torque
 * limits, closed around J dw/dt = T - T_load (exact integration over each
 * period; the torque computed at k is applied over [k+1, k+2) as with the
 * real drive). Speed loop Ts = 1 ms, rotor J = 0.021 kg m^2.
 */
#include "core_test_util.h"

#include "control/speed_ctrl.h"

#define TS  1e-3
#define J   0.021
#define RPM (2.0 * T_PI / 60.0)

typedef struct {
  double w;
  double t_pending; /* torque applied over the current period */
} rotor_t;

/* one period: the pending torque acts, the new command becomes pending */
static void rotor_step(rotor_t *r, double t_cmd, double t_load) {
  r->w += (r->t_pending - t_load) / J * TS;
  r->t_pending = t_cmd;
}

static speed_ctrl_t make(double wb, double accel, double tmax) {
  speed_ctrl_cfg_t cfg = {0.0f, 0.0f, (float)TS, (float)accel, (float)tmax, 0.0f};
  speed_ctrl_design(&cfg, (float)J, (float)wb);
  speed_ctrl_t sc;
  speed_ctrl_init(&sc, &cfg);
  return sc;
}

static void test_design(void **state) {
  (void)state;
  speed_ctrl_cfg_t cfg = {0.0f, 0.0f, (float)TS, 1.0f, 1.0f, 0.0f};
  speed_ctrl_design(&cfg, 0.021f, 100.0f);
  ASSERT_NEAR(cfg.kp, 2.1, 1e-6);      /* J wb */
  ASSERT_NEAR(cfg.ki, 52.5, 1e-4);     /* kp wb / 4 */
  ASSERT_NEAR(cfg.ts, (float)TS, 0.0); /* untouched */
}

/* The ramped reference moves by exactly accel_max * Ts per call and stops on the target. */
static void test_slew_exact(void **state) {
  (void)state;
  speed_ctrl_t sc = make(100.0, 125.0, 20.0);
  for (int k = 1; k <= 120; k++) {
    (void)speed_ctrl_update(&sc, 10.0f, 0.0f, -20.0f, 20.0f);
    ASSERT_NEAR(sc.w_ref_ramped, fmin(10.0, 0.125 * k), 2e-5);
  }
  ASSERT_NEAR(sc.w_ref_ramped, 10.0f, 0.0);
  for (int k = 1; k <= 40; k++) {
    (void)speed_ctrl_update(&sc, -10.0f, 0.0f, -20.0f, 20.0f);
    ASSERT_NEAR(sc.w_ref_ramped, 10.0 - 0.125 * k, 2e-5);
  }
  (void)speed_ctrl_update(&sc, NAN, 0.0f, -20.0f, 20.0f); /* NaN reference: hold */
  ASSERT_NEAR(sc.w_ref_ramped, 5.0, 2e-5);
}

/* Load step of 5 N m at 1000 rpm: zero steady-state speed error, torque = load. */
static void test_load_rejection(void **state) {
  (void)state;
  speed_ctrl_t sc = make(100.0, 1e6, 20.0);
  const float w_ref = (float)(1000.0 * RPM);
  rotor_t r = {w_ref, 0.0};
  speed_ctrl_reset(&sc, w_ref, 0.0f);
  double dip = 0.0, t = 0.0;
  for (int k = 0; k < 3000; k++) {
    t = speed_ctrl_update(&sc, w_ref, (float)r.w, -20.0f, 20.0f);
    rotor_step(&r, t, k >= 100 ? 5.0 : 0.0);
    dip = fmax(dip, w_ref - r.w);
  }
  printf("  load step 5 N m: dip %.3f rad/s, final error %.2e rad/s, torque %.5f\n", dip,
         w_ref - r.w, t);
  ASSERT_NEAR(r.w, w_ref, 1e-3);
  ASSERT_NEAR(t, 5.0, 1e-3);
  /* with the double closed-loop pole at wb/2, the dip is ~ 2 T_L/(e J wb) = 1.75 rad/s */
  ASSERT_IN(dip, 1.0, 3.0);
}

/* Dynamic torque limits are obeyed every call and clamped to +-torque_max. */
static void test_torque_limits(void **state) {
  (void)state;
  speed_ctrl_t sc = make(100.0, 1e6, 20.0);
  rotor_t r = {0.0, 0.0};
  for (int k = 0; k < 2000; k++) {
    const float tmax = (k < 1000) ? 3.0f : 50.0f; /* 50 is above torque_max */
    const float tmin = (k < 1000) ? -1.0f : -50.0f;
    const float w_ref = (k % 500 < 250) ? 300.0f : -300.0f;
    const float t = speed_ctrl_update(&sc, w_ref, (float)r.w, tmin, tmax);
    ASSERT_IN(t, (k < 1000) ? -1.0 : -20.0, (k < 1000) ? 3.0 : 20.0);
    rotor_step(&r, t, 0.0);
  }
  /* NaN limits fall back to the static limit */
  const float t = speed_ctrl_update(&sc, 1e4f, 0.0f, NAN, NAN);
  ASSERT_NEAR(t, 20.0, 0.0);
}

typedef struct {
  double overshoot_rel;
  double t_sat; /* time spent on the torque limit [s] */
} accel_run_t;

/* 0 -> 1200 rpm. naive = 1: a textbook PI with output clamp only (for contrast). */
static accel_run_t accel_run(double wb, double accel, double tmax, int naive) {
  speed_ctrl_t sc = make(wb, accel, tmax);
  const double w_ref = 1200.0 * RPM;
  rotor_t r = {0.0, 0.0};
  double integ = 0.0, w_max = 0.0;
  accel_run_t a = {0.0, 0.0};
  for (int k = 0; k < 5000; k++) {
    double t;
    if (naive) {
      const double e = w_ref - r.w;
      integ += sc.cfg.ki * TS * e;
      t = fmin(tmax, fmax(-tmax, sc.cfg.kp * e + integ));
    } else {
      t = speed_ctrl_update(&sc, (float)w_ref, (float)r.w, (float)-tmax, (float)tmax);
      ASSERT_IN(t, -tmax, tmax);
    }
    if (fabs(t) >= tmax - 1e-6) {
      a.t_sat += TS;
    }
    rotor_step(&r, t, 0.0);
    w_max = fmax(w_max, r.w);
  }
  ASSERT_NEAR(r.w, w_ref, 1e-3 * w_ref);
  a.overshoot_rel = w_max / w_ref - 1.0;
  return a;
}

/* Rubino 2020 Fig. 18 set-up: J = 0.021, 20 N m, 1200 rpm/s ramp to 1200 rpm.
 * With the ramp the loop tracks with zero ramp error (type 2); when the ramp
 * stops the stored J*a torque gives a peak of 2a/(e wb) = 0.92 rad/s
 * (0.74 %) for wb = 100 rad/s. Bound: 2 %. */
static void test_fig18_ramp(void **state) {
  (void)state;
  const accel_run_t a = accel_run(100.0, 1200.0 * RPM, 20.0, 0);
  printf("  ramp 1200 rpm/s: overshoot %.3f %%\n", 100.0 * a.overshoot_rel);
  assert_true(a.overshoot_rel < 0.02);
}

/* Same rotor, unlimited slew: the torque sits on 20 N m for ~0.13 s. With
 * anti-windup the overshoot stays < 2 %; the naive clamp-only PI overshoots
 * by > 10 % (its integral keeps growing while saturated). */
static void test_saturated_accel_no_windup(void **state) {
  (void)state;
  const accel_run_t a = accel_run(100.0, 1e6, 20.0, 0);
  const accel_run_t n = accel_run(100.0, 1e6, 20.0, 1);
  printf("  step, 20 N m: overshoot %.3f %% (saturated %.3f s); naive PI %.2f %%\n",
         100.0 * a.overshoot_rel, a.t_sat, 100.0 * n.overshoot_rel);
  assert_true(a.t_sat > 0.08); /* the limit really was active */
  assert_true(a.overshoot_rel < 0.02);
  assert_true(n.overshoot_rel > 0.10);
}

/* Bumpless: after reset the first output equals the torque in force and
 * the ramp starts from the measured speed. */
static void test_bumpless_reset(void **state) {
  (void)state;
  speed_ctrl_t sc = make(100.0, 100.0, 20.0);
  speed_ctrl_reset(&sc, 50.0f, 4.2f);
  ASSERT_NEAR(speed_ctrl_update(&sc, 50.0f, 50.0f, -20.0f, 20.0f), 4.2f, 0.0);
  (void)speed_ctrl_update(&sc, 60.0f, 50.0f, -20.0f, 20.0f);
  ASSERT_NEAR(sc.w_ref_ramped, 50.1, 1e-5);
  speed_ctrl_reset(&sc, NAN, 99.0f); /* torque beyond the limit is clamped */
  ASSERT_NEAR(sc.w_ref_ramped, 0.0, 0.0);
  ASSERT_NEAR(sc.pi.integ, 20.0, 0.0);
}

/* A live retune (speed_ctrl_retune): new gains, |torque_max|, the
 * feed-forward's 1 / ts; the integral and the ramp carry on. */
static void test_retune_keeps_state(void **state) {
  (void)state;
  speed_ctrl_t sc = make(100.0, 100.0, 20.0);
  speed_ctrl_reset(&sc, 50.0f, 4.2f);
  (void)speed_ctrl_update(&sc, 60.0f, 50.0f, -20.0f, 20.0f);
  const float integ = sc.pi.integ;
  const float ramp = sc.w_ref_ramped;
  speed_ctrl_cfg_t cfg = {0.0f, 0.0f, (float)(2.0 * TS), 100.0f, -15.0f, (float)J};
  speed_ctrl_design(&cfg, (float)J, 50.0f);
  speed_ctrl_retune(&sc, &cfg);
  ASSERT_NEAR(sc.pi.integ, integ, 0.0);
  ASSERT_NEAR(sc.w_ref_ramped, ramp, 0.0);
  ASSERT_NEAR(sc.cfg.torque_max, 15.0, 0.0);
  ASSERT_NEAR(sc.pi.kp, cfg.kp, 0.0);
  ASSERT_NEAR(sc.pi.ki, cfg.ki, 0.0);
  ASSERT_NEAR(sc.inv_ts, 1.0 / (2.0 * TS), 1e-3);
  /* on the ramp (100 rad/s^2 over 2 ms: 0.2 rad/s a call) at zero speed
   * error the output is the integral plus J times the ramp's acceleration */
  const float w = sc.w_ref_ramped + 0.2f;
  const float t = speed_ctrl_update(&sc, 1e3f, w, -15.0f, 15.0f);
  ASSERT_NEAR(t, integ + J * 100.0, 1e-3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_design),         cmocka_unit_test(test_slew_exact),
      cmocka_unit_test(test_load_rejection), cmocka_unit_test(test_torque_limits),
      cmocka_unit_test(test_fig18_ramp),     cmocka_unit_test(test_saturated_accel_no_windup),
      cmocka_unit_test(test_bumpless_reset), cmocka_unit_test(test_retune_keeps_state),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
