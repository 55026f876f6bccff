/*
 * drive_host.c - the main loop's side of the drive's concurrency contract
 * (drive.h): the telemetry copy, the watchdog kick, the command and
 * parameter requests the ISR takes at its next period. None of it runs in
 * the ISR (the STM32G474 link keeps it in flash, the ISR's code in CCM
 * SRAM).
 */
#include <math.h>
#include <string.h>

#include "drive.h"
#include "drive_sync.h"
#include "math/fd_math.h"

/* Attempts of drive_telemetry_read: a copy takes far less than a period,
 * so at most one attempt is ever preempted. */
#define DRIVE_TM_TRIES 4

bool drive_telemetry_read(drive_t *drv, drive_telemetry_t *out) {
  for (int n = 0; n < DRIVE_TM_TRIES; ++n) {
    const uint32_t s1 = drv->tm_seq;
    DRIVE_BARRIER();
    *out = drv->tm;
    DRIVE_BARRIER();
    /* the ISR may have run between the two reads (volatile) */
    // cppcheck-suppress knownConditionTrueFalse
    /* mut: race_tm_read_unchecked */
    if (drv->tm_seq == s1) {
      return true;
    }
    drv->host.tm_retries++;
  }
  return false;
}

/* The phase-balance check (protect/drive_phase_check.h) on the fresh
 * telemetry copy, with the parameters requested; its fault is requested
 * like any other main-loop fault (taken by the next ISR). */
static void phase_check(drive_t *drv) {
  const drive_telemetry_t *tm = &drv->host.tm;
  const drive_config_t *c = &drv->creq.cfg;
  const drive_phase_view_t v = {tm->isr_count, tm->state == DRIVE_STATE_RUN,
                                tm->omega_m,   tm->i_abc,
                                tm->v_ab_filt, tm->theta_e,
                                tm->v_dc,      c->pole_pairs,
                                c->ts,         c->rs,
                                c->i_max};
  const uint32_t f = drive_phase_check(&drv->host.ph, &v);
  if (f != 0u) {
    drive_request_fault(drv, f);
  }
}

void drive_background(drive_t *drv) {
  drive_telemetry_t tm;
  if (drive_telemetry_read(drv, &tm)) {
    drv->host.tm = tm;
    phase_check(drv);
  }
  const uint32_t n = drv->isr_count; /* one aligned word: read atomically */
  if (n != drv->host.isr_seen) {
    drv->host.isr_seen = n;
    hal_watchdog_kick();
  }
}

const drive_telemetry_t *drive_telemetry(const drive_t *drv) {
  return &drv->host.tm;
}

const drive_cmd_t *drive_commands(const drive_t *drv) {
  return &drv->req.cmd;
}

const drive_config_t *drive_requested_config(const drive_t *drv) {
  return &drv->creq.cfg;
}

/* The command block is written between cmd_begin and cmd_end (seq odd). */
static drive_cmd_t *cmd_begin(drive_t *drv) {
  drv->req.seq++;
  DRIVE_BARRIER();
  return &drv->req.cmd;
}

static void cmd_end(drive_t *drv) {
  drv->req.cmd.seq++;
  DRIVE_BARRIER();
  drv->req.seq++;
}

/* Command clamp: a non-finite command becomes 0 (not a limit). */
static float command_clamp(float x, float lo, float hi) {
  if (!fd_isfinite(x)) {
    return 0.0f;
  }
  return x < lo ? lo : (x > hi ? hi : x);
}

void drive_cmd_enable(drive_t *drv, bool enable) {
  drive_cmd_t *c = cmd_begin(drv);
  c->enable = enable ? 1u : 0u;
  c->enable_count += enable ? 1u : 0u; /* re-arms after a trip (drive.h) */
  cmd_end(drv);
}

/* mut: race_clear_in_main_loop.2 */
void drive_cmd_clear_fault(drive_t *drv) {
  drive_cmd_t *c = cmd_begin(drv);
  c->clear_count++;
  /* mut: clear_drops_enable */
  c->clear_enable_mark = c->enable_count; /* enables before the clear do not restart */
  cmd_end(drv);
}

const char *drive_cmd_set_law(drive_t *drv, drive_law_t law) {
  const ctrl_law_t *row = ctrl_law(law);
  if (row == NULL) {
    return "no such law";
  }
  if (drv->req.cmd.mode == DRIVE_MODE_CURRENT && (row->caps & CTRL_CAP_CURRENT) == 0u) {
    return "this law has no current mode: leave current mode first";
  }
  /* the whole validation, the law's initialisation included (into a
   * scratch state): a switch answered here is never refused by the ISR */
  machine_t m;
  flux_map_t map;
  drive_config_err_t err;
  if (drive_config_validate(&drv->creq.cfg, law, drv->caps, &m, &map, &err) != 0) {
    return err.reason; /* a static string */
  }
  drive_cmd_t *c = cmd_begin(drv);
  c->law = law;
  cmd_end(drv);
  return NULL;
}

