/*
 * The phase-balance check as a part (protect/drive_phase_check.h), on
 * hand-made telemetry copies without the SIL: balanced currents and a
 * voltage that matches R i pass; an open phase and a missing DC voltage
 * each trip after DRIVE_PH_TRIP unbalanced revolutions (not after one);
 * a copy out of run restarts the count; a revolution spanning too many
 * copies is not judged.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "drive_enums.h"
#include "protect/drive_phase_check.h"

#define TWO_PI 6.28318531f

typedef struct {
  float i_amp;   /* [A] */
  bool open_c;   /* phase c carries nothing */
  float d_alpha; /* a stationary voltage deficit along alpha [V] */
  float f_e;     /* electrical frequency [Hz] */
} machine_run_t;

/* A stationary current along alpha in every copy [A] (0 but in
 * resistive_drop_is_no_deficit), carried by the voltage through R. */
static float dc_alpha;

/* Copies every 10 ISRs of 100 us (1 kHz), pole pairs 1, R 0.1 Ohm, i_max
 * 10 A, 300 V. Returns the copy at which the check asks for the fault
 * (0: none within n copies); *p carries on. */
static int run(drive_phase_check_t *p, const machine_run_t *r, int n, uint32_t *isr, bool run) {
  for (int k = 1; k <= n; ++k) {
    *isr += 10u;
    const float th = fmodf(TWO_PI * r->f_e * (float)*isr * 1e-4f, TWO_PI);
    float i[3] = {r->i_amp * cosf(th), r->i_amp * cosf(th - TWO_PI / 3.0f),
                  r->i_amp * cosf(th + TWO_PI / 3.0f)};
    if (r->open_c) {
      i[0] = r->i_amp * cosf(th);
      i[1] = -i[0];
      i[2] = 0.0f;
    }
    i[0] += dc_alpha * (2.0f / 3.0f); /* alpha = (2 i_a - i_b - i_c) / 3 */
    i[1] -= dc_alpha * (1.0f / 3.0f);
    i[2] -= dc_alpha * (1.0f / 3.0f);
    const float ia = (2.0f * i[0] - i[1] - i[2]) * (1.0f / 3.0f), ib = (i[1] - i[2]) * 0.57735027f;
    const float vf[2] = {0.1f * ia + r->d_alpha, 0.1f * ib};
    const drive_phase_view_t v = {*isr,   run,  TWO_PI * r->f_e, i,    vf,   th,
                                  300.0f, 1.0f, 1e-4f,           0.1f, 10.0f};
    if (drive_phase_check(p, &v) != 0u) {
      assert_int_equal(drive_phase_check(p, &v), 0u); /* the same copy again: nothing */
      return k;
    }
  }
  return 0;
}

static void balanced_passes(void **state) {
  (void)state;
  drive_phase_check_t p = {0};
  uint32_t isr = 0u;
  const machine_run_t r = {8.0f, false, 0.0f, 50.0f};
  assert_int_equal(run(&p, &r, 400, &isr, true), 0);
  assert_true(p.vdef < 1e-3f);
  assert_int_equal(p.trips, 0u);
}

/* A stationary current is carried by a stationary voltage R i: that is no
 * deficit (the check subtracts R_s i before it fits the stationary part). */
static void resistive_drop_is_no_deficit(void **state) {
  (void)state;
  drive_phase_check_t p = {0};
  uint32_t isr = 0u;
  const machine_run_t r = {8.0f, false, 0.0f, 50.0f};
  dc_alpha = 3.0f; /* R i = 0.3 V stationary: 1e-3 of the link */
  const int k = run(&p, &r, 400, &isr, true);
  dc_alpha = 0.0f;
  assert_int_equal(k, 0);
  assert_true(p.vdef < 1e-4f);
}

static void open_phase_after_two_revolutions(void **state) {
  (void)state;
  drive_phase_check_t p = {0};
  uint32_t isr = 0u;
  const machine_run_t r = {8.0f, true, 0.0f, 50.0f};
  const int k = run(&p, &r, 400, &isr, true);
  /* 20 copies per revolution, the first copy only starts: the end of the
   * second revolution, not of the first */
  assert_true(k > 30 && k <= 42);
  assert_int_equal(p.trips, 1u);
}

static void missing_voltage_after_two_revolutions(void **state) {
  (void)state;
  drive_phase_check_t p = {0};
  uint32_t isr = 0u;
  const machine_run_t r = {8.0f, false, 10.0f, 50.0f}; /* 0.033 v_dc > DRIVE_PH_VDEF */
  const int k = run(&p, &r, 400, &isr, true);
  assert_true(k > 30 && k <= 42);
  assert_float_equal(p.vdef_ab[0], 10.0f / 300.0f, 2e-3f);
  const machine_run_t ok = {8.0f, false, 0.5f, 50.0f}; /* 0.0017 v_dc: healthy */
  drive_phase_check_t q = {0};
  isr = 0u;
  assert_int_equal(run(&q, &ok, 400, &isr, true), 0);
}

static void out_of_run_restarts_and_slow_is_not_judged(void **state) {
  (void)state;
  drive_phase_check_t p = {0};
  uint32_t isr = 0u;
  const machine_run_t r = {8.0f, true, 0.0f, 50.0f};
  for (int rep = 0; rep < 10; ++rep) { /* one and a half revolutions, then a copy out of run */
    assert_int_equal(run(&p, &r, 30, &isr, true), 0);
    assert_int_equal(run(&p, &r, 1, &isr, false), 0);
  }
  const machine_run_t slow = {8.0f, true, 0.0f, 10.0f}; /* 100 copies per revolution */
  drive_phase_check_t q = {0};
  isr = 0u;
  assert_int_equal(run(&q, &slow, 1000, &isr, true), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(balanced_passes),
      cmocka_unit_test(resistive_drop_is_no_deficit),
      cmocka_unit_test(open_phase_after_two_revolutions),
      cmocka_unit_test(missing_voltage_after_two_revolutions),
      cmocka_unit_test(out_of_run_restarts_and_slow_is_not_judged),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
