/*
 * test_codec_proto.c - the CAN protocol on the SIL HAL: replies, bad DLC,
 * out-of-range values naming the signal, unknown identifiers, parameters,
 * the bounded receive (floods), lossless replies, and the command timeout
 * (ramp, then fault) timed to one slow period; identifications (CMD_PROC,
 * TM_PROC) and the timeout during one.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_codec.h"
#include "can_proto.h"
#include "drive.h"
#include "drive_params.h"
#include "hal_sil.h"

typedef struct {
  hal_sil_t hal;
  drive_t drv;
  can_proto_t p;
  can_proto_cfg_t pc;
  uint64_t k; /* ISR count */
} rig_t;

static rig_t rig; /* large: off the stack */

static void rig_init(void) {
  memset(&rig, 0, sizeof rig);
  const hal_sil_board_t board = {0.0f, 1.0f, 0u, 1e-6f, 62.5e-6f, 0u, false, 0.0f, 0.0f, 0.0f};
  hal_sil_init(&rig.hal, &board);
  hal_sil_bind(&rig.hal);
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.mode = DRIVE_MODE_SPEED;
  /* no machine behind the rig's samples: the position check would
   * (rightly) find the applied voltage unexplained */
  cfg.pos_emf_tol = 0.0f;
  assert_int_equal(drive_init(&rig.drv, &cfg, NULL), 0);
  can_proto_cfg_default(&rig.pc);
  rig.pc.node = 3;
  assert_int_equal(can_proto_init(&rig.p, &rig.pc), 0);
  rig.hal.sample.v_dc = 310.0f;
  rig.hal.sample.enc_valid = true;
  rig.hal.sample.valid = true;
}

/* One slow period: protocol + background service, then slow_div ISRs. */
static void slow_tick(void) {
  rig.hal.time_us = (uint32_t)(rig.k * 1000000ull / 16000ull);
  drive_background(&rig.drv);
  can_proto_poll(&rig.p, &rig.drv, rig.hal.time_us);
  for (unsigned i = 0; i < rig.drv.cfg.slow_div; ++i) {
    drive_isr(&rig.drv);
    rig.k++;
  }
}

static void push(can_msg_t m, uint8_t dlc, const uint8_t data[8]) {
  hal_can_frame_t f = {0};
  f.id = can_codec_id(m, 3);
  f.dlc = dlc;
  memcpy(f.data, data, 8);
  assert_true(hal_sil_can_push(&rig.hal.can_rx, &f));
}

static void push_speed(float rpm) {
  uint8_t d[8] = {0};
  can_codec_set(CAN_SIG_CMD_SPEED_RPM, d, rpm);
  push(CAN_MSG_CMD_SPEED, 4, d);
}

static void push_state(unsigned en, unsigned clear, unsigned mode, unsigned law) {
  uint8_t d[8] = {0};
  can_codec_set_raw(CAN_SIG_ENABLE, d, en);
  can_codec_set_raw(CAN_SIG_CLEAR_FAULT, d, clear);
  can_codec_set_raw(CAN_SIG_MODE, d, mode);
  can_codec_set_raw(CAN_SIG_LAW, d, law);
  push(CAN_MSG_CMD_STATE, 4, d);
}

static void push_param(unsigned op, unsigned id, float v) {
  uint8_t d[8] = {0};
  can_codec_set_raw(CAN_SIG_PARAM_OP, d, op);
  can_codec_set_raw(CAN_SIG_PARAM_ID, d, id);
  can_codec_set(CAN_SIG_PARAM_VALUE, d, v);
  push(CAN_MSG_PARAM_REQ, 8, d);
}

typedef struct {
  unsigned req, result, signal, param;
  float value;
} reply_t;

/* Pops TX frames; returns the replies (at most max) and counts others. */
static unsigned pop_replies(reply_t *r, unsigned max, unsigned *status_n) {
  hal_can_frame_t f;
  unsigned n = 0;
  while (hal_sil_can_pop(&rig.hal.can_tx, &f)) {
    assert_false(f.extended);
    if (f.id == can_codec_id(CAN_MSG_REPLY, 3)) {
      assert_int_equal(f.dlc, 8);
      assert_true(n < max);
      r[n].req = can_codec_get_raw(CAN_SIG_REPLY_REQ, f.data);
      r[n].result = can_codec_get_raw(CAN_SIG_REPLY_RESULT, f.data);
      r[n].signal = can_codec_get_raw(CAN_SIG_REPLY_SIGNAL, f.data);
      r[n].param = can_codec_get_raw(CAN_SIG_REPLY_PARAM, f.data);
      r[n].value = can_codec_get(CAN_SIG_REPLY_VALUE, f.data);
      n++;
    } else if (f.id == can_codec_id(CAN_MSG_STATUS, 3) && status_n != NULL) {
      (*status_n)++;
    }
  }
  return n;
}

