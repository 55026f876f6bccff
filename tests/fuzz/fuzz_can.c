/*
 * fuzz_can.c - libFuzzer harness: the CAN codec and protocol
 * (can_codec.c, can_proto.c) driving the real drive (drive.c, the law
 * table, the position source) on the SIL HAL and the plant, stepped as
 * sil_run.c's CAN path does (main loop every slow_div periods:
 * drive_background, can_proto_poll; then sample, ISR, plant).
 *
 * The input is a sequence of operations (docs/fuzzing.md): CAN frames for
 * the drive's node (a message of the protocol, its DLC right or given;
 * CMD_PROC's identifications too, stopped by a timeout, an enable or a stop),
 * raw frames (any identifier, standard or extended, any DLC), time
 * advances (ISR periods, main-loop periods), typed parameter writes, and
 * a switch that stops draining the TX queue (a blocked bus). Checked after
 * every step, __builtin_trap() on a violation (a message first):
 *   - every CMD_* (CMD_PROC too) and PARAM_REQ frame for the node gets exactly one REPLY,
 *     in order, answering its request (reply_req), bad_dlc when and only
 *     when its DLC is wrong; no REPLY without a request; all replies out by
 *     the end;
 *   - the references the drive runs on are finite and within the limits in
 *     force: torque reference within torque_max, in current mode
 *     |(i_d, i_q)| within i_max, the ramped speed reference within
 *     speed_max or approaching it (it starts from the measured speed and
 *     follows a lowered speed_max at accel_max);
 *   - the gates are off in idle, offset calibration and fault;
 *   - the watchdog never expires (both loops run);
 *   - after the last frame, while the drive is enabled, the command
 *     timeout turns the gates off within can_timeout_ms + can_ramp_ms
 *     (+ two slow periods: the protocol's resolution, the ISR's latency).
 * The harness's protocol starts with a 50 ms timeout and a 20 ms ramp
 * (inputs stay short); an input may set others over CAN, and the final
 * check runs when their sum is at most FINAL_MAX_MS.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_codec.h"
#include "can_proto.h"
#include "drive.h"
#include "drive_params.h"
#include "sil_run.h"

#ifndef FD_SOURCE_DIR
#define FD_SOURCE_DIR "."
#endif

#define NODE           1u
#define MAX_PERIODS    32000u /* simulated time per input: 2 s at 16 kHz */
#define FINAL_MAX_MS   250u   /* the final timeout check up to this timeout + ramp */
#define REQ_QUEUE      1024u  /* requests awaiting their reply */
#define REL_TOL        1e-5f  /* float rounding of a limit */
#define CAN_BASE_CMD   0x100u /* CMD_STATE; CMD_* and PARAM_REQ every 0x10 */
#define CAN_BASE_HB    0x160u
#define CAN_BASE_PROC  0x170u /* CMD_PROC */
#define CAN_BASE_REPLY 0x180u

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static scenario_t sc;
static sil_ctx_t x; /* large: off the stack */
static can_proto_t proto;

typedef struct {
  const uint8_t *p;
  size_t n;
} input_t;

static struct {
  uint64_t k; /* ISR periods */
  bool tx_blocked;
  uint8_t req[REQ_QUEUE]; /* reply_req expected, in order */
  uint8_t bad_dlc[REQ_QUEUE];
  uint32_t head, tail;
  uint32_t rx_tail_seen; /* the HAL's RX queue tail at the last poll */
  uint32_t last_rx_us;   /* last poll that took a frame */
  uint32_t states;       /* drive states seen (bit per state) */
  float speed_ref_prev;  /* the ramped speed reference of the last ISR */
  bool speed_loop_prev;  /* and whether the speed loop ran then */
  bool last_rx_any;      /* a frame was taken since the start */
} st;

static void violated(const char *what) {
  const drive_telemetry_t *tm = &x.drv.tm;
  fprintf(stderr,
          "fuzz_can: invariant violated: %s (t = %.6f s, state %d, faults 0x%x, gates %d; "
          "torque ref %g / max %g N m, speed ref %g (before %g) / max %g / measured %g rad/s, "
          "i_ref (%g, %g) / max %g A)\n",
          what, (double)st.k * sc.plant.ts, (int)x.drv.state, (unsigned)x.drv.faults,
          (int)x.hal.gates_on, (double)tm->torque_ref, (double)x.drv.cfg.torque_max,
          (double)tm->speed_ref, (double)st.speed_ref_prev, (double)x.drv.cfg.speed_max,
          (double)tm->omega_m, (double)x.drv.cmd.id, (double)x.drv.cmd.iq, (double)x.drv.cfg.i_max);
  __builtin_trap();
}

