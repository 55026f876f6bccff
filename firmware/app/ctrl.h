/*
 * ctrl.h - the control laws behind one table. A law is a row
 * {name, capabilities, check, init, reset, step} (ctrl_law_t); its state
 * lives in a union (one law runs at a time, RAM of the smallest board); the
 * table (ctrl.c, `laws`) is generated from DRIVE_LAW_LIST (drive_enums.h):
 * one row ctrl_law_<name> per entry (declared in ctrl_laws.h). Adding a
 * law: its module (law_*.c defining its row) and one line in
 * DRIVE_LAW_LIST (docs/architecture.md).
 *
 * The drive hands a law one sample (currents, angle, speed, the voltage
 * available, references) and gets the alpha-beta voltage for the next
 * period, the currents it expects over that period (dead-time
 * compensation), the torque it can deliver now and telemetry.
 */
#ifndef FLUXDRIVE_CTRL_H
#define FLUXDRIVE_CTRL_H

#include <stdbool.h>
#include <stdint.h>

#include "control/current_ctrl.h"
#include "control/deadtime_comp.h"
#include "control/dfvc.h"
#include "control/dfvc_decoupled.h"
#include "control/law_io.h"
#include "drive_config.h"
#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"
#include "model/machine.h"
#include "signal_row.h"

/* Law-specific telemetry (zero where a law has no such quantity): the
 * core's type, so that a core law writes it in place (control/law_io.h). */
typedef law_telemetry_t ctrl_telemetry_t;

/* The load angle of a telemetry copy (main loop, logs): one atan2 where
 * it is read, not every ISR (the decoupled DFVC's: telemetry only). */
static inline float ctrl_tm_delta(const ctrl_telemetry_t *t) {
  return t->delta_lazy ? fd_atan2f(t->lam_q, t->lam_d) : t->delta;
}

/* One period's sample and references (current: the mode in force is
 * DRIVE_MODE_CURRENT): the core's type, so that a core law reads it where
 * the drive filled it (control/law_io.h). */
typedef law_in_t ctrl_in_t;

typedef struct {
  ab_t v_ref;                   /* voltage for the next period [V] */
  float torque_min, torque_max; /* torque the law can deliver now [N m] */
  uint32_t fault;               /* non-zero: the law asks for the gates to be disabled */
  dq_t i_dq;                    /* rotor frame currents [A] */
  ab_t i_pred;                  /* currents expected over the next period [A] */
  /* set by the caller: where the law writes its telemetry, in place (the
   * drive's published copy: no struct copy per period) */
  ctrl_telemetry_t *tm;
} ctrl_out_t;

/* What every law reads: the parameter set and the machine in force (owned
 * by the drive, which re-initialises the law when either changes) and the
 * output timing. */
typedef struct {
  const drive_config_t *cfg;
  const machine_t *machine;
  float t_out; /* from the current sample to the centre of the output interval [s] */
} ctrl_setup_t;

/* FOC: the current loop and the MTPA torque at i_max (machine and i_max
 * change only through init). */
typedef struct {
  current_ctrl_t cc;
  float t_mtpa_max; /* [N m] */
  /* the last MTPA point: the torque reference changes at the speed loop's
   * rate (slow_div periods) or with a command, so the MTPA solution (a few
   * hundred instructions on a salient machine) is reused in between */
  float mtpa_t; /* its torque [N m] (NaN: none) */
  dq_t mtpa_i;  /* its currents [A] */
} ctrl_foc_t;

/* PI-DFVC and DB-DFVC: one state and one step; the row's init says which
 * voltage law the step runs (no per-law wrapper call in the ISR). */
typedef struct {
  dfvc_t core;
  dfvc_law_t law; /* DFVC_LAW_PI or DFVC_LAW_DEADBEAT */
} ctrl_dfvc_t;

typedef union {
  ctrl_foc_t foc;
  ctrl_dfvc_t dfvc;
  dfvc_decoupled_t dfvc_decoupled;
} ctrl_state_t;

