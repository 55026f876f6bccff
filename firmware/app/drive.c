/*
 * drive.c - the drive: state machine, ISR body, protections, loss-of-control
 * monitor (drive.h).
 *
 * idle -> offset calibration -> [align] -> run -> (fault). The ISR takes the
 * main loop's requests at its start, evaluates the protections on the
 * sample just read, and a fault disables the gates in the same ISR,
 * latches its cause and keeps it until a clear request. The main loop's
 * side of the concurrency contract is drive_host.c.
 */
#include "drive.h"
#include "drive_pos_check.h"
#include "drive_overrun.h"
#include "drive_safe.h"
#include "drive_sync.h"
#include "proc.h"

#include <math.h>
#include <string.h>

#include "control/dfc_window.h"
#include "control/modulation.h"
#include "math/fd_math.h"
#include "math/frames.h"

static bool gates_on_state(drive_state_t s) {
  return s == DRIVE_STATE_RUN || s == DRIVE_STATE_ALIGN;
}

/* All gates off, the pattern back to the middle of the duty range (no
 * voltage when the gates come back). */
static void drive_gates_off(const drive_t *drv) {
  hal_pwm_disable();
  const float mid = 0.5f * (drv->duty_lo + drv->duty_hi);
  const hal_pwm_t p = hal_pwm_centred(mid, mid, mid);
  hal_pwm_write(&p, NULL);
}

/* A fault: gates off now (unless already shorted), the safe state chosen
 * in this ISR (drive_safe.c), the cause latched. */
static FD_NOINLINE void drive_trip(drive_t *drv, uint32_t bits) {
  if (!drv->safe.asc) {
    drive_gates_off(drv);
    drive_safe_leave_gates(drv);
  }
  drv->faults |= bits;
  drv->state = DRIVE_STATE_FAULT;
  /* the enable commands posted so far do not restart the drive after the
   * clear: only one posted after this trip does (docs/can.md, "Enable and
   * clear") */
  drv->armed = false;
  drv->tm.armed = 0u;
  drv->arm_mark = drv->cmd.enable_count;
}

/* ------------------------------------------------------------ configure */

static void speed_cfg_from(speed_ctrl_cfg_t *scfg, const drive_config_t *cfg) {
  speed_ctrl_design(scfg, cfg->inertia, cfg->speed_bw);
  scfg->ts = cfg->ts * (float)cfg->slow_div;
  scfg->accel_max = cfg->accel_max;
  scfg->torque_max = cfg->torque_max;
}

/* From the current sample to the centre of the interval the output acts:
 * the next period [Ts, 2 Ts) after the period start (hal.h). */
static float drive_t_out(const drive_t *drv, const drive_config_t *cfg) {
  return 1.5f * cfg->ts - drv->caps->t_i;
}

void drive_machine_copy(machine_t *dm, flux_map_t *dmap, const machine_t *m,
                        const flux_map_t *map) {
  *dmap = *map;
  *dm = *m;
  dm->map = m->kind == MACHINE_FLUX_MAP ? dmap : NULL;
}

FD_COLD int drive_config_usable(const drive_config_t *cfg, drive_law_t law, machine_t *m,
                                flux_map_t *map, drive_config_err_t *err) {
  if (drive_config_check(cfg, err) != 0) {
    return -1;
  }
  *map = (flux_map_t){0};
  const int linear = drive_config_map(cfg, map, err);
  if (linear < 0) {
    return -1;
  }
  if ((linear != 0
           ? machine_init_linear(m, cfg->pole_pairs, cfg->rs, cfg->ld, cfg->lq, cfg->lambda_m)
           : machine_init_map(m, cfg->rs, map)) != 0) {
    err->field = linear != 0 ? "ld" : "machine_map";
    err->reason = "the machine model refused the machine parameters";
    return -1;
  }
  const ctrl_law_t *row = ctrl_law(law);
  const ctrl_setup_t su = {cfg, m, 1.5f * cfg->ts};
  const char *why = row != NULL ? row->check(&su) : "no such law";
  if (why != NULL) {
    err->field = "law";
    err->reason = why;
    return -1;
  }
  if (cfg->mode == DRIVE_MODE_CURRENT && (row->caps & CTRL_CAP_CURRENT) == 0u) {
    err->field = "mode";
    err->reason = "the law has no current mode";
    return -1;
  }
  const pos_source_row_t *ps = pos_source(cfg->pos_source);
  const char *pwhy = ps->check != NULL ? ps->check(cfg, &err->field) : NULL;
  if (pwhy != NULL) {
    err->reason = pwhy;
    return -1;
  }
  /* the procedures of the start this set wants (proc.h) */
  const proc_setup_t psu = {cfg, m, ps, NULL, NULL, false};
  const char *why_p = proc_start_refusal(&psu, &err->field);
  if (why_p != NULL) {
    err->reason = why_p;
    return -1;
  }
  return 0;
}

/* What the ISR would otherwise divide for every period (LIVE parameters
 * included: called again when they change). */
FD_COLD static void drive_derive(drive_t *drv) {
  const drive_config_t *c = &drv->cfg;
  /* the duty range: the board's, narrowed by a DFC window */
  drv->duty_lo = drv->caps->duty_min;
  drv->duty_hi = drv->caps->duty_max;
  const pos_source_row_t *ps = pos_source(c->pos_source);
  drv->gated = ps != NULL && (ps->caps & POS_CAP_GATED) != 0u;
  if (drv->gated) {
    dfc_window_range(c->dfc_t0 / c->ts, c->dfc_tw / c->ts, drv->caps->duty_min, drv->caps->duty_max,
                     &drv->duty_lo, &drv->duty_hi);
  }
  drv->v_lin_k = modulation_v_max(1.0f, drv->duty_lo, drv->duty_hi);
  /* Ts / L of the window's sampling correction (linear machines; a
   * flux-map machine has no star-point model in the plant) */
  drv->win_k = (drv->gated && c->machine_map == NULL) ? 2.0f * c->ts / (c->ld + c->lq) : 0.0f;
  drv->lc_n_fast = c->lc_time / c->ts;
  drv->lc_n_track = c->lc_track_time / c->ts;
  drv->inv_pole_pairs = 1.0f / c->pole_pairs;
}