static uint8_t take(input_t *in) {
  if (in->n == 0u) {
    return 0u;
  }
  const uint8_t b = in->p[0];
  in->p++;
  in->n--;
  return b;
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
  char err[512];
  if (scenario_load_file(FD_SOURCE_DIR "/sil/scenarios/can_demo.json", &sc, err, sizeof err) != 0) {
    fprintf(stderr, "fuzz_can: %s\n", err);
    abort();
  }
  return 0;
}

/* The reply a frame for the node asks for: its reply_req, or -1 (none). */
static int expected_req(const hal_can_frame_t *f) {
  if (!f->extended && f->id == CAN_BASE_PROC + NODE) {
    return (int)CAN_MSG_CMD_PROC; /* after HOST_HB, answered */
  }
  if (f->extended || f->id < CAN_BASE_CMD + NODE || f->id >= CAN_BASE_HB + NODE) {
    return -1;
  }
  const uint32_t off = f->id - CAN_BASE_CMD - NODE;
  return off % 0x10u == 0u ? (int)(off / 0x10u) : -1;
}

static void push_frame(const hal_can_frame_t *f) {
  if (!hal_sil_can_push(&x.hal.can_rx, f)) {
    return; /* the bus lost it: no reply owed */
  }
  const int r = expected_req(f);
  if (r < 0) {
    return;
  }
  /* by reply_req (docs/can.md); HOST_HB (6) is never answered, CMD_PROC is 7 */
  static const uint8_t dlc[] = {4u, 4u, 4u, 8u, 4u, 8u, 1u, 1u};
  _Static_assert(CAN_MSG_CMD_PROC == 7, "reply_req of CMD_PROC");
  if (st.head - st.tail >= REQ_QUEUE) {
    violated("more requests outstanding than the harness tracks");
  }
  st.req[st.head % REQ_QUEUE] = (uint8_t)r;
  st.bad_dlc[st.head % REQ_QUEUE] = f->dlc != dlc[r];
  st.head++;
}

/* Drains the TX queue (unless blocked), matching replies to requests. */
static void drain_tx(void) {
  if (st.tx_blocked) {
    return;
  }
  hal_can_frame_t f;
  while (hal_sil_can_pop(&x.hal.can_tx, &f)) {
    if (f.id != CAN_BASE_REPLY + NODE) {
      continue;
    }
    if (f.extended || f.dlc != 8u) {
      violated("REPLY frame malformed");
    }
    if (st.head == st.tail) {
      violated("REPLY without a request");
    }
    const uint32_t req = can_codec_get_raw(CAN_SIG_REPLY_REQ, f.data);
    const uint32_t res = can_codec_get_raw(CAN_SIG_REPLY_RESULT, f.data);
    if (req != st.req[st.tail % REQ_QUEUE]) {
      violated("REPLY answers another request (order)");
    }
    if (st.bad_dlc[st.tail % REQ_QUEUE] && res != 2u) {
      violated("wrong DLC not answered bad_dlc");
    }
    if (!st.bad_dlc[st.tail % REQ_QUEUE] && res == 2u) {
      violated("right DLC answered bad_dlc");
    }
    st.tail++;
  }
}

