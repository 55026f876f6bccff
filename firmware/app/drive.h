/*
 * drive.h - the drive: state machine, ISR body, protections, the command
 * interface of the main loop, telemetry.
 *
 * Concurrency contract (docs/architecture.md, "Concurrency"). Two contexts
 * touch a drive_t: the PWM-period interrupt (drive_isr) and the main loop
 * (drive_cmd_*, drive_params_set, drive_background, can_proto). The ISR
 * preempts the main loop, never the reverse.
 *  - The ISR is the only writer of drive state: state, faults, the
 *    parameter set in force, the machine, laws, position, speed loop,
 *    offsets. Nothing else writes them.
 *  - The main loop posts requests; it is the only writer of:
 *      req   the command block (enable, law, mode, references, clear-fault
 *            and fault-request counters), published under a sequence lock:
 *            seq odd while writing; the ISR takes a copy when seq is even
 *            and changed (it cannot be preempted by the writer, so an even
 *            seq seen at its start means the block is consistent);
 *      creq  a requested parameter set, same protocol; the ISR applies it
 *            at its next period (all of it with the gates off, the LIVE
 *            parameters while running, the rest as soon as the gates are
 *            off again);
 *      host  the main loop's own view (telemetry copy, watchdog bookkeeping).
 *    Counters (clear, fault requests) are compared, never reset, so a
 *    request is never lost and never applied twice.
 *  - Telemetry leaves the ISR under a sequence lock (tm_seq);
 *    drive_telemetry_read() copies it consistently (bounded retries).
 *  - The watchdog is refreshed by drive_background() only, and only when
 *    the ISR has run since the last refresh: a hung main loop or a stopped
 *    interrupt both reset the MCU.
 *
 * Call pattern (board, SIL, PIL):
 *   drive_init(&drv, &cfg, &err)   once, before the interrupt starts
 *   drive_isr(&drv)                every PWM period, right after the samples
 *   drive_cmd_*(&drv, ...)         main loop: post commands (next ISR)
 *   drive_background(&drv)         main loop, every slow period (~1 kHz)
 */
#ifndef FLUXDRIVE_DRIVE_H
#define FLUXDRIVE_DRIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "control/current_ctrl.h"
#include "control/speed_ctrl.h"
#include "ctrl.h"
#include "drive_config.h"
#include "hal.h"
#include "model/machine.h"
#include "pos_source.h"
#include "proc.h"
/* the protections, each an owned part (docs/architecture.md, "Adding a
 * protection"); lc_monitor.h defines the DRIVE_LC_* causes */
#include "protect/drive_phase_check.h"
#include "protect/drive_pos_check.h"
#include "protect/drive_safe.h"
#include "protect/isum.h"
#include "protect/lc_monitor.h"
#include "protect/overrun.h"
#include "protect/runaway.h"

/* Low-pass of the applied voltage for the main loop's voltage balance
 * (drive_telemetry_t.v_ab_filt): the share of each ISR's voltage. */
#define DRIVE_VF_K 0.0625f

/* Everything the drive exposes for telemetry (CAN) and logs. */
typedef struct {
  uint32_t isr_count; /* written first ... */
  drive_state_t state;
  uint32_t faults; /* latched fault bits */
  drive_law_t law;
  drive_mode_t mode;
  float v_dc;            /* [V] */
  float i_abc[3];        /* offset-corrected phase currents [A] */
  float i_dq[2];         /* rotor frame currents [A] */
  float v_ab_applied[2]; /* voltage the last pattern applies [V] */
  float v_ab_filt[2];    /* v_ab_applied through a first-order low-pass of
                            DRIVE_VF_K per ISR (about 1 ms at 16 kHz): the
                            main loop's phase check, drive_phase_check.h [V] */
  float duty[3];         /* duties as the HAL applies them */
  float theta_e;         /* electrical angle at the current sample [rad] */
  float omega_m;         /* mechanical speed estimate [rad/s] */
  float speed_ref;       /* ramped speed reference [rad/s] */
  float torque_ref;      /* [N m] */
  float torque_est;      /* [N m] */
  float pos_health;      /* position source: |measured - predicted| [rad] */
  float load_est;        /* position source's load torque estimate (Kalman filter) [N m] */
  bool rls_ok;           /* ivd+kf+rls: the identified a, b have settled (docs/dfc.md) */
  uint32_t lc_cause;     /* DRIVE_LC_* that tripped lost_control */
  uint32_t cmd_seq;      /* last command block taken (drive_cmd_t.seq) */
  uint32_t armed;        /* drive_t.armed, written where it changes (a trip, a clear that
                            cleared a fault, an enable command after them) */
  ctrl_telemetry_t law_tm;
  proc_telemetry_t proc;  /* the procedure in force or the last one: progress, results (proc.h) */
  uint32_t isr_count_end; /* ... and last: equal to isr_count in a consistent copy */
} drive_telemetry_t;

