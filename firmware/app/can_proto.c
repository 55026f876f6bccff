/*
 * can_proto.c - commands, parameters, status, telemetry and the command
 * timeout over CAN (see can_proto.h for the rules).
 */
#include "can_proto.h"

#include <math.h>
#include <string.h>

#include "drive_params.h"
#include "drive_signals.h"
#include "hal.h"

#define RPM_PER_RADS 9.54929659f /* 60 / (2 pi) */
#define NO_SIGNAL    ((can_sig_t)CAN_SIG_COUNT)

void can_proto_cfg_default(can_proto_cfg_t *cfg) {
  *cfg = (can_proto_cfg_t){0};
  cfg->node = 1;
  cfg->timeout_ms = 500;
  cfg->ramp_ms = 200;
#define PERIOD_DEFAULT(E, n, ms) cfg->period_ms[CAN_PERIOD_##E] = (ms);
  CAN_PERIOD_LIST(PERIOD_DEFAULT)
#undef PERIOD_DEFAULT
}

int can_proto_init(can_proto_t *p, const can_proto_cfg_t *cfg) {
  if (cfg->node > CAN_NODE_MAX) {
    return -1;
  }
  *p = (can_proto_t){0};
  p->cfg = *cfg;
  p->st_state = DRIVE_STATE_IDLE;
  return 0;
}

static void frame_init(hal_can_frame_t *f, can_msg_t m, uint8_t node) {
  memset(f, 0, sizeof *f);
  f->id = can_codec_id(m, node);
  f->dlc = can_codec_msg(m)->dlc;
}

/* ---------------------------------------------------------------- params */
const char *can_proto_param_name(uint8_t id) {
#define PERIOD_NAME(E, n, ms) "can_" #n "_ms",
  static const char *const names[CAN_PROTO_PARAM_COUNT] = {
      "can_node", "can_timeout_ms", "can_ramp_ms", CAN_PERIOD_LIST(PERIOD_NAME)};
#undef PERIOD_NAME
  const unsigned k = (unsigned)id - CAN_PROTO_PARAM_FIRST;
  return id >= CAN_PROTO_PARAM_FIRST && k < CAN_PROTO_PARAM_COUNT ? names[k] : NULL;
}

bool can_proto_param_get(const can_proto_t *p, uint8_t id, float *value) {
  if (id == CAN_PROTO_PARAM_FIRST) {
    *value = (float)p->cfg.node;
  } else if (id == CAN_PROTO_PARAM_FIRST + 1u) {
    *value = (float)p->cfg.timeout_ms;
  } else if (id == CAN_PROTO_PARAM_FIRST + 2u) {
    *value = (float)p->cfg.ramp_ms;
  } else if (id >= CAN_PROTO_PARAM_FIRST + 3u &&
             id < CAN_PROTO_PARAM_FIRST + CAN_PROTO_PARAM_COUNT) {
    *value = (float)p->cfg.period_ms[id - CAN_PROTO_PARAM_FIRST - 3u];
  } else {
    return false;
  }
  return true;
}

can_result_t can_proto_param_set(can_proto_t *p, uint8_t id, float value) {
  float dummy;
  if (!can_proto_param_get(p, id, &dummy)) {
    return CAN_RESULT_UNKNOWN_PARAM;
  }
  if (id == CAN_PROTO_PARAM_FIRST) {
    return CAN_RESULT_READ_ONLY; /* the node is set at start-up */
  }
  if (!isfinite(value) || value < 0.0f || value > 60000.0f || fabsf(value - roundf(value)) > 0.0f) {
    return CAN_RESULT_OUT_OF_RANGE;
  }
  uint16_t v = (uint16_t)value;
  if (id == CAN_PROTO_PARAM_FIRST + 1u) {
    p->cfg.timeout_ms = v;
  } else if (id == CAN_PROTO_PARAM_FIRST + 2u) {
    p->cfg.ramp_ms = v;
  } else {
    p->cfg.period_ms[id - CAN_PROTO_PARAM_FIRST - 3u] = v;
  }
  return CAN_RESULT_OK;
}