static void test_unknown_and_other_nodes_ignored(void **state) {
  (void)state;
  rig_init();
  uint8_t d[8] = {0};
  can_codec_set(CAN_SIG_CMD_SPEED_RPM, d, 100.0f);
  hal_can_frame_t f = {0};
  memcpy(f.data, d, 8);
  f.dlc = 4;
  f.id = can_codec_id(CAN_MSG_CMD_SPEED, 2); /* another node */
  hal_sil_can_push(&rig.hal.can_rx, &f);
  f.id = 0x7FF;
  hal_sil_can_push(&rig.hal.can_rx, &f);
  f.id = can_codec_id(CAN_MSG_CMD_SPEED, 3);
  f.extended = true;
  hal_sil_can_push(&rig.hal.can_rx, &f);
  f.extended = false;
  f.id = can_codec_id(CAN_MSG_TM_SPEED, 3); /* a drive->host message */
  hal_sil_can_push(&rig.hal.can_rx, &f);
  slow_tick();
  reply_t r[4];
  assert_int_equal(pop_replies(r, 4, NULL), 0);
  assert_int_equal(rig.p.stats.rx_ignored, 4);
  assert_true(rig.drv.cmd.speed == 0.0f);
}

static void test_bad_dlc_rejected(void **state) {
  (void)state;
  rig_init();
  push_speed(100.0f);
  slow_tick();
  uint8_t d[8] = {0};
  can_codec_set(CAN_SIG_CMD_SPEED_RPM, d, 200.0f);
  push(CAN_MSG_CMD_SPEED, 8, d);
  push(CAN_MSG_CMD_SPEED, 3, d);
  push(CAN_MSG_PARAM_REQ, 0, d);
  slow_tick();
  reply_t r[8];
  unsigned n = pop_replies(r, 8, NULL);
  assert_int_equal(n, 4);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  for (unsigned i = 1; i < 4; ++i) {
    assert_int_equal(r[i].result, CAN_RESULT_BAD_DLC);
    assert_int_equal(r[i].signal, 0);
  }
  assert_int_equal(r[1].req, CAN_MSG_CMD_SPEED);
  assert_int_equal(r[3].req, CAN_MSG_PARAM_REQ);
  assert_float_equal(r[1].value, 0.0f, 1e-6f);
  /* the reference in force stays */
  assert_float_equal(rig.drv.cmd.speed * 9.54929659f, 100.0f, 1e-3f);
}

static void test_out_of_range_names_signal(void **state) {
  (void)state;
  rig_init();
  push_speed(150.0f);
  push_speed(1300.0f); /* above speed_max (1200 rpm) */
  uint8_t d[8] = {0};
  can_codec_set_raw(CAN_SIG_CMD_SPEED_RPM, d, (uint32_t)(int32_t)-20000001); /* beyond the DBC */
  push(CAN_MSG_CMD_SPEED, 4, d);
  push_state(1, 0, 7, CAN_KEEP); /* mode 7: no such mode */
  memset(d, 0, sizeof d);
  can_codec_set(CAN_SIG_CMD_TORQUE, d, 25.0f); /* above torque_max (20 N m) */
  push(CAN_MSG_CMD_TORQUE, 4, d);
  slow_tick();
  reply_t r[8];
  assert_int_equal(pop_replies(r, 8, NULL), 5);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_float_equal(r[0].value, 150.0f, 1e-3f);
  for (unsigned i = 1; i < 3; ++i) {
    assert_int_equal(r[i].result, CAN_RESULT_OUT_OF_RANGE);
    assert_int_equal(r[i].signal, CAN_SIG_CMD_SPEED_RPM + 1);
    assert_float_equal(r[i].value, 150.0f, 1e-3f); /* the reference in force */
  }
  assert_int_equal(r[3].result, CAN_RESULT_OUT_OF_RANGE);
  assert_int_equal(r[3].signal, CAN_SIG_MODE + 1);
  assert_false(rig.drv.cmd.enable); /* nothing of the bad frame applied */
  assert_int_equal(r[4].signal, CAN_SIG_CMD_TORQUE + 1);
  assert_float_equal(rig.drv.cmd.speed * 9.54929659f, 150.0f, 1e-3f);
  assert_true(rig.drv.cmd.torque == 0.0f);
  assert_int_equal(rig.p.stats.rx_errors, 4);
  assert_int_equal(rig.p.stats.rx_ok, 1);
}