/* The command block the main loop publishes (drive_t.req). */
typedef struct {
  uint32_t seq;    /* incremented by every drive_cmd_* (echoed in telemetry) */
  uint32_t enable; /* 0 or 1 */
  drive_law_t law;
  drive_mode_t mode;
  float torque;
  float speed;                             /* mechanical [rad/s] */
  float id, iq;                            /* current mode [A] */
  float flux;                              /* stator flux amplitude reference, 0 = automatic [Vs] */
  uint32_t enable_count;                   /* drive_cmd_enable(true) calls */
  uint32_t clear_count;                    /* drive_cmd_clear_fault() calls */
  uint32_t clear_enable_mark;              /* enable_count at the last clear */
  uint32_t fault_count[DRIVE_FAULT_COUNT]; /* drive_request_fault() per bit */
  uint32_t fault_total;                    /* drive_request_fault() calls, all bits */
} drive_cmd_t;

/* The main loop's identification request (drive_t.req.ident, beside the
 * command block and under its sequence lock, but not copied with it: the
 * ISR reads it only in idle and during an identification, when seq is
 * even, so the run's command copy stays as short as it was). */
typedef struct {
  uint32_t proc;  /* the identification asked for (proc_id_t; PROC_NONE: stop it) */
  uint32_t count; /* drive_cmd_identify() calls */
} drive_ident_req_t;

