/*
 * drive.c - the drive: state machine, ISR body, the per-period checks of
 * the sample set, and the views through which the protections (owned parts
 * in protect/) see the drive, with the slow-rate schedule that runs them
 * (drive.h).
 *
 * idle -> offset calibration -> [align] -> run -> (fault). The ISR takes the
 * main loop's requests at its start, evaluates the protections on the
 * sample just read, and a fault disables the gates in the same ISR,
 * latches its cause and keeps it until a clear request. The main loop's
 * side of the concurrency contract is drive_host.c.
 */
#include "drive.h"
#include "drive_sync.h"
#include "proc.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "control/dfc_window.h"
#include "control/modulation.h"
#include "math/fd_math.h"
#include "math/frames.h"

__attribute__((always_inline)) static inline bool gates_on_state(drive_state_t s) {
  /* the run, and the states from the alignment on (drive.h: the last two) */
  return s == DRIVE_STATE_RUN || s >= DRIVE_STATE_ALIGN;
}

/* The mode in force (drive_t.mode): current mode only with a law that has
 * it. Taken where either changes (a command block, a law's selection or
 * initialisation), not every period. */
FD_COLD static void drive_mode_refresh(drive_t *drv) {
  const drive_mode_t m = drv->cmd.mode;
  /* no law after a refused initialisation (ctrl_init): the set in force
   * is configured again at once (take_config), or the drive not started */
  const uint32_t caps = drv->ctrl.impl != NULL ? drv->ctrl.impl->caps : 0u;
  drv->mode = ((unsigned)m >= (unsigned)DRIVE_MODE_COUNT ||
               (m == DRIVE_MODE_CURRENT && (caps & CTRL_CAP_CURRENT) == 0u))
                  ? DRIVE_MODE_TORQUE
                  : m;
  /* the loss-of-control conditions that apply with this law and mode */
  drv->lc_checks =
      (drv->mode != DRIVE_MODE_CURRENT ? PROTECT_LC_CHECK_TORQUE : 0u) |
      ((caps & CTRL_CAP_FLUX) != 0u
           ? PROTECT_LC_CHECK_FLUX | ((caps & CTRL_CAP_DELTA) != 0u ? PROTECT_LC_CHECK_DELTA : 0u)
           : 0u);
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
 * in this ISR (protect/drive_safe.c), the cause latched. */
static FD_NOINLINE void drive_trip(drive_t *drv, uint32_t bits) {
  if (!drv->safe.asc) {
    drive_gates_off(drv);
    protect_safe_leave_gates(&drv->safe);
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

/* Cold (flash): a parameter set is applied with the gates off. */
FD_COLD void drive_machine_copy(machine_t *dm, flux_map_t *dmap, const machine_t *m,
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
  const proc_setup_t psu = {cfg, m, ps, NULL, NULL, NULL, false};
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
  drv->inv_pole_pairs = 1.0f / c->pole_pairs;
}

/* The position check runs every DRIVE_POS_CHECK_DIV-th slow period (its
 * ISR cost: one sine, one model evaluation). */
#define DRIVE_POS_CHECK_DIV 2u

/* The protections' limits from the parameter set in force (LIVE ones
 * included: called again when they change) and the machine's scales. */
FD_COLD static void drive_protect_configure(drive_t *drv) {
  const drive_config_t *c = &drv->cfg;
  const protect_lc_cfg_t lc = {c->lc_current,     c->i_max,       c->lc_track,      c->delta_max,
                               c->lc_delta,       c->lc_time,     c->lc_track_time, c->ts,
                               drv->torque_scale, drv->flux_scale};
  protect_lc_configure(&drv->lc, &lc);
  protect_ra_configure(&drv->ra, c->speed_max, (float)c->slow_div * c->ts);
  const protect_pos_cfg_t pc = {DRIVE_POS_CHECK_DIV * (uint32_t)c->slow_div,
                                drive_t_out(drv, c),
                                c->ts,
                                c->rs,
                                c->pos_emf_tol,
                                &drv->machine,
                                drv->psi0,
                                drv->psi_pm};
  protect_pos_configure(&drv->pos_chk, &pc);
}

FD_COLD int drive_config_fits_board(const drive_config_t *cfg, const hal_caps_t *caps,
                                    drive_config_err_t *err) {
  /* mut: adc_range_not_checked */
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
  /* mut: star_point_board_unchecked */
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
  drv->slow_wait = 0u; /* the schedule's next phase from slow_div in force */
  drive_machine_copy(&drv->machine, &drv->map, &m, &map);
  drive_derive(drv);
  const char *reason = "";
  const int law_err =
      ctrl_init(&drv->ctrl, &drv->cfg, &drv->machine, drive_t_out(drv, cfg), law, &reason);
  drive_mode_refresh(drv);
  if (law_err != 0) {
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
  drv->flux_scale = sqrtf(l_rated.d * l_rated.d + l_rated.q * l_rated.q);
  /* this set's flux scale bounds the short's bisection (the previous set's,
   * 0 at start-up, bounded a reluctance machine's trapped flux at 0: every
   * short refused until a second set was taken) */
  protect_safe_configure(&drv->safe, &drv->machine, drv->psi_pm,
                         sqrtf(i_sc.d * i_sc.d + i_sc.q * i_sc.q), drv->flux_scale, cfg->i_trip);
  drive_protect_configure(drv);
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
  drive_protect_configure(drv);
  speed_ctrl_cfg_t scfg;
  speed_cfg_from(&scfg, &drv->cfg);
  /* new gains and limits; the integral and the ramp carry on */
  speed_ctrl_retune(&drv->speed, &scfg);
  /* the torque the law has, within a lowered torque_max at once */
  const float tm = drv->speed.cfg.torque_max;
  drv->speed_torque = fd_clampf(drv->speed_torque, -tm, tm);
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
  drive_mode_refresh(drv);
  drv->armed = true;
  drv->tm.armed = 1u;
  drv->req.cmd = drv->cmd;
  drv->creq.cfg = *cfg;
  if (hal_reset_by_watchdog()) {
    drv->faults = DRIVE_FAULT_WATCHDOG;
    drv->state = DRIVE_STATE_FAULT;
  }
  protect_overrun_init(&drv->overrun, hal_isr_overruns());
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
  /* mut: race_config_odd_seq */
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
  /* mut: write_in_fault_applied */
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
  /* mut: race_commands_odd_seq */
  if ((seq & 1u) != 0u || seq == drv->cmd.seq) {
    return;
  }
  DRIVE_BARRIER();
  drv->cmd = drv->req.cmd;
  drv->cmd.seq = seq;
  drive_mode_refresh(drv);
  if (drv->cmd.clear_count != drv->clear_seen) {
    /* mut: clear_voids_unseen_requests */
    drv->clear_seen = drv->cmd.clear_count;
    /* mut: race_clear_in_main_loop.1 */
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
  /* mut: break_source_ignored */
  if ((src & HAL_BREAK_OVERCURRENT) != 0u || f == 0u) {
    f |= DRIVE_FAULT_HW_OVERCURRENT;
  }
  return f;
}

/* The checks that do not depend on the sample's values: the hardware
 * break, and the position: usable before the gates go on, and plausible
 * while they are. */
static uint32_t drive_protect_rest(const drive_t *drv) {
  uint32_t f = 0u;
  if (hal_fault_hw_tripped()) {
    f |= drive_break_causes();
  }
  const bool need = drv->gated ? drv->state == DRIVE_STATE_RUN : drive_state_enabled(drv->state);
  if (need && (!drv->pos.out.valid ||
               (drv->state == DRIVE_STATE_RUN && drv->pos.out.health > drv->cfg.pos_err_max))) {
    f |= DRIVE_FAULT_POSITION;
  }
  return f;
}

static uint32_t drive_protect_values(const drive_t *drv, const hal_sample_t *s, const float i[3]);

/* The per-period checks on the sample set. The usual period first: each
 * comparison below is false for a NaN, and an infinity fails one of them
 * too, so a sample that passes them all is finite, valid and trips none of
 * the limits; anything else takes the full checks, which name the causes.
 * What remains for the usual period is the break and the position. */
static uint32_t drive_protect(const drive_t *drv, const hal_sample_t *s, const float i[3]) {
  const drive_config_t *c = &drv->cfg;
  const float v_lo = gates_on_state(drv->state) ? c->v_dc_min : -FLT_MAX;
  const float t = c->i_trip;
  uint32_t f = 0u;
  if (!(s->valid && fabsf(i[0]) <= t && fabsf(i[1]) <= t && fabsf(i[2]) <= t &&
        s->v_dc <= c->v_dc_max && s->v_dc >= v_lo && fabsf(drv->omega_m) <= c->speed_trip)) {
    f = drive_protect_values(drv, s, i);
    if (f == DRIVE_FAULT_SAMPLE) {
      return f; /* nothing else is judged on a bad sample */
    }
  }
  return f | drive_protect_rest(drv);
}

/* The sample's checks off the usual path (a trip, a bad sample): in flash.
 * DRIVE_FAULT_SAMPLE alone for an invalid or non-finite sample set. */
FD_COLD static FD_NOINLINE uint32_t drive_protect_values(const drive_t *drv, const hal_sample_t *s,
                                                         const float i[3]) {
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
  return f;
}

/* Loss of control (protect/lc_monitor.h): each condition must hold for its
 * time before the trip. */
static void drive_monitor(drive_t *drv, const ctrl_in_t *in, const ctrl_out_t *out) {
  const uint32_t checks = drv->lc_checks; /* of drv->mode, as in.current (drive_mode_refresh) */
  const ctrl_telemetry_t *t = out->tm;
  const protect_lc_view_t v = {out->i_dq.d,     out->i_dq.q,     t->torque, in->torque_ref,
                               out->torque_min, out->torque_max, t->delta,  t->flux,
                               t->flux_ref,     t->obs_err,      checks};
  const uint32_t trip = protect_lc_step(&drv->lc, &v);
  if (trip != 0u) {
    drv->tm.lc_cause = trip;
    drive_trip(drv, DRIVE_FAULT_LOST_CONTROL);
  }
}

/* The commanded law, gates off. The main loop validated it
 * (drive_config_validate); if it is refused all the same, the law in force
 * stays exactly as it was (ctrl_select) and the refusal trips config once
 * (no retry until another law is commanded). */
static FD_COLD FD_NOINLINE void drive_select_law(drive_t *drv) { /* gates off: flash */
  const int refused = ctrl_select(&drv->ctrl, drv->cmd.law);
  drive_mode_refresh(drv);
  if (refused != 0) {
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
  const float lo = drv->duty_lo;
  const float hi = drv->duty_hi;
#pragma GCC unroll 3 /* -Os keeps loops: three legs straight through save their overhead */
  for (int x = 0; x < 3; ++x) {
    dc[x] = fd_clampf(duty[x] + dtc[x], lo, hi);
  }
  hal_pwm_t req;
  /* mut: held_start_pulses_windowed */
  const bool window = drv->gated && !drv->plain;
  if (window) {
    drive_window_pattern(drv, dc, &req); /* every field of req */
  } else {
    /* centred pulses (hal_pwm_centred) */
#pragma GCC unroll 3
    for (int x = 0; x < 3; ++x) {
      req.on[x] = 0.5f - 0.5f * dc[x];
      req.off[x] = 0.5f + 0.5f * dc[x];
    }
    req.test_vector = 0u;
    req.n_star = 0u;
    req.t_star_req[0] = 0.0f;
    req.t_star_req[1] = 0.0f;
  }
  hal_pwm_t got;
  hal_pwm_write(&req, &got);
  float pole[3];
#pragma GCC unroll 3
  for (int x = 0; x < 3; ++x) {
    const float d = got.off[x] - got.on[x];
    drv->tm.duty[x] = d;
    /* mut: board_duty_range_ignored.2 */
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
  /* mut: dfc_window_sample_uncorrected */
  const float k = drv->win_k * v_dc;
  for (int x = 0; x < 3; ++x) {
    i[x] += k * drv->win_m[x];
  }
}

/* ------------------------------------------------- the slow-rate schedule */

/* The current-sum check (protect/isum.h) on the last period's currents. */
static FD_NOINLINE void drive_isum_row(drive_t *drv, bool due) {
  (void)due;
  const drive_config_t *c = &drv->cfg;
  /* the absolute bound no lower than the sensors' own noise (proc_offset.c)
   * plus the three channels' rounding (at most half a step each: at zero
   * current, without dither, the offsets' samples do not show it) */
  /* mut: isum_noise_floor_ignored */
  const float floor_n = drv->i_sum_noise + 1.5f * drv->caps->i_lsb;
  const protect_isum_view_t v = {drv->tm.i_abc, fd_maxf(c->i_sum_abs, floor_n), c->i_sum_rel,
                                 (drv->caps->features & HAL_CAP_I_ABC) != 0u &&
                                     gates_on_state(drv->state)};
  const uint32_t f = protect_isum_step(&drv->isum, &v);
  if (f != 0u) {
    drive_trip(drv, f);
  }
}

/* The ISR overrun check (protect/overrun.h): not while a fault holds. */
static void drive_overrun_row(drive_t *drv, bool due) {
  (void)due;
  const protect_overrun_view_t v = {hal_isr_overruns(), drv->cfg.overrun_n, drv->cfg.overrun_k};
  if (protect_overrun_step(&drv->overrun, &v) != 0u && drv->state != DRIVE_STATE_FAULT) {
    drive_trip(drv, DRIVE_FAULT_OVERRUN);
  }
}

/* The position plausibility check (protect/drive_pos_check.h) on the
 * telemetry of the last period, before the source's update. */
FD_COLD static FD_NOINLINE void drive_pos_check_row(drive_t *drv, bool due) {
  const drive_config_t *c = &drv->cfg;
  const drive_telemetry_t *tm = &drv->tm;
  /* !gated: the source's POS_CAP_GATED (drive_derive), one load */
  const protect_pos_view_t v = {c->pos_emf_tol > 0.0f && drv->state == DRIVE_STATE_RUN &&
                                    tm->state == DRIVE_STATE_RUN && !drv->gated &&
                                    fd_isfinite(tm->v_dc),
                                due,
                                drv->pos.out.omega,
                                tm->theta_e,
                                (dq_t){tm->i_dq[0], tm->i_dq[1]},
                                (ab_t){tm->v_ab_applied[0], tm->v_ab_applied[1]},
                                tm->v_dc};
  const uint32_t pf = protect_pos_step(&drv->pos_chk, &v);
  if (pf != 0u) {
    drive_trip(drv, pf);
  }
}

/* The speed loop, on the angle rate averaged over the slow period (no lag
 * under acceleration), and its run-away check (protect/runaway.h). */
static void drive_speed_row(drive_t *drv, bool due) {
  (void)due;
  const drive_config_t *c = &drv->cfg;
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
    const protect_ra_view_t v = {w, drv->speed.w_ref_ramped, drv->speed_torque};
    const uint32_t ra = protect_ra_step(&drv->ra, &v);
    if (ra != 0u) {
      drv->tm.lc_cause = ra;
      drive_trip(drv, DRIVE_FAULT_LOST_CONTROL);
    }
  } else if (drv->speed_active) { /* reset once, when the loop stops */
    speed_ctrl_reset(&drv->speed, drv->omega_m, 0.0f);
    drv->speed_active = false;
    drv->speed_torque = 0.0f;
  }
  drv->tm.speed_ref = drv->speed_active ? drv->speed.w_ref_ramped : 0.0f;
}

/* The slow-rate schedule: what runs once per slow period (slow_div ISRs,
 * the speed loop's period), at which ISR of it, how often. The ISR walks
 * the table every period (drive_schedule: DRIVE_SLOW_ROWS rows, bounded);
 * a row runs in the ISR whose phase in the slow period is its phase
 * (DRIVE_PHASE_START: the first ISR, the one after the slow period's last
 * rate sample; DRIVE_PHASE_NEXT: the second; DRIVE_PHASE_AFTER: the third;
 * DRIVE_PHASE_MID: slow_div / 2 ISRs after the first), and `due` tells it
 * whether this slow period is one of every `divider` (a row may need the
 * other periods too: the position check restarts when it does not apply,
 * checked or not). The rows of an ISR run in the table's order (phases
 * that fall in one ISR, slow_div < 4: MID, AFTER, START, NEXT). The phases split the slow work so
 * that no ISR carries two heavy items (issue 24 point 8): the current-sum
 * check at the start (where the main loop's commands come in the SIL), the
 * speed loop and its run-away check in the next ISR (its torque to the law
 * in that ISR: handed a period later it met the sensorless worst case's
 * target, 45 %, but lost a sensorless start, test_random_machines star seed
 * 1 dfc+kf from 0.99 rad), the overrun check in the one after,
 * the position check (one sine, one model evaluation) half a slow period
 * later. The first two ISRs (`defer`: the current-sum check, where
 * the main loop's commands come in too, the speed loop and the law's work
 * on its torque) are the position source's busy periods (pos_input_t.busy):
 * the RLS's halves wait for a free one (pos_rls.c). Before, the speed loop, the law's MTPA current
 * on its torque and an RLS half met in one ISR: the sensorless worst case (board estimate 51 % of
 * the budget). The current-sum check stays at the start: it samples one period a slow period, and
 * at another place in the slow period its trip in sil/test_adc_faults (a channel stuck at 0 at 0.2
 * N m) came at 25.5 ms, not 11 ms (the samples fall elsewhere on the currents' wave). A new slow
 * check is one row here and one part in protect/ (docs/architecture.md, "Adding a protection"). */
enum { DRIVE_PHASE_START, DRIVE_PHASE_NEXT, DRIVE_PHASE_AFTER, DRIVE_PHASE_MID, DRIVE_PHASES };

typedef struct {
  // cppcheck-suppress unusedStructMember
  const char *name; /* for docs and debuggers (a row's name in a backtrace) */
  uint8_t phase;    /* DRIVE_PHASE_* */
  uint8_t divider;  /* due every divider-th slow period (1: each) */
  bool defer;       /* heavy: the position source puts off what can wait (pos_input_t.busy) */
  void (*run)(drive_t *drv, bool due);
} drive_slow_row_t;

static const drive_slow_row_t drive_slow_rows[] = {
    {"pos_check", DRIVE_PHASE_MID, DRIVE_POS_CHECK_DIV, false, drive_pos_check_row},
    {"overrun", DRIVE_PHASE_AFTER, 1u, false, drive_overrun_row},
    {"current_sum", DRIVE_PHASE_START, 1u, true, drive_isum_row},
    {"speed_loop", DRIVE_PHASE_NEXT, 1u, true, drive_speed_row},
};
#define DRIVE_SLOW_ROWS (sizeof drive_slow_rows / sizeof drive_slow_rows[0])

/* Every ISR, before the position source's update (the speed loop runs on
 * the rates of the previous slow_div periods): the rows whose phase this
 * ISR is. */
static void drive_schedule(drive_t *drv) {
  /* the usual ISR: no row, a count down to the next phase instead of a
   * division of the ISR count (issue 24 point 8) */
  if (drv->slow_wait > 1u) {
    drv->slow_wait--;
    drv->pos.in.busy = false;
    return;
  }
  const uint32_t div = drv->cfg.slow_div;
  const uint32_t k = drv->isr_count - 1u;
  const uint32_t at = k % div;
  const uint32_t mid = div / 2u;
  /* the phases' offsets, START, NEXT, AFTER, MID: 0, 1, 2, slow_div / 2,
   * those beyond the slow period folded onto 0 (1 % div, 2 % div) */
  const uint32_t off[DRIVE_PHASES] = {0u, div > 1u ? 1u : 0u, div > 2u ? 2u : 0u, mid};
  /* the ISRs to the next phase, from this ISR's place in the slow period
   * (from any place: the count restarts here after a new slow_div): the
   * next of 0, 1, 2, then MID, then the next slow period's START (a folded
   * offset is one already passed) */
  const uint32_t next = at < off[2] ? at + 1u : (at < mid ? mid : div);
  drv->slow_wait = next - at;
  const uint32_t slow_n = k / div;
  /* unrolled: the table is constant, so each row's phase and divider fold
   * at compile time; the rows whose phase is this ISR, in the table's order */
#pragma GCC unroll 16
  for (unsigned r = 0; r < DRIVE_SLOW_ROWS; ++r) {
    const drive_slow_row_t *row = &drive_slow_rows[r];
    if (at == off[row->phase]) {
      if (row->defer) { /* the source puts off what can wait (pos_input_t.busy) */
        drv->pos.in.busy = true;
      }
      row->run(drv, slow_n % row->divider == 0u);
    }
  }
  /* cleared by the next ISR without a row (above): a phase without a
   * deferring row right after one (MID after AFTER, slow_div 6 or 7) stays
   * busy, which only puts an RLS half off by one more period */
}

static void drive_run(drive_t *drv, const float i[3], const hal_sample_t *s) {
  ctrl_in_t in;
  in.i_ab = frames_clarke((abc_t){i[0], i[1], i[2]});
  in.v_applied = drv->v_applied;
  /* the angle at the current sample, from the source's timestamp */
  in.theta_e = frames_wrap_pi(drv->pos.out.theta + drv->pos.out.omega * (s->t_i - drv->pos.out.t));
  in.omega_e = drv->pos.out.omega;
  in.v_lin = drv->v_lin;
  in.current = drv->mode == DRIVE_MODE_CURRENT;
  in.torque_ref = drv->mode == DRIVE_MODE_SPEED ? drv->speed_torque : drv->cmd.torque;
  in.id_ref = drv->cmd.id;
  in.iq_ref = drv->cmd.iq;
  in.flux_ref = drv->cmd.flux;

  ctrl_out_t out;
  /* the law writes its telemetry where it is published (also on the
   * period it faults: what it saw then; the safe state keeps reading the
   * last good period's flux, law_flux) */
  out.tm = &drv->tm.law_tm;
  ctrl_step(&drv->ctrl, &in, &out);
  if (out.fault != 0u) {
    drive_trip(drv, DRIVE_FAULT_CONTROL);
    return;
  }
  /* the duties alone: drive_write rebuilds the applied voltage from what
   * the board will apply */
  float duty[3];
  /* mut: board_duty_range_ignored.1 */
  /* mut: board_duty_range_only */
  (void)modulation_minmax_duty(out.v_ref, s->v_dc, drv->duty_lo, drv->duty_hi, duty);
  float dtc[3];
  ctrl_deadtime_delta(&drv->ctrl, &out, dtc);
  drv->v_applied = drive_write(drv, duty, dtc, s->v_dc);
  drv->torque_min_avail = out.torque_min;
  drv->torque_max_avail = out.torque_max;
  drv->law_flux = out.tm->flux;

  drive_telemetry_t *tm = &drv->tm;
  tm->i_dq[0] = out.i_dq.d;
  tm->i_dq[1] = out.i_dq.q;
  tm->theta_e = in.theta_e;
  tm->torque_ref = in.torque_ref;
  tm->torque_est = out.tm->torque;
  drv->pos.in.i_q = out.i_dq.q;
  drv->pos.in.torque = out.tm->torque;
  drive_monitor(drv, &in, &out);
}

/* ------------------------------------------------------- the procedures */

/* What a procedure sees of the drive (proc.h): the parameter set, the
 * machine, the position source and the offsets it hands its result to. */
static proc_setup_t drive_proc_setup(drive_t *drv) {
  return (proc_setup_t){&drv->cfg,   &drv->machine,     drv->pos_src, &drv->pos_st,
                        drv->offset, &drv->i_sum_noise, drv->gated};
}

/* The gates come on (a procedure that modulates, or the run): what the run
 * starts from (the law, the source's input, the speed loop, the monitor),
 * the pattern in the middle of the duty range, then the gates. */
FD_COLD FD_NOINLINE static void drive_gates_start(drive_t *drv) {
  ctrl_reset(&drv->ctrl);
  drv->pos.in = (pos_input_t){0.0f, 0.0f, false}; /* no torque before the run */
  drv->speed_active = false;
  drv->speed_torque = 0.0f;
  protect_lc_reset(&drv->lc);
  protect_ra_reset(&drv->ra);
  drv->tm.lc_cause = 0u;
  drv->v_applied = (ab_t){0.0f, 0.0f};
  drv->plain = false; /* a start aborted mid-pulse may have left it */
  const float mid = 0.5f * (drv->duty_lo + drv->duty_hi);
  const hal_pwm_t p = hal_pwm_centred(mid, mid, mid);
  hal_pwm_write(&p, NULL);
  hal_pwm_enable();
}

static void drive_proc_next(drive_t *drv, uint32_t k);

/* An identification request not yet taken (drive_ident_req_t): read only
 * when the main loop is not writing the block (seq even; it cannot write
 * while the ISR runs), so the procedure and its count agree. Idle and the
 * identification's states only. */
static bool ident_pending(const drive_t *drv) {
  const uint32_t seq = drv->req.seq;
  DRIVE_BARRIER();
  return (seq & 1u) == 0u && drv->req.ident.count != drv->ident_seen;
}

/* An identification run ends (done, stopped, aborted): the gates off if
 * they were on, idle. */
FD_COLD FD_NOINLINE static void drive_ident_end(drive_t *drv) {
  if (gates_on_state(drv->state)) {
    drive_gates_off(drv);
    protect_safe_leave_gates(&drv->safe);
  }
  drv->ident = false;
  drv->ident_seen = drv->req.ident.count; /* the request that ended it is taken */
  drv->plain = false;
  drv->state = DRIVE_STATE_IDLE;
}

/* An identification request taken in idle (drive_cmd_identify): the run
 * of the offsets and the procedure, or its refusal (PROC_ST_REFUSED: the
 * parameter set in force cannot run it; a stop request: nothing). */
FD_COLD FD_NOINLINE static void drive_ident_start(drive_t *drv) {
  drv->ident_seen = drv->req.ident.count;
  const proc_id_t id = (proc_id_t)drv->req.ident.proc; /* read with its count (ident_pending) */
  if (id >= PROC_NONE) {
    return;
  }
  const proc_setup_t su = drive_proc_setup(drv);
  const char *field;
  if (proc_ident_refusal(id, &su, &field) != NULL) {
    drv->tm.proc = (proc_telemetry_t){.id = (uint8_t)id, .status = PROC_ST_REFUSED};
    return;
  }
  unsigned n;
  proc_ident_sequence(id, drv->ident_seq, &n);
  drv->ident_n = n;
  drv->ident = true;
  drv->pos_src->reset(&drv->pos_st);
  drive_proc_next(drv, 0u);
}

/* The start from sequence index k on (proc_start_sequence): the next
 * procedure that applies begins, the gates coming on first if it
 * modulates; none left: the law runs (from a reset: a procedure's current
 * leaves the law's observers and integrators behind). */
FD_COLD FD_NOINLINE static void drive_proc_next(drive_t *drv, uint32_t k) {
  const proc_setup_t su = drive_proc_setup(drv);
  unsigned n = drv->ident_n;
  const proc_id_t *seq = drv->ident ? drv->ident_seq : proc_start_sequence(&n);
  /* an identification runs its procedures as they are; the start those it wants */
  while (k < n && !drv->ident && !proc_applies(seq[k], &su)) {
    ++k;
  }
  const proc_row_t *r = k < n ? proc_row(seq[k]) : NULL;
  const bool gates = gates_on_state(drv->state);
  if (r == NULL && drv->ident) { /* the identification's end: the gates off, idle */
    drive_ident_end(drv);
    return;
  }
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
  *t = (proc_telemetry_t){.id = (uint8_t)r->id, .status = PROC_ST_RUNNING};
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
    float duty[3];
    (void)modulation_minmax_duty(out.v_ab, s->v_dc, drv->duty_lo, drv->duty_hi, duty);
    const float none[3] = {0.0f, 0.0f, 0.0f};
    drv->v_applied = drive_write(drv, duty, none, s->v_dc);
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

/* The safe state with the gates not modulating (protect/drive_safe.h):
 * the part decides on its view, the drive applies its switch actions. In
 * flash: never in an ISR that runs the law. */
FD_COLD FD_NOINLINE static void drive_safe(drive_t *drv, const float i[3], const hal_sample_t *s) {
  const drive_config_t *c = &drv->cfg;
  const protect_safe_view_t v = {i,
                                 s->v_dc,
                                 drv->state,
                                 drv->faults,
                                 hal_fault_hw_tripped(),
                                 drv->pos.out.valid,
                                 (drv->pos_src->caps & POS_CAP_GATED) != 0u,
                                 drv->pos.out.omega,
                                 drv->tm.state == DRIVE_STATE_RUN,
                                 (dq_t){drv->tm.i_dq[0], drv->tm.i_dq[1]},
                                 drv->law_flux,
                                 (drv->ctrl.impl->caps & CTRL_CAP_FLUX) != 0u,
                                 &drv->machine,
                                 c->asc_speed,
                                 c->i_max,
                                 c->v_dc_max,
                                 c->ts,
                                 c->asc_hold};
  const uint32_t act = protect_safe_step(&drv->safe, &v);
  if ((act & PROTECT_SAFE_DISABLE) != 0u) {
    hal_pwm_disable();
  }
  if ((act & PROTECT_SAFE_SHORT) != 0u) {
    hal_pwm_short();
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
  protect_pos_integrate(&drv->pos_chk, drv->v_applied); /* the position check's window */
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
  /* mut: watchdog_kicked_in_isr */
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
  drive_schedule(
      drv); /* the slow rows; the speed loop on the rates of the previous slow_div periods */
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
  /* mut: rearm_on_enable_low */
  if (!drv->armed && drv->cmd.enable_count != drv->arm_mark) {
    drv->armed = true; /* an enable command since the last disarm */
    drv->tm.armed = 1u;
  }
  const bool enable = drv->cmd.enable && drv->armed;

  switch (drv->state) {
  case DRIVE_STATE_IDLE:
    /* a pending set first: it initialises the commanded law itself (the
     * switch was validated against that set, not the one in force) */
    /* mut: law_switch_before_pending_set */
    if (drv->cmd.law != drv->ctrl.law && drv->cmd.law != drv->law_refused && !drv->cfg_pending) {
      drive_select_law(drv);
    }
    /* an identification request is taken here (a start) or during its run
     * (a stop); an enable voids it, so does a fault (below): a request never
     * waits for a later idle */
    if (enable && !drv->safe.asc) { /* the short first ends (protect/drive_safe.c) */
      drv->ident_seen = drv->req.ident.count;
      drv->pos_src->reset(&drv->pos_st);
      drive_proc_next(drv, 0u); /* the start's first procedure: the offsets */
    } else if (ident_pending(drv)) {
      if (!enable && !drv->safe.asc) {
        drive_ident_start(drv);
      }
      drv->ident_seen = drv->req.ident.count;
    }
    break;
  case DRIVE_STATE_OFFSET_CAL:
  case DRIVE_STATE_IDENT:
    /* the start's offsets stop on a disable; an identification's run on an
     * enable or another request (a stop) */
    if (drv->ident ? (enable || ident_pending(drv)) : !enable) {
      drive_proc_abort(drv);
      if (drv->ident) {
        drive_ident_end(drv);
      } else {
        drv->state = DRIVE_STATE_IDLE;
      }
    } else {
      drive_proc_step(drv, i, &s);
    }
    break;
  case DRIVE_STATE_ALIGN:
  case DRIVE_STATE_RUN:
    if (!enable) {
      drive_gates_off(drv);
      protect_safe_leave_gates(&drv->safe);
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
    drv->ident = false; /* an identification ends with the fault, its requests void */
    drv->ident_seen = drv->req.ident.count;
    break; /* all off or shorted: drive_safe */
  }
  if (!gates_on_state(drv->state)) {
    drv->v_applied = (ab_t){0.0f, 0.0f};
    drive_safe(drv, i, &s);
  }
  drive_publish(drv, &s, i);
}