FD_COLD int drive_config_fits_board(const drive_config_t *cfg, const hal_caps_t *caps,
                                    drive_config_err_t *err) {
  if (caps->i_full_scale > 0.0f && !(cfg->i_trip < caps->i_full_scale)) {
    err->field = "i_trip";
    err->reason = "must be below the current ADC's full scale (hal_caps: i_full_scale); a "
                  "current beyond it reads as the full scale and would never trip";
    return -1;
  }
  if (caps->v_full_scale > 0.0f && !(cfg->v_dc_max < caps->v_full_scale)) {
    err->field = "v_dc_max";
    err->reason = "must be below the DC-link ADC's full scale (hal_caps: v_full_scale); a "
                  "voltage beyond it reads as the full scale and would never trip";
    return -1;
  }
  const pos_source_row_t *ps = pos_source(cfg->pos_source);
  const uint32_t need = HAL_CAP_STAR_POINT | HAL_CAP_ASYM_EDGES;
  if (ps != NULL && (ps->caps & POS_CAP_GATED) != 0u && (caps->features & need) != need) {
    err->field = "pos_source";
    err->reason = "the board has no star-point samples with asymmetric PWM edges (DFC window)";
    return -1;
  }
  return 0;
}

FD_COLD int drive_config_validate(const drive_config_t *cfg, drive_law_t law,
                                  const hal_caps_t *caps, machine_t *m, flux_map_t *map,
                                  drive_config_err_t *err) {
  if (drive_config_usable(cfg, law, m, map, err) != 0 ||
      drive_config_fits_board(cfg, caps, err) != 0) {
    return -1;
  }
  /* what the law's initialisation refuses beyond its check (into a
   * scratch state): nothing validated here is refused later by the ISR */
  const ctrl_setup_t su = {cfg, m, 1.5f * cfg->ts - caps->t_i};
  const char *why = ctrl_law_refusal(law, &su);
  if (why != NULL) {
    err->field = "law";
    err->reason = why;
    return -1;
  }
  return 0;
}

/* Everything derived from the parameter set (ISR-owned; gates off). */
FD_COLD static int drive_configure(drive_t *drv, const drive_config_t *cfg, drive_law_t law,
                                   drive_config_err_t *err) {
  machine_t m;
  flux_map_t map;
  if (drive_config_usable(cfg, law, &m, &map, err) != 0 ||
      drive_config_fits_board(cfg, drv->caps, err) != 0) {
    return -1;
  }
  drv->cfg = *cfg;
  drive_machine_copy(&drv->machine, &drv->map, &m, &map);
  drive_derive(drv);
  const char *reason = "";
  if (ctrl_init(&drv->ctrl, &drv->cfg, &drv->machine, drive_t_out(drv, cfg), law, &reason) != 0) {
    err->field = "law";
    err->reason = reason;
    return -1;
  }
  drv->pos_src = pos_source(cfg->pos_source);
  drv->pos_src->init(&drv->pos_st, cfg);
  drv->pos.out.load = 0.0f;    /* written by the sources that estimate it (pos_source.h) */
  drv->pos.out.rls_ok = false; /* the same: ivd+kf+rls */
  speed_ctrl_cfg_t scfg;
  speed_cfg_from(&scfg, cfg);
  speed_ctrl_init(&drv->speed, &scfg);
  drv->torque_min_avail = -cfg->torque_max;
  drv->torque_max_avail = cfg->torque_max;
  /* scales of the loss-of-control monitor: torque and flux on MTPA at i_max */
  const dq_t i_rated =
      machine_mtpa_current(&drv->machine, machine_mtpa_torque(&drv->machine, cfg->i_max));
  const dq_t l_rated = machine_flux(&drv->machine, i_rated);
  drv->torque_scale = machine_torque(&drv->machine, i_rated);
  const dq_t l_pm = machine_flux(&drv->machine, (dq_t){0.0f, 0.0f});
  drv->psi_pm = sqrtf(l_pm.d * l_pm.d + l_pm.q * l_pm.q);
  drv->psi0 = l_pm;
  const dq_t i_sc = machine_current(&drv->machine, (dq_t){0.0f, 0.0f});
  drv->i_sc = sqrtf(i_sc.d * i_sc.d + i_sc.q * i_sc.q);
  drv->asc_psi_max = drive_safe_psi_max(drv);
  drv->flux_scale = sqrtf(l_rated.d * l_rated.d + l_rated.q * l_rated.q);
  return 0;
}

/* The LIVE parameters of cfg into the set in force (running), if the set
 * they make with the others in force is valid (a request validated whole
 * may not be valid in part: its i_trip with the i_max in force); otherwise
 * nothing now. Returns true when something of cfg waits for the gates to
 * be off. */