static void check_isr(void) {
  const drive_t *d = &x.drv;
  const drive_config_t *c = &d->cfg;
  const drive_cmd_t *cmd = &d->cmd;
  if (!(isfinite(cmd->torque) && isfinite(cmd->speed) && isfinite(cmd->id) && isfinite(cmd->iq) &&
        isfinite(cmd->flux))) {
    violated("command not finite");
  }
  const bool off_state = d->state == DRIVE_STATE_IDLE || d->state == DRIVE_STATE_FAULT ||
                         d->state == DRIVE_STATE_OFFSET_CAL;
  if (off_state && x.hal.gates_on) {
    violated("gates on in idle, offset calibration or fault");
  }
  /* the ramped speed reference starts from the measured speed (bumpless)
   * and follows a lowered speed_max at accel_max (docs/can.md): beyond
   * speed_max it may only approach it */
  const float w = fabsf(d->tm.speed_ref);
  if (!isfinite(w)) {
    violated("speed reference not finite");
  }
  if (d->state != DRIVE_STATE_RUN) {
    st.speed_loop_prev = false;
  } else if ((d->isr_count - 1u) % c->slow_div == (c->slow_div > 1u ? 1u : 0u)) {
    /* the speed loop's ISR: the slow period's second (drive.c's schedule,
     * DRIVE_PHASE_NEXT; the first at slow_div 1), one loop step apart */
    const float w_prev = fabsf(st.speed_ref_prev);
    /* the ramp's step, where float resolves it at this speed */
    const float step = c->accel_max * c->ts * (float)c->slow_div;
    const float must = step > 1e-6f * w ? w_prev - 0.5f * step : w_prev;
    if (st.speed_loop_prev && d->speed_active && w > c->speed_max * (1.0f + REL_TOL) && w > must) {
      violated("speed reference beyond speed_max and not approaching it at accel_max");
    }
    st.speed_ref_prev = d->tm.speed_ref;
    st.speed_loop_prev = d->speed_active;
  }
  if (d->state != DRIVE_STATE_RUN) {
    return;
  }
  const drive_telemetry_t *tm = &d->tm;
  if (!(fabsf(tm->torque_ref) <= c->torque_max * (1.0f + REL_TOL))) {
    violated("torque reference beyond torque_max (or not finite)");
  }
  const bool current_mode =
      cmd->mode == DRIVE_MODE_CURRENT && (d->ctrl.impl->caps & CTRL_CAP_CURRENT) != 0u;
  if (current_mode && !(hypotf(cmd->id, cmd->iq) <= c->i_max * (1.0f + REL_TOL))) {
    violated("current reference beyond i_max");
  }
}

/* One PWM period as sil_run.c's CAN path runs it. */
static void period(void) {
  const double t = (double)st.k * sc.plant.ts;
  x.hal.time_us = (uint32_t)(uint64_t)(t * 1e6);
  if (st.k % x.drv.cfg.slow_div == 0u) {
    drive_background(&x.drv);
    can_proto_poll(&proto, &x.drv, x.hal.time_us);
    if (x.hal.can_rx.tail != st.rx_tail_seen) {
      st.rx_tail_seen = x.hal.can_rx.tail;
      st.last_rx_us = x.hal.time_us;
      st.last_rx_any = true;
    }
    drain_tx();
  }
  sil_sample(&x, &sc, t);
  drive_isr(&x.drv);
  if (hal_sil_watchdog_expired(&x.hal, x.hal.time_us)) {
    violated("watchdog expired with both loops running");
  }
  check_isr();
  st.states |= 1u << (unsigned)x.drv.state;
  sil_advance(&x, &sc, t);
  st.k++;
}

static void advance(uint32_t periods) {
  for (uint32_t i = 0; i < periods && st.k < MAX_PERIODS; ++i) {
    period();
  }
}

static can_msg_t node_msg(uint8_t b) {
  static const can_msg_t m[] = {CAN_MSG_CMD_STATE,   CAN_MSG_CMD_TORQUE, CAN_MSG_CMD_SPEED,
                                CAN_MSG_CMD_CURRENT, CAN_MSG_CMD_FLUX,   CAN_MSG_PARAM_REQ,
                                CAN_MSG_HOST_HB};
  if (b == 0xFFu) { /* CMD_PROC: the others keep the corpus's meaning (b % 7) */
    return CAN_MSG_CMD_PROC;
  }
  return m[b % (sizeof m / sizeof m[0])];
}

/* A parameter write of a value near the one requested now (a scale of it),
 * so that inputs reach accepted writes of every parameter. */
static void param_scaled(input_t *in) {
  static const float scale[] = {0.0f, 0.5f, 0.9f, 1.1f, 2.0f, 10.0f, -1.0f, 0.1f};
  const uint8_t id = take(in);
  const uint8_t s = take(in);
  float now = 0.0f;
  if (id >= CAN_PROTO_PARAM_FIRST && id < CAN_PROTO_PARAM_LAST) {
    (void)can_proto_param_get(&proto, id, &now);
  } else {
    (void)drive_params_get(&x.drv, id, &now);
  }
  hal_can_frame_t f = {0};
  f.id = can_codec_id(CAN_MSG_PARAM_REQ, NODE);
  f.dlc = 8u;
  can_codec_set_raw(CAN_SIG_PARAM_OP, f.data, 1u);
  can_codec_set_raw(CAN_SIG_PARAM_ID, f.data, id);
  can_codec_set(CAN_SIG_PARAM_VALUE, f.data, now * scale[s % (sizeof scale / sizeof scale[0])]);
  push_frame(&f);
}