enum {
  CTRL_CAP_CURRENT = 1u << 0, /* runs DRIVE_MODE_CURRENT */
  CTRL_CAP_FLUX = 1u << 1,    /* takes a flux reference, reports flux and load angle */
  CTRL_CAP_DELTA = 1u << 2,   /* keeps the load angle within delta_max (SPM laws) */
};

typedef struct {
  const char *name;
  uint32_t caps; /* CTRL_CAP_* */
  /* NULL when the law can serve this machine and parameter set, else why not */
  const char *(*check)(const ctrl_setup_t *su);
  /* 0, or -1 when the law refuses the parameters (state unusable) */
  int (*init)(ctrl_state_t *s, const ctrl_setup_t *su);
  void (*reset)(ctrl_state_t *s); /* on enable: observers and integrators restart */
  /* one period; writes every field of *out, and *out->tm */
  void (*step)(ctrl_state_t *s, const ctrl_setup_t *su, const ctrl_in_t *in, ctrl_out_t *out);
  /* the law's own signals beyond ctrl_telemetry_t (logs, docs/log-format.md):
   * getters on its ctrl_state_t, read after the ISR; NULL, 0: none */
  const signal_row_t *signals;
  unsigned n_signals;
} ctrl_law_t;

typedef struct {
  ctrl_setup_t su;
  drive_law_t law;        /* the law whose state is initialised */
  const ctrl_law_t *impl; /* its row */
  ctrl_state_t st;
  uint32_t available; /* bit per law: check() passed */
  deadtime_comp_t dtc;
} ctrl_t;

/* The row of a law (NULL out of range). */
const ctrl_law_t *ctrl_law(drive_law_t law);
/* Binds cfg and machine, checks every law (ctrl_t.available) and
 * initialises `law`. 0, or -1 with *reason when that law is unavailable or
 * refuses the parameters. */
int ctrl_init(ctrl_t *c, const drive_config_t *cfg, const machine_t *machine, float t_out,
              drive_law_t law, const char **reason);
/* Why `law` cannot run (NULL: it can). */
const char *ctrl_unavailable(const ctrl_t *c, drive_law_t law);
/* Why `law` cannot run with su (NULL: it can): its check, then its init
 * into a scratch state (nothing else is touched). The main loop's full
 * validation of a law switch or a parameter set (drive_config_validate). */
const char *ctrl_law_refusal(drive_law_t law, const ctrl_setup_t *su);
/* Switches to `law` (gates off): initialises its state into a scratch copy
 * and takes it only on success. 0, or -1 with the law in force, its state
 * and its row unchanged. */
int ctrl_select(ctrl_t *c, drive_law_t law);
/* Resets the law in force (on enable). */
void ctrl_reset(ctrl_t *c);
/* One period of the law in force: its row's step, called directly (an
 * inline wrapper, no call of its own in the ISR); a non-finite voltage is a
 * fault whatever the law said. out->tm must point at the telemetry. */
static inline void ctrl_step(ctrl_t *c, const ctrl_in_t *in, ctrl_out_t *out) {
  c->impl->step(&c->st, &c->su, in, out);
  if (!(fd_isfinite(out->v_ref.alpha) && fd_isfinite(out->v_ref.beta))) {
    out->fault = 1u;
  }
}
/* Predictive dead-time compensation (Rubino 2020, Fig. 8) with the
 * currents the law expects over the period the duties act: the duty
 * change it adds per phase. Inline (one caller, the ISR's run path): no
 * call, and the deltas stay in registers on their way to the duties. */
static inline void ctrl_deadtime_delta(const ctrl_t *c, const ctrl_out_t *out, float delta[3]) {
  /* mut: deadtime_comp_sign */
  const abc_t i = frames_clarke_inv(out->i_pred);
  /* all three before the first store: a store through delta could alias
   * *c, and would make the compiler read i_band and dt_ratio again per phase */
  const float r = c->dtc.dt_ratio;
  const float sa = deadtime_comp_sign(&c->dtc, i.a);
  const float sb = deadtime_comp_sign(&c->dtc, i.b);
  const float sc = deadtime_comp_sign(&c->dtc, i.c);
  delta[0] = r * sa;
  delta[1] = r * sb;
  delta[2] = r * sc;
}

#endif