/* --------------------------------------------------------------- receive */
typedef struct {
  can_result_t result;
  can_sig_t signal; /* NO_SIGNAL: none */
  uint8_t param;
  float value;
} reply_t;

/* First signal of message m outside its DBC range, NO_SIGNAL if none. */
static can_sig_t first_out_of_range(can_msg_t m, const uint8_t data[8]) {
  const can_msg_desc_t *md = can_codec_msg(m);
  for (unsigned i = 0; i < md->n_signals; ++i) {
    can_sig_t s = (can_sig_t)((unsigned)md->first + i);
    if (!can_codec_in_range(s, data)) {
      return s;
    }
  }
  return NO_SIGNAL;
}

static void reply_error(reply_t *r, can_result_t res, can_sig_t s) {
  r->result = res;
  r->signal = s;
}

/* The parameter a PARAM_REQ names and its value in force, into the reply
 * (also when the request is refused before it is handled). False when no
 * such parameter. */
static bool param_echo(const can_proto_t *p, const drive_t *drv, const uint8_t *d, reply_t *r) {
  const uint8_t id = (uint8_t)can_codec_get_raw(CAN_SIG_PARAM_ID, d);
  r->param = id;
  float now = 0.0f;
  const bool proto = id >= CAN_PROTO_PARAM_FIRST && id < CAN_PROTO_PARAM_LAST;
  const bool known =
      proto ? can_proto_param_get(p, id, &now) : drive_params_get(drv, id, &now) == DRIVE_PARAM_OK;
  r->value = now;
  return known;
}

static void handle_param(can_proto_t *p, drive_t *drv, const uint8_t *d, reply_t *r) {
  const uint8_t id = (uint8_t)can_codec_get_raw(CAN_SIG_PARAM_ID, d);
  const bool set = can_codec_get_raw(CAN_SIG_PARAM_OP, d) == 1u;
  const float v = can_codec_get(CAN_SIG_PARAM_VALUE, d);
  const bool proto = id >= CAN_PROTO_PARAM_FIRST && id < CAN_PROTO_PARAM_LAST;
  if (!param_echo(p, drv, d, r)) {
    reply_error(r, CAN_RESULT_UNKNOWN_PARAM, CAN_SIG_PARAM_ID);
    return;
  }
  if (!set) {
    return;
  }
  can_result_t res;
  if (proto) {
    res = can_proto_param_set(p, id, v);
  } else {
    switch (drive_params_set(drv, id, v, NULL)) {
    case DRIVE_PARAM_OK:
      res = CAN_RESULT_OK;
      break;
    case DRIVE_PARAM_READ_ONLY:
      res = CAN_RESULT_READ_ONLY;
      break;
    case DRIVE_PARAM_RANGE:
      res = CAN_RESULT_OUT_OF_RANGE;
      break;
    case DRIVE_PARAM_RUNNING:
      res = CAN_RESULT_NOT_WHILE_RUNNING;
      break;
    case DRIVE_PARAM_INCONSISTENT:
      res = CAN_RESULT_INCONSISTENT;
      break;
    case DRIVE_PARAM_UNKNOWN:
    default:
      res = CAN_RESULT_UNKNOWN_PARAM;
      break;
    }
  }
  if (res != CAN_RESULT_OK) {
    reply_error(r, res, res == CAN_RESULT_UNKNOWN_PARAM ? CAN_SIG_PARAM_ID : CAN_SIG_PARAM_VALUE);
  }
  if (proto) {
    (void)can_proto_param_get(p, id, &r->value);
  } else {
    (void)drive_params_get(drv, id, &r->value);
  }
}

