/*
 * drive.c - the drive: state machine, ISR body, slow loop and commands.
 *
 * idle -> offset calibration -> run -> (fault). Protections run every ISR
 * on the sample just read; a fault disables the gates in the same ISR,
 * latches its cause and keeps it until drive_cmd_clear_fault().
 */
#include "drive.h"

#include <math.h>

#include "control/modulation.h"
#include "hal.h"
#include "math/fd_math.h"
#include "math/frames.h"

/* All gates off, duties back to 50 % (no voltage when they come back). */
static void drive_gates_off(void) {
  hal_pwm_disable();
  hal_pwm_set_duty(0.5f, 0.5f, 0.5f);
}

static void drive_trip(drive_t *drv, uint32_t bits) {
  drive_gates_off();
  drv->faults |= bits;
  drv->state = DRIVE_STATE_FAULT;
}

static void refs_from_cmd(drive_t *drv) {
  drv->ref.enable = drv->cmd.enable;
  drv->ref.mode = drv->cmd.mode;
  drv->ref.torque = drv->cmd.torque;
  drv->ref.speed = drv->cmd.speed;
  drv->ref.id = drv->cmd.id;
  drv->ref.iq = drv->cmd.iq;
  drv->ref.flux = drv->cmd.flux;
}

static void speed_cfg_from(speed_ctrl_cfg_t *scfg, const drive_config_t *cfg) {
  speed_ctrl_design(scfg, cfg->inertia, cfg->speed_bw);
  scfg->ts = cfg->ts * (float)cfg->slow_div;
  scfg->accel_max = cfg->accel_max;
  scfg->torque_max = cfg->torque_max;
}

int drive_init(drive_t *drv, const drive_config_t *cfg, const char **field) {
  const char *dummy = "";
  if (field == 0) {
    field = &dummy;
  }
  int err = drive_config_check(cfg, field);
  if (err != 0) {
    return err;
  }
  *drv = (drive_t){0};
  drv->cfg = *cfg;
  drv->state = DRIVE_STATE_IDLE;
  drv->cmd.law = cfg->law;
  drv->cmd.mode = cfg->mode;
  drv->ref.law = cfg->law;
  refs_from_cmd(drv);
  if (ctrl_init(&drv->ctrl, cfg) != 0) {
    *field = "law parameters";
    return -1;
  }
  angle_pll_init(&drv->pll, cfg->pll_bw, cfg->ts);

  speed_ctrl_cfg_t scfg;
  speed_cfg_from(&scfg, cfg);
  speed_ctrl_init(&drv->speed, &scfg);
  drv->torque_min_avail = -cfg->torque_max;
  drv->torque_max_avail = cfg->torque_max;

  drive_gates_off();
  return 0;
}

/* Protections on the raw sample; returns the fault bits found. */
static uint32_t drive_protect(const drive_t *drv, const hal_adc_sample_t *s, const float i[3]) {
  const drive_config_t *c = &drv->cfg;
  uint32_t f = 0;
  if (!(fd_isfinite(i[0]) && fd_isfinite(i[1]) && fd_isfinite(i[2]) && fd_isfinite(s->v_dc))) {
    return DRIVE_FAULT_SAMPLE;
  }
  if (fabsf(i[0]) > c->i_trip || fabsf(i[1]) > c->i_trip || fabsf(i[2]) > c->i_trip) {
    f |= DRIVE_FAULT_OVERCURRENT;
  }
  if (s->v_dc > c->v_dc_max) {
    f |= DRIVE_FAULT_OVERVOLTAGE;
  }
  if (drv->state == DRIVE_STATE_RUN && s->v_dc < c->v_dc_min) {
    f |= DRIVE_FAULT_UNDERVOLTAGE;
  }
  if (fabsf(drv->pos.omega_m) > c->speed_trip) {
    f |= DRIVE_FAULT_OVERSPEED;
  }
  if (hal_fault_hw_tripped()) {
    f |= DRIVE_FAULT_HW_OVERCURRENT;
  }
  return f;
}

