/*
 * The procedure table (proc.h) and its procedures without the SIL: the
 * rows agree with PROC_LIST, the start sequence runs the offsets with the
 * gates off first; which procedures a parameter set wants and which it
 * refuses (the held start without an angle at standstill, named by
 * start_mode); the offset calibration's result and its fault; the
 * alignment's bounded voltage, its hand-over to the encoder and its
 * timeout; the held start's polarity from two pulses on a small R-L model
 * with d-axis saturation, its clean (plain) pulses, its failure without an
 * angle and its abort; and through the drive (SIL HAL, hand-made samples)
 * the procedure telemetry: id, status and the offsets found.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "hal_sil.h"
#include "proc.h"
#include "proc_fixture.h"

typedef struct {
  PROC_FIXTURE_FIELDS
  pos_estimate_t pos;
} fixture_t;

static fixture_t fx;

static void fixture(pos_source_t src) {
  memset(&fx, 0, sizeof fx);
  drive_config_default(&fx.cfg);
  fx.cfg.pos_source = src;
  proc_fixture_bind(&fx);
  fx.s.valid = true;
  fx.s.enc_valid = true;
  fx.s.v_dc = 310.0f;
}

static proc_in_t in_of(ab_t i_ab, float v_max) {
  return (proc_in_t){&fx.s, i_ab, v_max, &fx.pos};
}

/* ------------------------------------------------------------ the table */

static void rows_agree_with_the_list(void **state) {
  (void)state;
  static const char *const names[] = {
#define PROC_NAME(E, n, d) #n,
      PROC_LIST(PROC_NAME)
#undef PROC_NAME
  };
  for (unsigned k = 0; k < (unsigned)PROC_COUNT; ++k) {
    const proc_row_t *r = proc_row((proc_id_t)k);
    assert_non_null(r);
    assert_int_equal(r->id, k);
    assert_string_equal(r->name, names[k]);
    assert_non_null(r->init);
    assert_non_null(r->step);
    assert_non_null(r->publish);
    /* a procedure shows as a start state: gates off or on by its caps; an
     * identification's gated rows as ident */
    const bool gates = (r->caps & PROC_CAP_GATES) != 0u;
    const bool ident = (r->caps & PROC_CAP_IDENT) != 0u && gates;
    assert_int_equal(r->state, ident   ? DRIVE_STATE_IDENT
                               : gates ? DRIVE_STATE_ALIGN
                                       : DRIVE_STATE_OFFSET_CAL);
  }
  assert_null(proc_row(PROC_COUNT));
  assert_null(proc_row((proc_id_t)1000));
}

static void start_sequence_offsets_first(void **state) {
  (void)state;
  unsigned n = 0;
  const proc_id_t *seq = proc_start_sequence(&n);
  assert_true(n >= 1u);
  assert_int_equal(seq[0], PROC_OFFSET);
  bool gates = false; /* the gates, once on, stay on until the run */
  for (unsigned k = 0; k < n; ++k) {
    const proc_row_t *r = proc_row(seq[k]);
    assert_non_null(r);
    const bool g = (r->caps & PROC_CAP_GATES) != 0u;
    assert_true(g || !gates);
    gates = gates || g;
  }
}

static void which_procedures_apply(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  /* the default: an encoder with its known offset, no alignment */
  assert_true(proc_applies(PROC_OFFSET, &fx.su));
  assert_false(proc_applies(PROC_ALIGN, &fx.su));
  assert_false(proc_applies(PROC_HOLD, &fx.su));
  const char *field = NULL;
  assert_null(proc_start_refusal(&fx.su, &field));
  fx.cfg.align_time = 0.01f;
  assert_true(proc_applies(PROC_ALIGN, &fx.su));
  /* the held start needs an angle at standstill: refused for the encoder */
  fx.cfg.start_mode = 1u;
  assert_false(proc_applies(PROC_HOLD, &fx.su));
  assert_false(proc_applies(PROC_ALIGN, &fx.su));
  assert_non_null(proc_start_refusal(&fx.su, &field));
  assert_string_equal(field, "start_mode");
  /* a star-point source starts held, and does not align */
  fixture(POS_SOURCE_IVD);
  fx.cfg.align_time = 0.01f;
  fx.cfg.start_mode = 1u;
  assert_true(proc_applies(PROC_HOLD, &fx.su));
  assert_false(proc_applies(PROC_ALIGN, &fx.su));
  assert_null(proc_start_refusal(&fx.su, &field));
  fx.cfg.start_mode = 0u;
  assert_true(proc_applies(PROC_ALIGN, &fx.su));
  assert_false(proc_applies(PROC_HOLD, &fx.su));
}