typedef struct drive_s {
  /* ===== owned by the ISR ===== */
  const hal_caps_t *caps;
  drive_state_t state;
  uint32_t faults;
  uint32_t isr_count;
  drive_cmd_t cmd;    /* the commands in force (the ISR's copy of req) */
  uint32_t cfg_seen;  /* creq.seq taken */
  bool cfg_pending;   /* a parameter set waits for the gates to go off (or
                         for the fault and the short to end) */
  bool armed;         /* an enable command posted since the last disarm (arm_mark) */
  drive_mode_t mode;  /* the mode in force: cmd.mode unless the law lacks it (drive_mode_refresh) */
  uint32_t lc_checks; /* PROTECT_LC_CHECK_* with this law and mode (drive_mode_refresh) */

  /* the current offsets in force (the offset procedure's, proc_offset.c) */
  float offset[3];
  /* the current sum's noise at zero current the offset procedure measured,
   * times its margin [A] (0: none yet): the current-sum check's floor */
  float i_sum_noise;

  /* the procedure in force (proc.h: offset calibration, alignment, held
   * start, identification) and its place in its sequence; its state is
   * last (proc_st) */
  const proc_row_t *proc; /* NULL: none (idle, run, fault) */
  uint32_t proc_k;        /* its index in proc_start_sequence() */

  /* position */
  const pos_source_row_t *pos_src;
  pos_io_t pos;   /* the source's estimate (out), and its input (in): the last run
                     period's q current and torque (0 from a start) */
  float omega_m;  /* mechanical speed (source, per ISR) [rad/s] */
  float rate_acc; /* sum of the angle rate over the speed-loop period */
  uint32_t rate_n;
  uint32_t slow_wait; /* ISRs to the slow-rate schedule's next phase (drive_schedule;
                         0 or 1: this ISR's phase is computed) */

  /* control */
  ab_t v_applied;     /* voltage applied over the period ending at this sample */
  speed_ctrl_t speed; /* run every slow_div ISRs */
  bool speed_active;
  float speed_torque; /* torque reference from the speed loop, to the law [N m] */
  float torque_min_avail, torque_max_avail; /* what the law can deliver now */
  /* the law's flux of the last period it ran without a fault (the safe
   * state's trapped-flux input; tm.law_tm also holds a faulted period's) */
  float law_flux;
  protect_lc_t lc; /* the loss-of-control monitor (every run period) */
  float inv_pole_pairs;
  float v_lin;            /* linear voltage range now [V] */
  float duty_lo, duty_hi; /* duty range: the board's, narrowed by a DFC window */
  float v_lin_k;          /* linear voltage range per volt of DC link */
  unsigned dfc_leg;       /* leg of the next DFC test vector (0: v1, 1: v3, 2: v5) */
  bool gated;             /* the position source measures through the DFC window */
  bool plain;             /* the pattern without the DFC window: a procedure's clean sample
                             (the held start's pulses, proc_hold.c) */
  float win_m[3];         /* the window pattern in force: phase moments (dfc_window.h) */
  float win_k;            /* Ts / L of their current correction [s/H] */

  /* telemetry, under a sequence lock: written every period, right after
   * the per-period scalars (its floats within a VSTR's reach too) */
  volatile uint32_t tm_seq;
  drive_telemetry_t tm;

  /* the per-period parts the code reaches through a pointer (after the
   * per-period scalars: they do not push those beyond the short load
   * offsets: the asserts after the type) */
  ctrl_t ctrl;        /* the control law in force and its state */
  pos_state_t pos_st; /* the position source's state */

  /* the parameter set in force and its machine (after the per-period
   * state: a parameter added to the table does not move that state's
   * fields beyond the Cortex-M's short load offsets; the code reaches the
   * set through a pointer of its own) */
  drive_config_t cfg; /* in force */
  machine_t machine;
  flux_map_t map; /* cfg's flux map, parsed (machine.map points here) */

  /* ===== written by the main loop only ===== */
  struct {
    volatile uint32_t seq; /* odd while being written */
    drive_cmd_t cmd;
    drive_ident_req_t ident;
  } req;
  struct {
    volatile uint32_t seq;
    drive_config_t cfg;
  } creq;
  struct {
    uint32_t isr_seen;      /* ISR count at the last watchdog refresh */
    drive_telemetry_t tm;   /* last consistent telemetry copy */
    uint32_t tm_retries;    /* copies that had to be retried (preemption) */
    drive_phase_check_t ph; /* the phase-balance check (drive_phase_check.h) */
  } host;

  /* ===== ISR-owned, used at the slow rate or on a command (last: the
   * periodic path's fields stay within the load offsets of the Cortex-M's
   * single instructions from the drive's base) ===== */
  uint32_t clear_seen;       /* req.clear_count taken */
  uint32_t arm_mark;         /* cmd.enable_count at the last disarm: a trip, or a clear
                                that cleared a fault (cmd.clear_enable_mark) */
  drive_law_t law_refused;   /* a law whose switch the ISR refused (DRIVE_LAW_COUNT: none) */
  uint32_t fault_total_seen; /* req.fault_total taken */
  uint32_t fault_seen[DRIVE_FAULT_COUNT];
  uint32_t ident_seen;    /* req.ident.count taken (in idle, during an identification, on
                             an enable or in a fault: drive.c) */
  bool ident;             /* the procedures in force are an identification run's */
  proc_id_t ident_seq[2]; /* that run: the offsets, then the procedure (proc_ident_sequence) */
  uint32_t ident_n;       /* its length */
  /* the protections at the slow rate (drive.c's schedule table) or with
   * the gates off, each an owned part in protect/ */
  protect_isum_t isum;       /* the current-sum (current-sensor) check */
  protect_ra_t ra;           /* the speed loop's run-away check */
  protect_pos_t pos_chk;     /* the position plausibility check */
  protect_overrun_t overrun; /* the ISR overrun check */
  protect_safe_t safe;       /* the safe state with the gates not modulating */
  float torque_scale;        /* torque on MTPA at i_max [N m] */
  float flux_scale;          /* flux amplitude on MTPA at i_max [Vs] */
  float psi_pm;              /* |flux linkage at zero current| of the model [Vs] */
  dq_t psi0;                 /* that flux linkage [Vs] */
  /* the state of the procedure in force (proc.h), last: a procedure runs
   * from flash outside the run (FD_COLD), and its state, however large an
   * identification's, moves nothing the periodic path reads */
  proc_state_t proc_st;
} drive_t;

/* The layout rules the ISR's instruction counts depend on (docs/pil.md),
 * on a 32-bit target (the Cortex-M; a host's pointers make it larger):
 *  - the per-period scalars, up to win_k, within the reach of a single
 *    VLDR/VSTR from the drive's base (8-bit word offset: 1020 bytes), so
 *    that each float the ISR reads costs one instruction;
 *  - the parts reached through a pointer (the law, the position source,
 *    the parameter set in force) and the telemetry within one ADDW
 *    (12-bit offset) of the base;
 *  - the parameter set after the per-period state (a parameter added to
 *    the table moves nothing the ISR reads every period), and the fields
 *    used at the slow rate or on a command last, after the main loop's. */