static void drive_update_position(drive_t *drv, const hal_adc_sample_t *s) {
  if (s->enc_valid && fd_isfinite(s->enc_angle)) {
    /* The encoder angle is sampled at the ADC instant: Park uses it as is;
     * the PLL gives the speed. */
    const float th = frames_wrap_pi(drv->cfg.pole_pairs * s->enc_angle - drv->cfg.enc_offset);
    angle_pll_update(&drv->pll, th);
    drv->pos.theta_e = th;
  } else {
    drv->pos.theta_e = drv->pll.theta;
  }
  drv->pos.omega_e = drv->pll.omega;
  drv->pos.omega_m = drv->pll.omega / drv->cfg.pole_pairs;
  drv->pos.rate_acc += drv->pll.omega_rate;
  drv->pos.rate_n++;
}

static void drive_offset_cal(drive_t *drv, const hal_adc_sample_t *s) {
  for (int x = 0; x < 3; ++x) {
    drv->offset_acc[x] += s->i_abc[x];
  }
  drv->offset_n++;
  if (drv->offset_n < drv->cfg.offset_samples) {
    return;
  }
  float n = (float)drv->offset_n;
  for (int x = 0; x < 3; ++x) {
    drv->offset[x] = drv->offset_acc[x] / n;
    if (fabsf(drv->offset[x]) > drv->cfg.offset_max) {
      drive_trip(drv, DRIVE_FAULT_OFFSET);
      return;
    }
  }
  ctrl_reset(&drv->ctrl, drv->ref.law);
  speed_ctrl_reset(&drv->speed, drv->pos.omega_m, 0.0f);
  drv->speed_torque = 0.0f;
  hal_pwm_set_duty(0.5f, 0.5f, 0.5f);
  hal_pwm_enable();
  drv->state = DRIVE_STATE_RUN;
}

static void drive_run(drive_t *drv, const float i[3], float v_dc) {
  ctrl_in_t in;
  in.i_ab = frames_clarke((abc_t){i[0], i[1], i[2]});
  in.theta_e = drv->pos.theta_e;
  in.omega_e = drv->pos.omega_e;
  in.v_dc = v_dc;
  in.mode = drv->ref.mode;
  in.torque_ref = drv->ref.mode == DRIVE_MODE_SPEED ? drv->speed_torque : drv->ref.torque;
  in.id_ref = drv->ref.id;
  in.iq_ref = drv->ref.iq;
  in.flux_ref = drv->ref.flux;

  ctrl_out_t out;
  ctrl_step(&drv->ctrl, &in, &out);
  if (out.fault != 0u) {
    drive_trip(drv, DRIVE_FAULT_CONTROL);
    return;
  }
  modulation_out_t m = modulation_minmax(out.v_ref, v_dc);
  float d[3] = {m.duty[0], m.duty[1], m.duty[2]};
  ctrl_compensate_deadtime(&drv->ctrl, &out, d);
  hal_pwm_set_duty(d[0], d[1], d[2]);
  ctrl_set_applied(&drv->ctrl, m.v_applied);
  drv->torque_min_avail = out.torque_min;
  drv->torque_max_avail = out.torque_max;

  drive_telemetry_t *tm = &drv->tm;
  tm->i_dq[0] = out.i_dq.d;
  tm->i_dq[1] = out.i_dq.q;
  tm->v_ab_applied[0] = m.v_applied.alpha;
  tm->v_ab_applied[1] = m.v_applied.beta;
  tm->duty[0] = d[0];
  tm->duty[1] = d[1];
  tm->duty[2] = d[2];
  tm->torque_ref = in.torque_ref;
  tm->torque_est = out.tm.torque;
  tm->law_tm = out.tm;
}

void drive_isr(drive_t *drv) {
  hal_adc_sample_t s;
  hal_adc_read(&s);
  drv->isr_count++;

  float i[3];
  for (int x = 0; x < 3; ++x) {
    i[x] = s.i_abc[x] - drv->offset[x];
  }
  drive_update_position(drv, &s);

  uint32_t f = drive_protect(drv, &s, i);
  if (f != 0u) {
    drive_trip(drv, f);
  }

  switch (drv->state) {
  case DRIVE_STATE_IDLE:
    if (drv->ref.enable) {
      drv->offset_acc[0] = drv->offset_acc[1] = drv->offset_acc[2] = 0.0f;
      drv->offset_n = 0;
      drv->state = DRIVE_STATE_OFFSET_CAL;
    }
    break;
  case DRIVE_STATE_OFFSET_CAL:
    if (!drv->ref.enable) {
      drv->state = DRIVE_STATE_IDLE;
    } else {
      drive_offset_cal(drv, &s);
    }
    break;
  case DRIVE_STATE_RUN:
    if (!drv->ref.enable) {
      drive_gates_off();
      drv->state = DRIVE_STATE_IDLE;
    } else {
      drive_run(drv, i, s.v_dc);
    }
    break;
  case DRIVE_STATE_FAULT:
  default:
    hal_pwm_disable();
    break;
  }
  if (drv->state != DRIVE_STATE_RUN) {
    ctrl_set_applied(&drv->ctrl, (ab_t){0.0f, 0.0f});
  }

  drive_telemetry_t *tm = &drv->tm;
  tm->state = drv->state;
  tm->faults = drv->faults;
  tm->v_dc = s.v_dc;
  tm->i_abc[0] = i[0];
  tm->i_abc[1] = i[1];
  tm->i_abc[2] = i[2];
  tm->theta_e = drv->pos.theta_e;
  tm->omega_m = drv->pos.omega_m;
  tm->isr_count = drv->isr_count;
  hal_watchdog_kick();
}