/* ------------------------------------------------------ offset procedure */

static void offsets_found_and_handed_over(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  fx.cfg.offset_samples = 64u;
  const proc_row_t *r = proc_row(PROC_OFFSET);
  r->init(&fx.st, &fx.su);
  proc_out_t out;
  proc_telemetry_t tm;
  memset(&tm, 0, sizeof tm);
  for (unsigned k = 0; k < 64u; ++k) {
    /* offsets 0.1, -0.05, 0.02 A with a +-0.01 A alternation */
    const float e = (k & 1u) != 0u ? 0.01f : -0.01f;
    fx.s.i_abc[0] = 0.1f + e;
    fx.s.i_abc[1] = -0.05f - e;
    fx.s.i_abc[2] = 0.02f + e;
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, 0.0f);
    const int res = r->step(&fx.st, &fx.su, &in, &out);
    assert_false(out.apply); /* the gates stay off */
    assert_int_equal(res, k + 1u < 64u ? PROC_RUNNING : PROC_DONE);
    r->publish(&fx.st, &tm);
    assert_int_equal(tm.n, k + 1u);
  }
  assert_float_equal(fx.offset[0], 0.1f, 1e-6f);
  assert_float_equal(fx.offset[1], -0.05f, 1e-6f);
  assert_float_equal(fx.offset[2], 0.02f, 1e-6f);
  for (int x = 0; x < 3; ++x) {
    assert_float_equal(tm.result[x], fx.offset[x], 1e-7f);
  }
}

static void offset_beyond_its_limit_fails(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  fx.cfg.offset_samples = 8u;
  fx.cfg.offset_max = 0.5f;
  const proc_row_t *r = proc_row(PROC_OFFSET);
  r->init(&fx.st, &fx.su);
  fx.s.i_abc[1] = 0.6f;
  proc_out_t out;
  int res = PROC_RUNNING;
  for (unsigned k = 0; k < 8u; ++k) {
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, 0.0f);
    res = r->step(&fx.st, &fx.su, &in, &out);
  }
  assert_int_equal(res, PROC_FAILED);
  assert_int_equal(out.fault, DRIVE_FAULT_OFFSET);
}

/* ------------------------------------------------------------ alignment */

static void alignment_bounded_then_hands_over(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  fx.cfg.align_time = 0.01f;
  fx.cfg.align_current = 1.0f;
  fx.s.enc_angle = 0.5f; /* the rotor rests here */
  const proc_row_t *r = proc_row(PROC_ALIGN);
  r->init(&fx.st, &fx.su);
  proc_align_timing_t t;
  proc_align_timing(&fx.cfg, fx.cfg.lambda_m, &t);
  assert_true(t.kd > 0.0f && t.still_need > 0u && t.n_timeout > t.still_need);
  const float v_max = 20.0f;
  const uint32_t need = t.still_need > (uint32_t)(0.01f / fx.cfg.ts) + 1u
                            ? t.still_need
                            : (uint32_t)(0.01f / fx.cfg.ts) + 1u;
  proc_out_t out;
  int res = PROC_RUNNING;
  uint32_t n = 0u;
  while (res == PROC_RUNNING && n < 10u * need) {
    /* no current: the loop asks for more, bounded by v_max */
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, v_max);
    res = r->step(&fx.st, &fx.su, &in, &out);
    ++n;
    assert_true(out.apply);
    assert_false(out.plain);
    assert_true(hypotf(out.v_ab.alpha, out.v_ab.beta) <= v_max * (1.0f + 1e-6f));
  }
  assert_int_equal(res, PROC_DONE);
  assert_int_equal(n, need);
  /* the encoder took the current's angle (0) as its reference there */
  const float half = 3.14159265f / (float)fx.cfg.enc_cpr;
  const float want = remainderf(fx.cfg.pole_pairs * (0.5f + half), 6.2831853f);
  assert_float_equal(fx.pos_st.enc.offset, want, 1e-4f);
}

