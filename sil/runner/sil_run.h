/*
 * sil_run.h - advances the plant and the drive ISR in lock-step.
 *
 * Per PWM period k (t_k = k Ts):
 *   1. the plant's sensors are sampled at t_k (carrier valley) -> HAL;
 *   2. drive_isr() runs: its duties are preloaded and act from t_{k+1};
 *      a gate disable acts at once (like clearing TIM1 MOE);
 *   3. observers see the true plant state at t_k with the ISR's outputs;
 *   4. the plant advances over [t_k, t_{k+1}) with the duties preloaded by
 *      ISR k-1 (the one-period command delay of the timing model);
 *   5. every slow_div periods, the scenario's references are commanded and
 *      drive_slow_loop() runs (commands take effect there).
 */
#ifndef FD_SIL_RUN_H
#define FD_SIL_RUN_H

#include <stdbool.h>
#include <stdint.h>

#include "drive.h"
#include "hal_sil.h"
#include "plant.h"
#include "scenario.h"

typedef struct {
  uint64_t k;
  double t;
  const plant_state_t *plant;  /* true state at t_k */
  const hal_adc_sample_t *adc; /* what the ISR read */
  const drive_t *drive;        /* after ISR k */
  const scenario_t *scenario;
  const float *duty_active; /* duties acting over [t_k, t_{k+1}) */
  bool gates_on;            /* gate state over [t_k, t_{k+1}) */
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
} sil_result_t;

/* Runs the scenario. obs (may be NULL) is called every period. Returns 0,
 * or -1 with a message in err (plant or drive rejected the parameters). */
int sil_run(const scenario_t *sc, sil_observer_fn obs, void *user, sil_result_t *res, char *err,
            size_t errlen);

#endif
