/*
 * test_tm_signals.c - the CAN telemetry frames carry the drive's signal
 * table (firmware/app/drive_signal_table.h): every signal of TM_SPEED ..
 * TM_POSITION has a row, and every frame the protocol sends holds, in each
 * signal a row names, that row's value times its CAN scale (to one step of
 * the signal), from the main loop's telemetry copy.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "can_codec.h"
#include "can_proto.h"
#include "drive.h"
#include "drive_signals.h"
#include "hal_sil.h"

static hal_sil_t hal;
static drive_t drv;
static can_proto_t proto;

static void test_every_telemetry_signal_has_a_row(void **state) {
  (void)state;
  for (unsigned m = (unsigned)CAN_MSG_TM_SPEED; m <= (unsigned)CAN_MSG_TM_POSITION; ++m) {
    if (m == (unsigned)CAN_MSG_TM_CPU) {
      continue; /* the board's own measurement, not the drive's */
    }
    const can_msg_desc_t *d = can_codec_msg((can_msg_t)m);
    for (unsigned i = 0u; i < d->n_signals; ++i) {
      const can_sig_t s = (can_sig_t)((unsigned)d->first + i);
      if (drive_signal_of_can(s) == NULL) {
        fail_msg("%s.%s has no row in the signal table", d->name, can_codec_sig(s)->name);
      }
    }
  }
}

static void test_frames_carry_the_table(void **state) {
  (void)state;
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 0u, false, 0.0f, 0.0f, 0.0f};
  hal_sil_init(&hal, &board);
  hal_sil_bind(&hal);
  drive_config_t cfg;
  drive_config_default(&cfg);
  assert_int_equal(drive_init(&drv, &cfg, NULL), 0);
  can_proto_cfg_t pc;
  can_proto_cfg_default(&pc);
  pc.node = 2;
  assert_int_equal(can_proto_init(&proto, &pc), 0);
  /* distinct values in the ISR's telemetry (no ISR runs: they stay) */
  drive_telemetry_t *tm = &drv.tm;
  tm->state = DRIVE_STATE_FAULT;
  tm->faults = 0x0205u;
  tm->v_dc = 301.3f;
  tm->i_abc[0] = 1.25f;
  tm->i_abc[1] = -2.5f;
  tm->i_abc[2] = 1.25f;
  tm->i_dq[0] = -0.75f;
  tm->i_dq[1] = 3.5f;
  tm->omega_m = 104.7f;
  tm->speed_ref = 99.0f;
  tm->torque_ref = 12.5f;
  tm->torque_est = 12.25f;
  tm->pos_health = 0.0125f;
  tm->load_est = -3.75f;
  tm->rls_ok = true;
  tm->law_tm.flux = 0.125f;
  tm->law_tm.flux_ref = 0.13f;
  tm->law_tm.delta = 0.5f;
  tm->law_tm.i_ds = 0.5f;
  tm->law_tm.i_qs = 7.5f;
  tm->law_tm.i_qs_ref = 8.0f;
  drive_background(&drv); /* the main loop's copy */
  const drive_signal_src_t src = {&drv, drive_telemetry(&drv)};
  assert_float_equal((float)src.tm->omega_m, 104.7f, 0.0f);
  can_proto_poll(&proto, &drv, 1000000u);
  unsigned checked = 0u, frames = 0u;
  hal_can_frame_t f;
  while (hal_sil_can_pop(&hal.can_tx, &f)) {
    const can_msg_t m = can_codec_lookup(f.id, false, 2);
    assert_true(m != CAN_MSG_COUNT);
    frames++;
    const can_msg_desc_t *d = can_codec_msg(m);
    for (unsigned i = 0u; i < d->n_signals; ++i) {
      const can_sig_t s = (can_sig_t)((unsigned)d->first + i);
      const drive_signal_t *row = drive_signal_of_can(s);
      if (row == NULL) {
        continue;
      }
      const double want = row->row.get(&src) * (double)row->can_scale;
      const double got = (double)can_codec_get(s, f.data);
      const double step = can_codec_sig(s)->is_float ? 0.0 : (double)can_codec_sig(s)->scale;
      if (fabs(got - want) > 0.5 * step + 1e-6 * fabs(want)) {
        fail_msg("%s.%s = %g, its row %s gives %g", d->name, can_codec_sig(s)->name, got,
                 row->row.name, want);
      }
      checked++;
    }
  }
  assert_true(frames >= 8u); /* STATUS, heartbeat and the TM_* frames, all due at the start */
  unsigned n, on_can = 0u;
  const drive_signal_t *t = drive_signals(&n);
  for (unsigned i = 0u; i < n; ++i) {
    on_can += t[i].can != CAN_SIG_NONE;
  }
  assert_int_equal(checked, on_can); /* every row on CAN was sent and checked */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_every_telemetry_signal_has_a_row),
      cmocka_unit_test(test_frames_carry_the_table),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