static void alignment_times_out_on_a_swinging_rotor(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  fx.cfg.align_time = 0.01f;
  fx.cfg.align_current = 1.0f;
  const proc_row_t *r = proc_row(PROC_ALIGN);
  r->init(&fx.st, &fx.su);
  proc_align_timing_t t;
  proc_align_timing(&fx.cfg, fx.cfg.lambda_m, &t);
  proc_out_t out;
  int res = PROC_RUNNING;
  uint32_t n = 0u;
  while (res == PROC_RUNNING && n < 2u * t.n_timeout) {
    fx.pos.omega = 50.0f * sinf(31.4159f * (float)n * fx.cfg.ts); /* never calm */
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, 20.0f);
    res = r->step(&fx.st, &fx.su, &in, &out);
    ++n;
  }
  assert_int_equal(res, PROC_FAILED);
  assert_int_equal(out.fault, DRIVE_FAULT_POSITION);
  assert_int_equal(n, t.n_timeout);
}

/* ----------------------------------------------------------- held start */

/* A small R-L model along the estimate with d-axis saturation: the
 * incremental inductance 1/(1 + sat) lower where the current adds to the
 * magnet's flux (along the north pole at theta_n); the voltage written in
 * a period acts over the next (hal.h). Returns the procedure's result. */
static int held_start(float theta_est, float theta_n, float sat, float *theta_out,
                      unsigned *periods) {
  fixture(POS_SOURCE_IVD);
  fx.cfg.start_mode = 1u;
  const drive_config_t *c = &fx.cfg;
  const proc_row_t *r = proc_row(PROC_HOLD);
  r->init(&fx.st, &fx.su);
  fx.pos.valid = true;
  fx.pos.theta = theta_est;
  ab_t i = {0.0f, 0.0f}, v_act = {0.0f, 0.0f};
  const float v_max = 20.0f;
  proc_out_t out;
  int res = PROC_RUNNING;
  unsigned n = 0u;
  bool saw_plain = false;
  const sincos_t sn = frames_sincos(theta_n);
  while (res == PROC_RUNNING && n < 200u) {
    const proc_in_t in = in_of(i, v_max);
    res = r->step(&fx.st, &fx.su, &in, &out);
    ++n;
    saw_plain = saw_plain || out.plain;
    if (res == PROC_FAILED) {
      assert_false(out.apply);
      break;
    }
    assert_true(out.apply);
    assert_true(hypotf(out.v_ab.alpha, out.v_ab.beta) <= v_max * (1.0f + 1e-5f));
    /* the plant over the period: the pattern written last period acts */
    const float i_n = i.alpha * sn.c + i.beta * sn.s;
    const float l = i_n > 0.0f ? c->ld / (1.0f + sat) : c->ld;
    i.alpha += (v_act.alpha - c->rs * i.alpha) * c->ts / l;
    i.beta += (v_act.beta - c->rs * i.beta) * c->ts / l;
    v_act = out.v_ab;
  }
  assert_true(saw_plain); /* the pulses are sampled without the DFC window */
  proc_telemetry_t tm;
  memset(&tm, 0, sizeof tm);
  r->publish(&fx.st, &tm);
  *theta_out = tm.result[1];
  *periods = n;
  return res;
}

static void held_start_finds_the_north_pole(void **state) {
  (void)state;
  float th = 0.0f;
  unsigned n = 0u;
  /* the estimate along the north pole, and pi off it */
  assert_int_equal(held_start(1.0f, 1.0f, 0.1f, &th, &n), PROC_DONE);
  assert_float_equal(th, 1.0f, 1e-6f);
  assert_true(n >= 30u && n <= 60u); /* 2.44 .. 3.25 ms at 16 kHz (proc_hold.c) */
  assert_int_equal(held_start(1.0f + 3.14159265f, 1.0f, 0.1f, &th, &n), PROC_DONE);
  assert_float_equal(remainderf(th - 1.0f, 6.2831853f), 0.0f, 1e-5f);
  /* no saturation, no evidence: the position fault */
  assert_int_equal(held_start(1.0f, 1.0f, 0.0f, &th, &n), PROC_FAILED);
}