static void test_params(void **state) {
  (void)state;
  rig_init();
  push_param(0, 31, 0.0f);   /* get speed_bw */
  push_param(1, 31, 40.0f);  /* set speed_bw */
  push_param(1, 10, 50.0f);  /* i_max 50 A > i_trip: inconsistent */
  push_param(1, 250, 1.0f);  /* unknown */
  push_param(1, 40, 1e-4f);  /* ts: read only */
  push_param(1, 2, -1.0f);   /* rs < 0: out of range */
  push_param(1, 65, 250.0f); /* can_timeout_ms */
  push_param(0, 64, 0.0f);   /* can_node */
  slow_tick();
  reply_t r[8];
  assert_int_equal(pop_replies(r, 8, NULL), 8);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_float_equal(r[0].value, 60.0f, 1e-6f);
  assert_int_equal(r[1].result, CAN_RESULT_OK);
  assert_float_equal(r[1].value, 40.0f, 1e-6f);
  assert_float_equal(rig.drv.cfg.speed_bw, 40.0f, 1e-6f);
  assert_float_equal(rig.drv.speed.cfg.kp, rig.drv.cfg.inertia * 40.0f, 1e-6f);
  assert_int_equal(r[2].result, CAN_RESULT_INCONSISTENT);
  assert_int_equal(r[2].param, 10);
  assert_int_equal(r[2].signal, CAN_SIG_PARAM_VALUE + 1);
  assert_float_equal(r[2].value, rig.drv.cfg.i_max, 1e-6f); /* unchanged */
  assert_int_equal(r[3].result, CAN_RESULT_UNKNOWN_PARAM);
  assert_int_equal(r[3].signal, CAN_SIG_PARAM_ID + 1);
  assert_int_equal(r[4].result, CAN_RESULT_READ_ONLY);
  assert_int_equal(r[5].result, CAN_RESULT_OUT_OF_RANGE);
  assert_int_equal(r[6].result, CAN_RESULT_OK);
  assert_int_equal(rig.p.cfg.timeout_ms, 250);
  assert_float_equal(r[7].value, 3.0f, 1e-6f);
}

static void run_until_state(drive_state_t st, unsigned max_ticks) {
  for (unsigned i = 0; i < max_ticks && rig.drv.state != st; ++i) {
    push_param(0, 31, 0.0f); /* keeps the host alive */
    slow_tick();
  }
  assert_int_equal(rig.drv.state, st);
}

static void test_idle_only_params_refused_while_running(void **state) {
  (void)state;
  rig_init();
  push_state(1, 0, CAN_KEEP, CAN_KEEP);
  run_until_state(DRIVE_STATE_RUN, 100);
  reply_t r[64];
  pop_replies(r, 64, NULL);
  push_param(1, 2, 8.0f);   /* rs: idle only */
  push_param(1, 11, 10.0f); /* torque_max: live */
  slow_tick();
  assert_int_equal(pop_replies(r, 64, NULL), 2);
  assert_int_equal(r[0].result, CAN_RESULT_NOT_WHILE_RUNNING);
  assert_float_equal(rig.drv.cfg.rs, 7.1f, 1e-6f);
  assert_int_equal(r[1].result, CAN_RESULT_OK);
  assert_float_equal(rig.drv.speed.cfg.torque_max, 10.0f, 1e-6f);
  assert_int_equal(rig.drv.state, DRIVE_STATE_RUN);
}

static void test_flood_bounded_per_poll(void **state) {
  (void)state;
  rig_init();
  for (unsigned i = 0; i < 200; ++i) {
    push_speed(10.0f);
  }
  rig.hal.time_us = 0;
  can_proto_poll(&rig.p, &rig.drv, 0);
  assert_int_equal(rig.p.stats.rx_frames, CAN_PROTO_RX_MAX);
  assert_int_equal(rig.hal.can_rx.head - rig.hal.can_rx.tail, 200 - CAN_PROTO_RX_MAX);
}

static void test_replies_never_lost_on_full_tx(void **state) {
  (void)state;
  rig_init();
  hal_can_frame_t junk = {0};
  while (hal_sil_can_push(&rig.hal.can_tx, &junk)) {
  }
  for (unsigned i = 0; i < 40; ++i) {
    push_speed((float)i);
  }
  unsigned replies = 0;
  reply_t r[64];
  for (unsigned t = 0; t < 400 && replies < 40; ++t) {
    slow_tick();
    hal_can_frame_t f;
    /* the host reads a few frames per period */
    for (unsigned j = 0; j < 16 && hal_sil_can_pop(&rig.hal.can_tx, &f); ++j) {
      if (f.id == can_codec_id(CAN_MSG_REPLY, 3)) {
        replies++;
      }
    }
    if (rig.hal.can_tx.head - rig.hal.can_tx.tail < HAL_SIL_CAN_QUEUE / 2) {
      replies += pop_replies(r, 64, NULL);
    }
  }
  assert_int_equal(replies, 40);
  assert_int_equal(rig.p.stats.rx_ok, 40);
  assert_float_equal(rig.drv.cmd.speed * 9.54929659f, 39.0f, 1e-3f);
}

/* Silence while running: ramp at timeout_ms, fault at timeout_ms + ramp_ms,
 * both to one slow period. */