void drive_slow_loop(drive_t *drv) {
  drv->slow_count++;
  if (drv->pos.rate_n > 0u) {
    drv->pos.omega_m_slow = drv->pos.rate_acc / ((float)drv->pos.rate_n * drv->cfg.pole_pairs);
    drv->pos.rate_acc = 0.0f;
    drv->pos.rate_n = 0u;
  }
  if (drv->cmd.clear_fault) {
    drv->cmd.clear_fault = false;
    if (drv->state == DRIVE_STATE_FAULT) {
      /* Clearing needs a fresh enable: the operator re-arms explicitly. */
      hal_fault_hw_clear();
      drv->faults = 0;
      drv->cmd.enable = false;
      drv->ref.enable = false;
      drv->state = DRIVE_STATE_IDLE;
    }
  }
  /* A law change takes effect only while the gates are off. */
  if (drv->state != DRIVE_STATE_RUN && drv->state != DRIVE_STATE_OFFSET_CAL) {
    drv->ref.law = drv->cmd.law;
  }
  if (drv->state == DRIVE_STATE_FAULT) {
    drv->cmd.enable = false;
  }
  /* The mode (torque/speed/current) may change on the fly except into
   * current mode with a DFVC law. */
  if (drv->cmd.mode == DRIVE_MODE_CURRENT && drv->ref.law != DRIVE_LAW_FOC) {
    drv->cmd.mode = drv->ref.mode == DRIVE_MODE_CURRENT ? DRIVE_MODE_TORQUE : drv->ref.mode;
  }
  bool was_speed = drv->ref.mode == DRIVE_MODE_SPEED;
  refs_from_cmd(drv);

  if (drv->state == DRIVE_STATE_RUN && drv->ref.mode == DRIVE_MODE_SPEED) {
    if (!was_speed) {
      speed_ctrl_reset(&drv->speed, drv->pos.omega_m_slow, drv->tm.torque_ref);
    }
    drv->speed_torque = speed_ctrl_update(&drv->speed, drv->ref.speed, drv->pos.omega_m_slow,
                                          drv->torque_min_avail, drv->torque_max_avail);
  } else {
    speed_ctrl_reset(&drv->speed, drv->pos.omega_m, 0.0f);
    drv->speed_torque = 0.0f;
  }
  drv->tm.law = drv->ref.law;
  drv->tm.mode = drv->ref.mode;
  drv->tm.speed_ref = drv->ref.mode == DRIVE_MODE_SPEED ? drv->speed.w_ref_ramped : 0.0f;
}

void drive_cmd_enable(drive_t *drv, bool enable) {
  drv->cmd.enable = enable;
}

void drive_cmd_clear_fault(drive_t *drv) {
  drv->cmd.clear_fault = true;
}

bool drive_cmd_set_law(drive_t *drv, drive_law_t law) {
  if ((unsigned)law >= (unsigned)DRIVE_LAW_COUNT) {
    return false;
  }
  drv->cmd.law = law;
  return true;
}

bool drive_cmd_set_mode(drive_t *drv, drive_mode_t mode) {
  if ((unsigned)mode >= (unsigned)DRIVE_MODE_COUNT) {
    return false;
  }
  drv->cmd.mode = mode;
  return true;
}

/* Command clamp: a non-finite command becomes 0 (not a limit, as
 * fd_clampf would make it). */
static float command_clamp(float x, float lo, float hi) {
  if (!fd_isfinite(x)) {
    return 0.0f;
  }
  return x < lo ? lo : (x > hi ? hi : x);
}