_Static_assert(sizeof(void *) != 4u || offsetof(drive_t, win_k) + sizeof(float) <= 1024u,
               "drive_t: a per-period scalar beyond a VLDR's reach from the base");
_Static_assert(sizeof(void *) != 4u || offsetof(drive_t, tm) + sizeof(drive_telemetry_t) <= 4095u,
               "drive_t: the telemetry beyond an ADDW's reach from the base");
_Static_assert(sizeof(void *) != 4u || offsetof(drive_t, cfg) <= 4095u,
               "drive_t: the parameter set beyond an ADDW's reach from the base");
_Static_assert(offsetof(drive_t, cfg) > offsetof(drive_t, win_k) &&
                   offsetof(drive_t, ctrl) > offsetof(drive_t, win_k) &&
                   offsetof(drive_t, pos_st) > offsetof(drive_t, win_k),
               "drive_t: the parts reached through a pointer after the per-period scalars");
_Static_assert(sizeof(proc_state_t) <= 1024u, "proc_state_t: a procedure's state beyond 1 KiB");
_Static_assert(offsetof(drive_t, clear_seen) > offsetof(drive_t, host) &&
                   offsetof(drive_t, psi0) > offsetof(drive_t, clear_seen),
               "drive_t: the slow-rate and command fields last");

/* Validates cfg, initialises everything and latches DRIVE_FAULT_WATCHDOG
 * if the last reset was the watchdog's. 0, or -1 with *err naming the
 * parameter (its reason, e.g. the start-up law is unavailable on this
 * machine). Gates are off. err may be NULL. */
int drive_init(drive_t *drv, const drive_config_t *cfg, drive_config_err_t *err);

/* Whether cfg is valid and can run `law` on its machine (drive_config_check,
 * the machine model, the law's check), without touching a drive: 0, or -1
 * with *err (field and reason). *m receives the machine; a flux-map
 * machine's map is parsed into *map, which m points to (copy both together:
 * drive_machine_copy). */
int drive_config_usable(const drive_config_t *cfg, drive_law_t law, machine_t *m, flux_map_t *map,
                        drive_config_err_t *err);
/* Whether cfg's protections can see what they protect on this board: the
 * current trip below the current ADC's full scale, the overvoltage trip
 * below the DC-link ADC's (a quantity beyond its ADC's range reads as the
 * full scale and would never trip); a star-point position source only on
 * a board with the star-point samples and asymmetric edges. 0, or -1 with
 * *err. Ranges not known (0 in hal_caps_t) are not checked. */
int drive_config_fits_board(const drive_config_t *cfg, const hal_caps_t *caps,
                            drive_config_err_t *err);
/* The one validation of a parameter set with a law on a board, for every
 * path (parameter writes, law switches, scenario files, start-up):
 * drive_config_usable, drive_config_fits_board (the star-point window
 * included) and the law's initialisation into a scratch state. What it
 * accepts the ISR never refuses. 0, or -1 with *err (field and reason). */
int drive_config_validate(const drive_config_t *cfg, drive_law_t law, const hal_caps_t *caps,
                          machine_t *m, flux_map_t *map, drive_config_err_t *err);
/* *dm, *dmap = *m, *map with dm's map pointer on dmap. */
void drive_machine_copy(machine_t *dm, flux_map_t *dmap, const machine_t *m, const flux_map_t *map);

/* The states with the gates modulating, and those in which the drive is
 * enabled (below), as masks of 1 << state. */
#define DRIVE_GATES_ON_STATES                                                                      \
  ((1u << DRIVE_STATE_RUN) | (1u << DRIVE_STATE_ALIGN) | (1u << DRIVE_STATE_IDENT))
#define DRIVE_ENABLED_STATES (DRIVE_GATES_ON_STATES | (1u << DRIVE_STATE_OFFSET_CAL))
_Static_assert(DRIVE_STATE_COUNT <= 32, "drive states: a mask of 1 << state");
/* what drive_state_enabled() and drive.c's gates_on_state() test, in their
 * cheapest form (every period): */