/* What REPLY.reply_value reports for a CMD_* message: the command posted. */
static float value_in_force(const drive_t *drv, can_msg_t m) {
  const drive_cmd_t *c = drive_commands(drv);
  switch (m) {
  case CAN_MSG_CMD_STATE:
    return c->enable != 0u ? 1.0f : 0.0f;
  case CAN_MSG_CMD_TORQUE:
    return c->torque;
  case CAN_MSG_CMD_SPEED:
    return c->speed * RPM_PER_RADS;
  case CAN_MSG_CMD_CURRENT:
    return c->id;
  case CAN_MSG_CMD_FLUX:
    return c->flux;
  case CAN_MSG_CMD_PROC: /* the identification last asked for (255: a stop, or none) */
    return drv->req.ident.count != 0u && drv->req.ident.proc < (uint32_t)PROC_COUNT
               ? (float)drv->req.ident.proc
               : (float)CAN_PROC_NONE; /* the main loop's own block */
  default:
    return 0.0f;
  }
}

/* CMD_STATE: checks every signal first, then applies all of it or
 * nothing. */
static void handle_state(const can_proto_t *p, drive_t *drv, const uint8_t *d, reply_t *r) {
  const uint32_t en = can_codec_get_raw(CAN_SIG_ENABLE, d);
  const uint32_t mode = can_codec_get_raw(CAN_SIG_MODE, d);
  const uint32_t law = can_codec_get_raw(CAN_SIG_LAW, d);
  if (en > 1u && en != CAN_KEEP) {
    reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_ENABLE);
  } else if (mode >= (uint32_t)DRIVE_MODE_COUNT && mode != CAN_KEEP) {
    reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_MODE);
  } else if (law >= (uint32_t)DRIVE_LAW_COUNT && law != CAN_KEEP) {
    reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_LAW);
  } else if (!p->ramp) {
    /* the clear first: it clears the faults latched before it and leaves
     * the enable as it is; an enable = 1 in the same frame is posted after
     * it, so it restarts a cleared drive (docs/can.md, "Enable and clear") */
    if (can_codec_get_raw(CAN_SIG_CLEAR_FAULT, d) == 1u) {
      drive_cmd_clear_fault(drv);
    }
    /* mode before law when leaving current mode, law first when entering */
    const bool into_current = mode == (uint32_t)DRIVE_MODE_CURRENT;
    const char *why = NULL;
    if (law != CAN_KEEP && !into_current) {
      why = drive_cmd_set_law(drv, (drive_law_t)law);
    }
    if (why == NULL && mode != CAN_KEEP) {
      why = drive_cmd_set_mode(drv, (drive_mode_t)mode);
      if (why != NULL) {
        reply_error(r, CAN_RESULT_UNAVAILABLE, CAN_SIG_MODE);
      }
    } else if (why != NULL) {
      reply_error(r, CAN_RESULT_UNAVAILABLE, CAN_SIG_LAW);
    }
    if (why == NULL && law != CAN_KEEP && into_current) {
      why = drive_cmd_set_law(drv, (drive_law_t)law);
      if (why != NULL) {
        reply_error(r, CAN_RESULT_UNAVAILABLE, CAN_SIG_LAW);
      }
    }
    if (why == NULL && en != CAN_KEEP) {
      drive_cmd_enable(drv, en == 1u);
    }
  }
  r->value = value_in_force(drv, CAN_MSG_CMD_STATE);
}

/* CMD_PROC: an identification procedure run alone, or 255 the stop
 * (drive_cmd_identify). Refused: an id that is no procedure out_of_range,
 * a procedure that is no identification unavailable (both naming
 * cmd_proc), the drive enabled not_while_running (naming enable). Whether
 * the parameter set in force can run it is the ISR's to say (TM_PROC
 * status refused). */