FD_COLD static bool configure_live(drive_t *drv, const drive_config_t *cfg) {
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  drive_config_t next = drv->cfg;
  bool rest = false;
  for (unsigned k = 0; k < n; ++k) {
    const float v = drive_param_get(cfg, &t[k]);
    if (t[k].access == DRIVE_PARAM_LIVE) {
      drive_param_set(&next, &t[k], v);
    } else {
      const float w = drive_param_get(&drv->cfg, &t[k]);
      rest = rest || v < w || v > w;
    }
  }
  const char *pf = NULL;
  const pos_source_row_t *ps = pos_source(next.pos_source);
  drive_config_err_t e;
  if (drive_config_check(&next, NULL) != 0 ||
      (ps->check != NULL && ps->check(&next, &pf) != NULL) ||
      drive_config_fits_board(&next, drv->caps, &e) != 0) {
    return true; /* all of it when the gates are off */
  }
  drv->cfg = next;
  drive_derive(drv);
  speed_ctrl_cfg_t scfg;
  speed_cfg_from(&scfg, &drv->cfg);
  /* new gains and limits; the integral and the ramp carry on */
  drv->speed.cfg = scfg;
  drv->speed.cfg.torque_max = fabsf(scfg.torque_max);
  drv->speed.pi.kp = scfg.kp;
  drv->speed.pi.ki = scfg.ki;
  return rest;
}

FD_COLD int drive_init(drive_t *drv, const drive_config_t *cfg, drive_config_err_t *err) {
  drive_config_err_t dummy;
  if (err == NULL) {
    err = &dummy;
  }
  memset(drv, 0, sizeof *drv);
  drv->caps = hal_caps();
  machine_t m;
  flux_map_t map;
  if (drive_config_validate(cfg, cfg->law, drv->caps, &m, &map, err) != 0 ||
      drive_configure(drv, cfg, cfg->law, err) != 0) {
    return -1;
  }
  drv->law_refused = DRIVE_LAW_COUNT;
  drv->state = DRIVE_STATE_IDLE;
  drv->cmd.law = cfg->law;
  drv->cmd.mode = cfg->mode;
  drv->armed = true;
  drv->tm.armed = 1u;
  drv->req.cmd = drv->cmd;
  drv->creq.cfg = *cfg;
  if (hal_reset_by_watchdog()) {
    drv->faults = DRIVE_FAULT_WATCHDOG;
    drv->state = DRIVE_STATE_FAULT;
  }
  drive_overrun_init(drv);
  drive_gates_off(drv);
  drv->tm.state = drv->state;
  drv->tm.faults = drv->faults;
  drv->tm.law = drv->ctrl.law;
  drv->tm.mode = drv->cmd.mode;
  drv->host.tm = drv->tm;
  err->field = "";
  err->reason = "";
  return 0;
}

/* ------------------------------------------------------------- requests */

/* The main loop's parameter request (creq): all of it with the gates off,
 * the LIVE part while running (the rest when the gates are off again). */
static void take_config(drive_t *drv) {
  const uint32_t seq = drv->creq.seq;
  if ((seq & 1u) != 0u || (seq == drv->cfg_seen && !drv->cfg_pending)) {
    return;
  }
  DRIVE_BARRIER();
  drv->cfg_seen = seq;
  if (gates_on_state(drv->state) || drv->state == DRIVE_STATE_OFFSET_CAL) {
    drv->cfg_pending = configure_live(drv, &drv->creq.cfg);
    return;
  }
  /* nothing written in a fault or under the short changes how the safe
   * state is held (asc_speed, i_max, the machine ...): the set waits until
   * the fault is cleared and the short has ended (issue 22, point 1) */
  if (drv->state == DRIVE_STATE_FAULT || drv->safe.asc) {
    drv->cfg_pending = true;
    return;
  }
  drv->cfg_pending = false;
  const drive_config_t prev = drv->cfg;
  const drive_law_t prev_law = drv->ctrl.law;
  drive_config_err_t err;
  /* with the law commanded: the main loop validated the request against it */
  if (drive_configure(drv, &drv->creq.cfg, drv->cmd.law, &err) != 0) {
    /* cannot happen (validated): keep the set in force and say so */
    (void)drive_configure(drv, &prev, prev_law, &err);
    drive_trip(drv, DRIVE_FAULT_CONFIG);
  }
}

/* The fault requests of the command block in force, per bit, against
 * those seen (the clear marks them void): only when their total changed. */
static FD_NOINLINE void take_fault_requests(drive_t *drv) {
  uint32_t req = 0u;
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    if (drv->cmd.fault_count[b] != drv->fault_seen[b]) {
      drv->fault_seen[b] = drv->cmd.fault_count[b];
      req |= 1u << b;
    }
  }
  if (req != 0u) {
    drive_trip(drv, req);
  }
}

/* The main loop's command block (req): references, enable, law and mode,
 * then the clear, then the fault requests not yet taken. A clear clears
 * the faults latched before it, never a request it has not seen: a request
 * posted in the same period, before or after the clear, latches after it
 * (issue 22, point 3). A clear that clears a fault disarms: the drive
 * starts again on an enable command posted after the clear. */
static void take_commands(drive_t *drv) {
  const uint32_t seq = drv->req.seq;
  if ((seq & 1u) != 0u || seq == drv->cmd.seq) {
    return;
  }
  DRIVE_BARRIER();
  drv->cmd = drv->req.cmd;
  drv->cmd.seq = seq;
  if (drv->cmd.clear_count != drv->clear_seen) {
    drv->clear_seen = drv->cmd.clear_count;
    if (drv->state == DRIVE_STATE_FAULT) {
      hal_fault_hw_clear();
      drv->faults = 0u;
      drv->state = DRIVE_STATE_IDLE;
      drv->armed = false; /* an enable posted after the clear is needed */
      drv->tm.armed = 0u;
      drv->arm_mark = drv->cmd.clear_enable_mark;
    }
  }
  if (drv->cmd.fault_total != drv->fault_total_seen) {
    drv->fault_total_seen = drv->cmd.fault_total;
    take_fault_requests(drv);
  }
}

