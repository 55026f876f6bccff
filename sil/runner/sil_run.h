/*
 * sil_run.h - advances the plant and the drive ISR in lock-step.
 *
 * Per PWM period k (t_k = k Ts):
 *   0. every slow_div periods, the main loop: the scenario's references are
 *      commanded (drive_cmd_*, taken by the next ISR) and
 *      drive_background() runs (telemetry copy, watchdog refresh);
 *   1. the plant's sensors are sampled at t_k (carrier valley) -> HAL;
 *   2. drive_isr() runs: its pattern is preloaded and acts from t_{k+1};
 *      a gate disable acts at once (like clearing TIM1 MOE); then the
 *      watchdog is checked (an expiry resets the MCU: gates off,
 *      drive_init, DRIVE_FAULT_WATCHDOG latched);
 *   3. observers see the true plant state at t_k with the ISR's outputs;
 *   4. the plant advances over [t_k, t_{k+1}) with the pattern preloaded by
 *      ISR k-1 (the one-period command delay of the timing model).
 * Injected failures (scenario "inject"): main_stall skips step 0,
 * isr_stall skips step 2, isr_overrun makes ISR k end after the valley
 * t_{k+1} (below), encoder_invalid marks the encoder sample invalid,
 * current (sil_adc_faults.h) alters the current channels of step 1; the
 * plant-parameter faults act inside the plant (plant_faults_t).
 *
 *
 * ISR overrun (inject.isr_overrun > 0.5 at t_k), as on the STM32G4: ISR k
 * still runs on the samples of t_k but ends after the next valley, so its
 * compare values miss the update at t_{k+1} (TIM1 preload) and the pattern
 * written before it acts once more over [t_{k+1}, t_{k+2}); ISR k's pattern
 * acts from t_{k+2} unless ISR k+1 (pending meanwhile, tail-chained, on the
 * samples of t_{k+1}) overwrites it before that update. The HAL counts the
 * overrun (hal_isr_stats().overruns, the board's "update pending at exit").
 * A sustained overrun thus delays every pattern by one more period. Not
 * modelled: the main loop starved by the busy CPU, a third interrupt
 * coalesced (an ISR longer than two periods).
 *
 * Power-stage faults:
 * at step 4 the power-stage faults in force at t_k are set in the plant,
 * gate_driver (or a shoot-through the plant reports after the step)
 * latches the break input with the gate-driver source and turns the gates
 * off in hardware, like the overcurrent comparator (inverter.hw_trip).
 *
 * With CAN (sil_opts_t.can, fluxdrive-sil --can): at step 0 the transport
 * moves frames from the bus into the HAL queue, can_proto_poll() handles
 * them after drive_background() (telemetry copy, watchdog), commands are
 * posted for the next ISR, and the transport sends what the drive queued,
 * stamped with t_k. The scenario's
 * references and enable/disable times are not applied: the CAN client
 * commands; its injections (trip_at, cm_scale_*: sil_main_injections) are,
 * after the protocol's poll. With sil_opts_t.realtime the loop sleeps at each slow period
 * until the wall clock has caught up with the simulated time.
 */
#ifndef FD_SIL_RUN_H
#define FD_SIL_RUN_H

#include <stdbool.h>
#include <stdint.h>

#include "can_proto.h"
#include "drive.h"
#include "hal_sil.h"
#include "plant.h"
#include "scenario.h"
#include "sil_commission.h"

typedef struct {
  uint64_t k;
  double t;
  const plant_state_t *plant; /* true state at t_k */
  const hal_sample_t *adc;    /* what the ISR read */
  const drive_t *drive;       /* after ISR k */
  const scenario_t *scenario;
  const float *duty_active; /* duties acting over [t_k, t_{k+1}) */
  bool gates_on;            /* gate state over [t_k, t_{k+1}) */
  bool asc;                 /* active short circuit over [t_k, t_{k+1}) */
  bool hw_tripped;          /* the break input as ISR k found it */
  uint32_t timer_counts;    /* the SIL board's compare steps per period */
  uint32_t hw_source;       /* which break input (HAL_BREAK_*) as ISR k found it */
} sil_step_t;

typedef void (*sil_observer_fn)(void *user, const sil_step_t *st);

