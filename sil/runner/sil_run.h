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
 *
 * With CAN (sil_opts_t.can, fluxdrive-sil --can): at step 5 the transport
 * moves frames from the bus into the HAL queue, can_proto_poll() handles
 * them (commands staged for this slow loop), drive_slow_loop() runs and the
 * transport sends what the drive queued, stamped with t_k. The scenario's
 * references and enable/disable times are not applied: the CAN client
 * commands. With sil_opts_t.realtime the loop sleeps at each slow period
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
  can_proto_stats_t can; /* CAN runs only */
  bool stopped;          /* ended early on request (sil_opts_t.stop) */
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

/* Runs the scenario. obs (may be NULL) is called every period. Returns 0,
 * or -1 with a message in err (plant or drive rejected the parameters). */
int sil_run(const scenario_t *sc, sil_observer_fn obs, void *user, sil_result_t *res, char *err,
            size_t errlen);
/* The same with options (opts may be NULL: sil_run). */
int sil_run_ex(const scenario_t *sc, const sil_opts_t *opts, sil_observer_fn obs, void *user,
               sil_result_t *res, char *err, size_t errlen);

#endif