/* ---------------------------------------------------------- protections */

/* The causes of a latched break: the comparator's (also when the board
 * cannot tell) and / or the gate driver's. Off the periodic path: called
 * only once a break has tripped. */
static FD_NOINLINE uint32_t drive_break_causes(void) {
  const uint32_t src = hal_fault_hw_source();
  uint32_t f = (src & HAL_BREAK_GATE_DRIVER) != 0u ? DRIVE_FAULT_GATE_DRIVER : 0u;
  if ((src & HAL_BREAK_OVERCURRENT) != 0u || f == 0u) {
    f |= DRIVE_FAULT_HW_OVERCURRENT;
  }
  return f;
}

static uint32_t drive_protect(const drive_t *drv, const hal_sample_t *s, const float i[3]) {
  const drive_config_t *c = &drv->cfg;
  if (!s->valid ||
      !(fd_isfinite(i[0]) && fd_isfinite(i[1]) && fd_isfinite(i[2]) && fd_isfinite(s->v_dc))) {
    return DRIVE_FAULT_SAMPLE;
  }
  uint32_t f = 0u;
  if (fabsf(i[0]) > c->i_trip || fabsf(i[1]) > c->i_trip || fabsf(i[2]) > c->i_trip) {
    f |= DRIVE_FAULT_OVERCURRENT;
  }
  if (s->v_dc > c->v_dc_max) {
    f |= DRIVE_FAULT_OVERVOLTAGE;
  }
  if (gates_on_state(drv->state) && s->v_dc < c->v_dc_min) {
    f |= DRIVE_FAULT_UNDERVOLTAGE;
  }
  if (fabsf(drv->omega_m) > c->speed_trip) {
    f |= DRIVE_FAULT_OVERSPEED;
  }
  if (hal_fault_hw_tripped()) {
    f |= drive_break_causes();
  }
  /* the position must be usable before the gates go on, and plausible
   * while they are */
  const bool need = drv->gated ? drv->state == DRIVE_STATE_RUN : drive_state_enabled(drv->state);
  if (need && (!drv->pos.out.valid ||
               (drv->state == DRIVE_STATE_RUN && drv->pos.out.health > c->pos_err_max))) {
    f |= DRIVE_FAULT_POSITION;
  }
  return f;
}

/* Loss of control: each condition must hold for lc_time before the trip. */
static void drive_monitor(drive_t *drv, const ctrl_in_t *in, const ctrl_out_t *out) {
  const drive_config_t *c = &drv->cfg;
  uint32_t cond = 0u;
  const float i_lim = c->lc_current * c->i_max;
  if (out->i_dq.d * out->i_dq.d + out->i_dq.q * out->i_dq.q > i_lim * i_lim) {
    cond |= DRIVE_LC_CURRENT;
  }
  if (in->mode != DRIVE_MODE_CURRENT) {
    /* the torque the law says it can deliver now, against its estimate,
     * on the scale of the torque at i_max */
    const float t_ref = fd_clampf(in->torque_ref, out->torque_min, out->torque_max);
    if (fabsf(out->tm.torque - t_ref) > c->lc_track * drv->torque_scale) {
      cond |= DRIVE_LC_TORQUE;
    }
  }
  if ((drv->ctrl.impl->caps & CTRL_CAP_FLUX) != 0u) {
    /* the SPM laws' load-angle limit (the decoupled DFVC's MTPV limit is
     * its torque margin k_T: its load angle from d is near 90 deg on a
     * reluctance machine) */
    if ((drv->ctrl.impl->caps & CTRL_CAP_DELTA) != 0u &&
        fabsf(out->tm.delta) > c->delta_max + c->lc_delta) {
      cond |= DRIVE_LC_DELTA;
    }
    if (fabsf(out->tm.flux - out->tm.flux_ref) > c->lc_track * out->tm.flux_ref) {
      cond |= DRIVE_LC_FLUX;
    }
    /* the observer against its current model, on the scale of the flux at
     * i_max: a detuned model (Rubino 2020, Figs. 19-20) differs by tens of
     * per cent of that at most, a diverging integration by more */
    if (out->tm.obs_err > c->lc_track * drv->flux_scale) {
      cond |= DRIVE_LC_OBSERVER;
    }
  }
  /* current and load angle within lc_time; tracking within lc_track_time */
  const float n_fast = drv->lc_n_fast, n_track = drv->lc_n_track;
  uint32_t trip = 0u;
  for (unsigned k = 0; k < DRIVE_LC_COUNT; ++k) {
    drv->lc_n[k] = (cond & (1u << k)) != 0u ? drv->lc_n[k] + 1u : 0u;
    const uint32_t bit = 1u << k;
    const float n_max = (bit & (DRIVE_LC_CURRENT | DRIVE_LC_DELTA)) != 0u ? n_fast : n_track;
    if ((float)drv->lc_n[k] >= n_max) {
      trip |= bit;
    }
  }
  if (trip != 0u) {
    drv->tm.lc_cause = trip;
    drive_trip(drv, DRIVE_FAULT_LOST_CONTROL);
  }
}

/* The commanded law, gates off. The main loop validated it
 * (drive_config_validate); if it is refused all the same, the law in force
 * stays exactly as it was (ctrl_select) and the refusal trips config once
 * (no retry until another law is commanded). */