static void held_start_without_an_angle_fails_and_aborts_clean(void **state) {
  (void)state;
  fixture(POS_SOURCE_IVD);
  fx.cfg.start_mode = 1u;
  const proc_row_t *r = proc_row(PROC_HOLD);
  r->init(&fx.st, &fx.su);
  fx.pos.valid = false; /* no angle at standstill */
  proc_out_t out;
  int res = PROC_RUNNING;
  unsigned n = 0u;
  while (res == PROC_RUNNING && n < 100u) {
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, 20.0f);
    res = r->step(&fx.st, &fx.su, &in, &out);
    ++n;
  }
  assert_int_equal(res, PROC_FAILED);
  assert_int_equal(out.fault, DRIVE_FAULT_POSITION);
  assert_int_equal(n, 33u); /* 4 x the acquisition's 8 periods, then the fault */
  /* aborted mid-pulse: the plain pattern is undone */
  r->init(&fx.st, &fx.su);
  fx.pos.valid = true;
  for (unsigned k = 0; k < 10u; ++k) {
    const proc_in_t in = in_of((ab_t){0.0f, 0.0f}, 20.0f);
    (void)r->step(&fx.st, &fx.su, &in, &out);
  }
  assert_true(out.plain);
  r->abort(&fx.st);
  assert_false(fx.st.hold.plain);
}

/* ------------------------------------------------------ through the drive */

static void drive_publishes_the_procedures(void **state) {
  (void)state;
  static hal_sil_t hal;
  static drive_t drv;
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 50u, false, 0.0f, 0.0f, 0.0f};
  hal_sil_init(&hal, &board);
  hal_sil_bind(&hal);
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.align_time = 0.001f;
  cfg.align_current = 1.0f;
  assert_int_equal(drive_init(&drv, &cfg, NULL), 0);
  memset(&hal.sample, 0, sizeof hal.sample);
  hal.sample.i_abc[0] = 0.1f;
  hal.sample.i_abc[1] = -0.05f;
  hal.sample.i_abc[2] = -0.05f;
  hal.sample.v_dc = 310.0f;
  hal.sample.enc_valid = true;
  hal.sample.valid = true;
  drive_telemetry_t tm;
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.status, PROC_ST_IDLE);
  drive_cmd_enable(&drv, true);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.id, PROC_OFFSET);
  assert_int_equal(tm.proc.status, PROC_ST_RUNNING);
  for (unsigned k = 0; k < cfg.offset_samples; ++k) {
    drive_isr(&drv);
  }
  assert_int_equal(drv.state, DRIVE_STATE_ALIGN);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.id, PROC_ALIGN);
  assert_int_equal(tm.proc.status, PROC_ST_RUNNING);
  proc_align_timing_t tmg; /* a rotor that never moves: still_need periods */
  proc_align_timing(&cfg, cfg.lambda_m, &tmg);
  for (uint32_t k = 0; k < tmg.still_need && drv.state == DRIVE_STATE_ALIGN; ++k) {
    drive_isr(&drv);
  }
  assert_int_equal(drv.state, DRIVE_STATE_RUN);
  assert_null(drv.proc);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.id, PROC_ALIGN);
  assert_int_equal(tm.proc.status, PROC_ST_DONE);
  assert_float_equal(drv.offset[0], 0.1f, 1e-6f);
  /* a disable during the offsets aborts them */
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  drive_cmd_enable(&drv, true);
  drive_isr(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.id, PROC_OFFSET);
  assert_int_equal(tm.proc.status, PROC_ST_ABORTED);
}

/* An identification run (drive_cmd_identify): only rows with
 * PROC_CAP_IDENT, not while enabled; the offsets, then idle with the gates
 * off and the results published; a stop request and an enable end it. */