#define DRIVE_ALL_STATES ((1u << DRIVE_STATE_COUNT) - 1u)
_Static_assert(DRIVE_ENABLED_STATES ==
                   (DRIVE_ALL_STATES & ~((1u << DRIVE_STATE_IDLE) | (1u << DRIVE_STATE_FAULT))),
               "drive states: enabled = all but idle and fault");
_Static_assert(DRIVE_GATES_ON_STATES == ((1u << DRIVE_STATE_RUN) |
                                         (DRIVE_ALL_STATES & ~((1u << DRIVE_STATE_ALIGN) - 1u))),
               "drive states: gates on = the run and the states from the alignment on");

/* States in which the drive is enabled: offset calibration, alignment, run,
 * identification
 * (non-LIVE parameters are refused then). Inline: the ISR asks every
 * period. */
static inline bool drive_state_enabled(drive_state_t s) {
  return s != DRIVE_STATE_IDLE && s != DRIVE_STATE_FAULT; /* two tests, every period */
}

/* The enable in force as the main loop sees it (STATUS.cmd_enabled): an
 * enable command posted after the last trip and after the last clear that
 * cleared a fault (tm->armed), and no fault latched. */
static inline bool drive_enable_in_force(const drive_telemetry_t *tm, const drive_cmd_t *c) {
  return c->enable != 0u && tm->armed != 0u && tm->state != DRIVE_STATE_FAULT;
}

/* The PWM-period interrupt body. Bounded time, never blocks. */
void drive_isr(drive_t *drv);

/* Main loop, every slow period: telemetry copy (drv->host.tm) and the
 * watchdog refresh (only if the ISR advanced). */
void drive_background(drive_t *drv);

/* Commands (main loop), in force from the next ISR. Values are clamped to
 * the configured limits (non-finite: 0). */
void drive_cmd_enable(drive_t *drv, bool enable);
/* Clears the faults latched before the ISR takes it (the drive returns to
 * idle); requests it has not seen still latch. The enable command is left
 * as it is; after a cleared fault the drive starts again only on an enable
 * command posted after the clear (docs/can.md, "Enable and clear"). */
void drive_cmd_clear_fault(drive_t *drv);
/* NULL when accepted, else why not (unknown law, unavailable on this
 * machine); the law changes when the gates are off. */
const char *drive_cmd_set_law(drive_t *drv, drive_law_t law);
/* NULL when accepted, else why not (unknown, or current mode with a law
 * that has no current mode). */
const char *drive_cmd_set_mode(drive_t *drv, drive_mode_t mode);
void drive_cmd_torque(drive_t *drv, float torque);
void drive_cmd_speed(drive_t *drv, float speed_m);
void drive_cmd_current(drive_t *drv, float id, float iq);
void drive_cmd_flux(drive_t *drv, float flux);
/* Runs an identification procedure (a row with PROC_CAP_IDENT, proc.h)
 * with the drive disabled: the offsets, then the procedure, then the gates
 * off again, its progress and results in the telemetry (tm.proc). PROC_NONE
 * stops the one running; so does an enable command, another request, a
 * fault and every protection. NULL when posted, else why not (not an
 * identification procedure, the drive enabled, the requested parameter
 * set cannot run it: *field names the parameter). field may be NULL. */
const char *drive_cmd_identify(drive_t *drv, proc_id_t id, const char **field);
/* Asks the ISR to latch a fault (e.g. the CAN command timeout). */
void drive_request_fault(drive_t *drv, uint32_t fault_bits);

/* Requests a new parameter set (main loop): validated here (on failure
 * nothing changes and *err names the field), applied by the next ISR; the
 * parameters that are not LIVE wait until the gates are off. 0 or -1. */
int drive_request_config(drive_t *drv, const drive_config_t *cfg, drive_config_err_t *err);
/* The parameter set most recently requested (or in force). */
const drive_config_t *drive_requested_config(const drive_t *drv);

/* Consistent copy of the ISR's telemetry (main loop); false when every
 * retry was preempted (*out then holds the previous copy). */
bool drive_telemetry_read(drive_t *drv, drive_telemetry_t *out);
/* The main loop's last copy (drive_background). */
const drive_telemetry_t *drive_telemetry(const drive_t *drv);
/* The command block the main loop published last. */
const drive_cmd_t *drive_commands(const drive_t *drv);

#endif /* FLUXDRIVE_DRIVE_H */