static FD_NOINLINE void drive_select_law(drive_t *drv) {
  if (ctrl_select(&drv->ctrl, drv->cmd.law) != 0) {
    drv->law_refused = drv->cmd.law;
    drive_trip(drv, DRIVE_FAULT_CONFIG);
  } else {
    drv->law_refused = DRIVE_LAW_COUNT;
  }
}

/* ------------------------------------------------------------- the loop */

/* The DFC window (Fig. 2.11) in the pattern: test vectors v1, v3, v5 in
 * turn, the two star-point samples around the edge. */
static FD_NOINLINE void drive_window_pattern(drive_t *drv, const float dc[3], hal_pwm_t *req) {
  const drive_config_t *c = &drv->cfg;
  const float inv_ts = 1.0f / c->ts;
  const unsigned leg = drv->dfc_leg;
  drv->dfc_leg = leg >= 2u ? 0u : leg + 1u;
  dfc_window_pattern(dc, leg, c->dfc_t0 * inv_ts, c->dfc_tw * inv_ts, req->on, req->off);
  req->test_vector = (uint8_t)(2u * leg + 1u);
  req->n_star = 2u;
  req->t_star_req[0] = 0.5f * c->dfc_t0;
  req->t_star_req[1] = c->dfc_t0 + c->dfc_t_meas;
}

/* Writes duties (gates on states), returns the voltage the board applies
 * over the next period, rebuilt from the pattern the HAL reports it will
 * really apply (rounding, limits) less the dead-time correction where the
 * leg switches (no switching, no dead-time error). */
static ab_t drive_write(drive_t *drv, const float duty[3], const float dtc[3], float v_dc) {
  /* the correction may not take a leg out of the board's range: the drive
   * asks only for what the board can do (the HAL would clamp the same) */
  float dc[3];
  hal_pwm_t req; /* centred pulses (hal_pwm_centred), built in the same loop */
  for (int x = 0; x < 3; ++x) {
    dc[x] = fd_clampf(duty[x] + dtc[x], drv->duty_lo, drv->duty_hi);
    req.on[x] = 0.5f - 0.5f * dc[x];
    req.off[x] = 0.5f + 0.5f * dc[x];
  }
  req.test_vector = 0u;
  req.n_star = 0u;
  req.t_star_req[0] = 0.0f;
  req.t_star_req[1] = 0.0f;
  const bool window = drv->gated && !drv->plain;
  if (window) {
    drive_window_pattern(drv, dc, &req);
  }
  hal_pwm_t got;
  hal_pwm_write(&req, &got);
  float pole[3];
  for (int x = 0; x < 3; ++x) {
    const float d = got.off[x] - got.on[x];
    drv->tm.duty[x] = d;
    pole[x] = (d > 0.0f && d < 1.0f) ? d - dtc[x] : d;
  }
  if (window) {
    dfc_window_moments(got.on, got.off, drv->win_m); /* for the next sample */
  } else if (drv->gated) {
    drv->win_m[0] = drv->win_m[1] = drv->win_m[2] = 0.0f; /* a plain pattern: nothing to correct */
  }
  return frames_clarke((abc_t){pole[0] * v_dc, pole[1] * v_dc, pole[2] * v_dc});
}

/* The DFC window moves the pulses: the valley sample is corrected to what
 * centred pulses would have given (dfc_window_moments); out of line, the
 * encoder's ISR path pays only the test. */
static FD_NOINLINE void drive_window_sample(const drive_t *drv, float i[3], float v_dc) {
  if (!gates_on_state(drv->state)) {
    return;
  }
  const float k = drv->win_k * v_dc;
  for (int x = 0; x < 3; ++x) {
    i[x] += k * drv->win_m[x];
  }
}

/* The three measured phase currents sum to zero (Kirchhoff, star
 * connection): a gain error, an offset drift or a lost channel shows as a
 * sum beyond i_sum_rel of the largest current (and the noise floor
 * i_sum_abs). Checked at the slow rate with a leaky count (a single
 * channel's error vanishes where its current crosses zero): the fault after
 * DRIVE_I_SUM_TRIP more slow periods over than under. Only where the board
 * measures all three (HAL_CAP_I_ABC) and the gates are on. */
#define DRIVE_I_SUM_TRIP 8
static FD_NOINLINE void drive_current_sum_check(drive_t *drv) {
  const float *i = drv->tm.i_abc; /* the last period's offset-corrected currents */
  const drive_config_t *c = &drv->cfg;
  if ((drv->caps->features & HAL_CAP_I_ABC) == 0u || !gates_on_state(drv->state)) {
    drv->i_sum_n = 0;
    return;
  }
  const float big = fd_maxf(fabsf(i[0]), fd_maxf(fabsf(i[1]), fabsf(i[2])));
  if (fabsf(i[0] + i[1] + i[2]) > fd_maxf(c->i_sum_abs, c->i_sum_rel * big)) {
    if (++drv->i_sum_n >= DRIVE_I_SUM_TRIP) {
      drive_trip(drv, DRIVE_FAULT_CURRENT_SENSOR);
    }
  } else if (drv->i_sum_n > 0) {
    drv->i_sum_n--;
  }
}

/* The position plausibility check, half a slow period after the speed
 * loop (the worst-case ISR does not carry both). */
static FD_NOINLINE void drive_pos_check_step(drive_t *drv) {
  const uint32_t pf = drive_pos_check(drv);
  if (pf != 0u) {
    drive_trip(drv, pf);
  }
}