static void test_command_timeout(void **state) {
  (void)state;
  rig_init();
  rig.p.cfg.timeout_ms = 300;
  rig.p.cfg.ramp_ms = 100;
  push_state(1, 0, 0, CAN_KEEP); /* enable, torque mode */
  uint8_t d[8] = {0};
  can_codec_set(CAN_SIG_CMD_TORQUE, d, 4.0f);
  push(CAN_MSG_CMD_TORQUE, 4, d);
  run_until_state(DRIVE_STATE_RUN, 100);
  for (unsigned i = 0; i < 20; ++i) {
    push_param(0, 31, 0.0f);
    slow_tick();
  }
  assert_float_equal(rig.drv.tm.torque_ref, 4.0f, 1e-6f);
  reply_t r[256];
  pop_replies(r, 256, NULL);
  const uint32_t last = rig.p.last_rx_us;
  uint32_t t_ramp = 0, t_fault = 0;
  float prev_torque = 4.0f;
  for (unsigned i = 0; i < 1000 && t_fault == 0u; ++i) {
    slow_tick();
    if (rig.p.ramp && t_ramp == 0u) {
      t_ramp = rig.hal.time_us;
    }
    if (t_ramp != 0u && rig.drv.state == DRIVE_STATE_RUN) {
      assert_true(rig.drv.tm.torque_ref <= prev_torque + 1e-6f);
      prev_torque = rig.drv.tm.torque_ref;
    }
    if (rig.drv.state == DRIVE_STATE_FAULT) {
      t_fault = rig.hal.time_us;
    }
  }
  assert_true(t_ramp > 0u && t_fault > 0u);
  assert_true(abs((int)(t_ramp - last) - 300000) <= 1000);
  assert_true(abs((int)(t_fault - last) - 400000) <= 1000);
  assert_true(prev_torque < 0.1f); /* ramped down before the gates went off */
  assert_int_equal(rig.drv.faults, DRIVE_FAULT_CMD_TIMEOUT);
  assert_false(rig.hal.gates_on);
  assert_int_equal(rig.p.stats.timeouts, 1);
  /* STATUS was sent at once on the ramp and on the fault */
  unsigned status_n = 0;
  pop_replies(r, 256, &status_n);
  assert_true(status_n >= 2);
  /* clear + enable restarts from rest in the previous mode */
  push_state(CAN_KEEP, 1, CAN_KEEP, CAN_KEEP);
  slow_tick();
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  assert_true(rig.drv.cmd.torque == 0.0f);
  assert_int_equal(rig.drv.cmd.mode, DRIVE_MODE_TORQUE);
}

static void test_no_timeout_when_idle_or_off(void **state) {
  (void)state;
  rig_init();
  for (unsigned i = 0; i < 2000; ++i) {
    slow_tick();
  }
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(rig.p.stats.timeouts, 0);
  rig_init();
  rig.p.cfg.timeout_ms = 0;
  push_state(1, 0, CAN_KEEP, CAN_KEEP);
  for (unsigned i = 0; i < 2000; ++i) {
    slow_tick();
  }
  assert_int_equal(rig.drv.state, DRIVE_STATE_RUN);
}

static void test_telemetry_rates(void **state) {
  (void)state;
  rig_init();
  rig.p.cfg.period_ms[CAN_PERIOD_TM_SPEED] = 5;
  rig.p.cfg.period_ms[CAN_PERIOD_TM_FLUX] = 0;
  unsigned n_speed = 0, n_flux = 0, n_hb = 0;
  for (unsigned i = 0; i < 1000; ++i) {
    slow_tick();
    hal_can_frame_t f;
    while (hal_sil_can_pop(&rig.hal.can_tx, &f)) {
      n_speed += f.id == can_codec_id(CAN_MSG_TM_SPEED, 3);
      n_flux += f.id == can_codec_id(CAN_MSG_TM_FLUX, 3);
      n_hb += f.id == can_codec_id(CAN_MSG_HEARTBEAT, 3);
      assert_int_equal(f.dlc, can_codec_msg(can_codec_lookup(f.id, false, 3))->dlc);
    }
  }
  assert_int_equal(n_speed, 200); /* 1 s at 5 ms */
  assert_int_equal(n_flux, 0);
  assert_int_equal(n_hb, 2); /* 500 ms */
}

/* CMD_STATE: the keep value is outside every law and mode; a law the
 * machine cannot run is "unavailable" and nothing of the frame applies. */
static void test_keep_and_unavailable_law(void **state) {
  (void)state;
  rig_init();
  push_state(CAN_KEEP, 0, CAN_KEEP, 1);               /* pi_dfvc: available on the SPM default */
  push_state(CAN_KEEP, 0, CAN_KEEP, DRIVE_LAW_COUNT); /* no such law */
  push_param(1, 4, 0.1f); /* lq = 0.1 H with a DFVC law commanded: refused */
  slow_tick();
  reply_t r[8];
  assert_int_equal(pop_replies(r, 8, NULL), 3);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_int_equal(rig.drv.ctrl.law, DRIVE_LAW_PI_DFVC);
  assert_int_equal(r[1].result, CAN_RESULT_OUT_OF_RANGE);
  assert_int_equal(r[1].signal, CAN_SIG_LAW + 1);
  assert_int_equal(r[2].result, CAN_RESULT_INCONSISTENT);
  /* back to FOC, then the saliency is accepted and the DFVC laws are not */
  push_state(CAN_KEEP, 0, CAN_KEEP, 0);
  push_param(1, 4, 0.1f);
  push_state(1, 0, CAN_KEEP, 2); /* enable with db_dfvc: unavailable, not enabled */
  slow_tick();
  assert_int_equal(pop_replies(r, 8, NULL), 3);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_int_equal(r[1].result, CAN_RESULT_OK);
  assert_int_equal(r[2].result, CAN_RESULT_UNAVAILABLE);
  assert_int_equal(r[2].signal, CAN_SIG_LAW + 1);
  assert_int_equal(rig.drv.ctrl.law, DRIVE_LAW_FOC);
  assert_int_equal(rig.drv.cmd.enable, 0);
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  assert_float_equal(rig.drv.cfg.lq, 0.1f, 0.0f);
}