const char *drive_cmd_set_mode(drive_t *drv, drive_mode_t mode) {
  if ((unsigned)mode >= (unsigned)DRIVE_MODE_COUNT) {
    return "no such mode";
  }
  const ctrl_law_t *row = ctrl_law(drv->req.cmd.law);
  if (mode == DRIVE_MODE_CURRENT && (row->caps & CTRL_CAP_CURRENT) == 0u) {
    return "the law has no current mode";
  }
  drive_cmd_t *c = cmd_begin(drv);
  c->mode = mode;
  cmd_end(drv);
  return NULL;
}

void drive_cmd_torque(drive_t *drv, float torque) {
  const float lim = drv->creq.cfg.torque_max;
  drive_cmd_t *c = cmd_begin(drv);
  c->torque = command_clamp(torque, -lim, lim);
  cmd_end(drv);
}

void drive_cmd_speed(drive_t *drv, float speed_m) {
  const float lim = drv->creq.cfg.speed_max;
  drive_cmd_t *c = cmd_begin(drv);
  c->speed = command_clamp(speed_m, -lim, lim);
  cmd_end(drv);
}

/* The current references within the circle of radius lim (each axis
 * first, so that the magnitude is finite). */
static void current_clamp(float *id, float *iq, float lim) {
  *id = command_clamp(*id, -lim, lim);
  *iq = command_clamp(*iq, -lim, lim);
  const float mag = sqrtf(*id * *id + *iq * *iq);
  if (mag > lim) {
    *id *= lim / mag;
    *iq *= lim / mag;
  }
}

void drive_cmd_current(drive_t *drv, float id, float iq) {
  current_clamp(&id, &iq, drv->creq.cfg.i_max);
  drive_cmd_t *c = cmd_begin(drv);
  c->id = id;
  c->iq = iq;
  cmd_end(drv);
}

void drive_cmd_flux(drive_t *drv, float flux) {
  drive_cmd_t *c = cmd_begin(drv);
  c->flux = command_clamp(flux, 0.0f, 10.0f);
  cmd_end(drv);
}

const char *drive_cmd_identify(drive_t *drv, proc_id_t id, const char **field) {
  const char *f_dummy = NULL;
  const char **f = field != NULL ? field : &f_dummy;
  *f = "proc";
  if (id != PROC_NONE) {
    const proc_row_t *r = proc_row(id);
    if (r == NULL || (r->caps & PROC_CAP_IDENT) == 0u) {
      return "not an identification procedure";
    }
    if (drv->req.cmd.enable != 0u) {
      *f = "enable";
      return "the drive is enabled: disable it first";
    }
  }
  *f = NULL;
  /* whether the parameter set in force can run it is the ISR's to say
   * (PROC_ST_REFUSED): the set and the machine are its */
  (void)cmd_begin(drv);
  drv->req.ident.proc = (uint32_t)id;
  drv->req.ident.count++;
  cmd_end(drv);
  return NULL;
}

void drive_request_fault(drive_t *drv, uint32_t fault_bits) {
  drive_cmd_t *c = cmd_begin(drv);
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    if ((fault_bits & (1u << b)) != 0u) {
      c->fault_count[b]++;
    }
  }
  c->fault_total++;
  cmd_end(drv);
}

int drive_request_config(drive_t *drv, const drive_config_t *cfg, drive_config_err_t *err) {
  drive_config_err_t dummy;
  if (err == NULL) {
    err = &dummy;
  }
  machine_t m;
  flux_map_t map;
  if (drive_config_validate(cfg, drv->req.cmd.law, drv->caps, &m, &map, err) != 0) {
    return -1;
  }
  /* first the command block within the new limits (a LIVE speed_max or
   * torque_max lowered while running, an i_max lowered with the gates off
   * under a current reference: fuzz_can's current-limit invariant): the ISR takes
   * it before or with the set, never an old reference beyond the limits in
   * force; the ISR's command block stays the published one */
  drive_cmd_t *c = cmd_begin(drv);
  /* mut: live_limit_not_reclamped */
  c->torque = command_clamp(c->torque, -cfg->torque_max, cfg->torque_max);
  c->speed = command_clamp(c->speed, -cfg->speed_max, cfg->speed_max);
  current_clamp(&c->id, &c->iq, cfg->i_max);
  cmd_end(drv);
  drv->creq.seq++;
  DRIVE_BARRIER();
  drv->creq.cfg = *cfg;
  DRIVE_BARRIER();
  drv->creq.seq++;
  return 0;
}
