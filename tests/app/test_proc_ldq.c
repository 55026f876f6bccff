/*
 * The ldq identification (proc_ldq.c) without the SIL: on a small
 * standstill R-L model with L_d != L_q (the rotor resting at theta = 0),
 * one or two periods' delay (the SIL's timer preload), an inverter voltage error per phase (a knee,
 * a plateau), current noise and quantisation, L_d and L_q within 5 % of the model's (the truth: the
 * model's parameters) over a spread of R, L and saliency, and with the parameter set's inductances
 * far off (the amplitude adapts); the current within 1.5 times the bias; the trip.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "proc.h"
#include "proc_fixture.h"

typedef struct {
  PROC_FIXTURE_FIELDS
  pos_estimate_t pos;
} fixture_t;

static fixture_t fx;

/* The model: R, L_d (alpha), L_q (beta: the rotor rests at theta = 0), the
 * voltage error's plateau V0 and knee per phase. */
#include "proc_rl_model.h"

static void fixture(float r, float l) {
  memset(&fx, 0, sizeof fx);
  drive_config_default(&fx.cfg);
  fx.cfg.pos_source = POS_SOURCE_ENCODER;
  fx.cfg.i_max = 10.0f;
  fx.cfg.rs = r * 1.3f; /* the controller's guesses: not the truth */
  fx.cfg.ld = l * 0.7f;
  fx.cfg.lq = l * 0.7f;
  fx.cfg.id_ldq_current = 3.0f;
  proc_fixture_bind(&fx);
  fx.s.valid = true;
  fx.s.v_dc = 48.0f;
}

/* Runs the procedure on the model to its end (or max periods): its return. */
static int run(model_t *m, proc_telemetry_t *tm, uint32_t max, unsigned *points) {
  const proc_row_t *row = proc_row(PROC_LDQ);
  row->init(&fx.st, &fx.su);
  int res = PROC_RUNNING;
  uint8_t phase = 0u;
  *points = 0u;
  for (uint32_t k = 0; k < max && res == PROC_RUNNING; ++k) {
    const proc_in_t in = {&fx.s, {model_meas(m, m->i_a), model_meas(m, m->i_b)}, 24.0f, &fx.pos};
    proc_out_t out;
    res = row->step(&fx.st, &fx.su, &in, &out);
    row->publish(&fx.st, tm);
    if (tm->phase != phase) {
      phase = tm->phase;
      ++*points;
    }
    if (res == PROC_FAILED) {
      tm->fault = out.fault;
      break;
    }
    const float vm = sqrtf(out.v_ab.alpha * out.v_ab.alpha + out.v_ab.beta * out.v_ab.beta);
    assert_true(vm <= 24.0f * 1.0001f);
    const ab_t v = out.apply ? out.v_ab : (ab_t){0.0f, 0.0f};
    model_step(m, m->delay2 ? m->pend : v, fx.cfg.ts);
    m->pend = v;
  }
  return res;
}

static void inductances_within_5_percent(void **state) {
  (void)state;
  /* R, L_d, L_q, the parameter set's L over the truth */
  static const float cases[][4] = {
      {0.05f, 1e-4f, 1.5e-4f, 1.0f}, {0.5f, 1e-3f, 2.5e-3f, 0.3f}, {3.0f, 2e-2f, 3e-2f, 3.0f},
      {2.0f, 0.057f, 0.057f, 1.0f},  {0.2f, 5e-4f, 1.5e-3f, 2.0f}, {1.0f, 4e-3f, 4e-3f, 0.05f},
      {3.0f, 1e-3f, 2e-3f, 1.0f},    {1.0f, 2e-4f, 3e-4f, 1.0f},
  };
  for (unsigned c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    const float r = cases[c][0], ld = cases[c][1], lq = cases[c][2];
    fixture(r, ld);
    fx.cfg.ld = ld * cases[c][3];
    fx.cfg.lq = ld * cases[c][3];
    model_t m = {r,    ld,   lq,      0.4f, 0.3f,          0.02f,       0.01f,
                 0.0f, 0.0f, 99u + c, 0.0f, (int)(c % 2u), {0.0f, 0.0f}};
    proc_telemetry_t tm;
    unsigned points;
    assert_int_equal(run(&m, &tm, 400000u, &points), PROC_DONE);
    assert_int_equal(tm.phase, 5u);
    assert_true(fabsf(tm.result[0] / ld - 1.0f) < 0.05f);
    assert_true(fabsf(tm.result[1] / lq - 1.0f) < 0.05f);
    assert_true(fabsf(tm.result[2] - 3.0f) < 1e-3f);
    /* never above 1.5 times the bias (its ripple's bound) */
    assert_true(m.i_peak <= 1.5f * 3.0f);
  }
}

static void overcurrent_fails(void **state) {
  (void)state;
  fixture(0.5f, 1e-3f);
  const proc_row_t *row = proc_row(PROC_LDQ);
  row->init(&fx.st, &fx.su);
  proc_out_t out;
  const proc_in_t in = {&fx.s, {2.01f * 3.0f, 0.0f}, 24.0f, &fx.pos};
  assert_int_equal(row->step(&fx.st, &fx.su, &in, &out), PROC_FAILED);
  assert_int_equal(out.fault, DRIVE_FAULT_OVERCURRENT);
}

static void is_an_identification(void **state) {
  (void)state;
  fixture(0.5f, 1e-3f);
  const char *field = NULL;
  assert_null(proc_ident_refusal(PROC_LDQ, &fx.su, &field));
  const proc_row_t *row = proc_row(PROC_LDQ);
  assert_int_equal(row->state, DRIVE_STATE_IDENT);
  assert_int_equal(row->caps, PROC_CAP_IDENT | PROC_CAP_GATES);
  assert_false(proc_applies(PROC_LDQ, &fx.su));
  assert_true(sizeof(proc_ldq_t) <= 400u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(inductances_within_5_percent),
      cmocka_unit_test(overcurrent_fails),
      cmocka_unit_test(is_an_identification),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