/* Run-away (issue 23, point 2; docs/faults.md): whatever the position
 * source says, the rotor must not run away from the speed reference
 * against the torque the speed loop asks. The condition, each speed-loop
 * period: the speed is off the (ramped) reference by more than
 * DRIVE_RA_MARGIN |w_ref| + DRIVE_RA_FLOOR speed_max, and the loop's torque
 * pushes it back (torque x error < 0). Held for DRIVE_RA_TIME without a
 * break, it trips lost_control (lc_cause DRIVE_LC_RUNAWAY) if the speed
 * itself has moved meanwhile by DRIVE_RA_FLOOR speed_max further from the
 * reference - the mean over the window's last quarter against the mean
 * over its first, not two single samples of a noisy estimate (a PLL's
 * speed swinging about a rotor that heads for its reference tripped it on a
 * drawn machine) - : the rotor went away against the torque (a wrong polarity or
 * angle turns the torque against the loop). A speed that moves back (a
 * healthy drive braking to its reference, a reversal, a load step the loop
 * catches) or that the reference outruns (a ramp faster than the torque
 * the voltage allows) starts the window again. Once per
 * speed-loop period (1 kHz: the ISR of every slow_div-th period), a few flops. */
#define DRIVE_RA_MARGIN 0.2f  /* of |w_ref| */
#define DRIVE_RA_FLOOR  0.02f /* of speed_max: the margin's floor, and the growth */
#define DRIVE_RA_TIME   0.02f /* s */
static void drive_runaway_check(drive_t *drv, float w, float w_ref, float torque) {
  const drive_config_t *c = &drv->cfg;
  const float e = w - w_ref;
  const float floor = DRIVE_RA_FLOOR * c->speed_max;
  const float ae = fabsf(e);
  if (!(ae > DRIVE_RA_MARGIN * fabsf(w_ref) + floor && torque * e < 0.0f)) {
    drv->ra_n = 0u;
    return;
  }
  const float t_loop = (float)c->slow_div * c->ts;
  const float nf = DRIVE_RA_TIME / t_loop + 0.5f; /* periods in the window, rounded */
  const uint32_t n_win = nf >= 2.0f ? (uint32_t)nf : 1u;
  const uint32_t q = n_win >= 4u ? n_win / 4u : 1u;
  if (drv->ra_n == 0u) {
    drv->ra_w0 = 0.0f;
    drv->ra_w1 = 0.0f;
  }
  drv->ra_n++;
  if (drv->ra_n <= q) {
    drv->ra_w0 += w;
  }
  if (drv->ra_n + q > n_win) {
    drv->ra_w1 += w;
  }
  if (drv->ra_n >= n_win) {
    const float d = (drv->ra_w1 - drv->ra_w0) / (float)q;
    const float away = e > 0.0f ? d : -d;
    if (away > floor) {
      drv->tm.lc_cause = DRIVE_LC_RUNAWAY;
      drive_trip(drv, DRIVE_FAULT_LOST_CONTROL);
    }
    drv->ra_n = 0u; /* a new window */
  }
}

/* The speed loop, every slow_div ISRs, on the angle rate averaged over that
 * period (no lag under acceleration), with the slow-rate checks. */
static void drive_speed_loop(drive_t *drv) {
  const drive_config_t *c = &drv->cfg;
  const uint32_t phase = (drv->isr_count - 1u) % c->slow_div;
  if (phase == c->slow_div / 2u) {
    drive_pos_check_step(drv);
  }
  if (phase != 0u) {
    return;
  }
  drive_current_sum_check(drv);
  if (drive_overrun_check(drv) && drv->state != DRIVE_STATE_FAULT) {
    drive_trip(drv, DRIVE_FAULT_OVERRUN);
  }
  const float w =
      drv->rate_n > 0u ? drv->rate_acc / ((float)drv->rate_n * c->pole_pairs) : drv->omega_m;
  drv->rate_acc = 0.0f;
  drv->rate_n = 0u;
  if (drv->state == DRIVE_STATE_RUN && drv->cmd.mode == DRIVE_MODE_SPEED) {
    if (!drv->speed_active) {
      speed_ctrl_reset(&drv->speed, w, drv->tm.torque_ref);
      drv->speed_active = true;
    }
    /* the limit in force re-clamps the reference (a live speed_max write) */
    const float w_ref = fd_clampf(drv->cmd.speed, -c->speed_max, c->speed_max);
    drv->speed_torque =
        speed_ctrl_update(&drv->speed, w_ref, w, drv->torque_min_avail, drv->torque_max_avail);
    drive_runaway_check(drv, w, drv->speed.w_ref_ramped, drv->speed_torque);
  } else if (drv->speed_active) { /* reset once, when the loop stops */
    speed_ctrl_reset(&drv->speed, drv->omega_m, 0.0f);
    drv->speed_active = false;
    drv->speed_torque = 0.0f;
  }
  drv->tm.speed_ref = drv->speed_active ? drv->speed.w_ref_ramped : 0.0f;
}

/* The mode in force: current mode only with a law that has it. */
static drive_mode_t mode_in_force(const drive_t *drv) {
  const drive_mode_t m = drv->cmd.mode;
  if ((unsigned)m >= (unsigned)DRIVE_MODE_COUNT ||
      (m == DRIVE_MODE_CURRENT && (drv->ctrl.impl->caps & CTRL_CAP_CURRENT) == 0u)) {
    return DRIVE_MODE_TORQUE;
  }
  return m;
}