static void handle_proc(const can_proto_t *p, drive_t *drv, const uint8_t *d, reply_t *r) {
  const uint32_t v = can_codec_get_raw(CAN_SIG_CMD_PROC, d);
  if (v >= (uint32_t)PROC_COUNT && v != CAN_PROC_NONE) {
    reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_CMD_PROC);
  } else if (!p->ramp) {
    const char *field = NULL;
    const proc_id_t id = v == CAN_PROC_NONE ? PROC_NONE : (proc_id_t)v;
    if (drive_cmd_identify(drv, id, &field) != NULL) {
      const bool enabled = field != NULL && strcmp(field, "enable") == 0;
      reply_error(r, enabled ? CAN_RESULT_NOT_WHILE_RUNNING : CAN_RESULT_UNAVAILABLE,
                  enabled ? CAN_SIG_ENABLE : CAN_SIG_CMD_PROC);
    }
  }
  r->value = value_in_force(drv, CAN_MSG_CMD_PROC);
}

/* Applies a CMD_* frame (DLC and DBC ranges already checked). */
static void handle_cmd(const can_proto_t *p, drive_t *drv, can_msg_t m, const uint8_t *d,
                       reply_t *r) {
  const drive_config_t *c = drive_requested_config(drv);
  switch (m) {
  case CAN_MSG_CMD_STATE:
    handle_state(p, drv, d, r);
    return;
  case CAN_MSG_CMD_PROC:
    handle_proc(p, drv, d, r);
    return;
  case CAN_MSG_CMD_TORQUE: {
    float t = can_codec_get(CAN_SIG_CMD_TORQUE, d);
    if (fabsf(t) > c->torque_max) {
      reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_CMD_TORQUE);
    } else if (!p->ramp) {
      drive_cmd_torque(drv, t);
    }
    r->value = value_in_force(drv, m);
    return;
  }
  case CAN_MSG_CMD_SPEED: {
    float rpm = can_codec_get(CAN_SIG_CMD_SPEED_RPM, d);
    if (fabsf(rpm) > c->speed_max * RPM_PER_RADS * (1.0f + 1e-6f)) {
      reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_CMD_SPEED_RPM);
    } else if (!p->ramp) {
      drive_cmd_speed(drv, rpm / RPM_PER_RADS);
    }
    r->value = value_in_force(drv, m);
    return;
  }
  case CAN_MSG_CMD_CURRENT: {
    float id = can_codec_get(CAN_SIG_CMD_ID, d);
    float iq = can_codec_get(CAN_SIG_CMD_IQ, d);
    if (fabsf(id) > c->i_max) {
      reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_CMD_ID);
    } else if (fabsf(iq) > c->i_max) {
      reply_error(r, CAN_RESULT_OUT_OF_RANGE, CAN_SIG_CMD_IQ);
    } else if (!p->ramp) {
      drive_cmd_current(drv, id, iq);
    }
    r->value = value_in_force(drv, m);
    return;
  }
  case CAN_MSG_CMD_FLUX:
  default:
    if (!p->ramp) {
      drive_cmd_flux(drv, can_codec_get(CAN_SIG_CMD_FLUX, d));
    }
    r->value = value_in_force(drv, m);
    return;
  }
}

static void encode_reply(const can_proto_t *p, can_msg_t req, const reply_t *r,
                         hal_can_frame_t *f) {
  frame_init(f, CAN_MSG_REPLY, p->cfg.node);
  can_codec_set_raw(CAN_SIG_REPLY_REQ, f->data, (uint32_t)req);
  can_codec_set_raw(CAN_SIG_REPLY_RESULT, f->data, (uint32_t)r->result);
  can_codec_set_raw(CAN_SIG_REPLY_SIGNAL, f->data,
                    r->signal == NO_SIGNAL ? 0u : (uint32_t)r->signal + 1u);
  can_codec_set_raw(CAN_SIG_REPLY_PARAM, f->data, r->param);
  can_codec_set(CAN_SIG_REPLY_VALUE, f->data, r->value);
}

/* Handles one received frame; returns true and fills `out` when it needs a
 * reply. */
