/*
 * The position plausibility check as a part (protect/drive_pos_check.h),
 * without the SIL: a machine turning under the check, its applied
 * voltage summed every period (protect_pos_integrate) and checked every
 * 32nd. The machine's own voltage passes, also through a current step of
 * two periods inside the window (the loop's L di/dt, 17 times the
 * tolerance in one period: the one-period check before issue 24 point 8
 * counted it); the same voltage half a turn off trips after POS_TRIP_S
 * worth of checks (and not one check earlier), a residual just inside the
 * tolerance does not, the leaky count, the restart when it does not apply,
 * nothing in a slow period that is not one of its own; above half a turn
 * per window the derivative form passes the machine and trips half a turn
 * off.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include <cmocka.h>

#include "drive_enums.h"
#include "protect/drive_pos_check.h"

static machine_t m;

/* 4 pole pairs, 0.1 Ohm, 1 mH, 0.1 Vs; 100 rad/s electrical, i = (0, 10) A:
 * psi = (0.1, 0.01) Vs, v = R i + w J psi = (-1, 11) V in the rotor frame.
 * Ts 1/16384 s (binary-exact), 32 periods between checks: 8.192 checks'
 * worth of POS_TRIP_S, the trip at the 9th over-count. Tolerance about
 * 0.3 (11 + 1) + 0.05 * 48 = 6 V. The view's angle, current and voltage
 * are the simulated machine's (one_check). */
static protect_pos_view_t view(float dv_d) {
  const protect_pos_view_t v = {
      true, true, 100.0f, 0.0f, (dq_t){0.0f, 10.0f}, (ab_t){-1.0f + dv_d, 11.0f}, 48.0f};
  return v;
}

/* The check's parameters: 32 periods, t_out 0, Ts, R, pos_emf_tol 0.3,
 * the machine and its flux at zero current. */
static const protect_pos_cfg_t cfg = {32u,  0.0f, 1.0f / 16384.0f, 0.1f,
                                      0.3f, &m,   {0.1f, 0.0f},    0.1f};

/* A check as the drive holds it: zeroed, then configured with the set. */
static protect_pos_t check_new(void) {
  protect_pos_t p = {0};
  protect_pos_configure(&p, &cfg);
  return p;
}

static int setup(void **state) {
  (void)state;
  return machine_init_linear(&m, 4.0f, 0.1f, 1e-3f, 1e-3f, 0.1f);
}

#define PER 32 /* periods per check (the view's `periods`) */

/* The current at the boundary of period j (the machine's operating
 * point, or a step of 10 A in q over two periods inside every window). */
static dq_t current_at(long j, bool step) {
  if (!step) {
    return (dq_t){0.0f, 10.0f};
  }
  const long k = j % PER; /* 0 at a window's start */
  const float q = k < 12 ? 10.0f : (k >= 14 ? 0.0f : 10.0f - 5.0f * (float)(k - 12));
  return (dq_t){0.0f, (j / PER) % 2 == 0 ? q : 10.0f - q};
}

typedef struct {
  long m;      /* ISRs so far */
  float delta; /* the machine's angle less the source's [rad] */
  float dv_d;  /* an error of the applied voltage, source frame d [V] */
  bool step;   /* the current steps inside the windows */
} sim_t;

/* The machine's stator flux at the boundary of period j (t_out 0: the
 * voltage of sample j acts from (j - 1/2) Ts to (j + 1/2) Ts). */
static ab_t flux_at(const sim_t *s, const protect_pos_view_t *v, long j, ab_t *i_ab) {
  const float th = v->omega_e * ((float)j - 0.5f) * cfg.ts + s->delta;
  const sincos_t sc = {sinf(th), cosf(th)};
  const dq_t i = current_at(j, s->step);
  *i_ab = frames_park_inv(i, sc);
  return frames_park_inv(machine_flux(&m, i), sc);
}

/* One check's worth of ISRs: each sums the last period's voltage (exact
 * for the machine: its flux change plus R i by the trapezoid), the last
 * one checks on the last period's sample. */
