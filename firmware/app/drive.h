/*
 * drive.h - the drive: state machine, ISR body, slow loop, protections and
 * the command interface used by the SIL runner and the CAN protocol.
 *
 * Call pattern (board or SIL):
 *   drive_init(&drv, &cfg, &err)    once; cfg is validated
 *   drive_isr(&drv)                 every PWM period, right after the ADC
 *   drive_slow_loop(&drv)           every cfg.slow_div ISRs (e.g. 1 kHz),
 *                                   outside the ISR; applies commands
 *   drive_cmd_*(&drv, ...)          any time from the slow context; staged,
 *                                   they take effect at the next slow loop
 */
#ifndef FLUXDRIVE_DRIVE_H
#define FLUXDRIVE_DRIVE_H

#include <stdbool.h>
#include <stdint.h>

#include "drive_config.h"
#include "control/speed_ctrl.h"
#include "drive_ctrl.h"
#include "estimation/angle_pll.h"

typedef enum {
  DRIVE_STATE_IDLE = 0,       /* gates off, waiting for enable */
  DRIVE_STATE_OFFSET_CAL = 1, /* gates off, averaging current offsets */
  DRIVE_STATE_RUN = 2,        /* gates on, control law active */
  DRIVE_STATE_FAULT = 3       /* gates off, cause latched until cleared */
} drive_state_t;

/* Fault causes: bits, latched until drive_cmd_clear_fault(). */
enum {
  DRIVE_FAULT_OVERCURRENT = 1u << 0,    /* |i_x| sample above i_trip */
  DRIVE_FAULT_OVERVOLTAGE = 1u << 1,    /* v_dc above v_dc_max */
  DRIVE_FAULT_UNDERVOLTAGE = 1u << 2,   /* v_dc below v_dc_min while running */
  DRIVE_FAULT_OVERSPEED = 1u << 3,      /* |speed| above speed_trip */
  DRIVE_FAULT_HW_OVERCURRENT = 1u << 4, /* hardware break input tripped */
  DRIVE_FAULT_OFFSET = 1u << 5,         /* current offset beyond offset_max */
  DRIVE_FAULT_CONTROL = 1u << 6,        /* control law reported a fault */
  DRIVE_FAULT_CMD_TIMEOUT = 1u << 7,    /* no command / heartbeat in time */
  DRIVE_FAULT_SAMPLE = 1u << 8          /* non-finite ADC sample */
};

/* Everything the drive exposes for telemetry and logs. */
typedef struct {
  drive_state_t state;
  uint32_t faults; /* latched fault bits */
  drive_law_t law;
  drive_mode_t mode;
  float v_dc;            /* [V] */
  float i_abc[3];        /* offset-corrected phase currents [A] */
  float i_dq[2];         /* rotor frame currents [A] */
  float v_ab_applied[2]; /* voltage the last duties apply [V] */
  float duty[3];
  float theta_e;           /* electrical angle used by the control [rad] */
  float omega_m;           /* mechanical speed estimate [rad/s] */
  float speed_ref;         /* ramped speed reference [rad/s] */
  float torque_ref;        /* [N m] */
  float torque_est;        /* [N m] */
  ctrl_telemetry_t law_tm; /* law-specific values (flux, load angle, i_qs) */
  uint32_t isr_count;
} drive_telemetry_t;

typedef struct {
  drive_config_t cfg;
  drive_state_t state;
  uint32_t faults;
  uint32_t isr_count;
  uint32_t slow_count;

  /* offset calibration */
  float offset[3];
  float offset_acc[3];
  uint32_t offset_n;

  /* commands staged by drive_cmd_*, applied at the slow loop */
  struct {
    bool enable;
    bool clear_fault;
    drive_law_t law;
    drive_mode_t mode;
    float torque;
    float speed;  /* mechanical [rad/s] */
    float id, iq; /* current mode [A] */
    float flux;   /* stator flux amplitude reference, 0 = automatic [Vs] */
  } cmd;

  /* references in force (written by the slow loop, read by the ISR; each
   * field is one 32-bit word, so an ISR that preempts the copy sees at worst
   * a mix of the previous and the new command for one period) */
  struct {
    bool enable;
    drive_law_t law;
    drive_mode_t mode;
    float torque;
    float speed;
    float id, iq;
    float flux;
  } ref;

  /* speed and position (encoder + PLL) */
  angle_pll_t pll;
  struct {
    float theta_e;
    float omega_e;
    float omega_m;  /* PLL speed, per ISR (protection, control laws) */
    float rate_acc; /* sum of the PLL angle rate over the slow period */
    uint32_t rate_n;
    float omega_m_slow; /* mean angle rate over the last slow period: no
                           lag under acceleration (speed loop) */
  } pos;

  ctrl_t ctrl;                              /* control laws (FOC, PI-DFVC, DB-DFVC) */
  speed_ctrl_t speed;                       /* speed loop, run by the slow loop */
  float speed_torque;                       /* torque reference from the speed loop [N m] */
  float torque_min_avail, torque_max_avail; /* what the law can deliver */

  /* last sample and outputs, for telemetry */
  drive_telemetry_t tm;
} drive_t;

/* Validates cfg (drive_config_check) and initialises. Returns 0 or a
 * negative number with *field naming the bad parameter. Gates are off. */
int drive_init(drive_t *drv, const drive_config_t *cfg, const char **field);

/* The PWM-period interrupt body: read the HAL sample, protect, estimate,
 * control, write duties. Bounded time, never blocks. */
void drive_isr(drive_t *drv);

/* The slow loop (cfg.slow_div ISRs): applies staged commands, runs the speed
 * loop and refreshes the telemetry snapshot. */
void drive_slow_loop(drive_t *drv);

/* Commands (staged). Values are clamped to the configured limits; an
 * unknown law or mode is ignored and returns false. */
void drive_cmd_enable(drive_t *drv, bool enable);
void drive_cmd_clear_fault(drive_t *drv);
bool drive_cmd_set_law(drive_t *drv, drive_law_t law);
bool drive_cmd_set_mode(drive_t *drv, drive_mode_t mode);
void drive_cmd_torque(drive_t *drv, float torque);
void drive_cmd_speed(drive_t *drv, float speed_m);
void drive_cmd_current(drive_t *drv, float id, float iq);
void drive_cmd_flux(drive_t *drv, float flux);

/* Replace the parameter set from the slow context (CAN parameter writes).
 * cfg is validated by drive_config_check (on failure nothing changes and
 * *field names the parameter). With the gates off (idle, fault) everything
 * is re-derived: control laws, PLL and speed loop (their states reset).
 * While enabled (offset calibration, run) only the live parameters are
 * taken from cfg - i_trip, v_dc_max, v_dc_min, speed_trip, offset_max,
 * speed_max, torque_max, accel_max, speed_bw (the speed loop keeps its
 * integral) - and the others keep their values. Returns 0 or negative. */
int drive_set_config(drive_t *drv, const drive_config_t *cfg, const char **field);

/* Latch a fault from outside the ISR (e.g. the CAN command timeout):
 * gates off at once. */
void drive_raise_fault(drive_t *drv, uint32_t fault_bits);

const drive_telemetry_t *drive_telemetry(const drive_t *drv);
const char *drive_state_name(drive_state_t s);
/* Name of the lowest set fault bit, "none" for 0. */
const char *drive_fault_name(uint32_t fault_bits);

#endif /* FLUXDRIVE_DRIVE_H */