typedef struct {
  uint64_t steps;
  double sim_time;
  double wall_time;
  double real_time_factor;
  double max_phase_current; /* true, over the run [A] */
  double max_phase_current_t;
  double v_dc_min, v_dc_max;
  double final_speed; /* true mechanical [rad/s] */
  double final_speed_ref;
  double max_speed, min_speed;
  double final_torque;  /* true, mean over the last 5 % [N m] */
  double first_fault_t; /* -1 if none */
  uint32_t faults;      /* latched at the end */
  uint32_t faults_seen; /* union over the run */
  drive_state_t final_state;
  uint32_t watchdog_kicks;
  uint32_t watchdog_resets;    /* MCU resets by the watchdog */
  uint32_t pwm_clamped;        /* PWM writes the board had to clamp (hal_sil_t) */
  double voltage_balance_max;  /* the phase check's largest |D| / v_dc (drive_phase_check.h) */
  double first_watchdog_t;     /* -1 if none */
  can_proto_stats_t can;       /* CAN runs only */
  bool stopped;                /* ended early on request (sil_opts_t.stop) */
  sil_commission_t commission; /* the scenario's identification run (key "commission") */
} sil_result_t;

/* Moves frames between a bus and the HAL queues; t is the simulated time. */
typedef void (*sil_can_io_fn)(void *user, hal_sil_t *hal, double t);

typedef struct {
  bool realtime;                 /* pace to the wall clock */
  const can_proto_cfg_t *can;    /* non-NULL: commanded over CAN (see above) */
  sil_can_io_fn can_io;          /* the transport (may be NULL: queues only) */
  bool (*can_ready)(void *user); /* non-NULL: before t = 0, poll can_io
                                    every 10 ms until this is true */
  void *can_user;
  volatile int *stop; /* non-NULL: the run ends when *stop != 0 */
} sil_opts_t;

/* The pieces of the loop, shared with the preempting mode (sil_preempt.h). */
typedef struct {
  plant_t plant;
  drive_t drv;
  hal_sil_t hal;
  double pwm_on[3], pwm_off[3]; /* the pattern acting over the present period */
  /* its star-point requests, and the samples they gave (delivered with the
   * next sample set: taken in the period before it, t_star < 0) */
  int star_n;
  double star_t[HAL_STAR_MAX];
  uint8_t star_tv;
  int star_got;
  double star_v[HAL_STAR_MAX], star_tt[HAL_STAR_MAX];
  uint8_t star_got_tv;
  double enc_err, enc_err_end; /* encoder error profile, constant until _end */
  double v_src, v_src_end;     /* DC source profile, constant until _end */
  sil_adc_state_t adc_faults;  /* the current-ADC faults' memory */
  sil_enc_state_t enc_faults;  /* the encoder faults' memory */
  bool enc_faults_on;          /* any encoder fault in the scenario (sil_setup) */
  /* any injection the sample or the advance checks every period (encoder
   * invalid or faults, current faults, ISR stall or overrun, gate driver,
   * power faults, the hardware comparator): sil_setup; without, one test */
  bool rare;
  bool isr_late;        /* ISR k overran: its pattern misses t_{k+1} */
  hal_pwm_t pwm_before; /* then: the pattern written before it */
  bool trip_posted;     /* inject.trip_at done (once per run, resets included) */
  bool cm_written;      /* inject.cm_scale_*: a value written, cm_last holds it */
  float cm_last[2];
  /* the plant's true values at the last sil_sample: the state the ISR and
   * the run's metrics see (the plant does not move before sil_advance) */
  plant_brief_t br;
} sil_ctx_t;

/* Plant, HAL and drive from the scenario; 0 or -1 with the message. */
int sil_setup(sil_ctx_t *x, const scenario_t *sc, char *err, size_t errlen);
/* Step 1: the plant's sensors at t into the HAL's sample set. */
void sil_sample(sil_ctx_t *x, const scenario_t *sc, double t);
/* Step 4: the plant over [t, t + Ts) with the preloaded pattern. */
void sil_advance(sil_ctx_t *x, const scenario_t *sc, double t);
/* The scenario's references at t, posted through drive_cmd_* (not with CAN). */
void sil_command_references(drive_t *drv, const scenario_t *sc, double t);
/* The main loop's injections at t (inject.trip_at, inject.cm_scale_*), with
 * or without CAN: the fault posted once, the parameters written when their
 * profile changes. */
void sil_main_injections(sil_ctx_t *x, const scenario_t *sc, double t);

/* Runs the scenario. obs (may be NULL) is called every period. Returns 0,
 * or -1 with a message in err (plant or drive rejected the parameters). */
int sil_run(const scenario_t *sc, sil_observer_fn obs, void *user, sil_result_t *res, char *err,
            size_t errlen);
/* The same with options (opts may be NULL: sil_run). */
int sil_run_ex(const scenario_t *sc, const sil_opts_t *opts, sil_observer_fn obs, void *user,
               sil_result_t *res, char *err, size_t errlen);

#endif