static uint32_t one_check(protect_pos_t *p, sim_t *s, protect_pos_view_t v) {
  ab_t v_ab = {0.0f, 0.0f};
  for (int k = 0; k < PER; ++k) {
    const long j = s->m++; /* the voltage of sample j, read in ISR j + 1 */
    ab_t i0, i1;
    const ab_t p0 = flux_at(s, &v, j, &i0), p1 = flux_at(s, &v, j + 1, &i1);
    const float th = v.omega_e * (float)j * cfg.ts;
    const ab_t err = frames_park_inv((dq_t){s->dv_d, 0.0f}, (sincos_t){sinf(th), cosf(th)});
    v_ab.alpha = (p1.alpha - p0.alpha) / cfg.ts + 0.5f * cfg.rs * (i0.alpha + i1.alpha) + err.alpha;
    v_ab.beta = (p1.beta - p0.beta) / cfg.ts + 0.5f * cfg.rs * (i0.beta + i1.beta) + err.beta;
    protect_pos_integrate(p, v_ab);
  }
  v.theta_e = frames_wrap_pi(v.omega_e * (float)(s->m - 1) * cfg.ts);
  v.i_dq = current_at(s->m - 1, s->step);
  v.v_ab = v_ab;
  return protect_pos_step(p, &v);
}

static int checks_to_trip(protect_pos_t *p, sim_t *s, const protect_pos_view_t *v, int n) {
  for (int k = 1; k <= n; ++k) {
    if (one_check(p, s, *v) != 0u) {
      return k;
    }
  }
  return 0;
}

static void the_machine_passes(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t s = {0};
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 0);
  assert_true(p.res < 0.01f);
}

static void a_current_step_passes(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t s = {0};
  s.step = true;
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 0);
  assert_true(p.res < 0.2f);
}

/* The first check opens the window: the 9th over-count is the 10th check. */
static void half_a_turn_off_trips(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t s = {0};
  s.delta = 3.14159265f; /* the source's angle off by pi */
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 10);
  assert_true(p.res > 3.0f);
  p = check_new(); /* and through the current steps */
  s = (sim_t){0};
  s.delta = 3.14159265f;
  s.step = true;
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 10);
}

/* The tolerance 0.3 (11 sinc(phi / 2) + 1) + 0.05 * 48 = 5.995 V (phi =
 * 100 * 32 / 16384 rad); the error's window mean dv sinc(phi / 2). */
static void just_inside_the_tolerance(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t s = {0};
  s.dv_d = 5.9f;
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 0);
  p = check_new();
  s = (sim_t){0};
  s.dv_d = 6.1f;
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 10);
}

static void leaky_count_restart_and_due(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t bad = {0}, good = {0};
  bad.dv_d = 10.0f;
  const protect_pos_view_t v = view(0.0f);
  assert_int_equal(one_check(&p, &good, v), 0u); /* the window's start */
  for (int k = 0; k < 50; ++k) {                 /* one over, one under: never */
    bad.m = good.m;
    assert_int_equal(one_check(&p, &bad, v), 0u);
    good.m = bad.m;
    assert_int_equal(one_check(&p, &good, v), 0u);
  }
  bad.m = good.m;
  assert_int_equal(checks_to_trip(&p, &bad, &v, 8), 0);
  assert_int_equal(p.n, 8);
  protect_pos_view_t off = v;
  off.due = false; /* not one of its slow periods: nothing */
  assert_int_equal(checks_to_trip(&p, &bad, &off, 10), 0);
  assert_int_equal(p.n, 8);
  off.active = false; /* out of run, a star-point source ...: restart */
  off.due = false;
  assert_int_equal(one_check(&p, &bad, off), 0u);
  assert_int_equal(p.n, 0);
  assert_false(p.psi_ok);
  assert_int_equal(checks_to_trip(&p, &bad, &v, 100), 10);
}

/* 2500 rad/s: 4.9 rad per window, the derivative form. Tolerance 0.3
 * (2500 * 0.11 + 1) + 2.4 = 85.2 V; half a turn off: 2 * 275 V. */
static void above_half_a_turn_per_window(void **state) {
  (void)state;
  protect_pos_t p = check_new();
  sim_t s = {0};
  protect_pos_view_t v = view(0.0f);
  v.omega_e = 2500.0f;
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 0);
  assert_true(p.res < 0.1f);
  p = check_new();
  s = (sim_t){0};
  s.delta = 3.14159265f;
  assert_int_equal(checks_to_trip(&p, &s, &v, 100), 10);
  assert_true(p.res > 5.0f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(the_machine_passes),          cmocka_unit_test(a_current_step_passes),
      cmocka_unit_test(half_a_turn_off_trips),       cmocka_unit_test(just_inside_the_tolerance),
      cmocka_unit_test(leaky_count_restart_and_due), cmocka_unit_test(above_half_a_turn_per_window),
  };
  return cmocka_run_group_tests(tests, setup, NULL);
}