static uint8_t pid(const char *name) {
  const drive_param_t *p = drive_params_by_name(name);
  assert_non_null(p);
  return p->id;
}

/* A NaN or inf value is refused naming the parameter it was for, with the
 * value in force (issue 22, point 7: it was parameter 0, value 0, and the
 * host matched no reply). */
static void test_non_finite_value_names_the_parameter(void **state) {
  (void)state;
  rig_init();
  const float bad[3] = {NAN, INFINITY, -INFINITY};
  for (unsigned i = 0; i < 3; ++i) {
    push_param(1, pid("i_trip"), bad[i]);
  }
  push_param(1, CAN_PROTO_PARAM_FIRST + 1u, NAN); /* a protocol parameter too */
  slow_tick();
  reply_t r[8];
  assert_int_equal(pop_replies(r, 8, NULL), 4);
  for (unsigned i = 0; i < 3; ++i) {
    assert_int_equal(r[i].result, CAN_RESULT_OUT_OF_RANGE);
    assert_int_equal(r[i].param, pid("i_trip"));
    assert_int_equal(r[i].signal, CAN_SIG_PARAM_VALUE + 1);
    assert_float_equal(r[i].value, rig.drv.cfg.i_trip, 0.0f);
  }
  assert_int_equal(r[3].result, CAN_RESULT_OUT_OF_RANGE);
  assert_int_equal(r[3].param, CAN_PROTO_PARAM_FIRST + 1u);
  assert_float_equal(r[3].value, (float)rig.p.cfg.timeout_ms, 0.0f);
}

/* Runs n slow periods keeping the host alive; no fault may appear. */
static void idle_ticks(unsigned n) {
  for (unsigned i = 0; i < n; ++i) {
    slow_tick();
    assert_int_equal(rig.drv.faults, 0u);
  }
}

/* In idle, switches to `law` (accepted) and writes `name` = v, which that
 * law refuses: answered inconsistent naming the parameter, and the reason
 * names it too. */
static void write_refused_under(drive_law_t law, const char *name, float v) {
  reply_t r[8];
  push_state(CAN_KEEP, 0, CAN_KEEP, law);
  push_param(1, pid(name), v);
  slow_tick();
  assert_int_equal(pop_replies(r, 8, NULL), 2);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_int_equal(rig.drv.ctrl.law, law);
  assert_int_equal(r[1].result, CAN_RESULT_INCONSISTENT);
  assert_int_equal(r[1].param, pid(name));
  drive_config_err_t err;
  assert_int_equal(drive_params_set(&rig.drv, pid(name), v, &err), DRIVE_PARAM_INCONSISTENT);
  assert_non_null(strstr(err.reason, name));
}

/* In idle, `from` in force with `name` = v (both accepted), then a switch
 * to `to`, which refuses that set: answered unavailable naming the law
 * signal, and `from` stays in force and commanded. */
static void switch_refused_after(drive_law_t from, const char *name, float v, drive_law_t to) {
  reply_t r[8];
  push_state(CAN_KEEP, 0, CAN_KEEP, from);
  push_param(1, pid(name), v);
  push_state(CAN_KEEP, 0, CAN_KEEP, to);
  slow_tick();
  assert_int_equal(pop_replies(r, 8, NULL), 3);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_int_equal(r[1].result, CAN_RESULT_OK);
  assert_int_equal(r[2].result, CAN_RESULT_UNAVAILABLE);
  assert_int_equal(r[2].signal, CAN_SIG_LAW + 1);
  assert_int_equal(rig.drv.ctrl.law, from);
  assert_int_equal(drive_commands(&rig.drv)->law, from);
}

/* What is acknowledged is never refused later (issue 22, points 4 and 5),
 * on a board without the star-point window (this rig's, like the ESC1):
 * every write and law switch is answered with its verdict, the GET reports
 * the set in force, enable / disable cycles after it never trip config. */