static void identification_runs_alone_and_stops(void **state) {
  (void)state;
  static hal_sil_t hal;
  static drive_t drv;
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 50u, false, 0.0f, 0.0f, 0.0f};
  hal_sil_init(&hal, &board);
  hal_sil_bind(&hal);
  drive_config_t cfg;
  drive_config_default(&cfg);
  assert_int_equal(drive_init(&drv, &cfg, NULL), 0);
  memset(&hal.sample, 0, sizeof hal.sample);
  hal.sample.i_abc[0] = 0.2f;
  hal.sample.i_abc[1] = -0.1f;
  hal.sample.i_abc[2] = -0.1f;
  hal.sample.v_dc = 310.0f;
  hal.sample.enc_valid = true;
  hal.sample.valid = true;
  const char *field = NULL;
  assert_non_null(drive_cmd_identify(&drv, PROC_ALIGN, &field)); /* not an identification */
  assert_string_equal(field, "proc");
  assert_non_null(drive_cmd_identify(&drv, PROC_COUNT + 3, &field));
  drive_cmd_enable(&drv, true);
  assert_non_null(drive_cmd_identify(&drv, PROC_OFFSET, &field)); /* enabled */
  assert_string_equal(field, "enable");
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_null(drive_cmd_identify(&drv, PROC_OFFSET, &field));
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  assert_false(hal.gates_on);
  for (unsigned k = 0; k < cfg.offset_samples; ++k) {
    drive_isr(&drv);
  }
  assert_int_equal(drv.state, DRIVE_STATE_IDLE); /* not the run: no enable */
  assert_false(hal.gates_on);
  drive_telemetry_t tm;
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.id, PROC_OFFSET);
  assert_int_equal(tm.proc.status, PROC_ST_DONE);
  assert_float_equal(tm.proc.result[0], 0.2f, 1e-6f);
  assert_float_equal(drv.offset[1], -0.1f, 1e-6f);
  /* a stop request ends it */
  assert_null(drive_cmd_identify(&drv, PROC_OFFSET, NULL));
  drive_isr(&drv);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  assert_null(drive_cmd_identify(&drv, PROC_NONE, NULL));
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  assert_false(drv.ident);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.status, PROC_ST_ABORTED);
  /* so does an enable: the start then begins from idle */
  assert_null(drive_cmd_identify(&drv, PROC_OFFSET, NULL));
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL);
  drive_cmd_enable(&drv, true);
  drive_isr(&drv);
  assert_false(drv.ident);
  assert_true(drive_telemetry_read(&drv, &tm));
  assert_int_equal(tm.proc.status, PROC_ST_ABORTED);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_OFFSET_CAL); /* the start's offsets */
  /* a request posted while enabled and running is void, later too */
  drive_cmd_enable(&drv, false);
  drive_isr(&drv);
  assert_int_equal(drv.state, DRIVE_STATE_IDLE);
  drv.req.ident.proc = PROC_OFFSET; /* as if posted while enabled (the main loop refuses it) */
  drv.state = DRIVE_STATE_RUN;
  drv.req.ident.count++;
  drv.req.seq += 2u;
  drive_isr(&drv);
  drv.state = DRIVE_STATE_IDLE;
  drive_cmd_enable(&drv, true); /* then an enable: it voids the request */
  drive_isr(&drv);
  assert_false(drv.ident);
  assert_int_equal(drv.ident_seen, drv.req.ident.count);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(rows_agree_with_the_list),
      cmocka_unit_test(start_sequence_offsets_first),
      cmocka_unit_test(which_procedures_apply),
      cmocka_unit_test(offsets_found_and_handed_over),
      cmocka_unit_test(offset_beyond_its_limit_fails),
      cmocka_unit_test(alignment_bounded_then_hands_over),
      cmocka_unit_test(alignment_times_out_on_a_swinging_rotor),
      cmocka_unit_test(held_start_finds_the_north_pole),
      cmocka_unit_test(held_start_without_an_angle_fails_and_aborts_clean),
      cmocka_unit_test(drive_publishes_the_procedures),
      cmocka_unit_test(identification_runs_alone_and_stops),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