static void run_op(input_t *in) {
  const uint8_t op = take(in);
  hal_can_frame_t f = {0};
  switch (op % 8u) {
  case 0:
  case 1: { /* a message of the protocol for the node */
    const can_msg_t m = node_msg(take(in));
    const uint8_t dlc = take(in);
    f.id = can_codec_id(m, NODE);
    f.dlc = (dlc & 0x80u) != 0u ? (uint8_t)(dlc & 0x0Fu) : can_codec_msg(m)->dlc;
    for (int i = 0; i < 8; ++i) {
      f.data[i] = take(in);
    }
    push_frame(&f);
    break;
  }
  case 2: { /* any frame */
    const uint32_t id = take(in) | (uint32_t)take(in) << 8u;
    f.extended = (id & 0x8000u) != 0u;
    f.id = f.extended ? (id * 7919u) & 0x1FFFFFFFu : id & 0x7FFu;
    f.dlc = take(in) & 0x0Fu;
    for (int i = 0; i < 8; ++i) {
      f.data[i] = take(in);
    }
    push_frame(&f);
    break;
  }
  case 3: /* main-loop periods */
    advance(((uint32_t)take(in) + 1u) * x.drv.cfg.slow_div);
    break;
  case 4: /* ISR periods (the next poll off its usual phase) */
    advance((take(in) & 0x1Fu) + 1u);
    break;
  case 5: /* the bus stops / resumes taking the drive's frames */
    st.tx_blocked = !st.tx_blocked;
    drain_tx();
    break;
  case 6: /* a long wait: 50..800 ms */
    advance(((take(in) & 0x0Fu) + 1u) * 50u * x.drv.cfg.slow_div);
    break;
  default:
    param_scaled(in);
    break;
  }
}

/* After the last frame: the command timeout stops an enabled drive. */
static void final_timeout_check(void) {
  st.tx_blocked = false;
  drain_tx();
  /* a reply held back by a full TX queue goes out at the next poll; the
   * frames still queued are read within a few main-loop periods */
  for (int i = 0; i < 32 && (i < 2 || x.hal.can_rx.head != x.hal.can_rx.tail); ++i) {
    for (uint32_t j = 0; j < x.drv.cfg.slow_div; ++j) {
      period();
    }
  }
  const uint32_t budget_ms = (uint32_t)proto.cfg.timeout_ms + proto.cfg.ramp_ms;
  if (proto.cfg.timeout_ms > 0u && budget_ms <= FINAL_MAX_MS && drive_state_enabled(x.drv.state)) {
    const uint32_t slow_us = (uint32_t)llround(1e6 * sc.plant.ts * x.drv.cfg.slow_div);
    const uint32_t from = st.last_rx_any ? st.last_rx_us : 0u;
    const uint32_t deadline = from + budget_ms * 1000u + 2u * slow_us;
    const uint64_t n = (uint64_t)llround(1e-3 * (budget_ms + 4u) / sc.plant.ts);
    for (uint64_t i = 0; i < n; ++i) {
      period();
      if (x.hal.time_us >= deadline && x.hal.gates_on) {
        violated("command timeout did not turn the gates off within timeout + ramp");
      }
    }
  }
  drain_tx();
  if (st.head != st.tail) {
    violated("a request never answered");
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char err[512];
  memset(&st, 0, sizeof st);
  if (sil_setup(&x, &sc, err, sizeof err) != 0) {
    fprintf(stderr, "fuzz_can: %s\n", err);
    abort();
  }
  can_proto_cfg_t pc;
  can_proto_cfg_default(&pc);
  pc.node = NODE;
  pc.timeout_ms = 50u;
  pc.ramp_ms = 20u;
  if (can_proto_init(&proto, &pc) != 0) {
    abort();
  }
  input_t in = {data, size};
  while (in.n > 0u && st.k < MAX_PERIODS) {
    run_op(&in);
  }
  final_timeout_check();
  if (getenv("FUZZ_CAN_TRACE") != NULL) { /* what a seed reaches */
    fprintf(stderr,
            "fuzz_can: %.3f s simulated, %u replies, states seen 0x%x, faults 0x%x, timeouts %u\n",
            (double)st.k * sc.plant.ts, (unsigned)st.tail, (unsigned)st.states,
            (unsigned)x.drv.faults, (unsigned)proto.stats.timeouts);
  }
  return 0;
}