static void drive_run(drive_t *drv, const float i[3], const hal_sample_t *s) {
  ctrl_in_t in;
  in.i_ab = frames_clarke((abc_t){i[0], i[1], i[2]});
  in.v_applied = drv->v_applied;
  /* the angle at the current sample, from the source's timestamp */
  in.theta_e = frames_wrap_pi(drv->pos.out.theta + drv->pos.out.omega * (s->t_i - drv->pos.out.t));
  in.omega_e = drv->pos.out.omega;
  in.v_lin = drv->v_lin;
  in.mode = mode_in_force(drv);
  in.torque_ref = in.mode == DRIVE_MODE_SPEED ? drv->speed_torque : drv->cmd.torque;
  in.id_ref = drv->cmd.id;
  in.iq_ref = drv->cmd.iq;
  in.flux_ref = drv->cmd.flux;

  ctrl_out_t out;
  ctrl_step(&drv->ctrl, &in, &out);
  if (out.fault != 0u) {
    drive_trip(drv, DRIVE_FAULT_CONTROL);
    return;
  }
  const modulation_out_t m = modulation_minmax(out.v_ref, s->v_dc, drv->duty_lo, drv->duty_hi);
  float dtc[3];
  ctrl_deadtime_delta(&drv->ctrl, &out, dtc);
  drv->v_applied = drive_write(drv, m.duty, dtc, s->v_dc);
  drv->torque_min_avail = out.torque_min;
  drv->torque_max_avail = out.torque_max;

  drive_telemetry_t *tm = &drv->tm;
  tm->i_dq[0] = out.i_dq.d;
  tm->i_dq[1] = out.i_dq.q;
  tm->theta_e = in.theta_e;
  tm->torque_ref = in.torque_ref;
  tm->torque_est = out.tm.torque;
  drv->pos.in.i_q = out.i_dq.q;
  drv->pos.in.torque = out.tm.torque;
  tm->law_tm = out.tm;
  drive_monitor(drv, &in, &out);
}

/* ------------------------------------------------------- the procedures */

/* What a procedure sees of the drive (proc.h): the parameter set, the
 * machine, the position source and the offsets it hands its result to. */
static proc_setup_t drive_proc_setup(drive_t *drv) {
  return (proc_setup_t){&drv->cfg,    &drv->machine, drv->pos_src,
                        &drv->pos_st, drv->offset,   drv->gated};
}

/* The gates come on (a procedure that modulates, or the run): what the run
 * starts from (the law, the source's input, the speed loop, the monitor),
 * the pattern in the middle of the duty range, then the gates. */
FD_COLD FD_NOINLINE static void drive_gates_start(drive_t *drv) {
  ctrl_reset(&drv->ctrl);
  drv->pos.in = (pos_input_t){0.0f, 0.0f}; /* no torque before the run */
  drv->speed_active = false;
  drv->speed_torque = 0.0f;
  memset(drv->lc_n, 0, sizeof drv->lc_n);
  drv->ra_n = 0u;
  drv->ra_w0 = 0.0f;
  drv->ra_w1 = 0.0f;
  drv->tm.lc_cause = 0u;
  drv->v_applied = (ab_t){0.0f, 0.0f};
  drv->plain = false; /* a start aborted mid-pulse may have left it */
  const float mid = 0.5f * (drv->duty_lo + drv->duty_hi);
  const hal_pwm_t p = hal_pwm_centred(mid, mid, mid);
  hal_pwm_write(&p, NULL);
  hal_pwm_enable();
}

/* The start from sequence index k on (proc_start_sequence): the next
 * procedure that applies begins, the gates coming on first if it
 * modulates; none left: the law runs (from a reset: a procedure's current
 * leaves the law's observers and integrators behind). */
FD_COLD FD_NOINLINE static void drive_proc_next(drive_t *drv, uint32_t k) {
  const proc_setup_t su = drive_proc_setup(drv);
  unsigned n;
  const proc_id_t *seq = proc_start_sequence(&n);
  while (k < n && !proc_applies(seq[k], &su)) {
    ++k;
  }
  const proc_row_t *r = k < n ? proc_row(seq[k]) : NULL;
  const bool gates = gates_on_state(drv->state);
  if (!gates && (r == NULL || (r->caps & PROC_CAP_GATES) != 0u)) {
    drive_gates_start(drv);
  }
  drv->proc = r;
  drv->proc_k = k;
  drv->plain = false;
  if (r == NULL) {
    if (gates) { /* after a procedure with the gates on */
      ctrl_reset(&drv->ctrl);
      drv->v_applied = (ab_t){0.0f, 0.0f};
    }
    drv->state = DRIVE_STATE_RUN;
    return;
  }
  r->init(&drv->proc_st, &su);
  proc_telemetry_t *t = &drv->tm.proc;
  *t = (proc_telemetry_t){(uint8_t)r->id, PROC_ST_RUNNING, 0u, 0u, 0u, {0.0f, 0.0f, 0.0f}};
  drv->state = (drive_state_t)r->state;
}

/* Disabled, or tripped by another cause, while a procedure ran. */
FD_COLD FD_NOINLINE static void drive_proc_abort(drive_t *drv) {
  if (drv->proc->abort != NULL) {
    drv->proc->abort(&drv->proc_st);
  }
  drv->proc = NULL;
  drv->plain = false;
  drv->tm.proc.status = PROC_ST_ABORTED;
}

/* One period of the procedure in force: its voltage modulated and written
 * (as a law's, without dead-time compensation), its progress published;
 * done: the next one or the run; failed: its fault. In flash (FD_COLD): the
 * ISR's only during the start. */
