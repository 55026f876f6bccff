/*
 * protect/drive_safe.h - the safe state while the gates do not modulate:
 * all switches off below the rectifier speed, the active short circuit
 * above it or on DC-link overvoltage (drive_safe.c, docs/faults.md). An
 * owned part of the drive's protections (docs/architecture.md, "Adding a
 * protection"): its state, a step on a read-only view, and the switch
 * actions it asks for, which drive.c applies (the part itself touches no
 * hardware). The file keeps its name because the G474 linker script lists
 * it among the files kept out of the CCM (hal/stm32g4/stm32g474re.ld).
 */
#ifndef FLUXDRIVE_PROTECT_SAFE_H
#define FLUXDRIVE_PROTECT_SAFE_H

#include <stdbool.h>
#include <stdint.h>

#include "drive_enums.h"
#include "model/machine.h"

/* The switch actions of a step, applied in this order (protect_safe_step). */
enum {
  PROTECT_SAFE_DISABLE = 1u << 0, /* all switches off (hal_pwm_disable) */
  PROTECT_SAFE_SHORT = 1u << 1    /* all low sides on (hal_pwm_short) */
};

/* ISR-owned. */
typedef struct {
  bool decide;     /* the gates just left modulation: choose at this ISR */
  bool asc;        /* active short circuit engaged */
  float w_i;       /* electrical speed from the current vector's rotation [rad/s] */
  float i_prev[2]; /* the previous current vector (alpha, beta) [A] */
  uint32_t n;      /* periods since the short began */
  uint32_t n_low;  /* consecutive periods below the exit speed */
  uint32_t n_high; /* consecutive periods above the entry speed (gates off) */
  /* of the parameter set in force (protect_safe_configure) */
  float psi_pm;  /* |flux linkage at zero current| of the model [Vs] */
  float psi_max; /* largest stator flux a short may trap [Vs] */
  float i_sc;    /* |current at zero flux|: the steady short-circuit current at speed [A] */
} protect_safe_t;

/* What a step reads (filled by drive.c every ISR with the gates off). */
typedef struct {
  const float *i;      /* offset-corrected phase currents [A] */
  float v_dc;          /* [V] */
  drive_state_t state; /* the drive's state after its state machine */
  uint32_t faults;     /* latched */
  bool hw_tripped;     /* the hardware break is latched */
  bool pos_valid;      /* the position source's estimate is valid */
  bool pos_gated;      /* a star-point source (measures only while modulating) */
  float pos_omega;     /* its electrical speed [rad/s] */
  bool ran;            /* the last period was a run period (telemetry) */
  dq_t i_dq;           /* its rotor-frame currents [A] */
  float law_flux;      /* the law's observed flux, if it has one (else 0) [Vs] */
  bool law_has_flux;   /* the law has a flux observer (CTRL_CAP_FLUX) */
  const machine_t *machine;
  float asc_speed, i_max, v_dc_max, ts, asc_hold; /* the parameters in force */
} protect_safe_view_t;

/* The derived limits: psi_pm, i_sc and the largest flux a short may trap
 * without a current beyond i_trip (flux_scale: the flux on MTPA at
 * i_max). At configuration. */
void protect_safe_configure(protect_safe_t *z, const machine_t *m, float psi_pm, float i_sc,
                            float flux_scale, float i_trip);
/* The gates left modulation (a trip, a disable) in this ISR: the next
 * protect_safe_step() chooses between all off and the short. */
void protect_safe_leave_gates(protect_safe_t *z);
/* Every ISR in which the gates do not modulate, after the state machine:
 * the actions to apply (PROTECT_SAFE_*, DISABLE before SHORT). */
uint32_t protect_safe_step(protect_safe_t *z, const protect_safe_view_t *v);

#endif
