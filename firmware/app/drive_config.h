/*
 * drive_config.h - the drive's parameter set: machine, limits, protections,
 * controller tuning. Validated as a whole by drive_config_check() before it
 * is used; drive_config_default() gives a safe, documented starting point.
 */
#ifndef FLUXDRIVE_DRIVE_CONFIG_H
#define FLUXDRIVE_DRIVE_CONFIG_H

#include <stdint.h>

typedef enum {
  DRIVE_LAW_FOC = 0,     /* rotor-frame PI current control (baseline) */
  DRIVE_LAW_PI_DFVC = 1, /* PI direct flux vector control (Rubino 2020 IV.7) */
  DRIVE_LAW_DB_DFVC = 2, /* deadbeat DFVC (Rubino 2020) */
  DRIVE_LAW_COUNT
} drive_law_t;

typedef enum {
  DRIVE_MODE_TORQUE = 0,  /* torque reference */
  DRIVE_MODE_SPEED = 1,   /* speed loop produces the torque reference */
  DRIVE_MODE_CURRENT = 2, /* dq current references (FOC only) */
  DRIVE_MODE_COUNT
} drive_mode_t;

typedef struct {
  /* machine (the controller's estimates, may differ from the plant) */
  float pole_pairs;
  float rs;       /* [Ohm] */
  float ld, lq;   /* [H] */
  float lambda_m; /* [Vs] */
  float inertia;  /* [kg m^2], for the speed-loop design */

  /* timing */
  float ts;          /* PWM / ISR period [s] */
  uint16_t slow_div; /* slow loop every slow_div ISRs */
  float dead_time;   /* inverter dead time [s], for compensation */

  /* protections (evaluated every ISR) */
  float i_trip;            /* phase current trip [A] */
  float v_dc_max;          /* overvoltage trip [V] */
  float v_dc_min;          /* undervoltage trip while running [V] */
  float speed_trip;        /* overspeed trip, mechanical [rad/s] */
  float offset_max;        /* largest acceptable current offset [A] */
  uint16_t offset_samples; /* ISRs averaged by the offset calibration */

  /* limits used by the references */
  float i_max;      /* current amplitude limit [A peak] */
  float torque_max; /* [N m] */
  float speed_max;  /* speed reference limit, mechanical [rad/s] */
  float v_margin;   /* usable fraction of the linear voltage range (0..1] */

  /* control */
  drive_law_t law;
  drive_mode_t mode;
  float current_bw; /* FOC current-loop bandwidth [rad/s] */
  float speed_bw;   /* speed-loop bandwidth [rad/s] */
  float accel_max;  /* speed reference slew limit [rad/s^2] */
  float pll_bw;     /* encoder angle PLL bandwidth [rad/s] */
  float enc_offset; /* electrical angle at encoder zero [rad] */

  /* DFVC (Rubino 2020) */
  float flux_obs_wc;  /* hybrid observer crossover omega_c [rad/s] */
  float delta_max;    /* load-angle (MTPV) limit [rad] */
  float vsd_max;      /* flux-axis voltage limit v_sd,max [V] */
  float flux_min;     /* minimum flux reference [Vs] */
  float dfvc_flux_bw; /* PI-DFVC flux loop bandwidth [rad/s] */
  float dfvc_iqs_bw;  /* PI-DFVC i_qs loop bandwidth [rad/s] */
} drive_config_t;

/* A safe default for a small SPM machine; callers overwrite the machine. */
void drive_config_default(drive_config_t *cfg);
/* 0 when valid, else negative with *field naming the first bad parameter. */
int drive_config_check(const drive_config_t *cfg, const char **field);

#endif