static void test_acknowledged_writes_never_trip_later(void **state) {
  (void)state;
  rig_init();
  reply_t r[128];
  /* pos_source = dfc after align_time = 0.5: refused, naming it */
  push_param(1, pid("align_time"), 0.5f);
  push_param(1, pid("pos_source"), (float)POS_SOURCE_DFC);
  push_param(0, pid("pos_source"), 0.0f);
  slow_tick();
  assert_int_equal(pop_replies(r, 128, NULL), 3);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_int_equal(r[1].result, CAN_RESULT_INCONSISTENT);
  assert_int_equal(r[1].param, pid("pos_source"));
  assert_float_equal(r[1].value, (float)POS_SOURCE_ENCODER, 0.0f);
  assert_float_equal(r[2].value, (float)POS_SOURCE_ENCODER, 0.0f);
  drive_config_err_t err;
  assert_int_equal(drive_params_set(&rig.drv, pid("pos_source"), (float)POS_SOURCE_DFC, &err),
                   DRIVE_PARAM_INCONSISTENT);
  assert_string_equal(err.field, "pos_source");
  assert_non_null(strstr(err.reason, "star-point"));
  idle_ticks(20);
  push_param(1, pid("align_time"), 0.0f);
  slow_tick();
  assert_int_equal(pop_replies(r, 128, NULL), 1);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  /* DB-DFVC: vsd_max = 0 refused (its deadbeat needs a d_s voltage limit) */
  write_refused_under(DRIVE_LAW_DB_DFVC, "vsd_max", 0.0f);
  /* the decoupled DFVC: flux_min = 5 Vs (beyond the flux at i_max) refused */
  write_refused_under(DRIVE_LAW_DFVC_DECOUPLED, "flux_min", 5.0f);
  /* ... and flux_min = 1.76 under DB-DFVC is fine there, but a switch to
   * the decoupled DFVC with it is unavailable (point 2's sequence) */
  switch_refused_after(DRIVE_LAW_DB_DFVC, "flux_min", 1.76f, DRIVE_LAW_DFVC_DECOUPLED);
  push_param(1, pid("flux_min"), 0.038f);
  slow_tick();
  assert_int_equal(pop_replies(r, 128, NULL), 1);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  /* FOC: vsd_max = 0 is fine, the switch to DB-DFVC is unavailable and FOC
   * stays (point 5: it was answered ok, FOC stayed and the next write
   * tripped config) */
  switch_refused_after(DRIVE_LAW_FOC, "vsd_max", 0.0f, DRIVE_LAW_DB_DFVC);
  /* later writes and enable / disable cycles: nothing trips */
  push_param(1, pid("i_max"), 4.0f);
  idle_ticks(5);
  for (unsigned c = 0; c < 3; ++c) {
    push_state(1, 0, CAN_KEEP, CAN_KEEP);
    run_until_state(DRIVE_STATE_RUN, 100);
    push_state(0, 0, CAN_KEEP, CAN_KEEP);
    idle_ticks(3);
    push_param(1, pid("speed_bw"), 30.0f + (float)c);
    idle_ticks(3);
    pop_replies(r, 128, NULL);
  }
  pop_replies(r, 128, NULL);
  assert_float_equal(rig.drv.cfg.i_max, 4.0f, 0.0f);
  assert_int_equal(rig.drv.cfg.pos_source, POS_SOURCE_ENCODER);
}

/* The last STATUS frame's cmd_enabled and state (-1: none sent). */
static int g_cmd_enabled, g_state;
static void drain_status(void) {
  hal_can_frame_t f;
  while (hal_sil_can_pop(&rig.hal.can_tx, &f)) {
    if (f.id == can_codec_id(CAN_MSG_STATUS, 3)) {
      g_cmd_enabled = (int)can_codec_get_raw(CAN_SIG_CMD_ENABLED, f.data);
      g_state = (int)can_codec_get_raw(CAN_SIG_STATE, f.data);
    }
  }
}

static void status_ticks(unsigned n) {
  for (unsigned i = 0; i < n; ++i) {
    push_param(0, 31, 0.0f); /* keeps the host alive */
    slow_tick();
    drain_status();
  }
}

/* The enable / clear / keep state machine over CAN (docs/can.md, "Enable
 * and clear"; issue 22, point 6), every transition of its table in one
 * sequence, with STATUS (state, cmd_enabled) as the host sees it. */
static void test_enable_clear_keep_over_can(void **state) {
  (void)state;
  enum { K = CAN_KEEP, RUN = DRIVE_STATE_RUN, IDLE = DRIVE_STATE_IDLE, FLT = DRIVE_STATE_FAULT };
  static const struct {
    bool trip;          /* the main loop posts a fault first */
    unsigned en, clear; /* the CMD_STATE frame (en K and clear 0: none) */
    int state, enabled; /* STATUS 40 slow periods later */
  } steps[] = {
      {false, 1, 0, RUN, 1},  /* idle, armed + enable: runs */
      {false, K, 1, RUN, 1},  /* running + {keep, clear}: nothing changes */
      {false, 1, 1, RUN, 1},  /* running + {1, clear}: nothing changes */
      {true, K, 0, FLT, 0},   /* a trip: the enable is no longer in force */
      {false, 1, 1, RUN, 1},  /* fault + {1, clear}: restarts (the enable after the clear) */
      {true, K, 1, IDLE, 0},  /* fault + {keep, clear}: idle, not armed, and stays so */
      {false, 1, 0, RUN, 1},  /* ... until an enable = 1 (no enable = 0 needed) */
      {true, 1, 0, FLT, 0},   /* fault + enable without a clear: still the fault */
      {false, K, 1, IDLE, 0}, /* ... and that enable does not count after the clear */
      {false, 1, 0, RUN, 1},  {true, 0, 1, IDLE, 0},  /* fault + {0, clear}: idle, not armed */
      {false, 1, 0, RUN, 1},  {false, 0, 0, IDLE, 0}, /* running + enable = 0: idle */
      {false, 0, 1, IDLE, 0},                         /* idle + {0, clear}: nothing */
      {false, K, 0, IDLE, 0},                         /* keep: nothing */
  };
  rig_init();
  rig.p.cfg.period_ms[CAN_PERIOD_STATUS] = 1u;
  for (size_t n = 0; n < sizeof steps / sizeof steps[0]; ++n) {
    if (steps[n].trip) {
      drive_request_fault(&rig.drv, DRIVE_FAULT_CONTROL);
      status_ticks(2);
      assert_int_equal(g_state, FLT);
    }
    if (steps[n].en != K || steps[n].clear != 0u) {
      push_state(steps[n].en, steps[n].clear, K, K);
      slow_tick();
      reply_t r[64];
      assert_int_equal(pop_replies(r, 64, NULL), 1);
      assert_int_equal(r[0].result, CAN_RESULT_OK);
    }
    g_cmd_enabled = g_state = -1;
    status_ticks(40);
    printf("step %zu: state %d, cmd_enabled %d\n", n, g_state, g_cmd_enabled);
    assert_int_equal(g_state, steps[n].state);
    assert_int_equal(g_cmd_enabled, steps[n].enabled);
    assert_true(rig.hal.gates_on == (steps[n].state == RUN));
  }
}