void drive_cmd_torque(drive_t *drv, float torque) {
  drv->cmd.torque = command_clamp(torque, -drv->cfg.torque_max, drv->cfg.torque_max);
}

void drive_cmd_speed(drive_t *drv, float speed_m) {
  drv->cmd.speed = command_clamp(speed_m, -drv->cfg.speed_max, drv->cfg.speed_max);
}

void drive_cmd_current(drive_t *drv, float id, float iq) {
  float lim = drv->cfg.i_max;
  id = command_clamp(id, -lim, lim);
  iq = command_clamp(iq, -lim, lim);
  float mag = sqrtf(id * id + iq * iq);
  if (mag > lim) {
    id *= lim / mag;
    iq *= lim / mag;
  }
  drv->cmd.id = id;
  drv->cmd.iq = iq;
}

void drive_cmd_flux(drive_t *drv, float flux) {
  drv->cmd.flux = command_clamp(flux, 0.0f, 10.0f);
}

int drive_set_config(drive_t *drv, const drive_config_t *cfg, const char **field) {
  const char *dummy = "";
  if (field == 0) {
    field = &dummy;
  }
  const bool enabled = drv->state == DRIVE_STATE_RUN || drv->state == DRIVE_STATE_OFFSET_CAL;
  drive_config_t next = *cfg;
  if (enabled) {
    next = drv->cfg;
    next.i_trip = cfg->i_trip;
    next.v_dc_max = cfg->v_dc_max;
    next.v_dc_min = cfg->v_dc_min;
    next.speed_trip = cfg->speed_trip;
    next.offset_max = cfg->offset_max;
    next.speed_max = cfg->speed_max;
    next.torque_max = cfg->torque_max;
    next.accel_max = cfg->accel_max;
    next.speed_bw = cfg->speed_bw;
  }
  int err = drive_config_check(&next, field);
  if (err != 0) {
    return err;
  }
  speed_ctrl_cfg_t scfg;
  speed_cfg_from(&scfg, &next);
  if (enabled) {
    /* live: new gains and limits, the integral and ramp carry on */
    drv->speed.cfg.kp = scfg.kp;
    drv->speed.cfg.ki = scfg.ki;
    drv->speed.cfg.j_ff = scfg.j_ff;
    drv->speed.cfg.accel_max = scfg.accel_max;
    drv->speed.cfg.torque_max = fabsf(scfg.torque_max);
    drv->speed.pi.kp = scfg.kp;
    drv->speed.pi.ki = scfg.ki;
    drv->ctrl.torque_max = next.torque_max;
  } else {
    drive_law_t law = drv->ctrl.law;
    if (ctrl_init(&drv->ctrl, &next) != 0) {
      /* the laws refused: restore the previous (valid) set */
      (void)ctrl_init(&drv->ctrl, &drv->cfg);
      drv->ctrl.law = law;
      *field = "law parameters";
      return -1;
    }
    drv->ctrl.law = law;
    angle_pll_init(&drv->pll, next.pll_bw, next.ts);
    speed_ctrl_init(&drv->speed, &scfg);
  }
  drv->cfg = next;
  return 0;
}

void drive_raise_fault(drive_t *drv, uint32_t fault_bits) {
  drive_trip(drv, fault_bits);
  drv->tm.state = drv->state;
  drv->tm.faults = drv->faults;
}

const drive_telemetry_t *drive_telemetry(const drive_t *drv) {
  return &drv->tm;
}

const char *drive_state_name(drive_state_t s) {
  switch (s) {
  case DRIVE_STATE_IDLE:
    return "idle";
  case DRIVE_STATE_OFFSET_CAL:
    return "offset_cal";
  case DRIVE_STATE_RUN:
    return "run";
  case DRIVE_STATE_FAULT:
    return "fault";
  default:
    return "unknown";
  }
}

const char *drive_fault_name(uint32_t fault_bits) {
  static const char *const names[] = {"overcurrent", "overvoltage",    "undervoltage",
                                      "overspeed",   "hw_overcurrent", "offset",
                                      "control",     "cmd_timeout",    "sample"};
  if (fault_bits == 0u) {
    return "none";
  }
  for (unsigned b = 0; b < sizeof names / sizeof names[0]; ++b) {
    if ((fault_bits & (1u << b)) != 0u) {
      return names[b];
    }
  }
  return "unknown";
}
