/*
 * scenario.h - a SIL scenario: plant, controller parameters, reference
 * profiles, injected sensor faults, logging. Loaded from JSON (schema in
 * docs/scenarios.md); every error names the field and the reason.
 */
#ifndef FD_SIL_SCENARIO_H
#define FD_SIL_SCENARIO_H

#include <stddef.h>

#include "drive_config.h"
#include "hal_sil.h"
#include "plant.h"
#include "profile.h"
#include "sil_adc_faults.h"
#include "sil_enc_faults.h"
#include "sil_can_faults.h"
#include "sil_commission.h"

typedef struct {
  char name[96];
  double duration; /* simulated time [s] */
  plant_params_t plant;
  drive_config_t drive;  /* the controller's parameters (estimates) */
  hal_sil_board_t board; /* the board the SIL HAL models */
  double hw_trip;        /* hardware overcurrent comparator level [A], 0 = none */
  double enable_at;      /* enable command time [s] */
  double disable_at;     /* disable command time [s], <= enable_at = never */
  /* identification procedures run in turn before the enable (sil_commission.h) */
  sil_commission_list_t commission;
  struct {
    profile_t torque; /* [N m] */
    profile_t speed;  /* mechanical [rad/s] */
    profile_t id, iq; /* [A] */
    profile_t flux;   /* [Vs], 0 = automatic */
  } ref;
  profile_t v_source;      /* DC source voltage [V] */
  profile_t encoder_error; /* added to the encoder reading [rad mech] */
  /* injected failures, each active while its profile is > 0.5 */
  profile_t encoder_invalid; /* the encoder reports an error */
  profile_t main_stall;      /* the main loop does not run (hung) */
  profile_t isr_stall;       /* the PWM-period interrupt does not run */
  profile_t gate_driver;     /* the gate driver's nFAULT (break 2) is asserted */
  /* power-stage faults (switching model): `target` a switch (leg * 2 + 1
   * for the high side: PLANT_SW_* bit index), a phase (0..2) or, for
   * phase_short, a pair of phases (0 ab, 1 bc, 2 ca: phases target and
   * target + 1 mod 3), active while `active` > 0.5 (an empty profile: not
   * injected) */
  struct {
    int target;
    profile_t active;
  } switch_open, switch_closed, phase_lost, phase_open, phase_short, ground_short;
  int power_faults; /* any of the six given */
  /* the controller's flux-map error (LIVE parameters cm_scale_d, cm_scale_q,
   * written by the main loop as over CAN when the profile changes) */
  profile_t cm_scale_d, cm_scale_q;
  /* a fault the main loop posts once at trip_at (> 0; drive_request_fault):
   * as if one of its own checks had found it */
  double trip_at;
  uint32_t trip_cause; /* fault bit mask, 0: none */
  /* current-ADC channel faults (inject.current); the plant-parameter
   * faults are in plant.faults (inject.rs_scale, ...) */
  sil_adc_faults_t current_faults;
  sil_enc_faults_t encoder_faults; /* inject.encoder */
  /* CAN frame loss and delay in the socketcand transport (inject.can) */
  sil_can_faults_t can_faults;
  /* ISR overrun: while > 0.5 the PWM-period interrupt ends after the next
   * valley (inject.isr_overrun, sil_run.c) */
  profile_t isr_overrun;
  int log_decimation; /* log every n-th sample */
  char map_file[512]; /* the flux map's file as resolved ("" for a linear machine) */
} scenario_t;

/* Loads a scenario from JSON text; `origin` prefixes error messages (the
 * file name). Returns 0, or -1 with a message in err. */
int scenario_parse(const char *json, const char *origin, scenario_t *sc, char *err, size_t errlen);
int scenario_load_file(const char *path, scenario_t *sc, char *err, size_t errlen);

/* Writes the parsed scenario's bytes to `path` with its pointers (the flux
 * map's) zeroed, so two builds' parses of one file compare byte for byte
 * (fluxdrive-sil --dump-scenario). Returns 0, or -1 on an I/O error. */
int scenario_dump(const scenario_t *sc, const char *path);

#endif