/* Every main-loop fault request survives a clear frame in the same slow
 * period, before and after it (issue 22, point 3). */
static void test_clear_frames_keep_fault_requests(void **state) {
  (void)state;
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    rig_init();
    push_state(1, 0, CAN_KEEP, CAN_KEEP);
    run_until_state(DRIVE_STATE_RUN, 100);
    /* the main loop posts its request, then the flood's frame is handled */
    drive_request_fault(&rig.drv, 1u << b);
    push_state(1, 1, CAN_KEEP, CAN_KEEP);
    slow_tick();
    assert_int_equal(rig.drv.faults, 1u << b);
    assert_int_equal(rig.drv.state, DRIVE_STATE_FAULT);
    assert_false(rig.hal.gates_on);
  }
}

static void push_proc(unsigned v) {
  uint8_t d[8] = {0};
  can_codec_set_raw(CAN_SIG_CMD_PROC, d, v);
  push(CAN_MSG_CMD_PROC, 1, d);
}

/* The TM_PROC frames sent since the last pop: the results by index, how
 * many, and the last id and status. */
typedef struct {
  float result[PROC_RESULTS];
  unsigned n, id, status, index_prev;
  bool cycled; /* every frame's index one past the one before (mod 8) */
} tm_proc_t;

static void pop_tm_proc(tm_proc_t *t) {
  hal_can_frame_t f;
  while (hal_sil_can_pop(&rig.hal.can_tx, &f)) {
    if (f.id != can_codec_id(CAN_MSG_TM_PROC, 3)) {
      continue;
    }
    assert_int_equal(f.dlc, 8);
    const unsigned k = can_codec_get_raw(CAN_SIG_PROC_INDEX, f.data);
    assert_true(k < PROC_RESULTS);
    if (t->n > 0u && k != (t->index_prev + 1u) % PROC_RESULTS) {
      t->cycled = false;
    }
    t->index_prev = k;
    t->result[k] = can_codec_get(CAN_SIG_PROC_RESULT, f.data);
    t->id = can_codec_get_raw(CAN_SIG_PROC_ID, f.data);
    t->status = can_codec_get_raw(CAN_SIG_PROC_STATUS, f.data);
    t->n++;
  }
}

/* CMD_PROC: refusals naming the signal, the offsets run alone and stopped,
 * their results in TM_PROC (index cycling, one per frame, every 10 ms). */