static bool handle_frame(can_proto_t *p, drive_t *drv, const hal_can_frame_t *f, uint32_t now,
                         hal_can_frame_t *out) {
  can_msg_t m = can_codec_lookup(f->id, f->extended, p->cfg.node);
  const can_msg_desc_t *md = can_codec_msg(m);
  if (md == NULL || !md->to_drive) {
    p->stats.rx_ignored++;
    return false;
  }
  reply_t r = {CAN_RESULT_OK, NO_SIGNAL, 0, 0.0f};
  if (f->dlc != md->dlc) {
    reply_error(&r, CAN_RESULT_BAD_DLC, NO_SIGNAL);
  } else {
    p->last_rx_us = now; /* well-formed: the host is alive */
    if (m == CAN_MSG_HOST_HB) {
      p->stats.rx_ok++;
      return false;
    }
    can_sig_t bad = first_out_of_range(m, f->data);
    if (bad != NO_SIGNAL) {
      reply_error(&r, CAN_RESULT_OUT_OF_RANGE, bad);
      r.value = value_in_force(drv, m);
      if (m == CAN_MSG_PARAM_REQ) {
        /* mut: nan_reply_without_param */
        param_echo(p, drv, f->data, &r); /* a NaN or inf value: name the parameter */
      }
    } else if (m == CAN_MSG_PARAM_REQ) {
      handle_param(p, drv, f->data, &r);
    } else {
      handle_cmd(p, drv, m, f->data, &r);
      if (r.result == CAN_RESULT_OK && p->ramp) {
        r.result = CAN_RESULT_TIMED_OUT;
      }
    }
  }
  if (r.result == CAN_RESULT_OK) {
    p->stats.rx_ok++;
  } else {
    p->stats.rx_errors++;
  }
  if (m == CAN_MSG_HOST_HB) {
    return false; /* a bad heartbeat is counted, not answered */
  }
  if (r.result != CAN_RESULT_OK && m != CAN_MSG_PARAM_REQ && r.signal == NO_SIGNAL &&
      r.result != CAN_RESULT_BAD_DLC) {
    r.signal = md->first;
  }
  encode_reply(p, m, &r, out);
  return true;
}

/* -------------------------------------------------------------- timeout */
static void timeout_step(can_proto_t *p, drive_t *drv, uint32_t now) {
  /* as the main loop's last telemetry copy says (drive_background) */
  const bool enabled = drive_state_enabled(drive_telemetry(drv)->state);
  if (!p->ramp) {
    if (!enabled || p->cfg.timeout_ms == 0u ||
        now - p->last_rx_us < (uint32_t)p->cfg.timeout_ms * 1000u) {
      return;
    }
    if (drive_commands(drv)->enable == 0u) {
      /* enabled without an enable: an identification (drive_cmd_identify).
       * No torque to ramp down and nobody watching it: the fault at once */
      drive_request_fault(drv, DRIVE_FAULT_CMD_TIMEOUT);
      p->stats.timeouts++;
      p->last_rx_us = now; /* once: the next poll sees the fault */
      return;
    }
    p->ramp = true;
    p->ramp_t0_us = now;
    p->ramp_torque0 = drive_telemetry(drv)->torque_ref;
    p->ramp_mode = drive_commands(drv)->mode;
    (void)drive_cmd_set_mode(drv, DRIVE_MODE_TORQUE);
  }
  if (!enabled) { /* the drive stopped on its own (fault, disable) */
    p->ramp = false;
    return;
  }
  const uint32_t elapsed = now - p->ramp_t0_us;
  const uint32_t ramp_us = (uint32_t)p->cfg.ramp_ms * 1000u;
  if (elapsed >= ramp_us) {
    drive_cmd_torque(drv, 0.0f);
    drive_cmd_speed(drv, 0.0f);
    drive_cmd_current(drv, 0.0f, 0.0f);
    (void)drive_cmd_set_mode(drv, p->ramp_mode);
    drive_cmd_enable(drv, false);
    drive_request_fault(drv, DRIVE_FAULT_CMD_TIMEOUT);
    p->ramp = false;
    p->stats.timeouts++;
    return;
  }
  drive_cmd_torque(drv, p->ramp_torque0 * (1.0f - (float)elapsed / (float)ramp_us));
}