FD_COLD FD_NOINLINE static void drive_proc_step(drive_t *drv, const float i[3],
                                                const hal_sample_t *s) {
  const proc_row_t *r = drv->proc;
  const proc_setup_t su = drive_proc_setup(drv);
  const proc_in_t in = {s, frames_clarke((abc_t){i[0], i[1], i[2]}), drv->cfg.v_margin * drv->v_lin,
                        &drv->pos.out};
  proc_out_t out;
  const int res = r->step(&drv->proc_st, &su, &in, &out);
  drv->plain = out.plain;
  if (out.apply) {
    const modulation_out_t m = modulation_minmax(out.v_ab, s->v_dc, drv->duty_lo, drv->duty_hi);
    const float none[3] = {0.0f, 0.0f, 0.0f};
    drv->v_applied = drive_write(drv, m.duty, none, s->v_dc);
  }
  proc_telemetry_t *t = &drv->tm.proc;
  r->publish(&drv->proc_st, t);
  if (res == PROC_FAILED) {
    t->status = PROC_ST_FAILED;
    t->fault = out.fault;
    drv->proc = NULL;
    drv->plain = false;
    drive_trip(drv, out.fault);
  } else if (res == PROC_DONE) {
    t->status = PROC_ST_DONE;
    drive_proc_next(drv, drv->proc_k + 1u);
  }
}

static void drive_publish(drive_t *drv, const hal_sample_t *s, const float i[3]) {
  drive_telemetry_t *tm = &drv->tm;
  tm->isr_count = drv->isr_count;
  tm->state = drv->state;
  tm->faults = drv->faults;
  tm->law = drv->ctrl.law;
  tm->mode = drv->cmd.mode;
  tm->v_dc = s->v_dc;
  tm->i_abc[0] = i[0];
  tm->i_abc[1] = i[1];
  tm->i_abc[2] = i[2];
  tm->v_ab_applied[0] = drv->v_applied.alpha;
  tm->v_ab_applied[1] = drv->v_applied.beta;
  tm->v_ab_filt[0] += DRIVE_VF_K * (drv->v_applied.alpha - tm->v_ab_filt[0]);
  tm->v_ab_filt[1] += DRIVE_VF_K * (drv->v_applied.beta - tm->v_ab_filt[1]);
  tm->omega_m = drv->omega_m;
  tm->pos_health = drv->pos.out.health;
  tm->load_est = drv->pos.out.load;
  tm->rls_ok = drv->pos.out.rls_ok;
  tm->cmd_seq = drv->cmd.seq;
  if (drv->state != DRIVE_STATE_RUN) {
    tm->theta_e = drv->pos.out.theta;
  }
  tm->isr_count_end = drv->isr_count;
  DRIVE_BARRIER();
  drv->tm_seq++; /* the main loop's copy is consistent iff it saw no change */
}

void drive_isr(drive_t *drv) {
  hal_sample_t s;
  hal_adc_read(&s);
  drv->isr_count++;
  take_commands(drv); /* first: a parameter set is validated with the law commanded */
  take_config(drv);

  float i[3];
  for (int x = 0; x < 3; ++x) {
    i[x] = s.i_abc[x] - drv->offset[x];
  }
  if (drv->gated) {
    drive_window_sample(drv, i, s.v_dc);
  }
  drive_speed_loop(drv); /* on the rates of the previous slow_div periods */
  drv->pos_src->update(&drv->pos_st, &drv->cfg, &s, &drv->pos);
  drv->omega_m = drv->pos.out.omega * drv->inv_pole_pairs;
  drv->rate_acc += drv->pos.out.rate;
  drv->rate_n++;
  /* modulation_v_max() of the duty range in force, its span precomputed */
  drv->v_lin = (s.v_dc > 0.0f && fd_isfinite(s.v_dc)) ? drv->v_lin_k * s.v_dc : 0.0f;

  const uint32_t f = drive_protect(drv, &s, i);
  if (f != 0u) {
    drive_trip(drv, f);
  }
  if (!drv->armed && drv->cmd.enable_count != drv->arm_mark) {
    drv->armed = true; /* an enable command since the last disarm */
    drv->tm.armed = 1u;
  }
  const bool enable = drv->cmd.enable && drv->armed;

  switch (drv->state) {
  case DRIVE_STATE_IDLE:
    /* a pending set first: it initialises the commanded law itself (the
     * switch was validated against that set, not the one in force) */
    if (drv->cmd.law != drv->ctrl.law && drv->cmd.law != drv->law_refused && !drv->cfg_pending) {
      drive_select_law(drv);
    }
    if (enable && !drv->safe.asc) { /* the short first ends (drive_safe.c) */
      drv->pos_src->reset(&drv->pos_st);
      drive_proc_next(drv, 0u); /* the start's first procedure: the offsets */
    }
    break;
  case DRIVE_STATE_OFFSET_CAL:
    if (!enable) {
      drive_proc_abort(drv);
      drv->state = DRIVE_STATE_IDLE;
    } else {
      drive_proc_step(drv, i, &s);
    }
    break;
  case DRIVE_STATE_ALIGN:
  case DRIVE_STATE_RUN:
    if (!enable) {
      drive_gates_off(drv);
      drive_safe_leave_gates(drv);
      if (drv->proc != NULL) {
        drive_proc_abort(drv);
      }
      drv->state = DRIVE_STATE_IDLE;
    } else if (drv->state == DRIVE_STATE_ALIGN) {
      drive_proc_step(drv, i, &s); /* the alignment or the held start */
    } else {
      drive_run(drv, i, &s);
    }
    break;
  case DRIVE_STATE_FAULT:
  default:
    if (drv->proc != NULL) { /* tripped by another cause during a procedure */
      drive_proc_abort(drv);
    }
    break; /* all off or shorted: drive_safe_step */
  }
  if (!gates_on_state(drv->state)) {
    drv->v_applied = (ab_t){0.0f, 0.0f};
    drive_safe_step(drv, i, &s);
  }
  drive_publish(drv, &s, i);
}