static void test_proc_over_can(void **state) {
  (void)state;
  rig_init();
  const float off[3] = {0.25f, -0.5f, 0.25f};
  memcpy(rig.hal.sample.i_abc, off, sizeof off);
  reply_t r[64];
  tm_proc_t t = {.cycled = true};
  slow_tick();
  pop_tm_proc(&t);
  assert_int_equal(t.n, 1);
  assert_int_equal(t.id, CAN_PROC_NONE); /* none since start-up */
  assert_int_equal(t.status, PROC_ST_IDLE);
  push_proc(PROC_ALIGN);                      /* not an identification */
  push_proc(PROC_COUNT);                      /* no such procedure */
  push_proc(CAN_PROC_NONE);                   /* a stop with none running: ok */
  push(CAN_MSG_CMD_PROC, 2, (uint8_t[8]){0}); /* bad DLC */
  slow_tick();
  assert_int_equal(pop_replies(r, 64, NULL), 4);
  for (unsigned i = 0; i < 4; ++i) {
    assert_int_equal(r[i].req, CAN_MSG_CMD_PROC);
    if (i < 3u) { /* the identification asked for: none (a bad DLC reports nothing) */
      assert_float_equal(r[i].value, (float)CAN_PROC_NONE, 0.0f);
    }
  }
  assert_int_equal(r[0].result, CAN_RESULT_UNAVAILABLE);
  assert_int_equal(r[0].signal, CAN_SIG_CMD_PROC + 1u);
  assert_int_equal(r[1].result, CAN_RESULT_OUT_OF_RANGE);
  assert_int_equal(r[1].signal, CAN_SIG_CMD_PROC + 1u);
  assert_int_equal(r[2].result, CAN_RESULT_OK);
  assert_int_equal(r[3].result, CAN_RESULT_BAD_DLC);
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  /* the offsets over 256 samples (16 ms): running, then done */
  push_proc(PROC_OFFSET);
  slow_tick();
  assert_int_equal(pop_replies(r, 64, NULL), 1);
  assert_int_equal(r[0].result, CAN_RESULT_OK);
  assert_float_equal(r[0].value, (float)PROC_OFFSET, 0.0f);
  assert_int_equal(rig.drv.state, DRIVE_STATE_OFFSET_CAL);
  memset(&t, 0, sizeof t);
  t.cycled = true;
  bool saw_running = false;
  for (unsigned i = 0; i < 100; ++i) {
    push_param(0, 31, 0.0f);
    slow_tick();
    pop_tm_proc(&t);
    saw_running |= t.status == PROC_ST_RUNNING;
  }
  assert_true(saw_running);
  assert_int_equal(t.n, 10); /* 100 ms at 10 ms */
  assert_true(t.cycled);
  assert_int_equal(t.id, PROC_OFFSET);
  assert_int_equal(t.status, PROC_ST_DONE);
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  for (unsigned k = 0; k < PROC_RESULTS; ++k) {
    assert_float_equal(t.result[k], rig.drv.tm.proc.result[k], 0.0f);
    assert_float_equal(t.result[k], k < 3u ? off[k] : 0.0f, 1e-6f);
  }
  /* stopped while it runs (offset_samples 60000: 3.75 s) */
  push_param(1, 43, 60000.0f);
  slow_tick();
  push_proc(PROC_OFFSET);
  for (unsigned i = 0; i < 10; ++i) {
    slow_tick();
  }
  assert_int_equal(rig.drv.state, DRIVE_STATE_OFFSET_CAL);
  push_proc(CAN_PROC_NONE);
  slow_tick();
  slow_tick();
  assert_int_equal(rig.drv.state, DRIVE_STATE_IDLE);
  assert_int_equal(rig.drv.tm.proc.status, PROC_ST_ABORTED);
  pop_replies(r, 64, NULL);
  /* refused while the drive is enabled, naming the enable */
  push_state(1, 0, CAN_KEEP, CAN_KEEP);
  push_proc(PROC_OFFSET);
  slow_tick();
  assert_int_equal(pop_replies(r, 64, NULL), 2);
  assert_int_equal(r[1].result, CAN_RESULT_NOT_WHILE_RUNNING);
  assert_int_equal(r[1].signal, CAN_SIG_ENABLE + 1u);
}

/* A lost link during an identification: no torque ramp, the fault at
 * timeout_ms (to one slow period), gates off, the procedure aborted. */
static void test_proc_command_timeout(void **state) {
  (void)state;
  rig_init();
  rig.p.cfg.timeout_ms = 300;
  rig.p.cfg.ramp_ms = 100;
  push_param(1, 43, 60000.0f); /* offset_samples: 3.75 s */
  slow_tick();
  push_proc(PROC_OFFSET);
  slow_tick();
  assert_int_equal(rig.drv.state, DRIVE_STATE_OFFSET_CAL);
  const uint32_t last = rig.p.last_rx_us;
  uint32_t t_fault = 0;
  for (unsigned i = 0; i < 1000 && t_fault == 0u; ++i) {
    slow_tick();
    assert_false(rig.p.ramp);
    if (rig.drv.state == DRIVE_STATE_FAULT) {
      t_fault = rig.hal.time_us;
    }
  }
  assert_true(t_fault > 0u);
  assert_true(abs((int)(t_fault - last) - 300000) <= 1000);
  assert_int_equal(rig.drv.faults, DRIVE_FAULT_CMD_TIMEOUT);
  assert_false(rig.hal.gates_on);
  assert_int_equal(rig.drv.tm.proc.status, PROC_ST_ABORTED);
  assert_int_equal(rig.p.stats.timeouts, 1);
  for (unsigned i = 0; i < 100; ++i) { /* and stays there */
    slow_tick();
  }
  assert_int_equal(rig.drv.state, DRIVE_STATE_FAULT);
  assert_int_equal(rig.p.stats.timeouts, 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_unknown_and_other_nodes_ignored),
      cmocka_unit_test(test_bad_dlc_rejected),
      cmocka_unit_test(test_out_of_range_names_signal),
      cmocka_unit_test(test_params),
      cmocka_unit_test(test_idle_only_params_refused_while_running),
      cmocka_unit_test(test_flood_bounded_per_poll),
      cmocka_unit_test(test_replies_never_lost_on_full_tx),
      cmocka_unit_test(test_command_timeout),
      cmocka_unit_test(test_no_timeout_when_idle_or_off),
      cmocka_unit_test(test_telemetry_rates),
      cmocka_unit_test(test_keep_and_unavailable_law),
      cmocka_unit_test(test_non_finite_value_names_the_parameter),
      cmocka_unit_test(test_acknowledged_writes_never_trip_later),
      cmocka_unit_test(test_enable_clear_keep_over_can),
      cmocka_unit_test(test_clear_frames_keep_fault_requests),
      cmocka_unit_test(test_proc_over_can),
      cmocka_unit_test(test_proc_command_timeout),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