/* ------------------------------------------------------------- transmit */
/* A telemetry frame: every signal of message m that a row of the drive's
 * signal table names (drive_signal_table.h: value * can_scale); the
 * protocol's own signals stay 0 for the caller. */
static void telemetry_frame(hal_can_frame_t *f, can_msg_t m, uint8_t node,
                            const drive_signal_src_t *src) {
  frame_init(f, m, node);
  const can_msg_desc_t *d = can_codec_msg(m);
  for (unsigned i = 0u; i < d->n_signals; ++i) {
    const can_sig_t s = (can_sig_t)((unsigned)d->first + i);
    const drive_signal_t *row = drive_signal_of_can(s);
    if (row != NULL) {
      can_codec_set(s, f->data, (float)row->row.get(src) * row->can_scale);
    }
  }
}

static void send_periodic(can_proto_t *p, can_period_t which, const drive_t *drv) {
  const drive_telemetry_t *tm = drive_telemetry(drv);
  const drive_signal_src_t src = {drv, tm};
  const uint8_t node = p->cfg.node;
  hal_can_frame_t f;
  switch (which) {
  case CAN_PERIOD_STATUS:
    /* state, faults, v_dc from the signal table; the rest the protocol's */
    telemetry_frame(&f, CAN_MSG_STATUS, node, &src);
    can_codec_set_raw(CAN_SIG_CTRL_MODE, f.data, (uint32_t)tm->mode);
    can_codec_set_raw(CAN_SIG_CTRL_LAW, f.data, (uint32_t)tm->law);
    can_codec_set_raw(CAN_SIG_TIMEOUT_RAMP, f.data, p->ramp ? 1u : 0u);
    /* the enable in force as the ISR holds it (armed), not the level posted */
    can_codec_set_raw(CAN_SIG_CMD_ENABLED, f.data,
                      drive_enable_in_force(tm, drive_commands(drv)) ? 1u : 0u);
    can_codec_set_raw(CAN_SIG_ERR_COUNT, f.data, p->stats.rx_errors & 0xFFu);
    p->st_state = tm->state;
    p->st_faults = tm->faults;
    p->st_ramp = p->ramp;
    break;
  case CAN_PERIOD_HEARTBEAT:
    frame_init(&f, CAN_MSG_HEARTBEAT, node);
    can_codec_set_raw(CAN_SIG_HB_COUNT, f.data, p->hb_count++);
    can_codec_set_raw(CAN_SIG_HB_STATE, f.data, (uint32_t)tm->state);
    break;
  case CAN_PERIOD_TM_SPEED:
    telemetry_frame(&f, CAN_MSG_TM_SPEED, node, &src);
    break;
  case CAN_PERIOD_TM_TORQUE:
    telemetry_frame(&f, CAN_MSG_TM_TORQUE, node, &src);
    break;
  case CAN_PERIOD_TM_PHASE:
    telemetry_frame(&f, CAN_MSG_TM_PHASE, node, &src);
    break;
  case CAN_PERIOD_TM_DQ:
    telemetry_frame(&f, CAN_MSG_TM_DQ, node, &src);
    break;
  case CAN_PERIOD_TM_FLUX:
    telemetry_frame(&f, CAN_MSG_TM_FLUX, node, &src);
    break;
  case CAN_PERIOD_TM_POSITION:
    telemetry_frame(&f, CAN_MSG_TM_POSITION, node, &src);
    break;
  case CAN_PERIOD_TM_PROC: {
    /* the procedure telemetry (proc.h), one result per frame, cycling */
    const proc_telemetry_t *pt = &tm->proc;
    const unsigned k = p->proc_index % (unsigned)PROC_RESULTS;
    p->proc_index = (uint8_t)((k + 1u) % (unsigned)PROC_RESULTS);
    frame_init(&f, CAN_MSG_TM_PROC, node);
    const bool none = pt->status == PROC_ST_IDLE || pt->id >= (uint8_t)PROC_COUNT;
    can_codec_set_raw(CAN_SIG_PROC_ID, f.data, none ? CAN_PROC_NONE : (uint32_t)pt->id);
    can_codec_set_raw(CAN_SIG_PROC_STATUS, f.data, pt->status);
    can_codec_set_raw(CAN_SIG_PROC_PHASE, f.data, pt->phase);
    can_codec_set_raw(CAN_SIG_PROC_INDEX, f.data, k);
    can_codec_set(CAN_SIG_PROC_RESULT, f.data, pt->result[k]);
    break;
  }
  case CAN_PERIOD_TM_CPU:
  default: {
    /* the board's measured ISR cycles (hal_isr_stats, DWT): the figure
     * docs/benchmarks.md estimates, confirmed on hardware */
    hal_isr_stats_t st;
    hal_isr_stats(&st);
    const hal_caps_t *caps = hal_caps();
    frame_init(&f, CAN_MSG_TM_CPU, node);
    can_codec_set(CAN_SIG_ISR_CYCLES_MEAN, f.data, (float)st.cycles_mean);
    can_codec_set(CAN_SIG_ISR_CYCLES_MAX, f.data, (float)st.cycles_max);
    can_codec_set(CAN_SIG_ISR_LOAD, f.data,
                  caps->cpu_hz > 0.0f ? 100.0f * (float)st.cycles_mean / (caps->cpu_hz * caps->ts)
                                      : 0.0f);
    can_codec_set(CAN_SIG_ISR_OVERRUNS, f.data, (float)st.overruns);
    break;
  }
  }
  if (!hal_can_send(&f)) {
    p->stats.tx_dropped++;
  }
}

void can_proto_poll(can_proto_t *p, drive_t *drv, uint32_t now_us) {
  if (!p->started) {
    p->started = true;
    p->last_rx_us = now_us;
    for (unsigned i = 0; i < (unsigned)CAN_PERIOD_COUNT; ++i) {
      p->last_tx_us[i] = now_us - (uint32_t)p->cfg.period_ms[i] * 1000u;
    }
  }
  /* 1. a reply that did not fit last time goes first */
  bool blocked = false;
  if (p->pending) {
    blocked = !hal_can_send(&p->pending_frame);
    p->pending = blocked;
  }
  /* 2. at most CAN_PROTO_RX_MAX received frames */
  hal_can_frame_t in, out;
  for (unsigned n = 0; !blocked && n < CAN_PROTO_RX_MAX && hal_can_receive(&in); ++n) {
    p->stats.rx_frames++;
    if (in.dlc > 8u) {
      in.dlc = 9u; /* never a valid length; keep the data untouched */
    }
    if (handle_frame(p, drv, &in, now_us, &out) && !hal_can_send(&out)) {
      p->pending_frame = out;
      p->pending = true;
      blocked = true;
    }
  }
  /* 3. command timeout */
  timeout_step(p, drv, now_us);
  /* 4. status at once on a change, then periodic transmissions */
  const drive_telemetry_t *tm = drive_telemetry(drv);
  bool changed = tm->state != p->st_state || tm->faults != p->st_faults || p->ramp != p->st_ramp;
  for (unsigned i = 0; i < (unsigned)CAN_PERIOD_COUNT; ++i) {
    uint32_t period = (uint32_t)p->cfg.period_ms[i] * 1000u;
    bool due = period > 0u && now_us - p->last_tx_us[i] >= period;
    if (i == (unsigned)CAN_PERIOD_STATUS && changed) {
      due = true;
    }
    if (due) {
      p->last_tx_us[i] = now_us;
      send_periodic(p, (can_period_t)i, drv);
    }
  }
}
