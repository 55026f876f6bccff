/*
 * sil_run.c - the lock-step loop (see sil_run.h for the timing).
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "sil_run.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define SIL_PI 3.14159265358979323846

static double wall_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void to_hal_sample(const plant_adc_t *a, double enc_error, hal_adc_sample_t *s) {
  for (int x = 0; x < 3; ++x) {
    s->i_abc[x] = (float)a->i_abc[x];
  }
  s->v_dc = (float)a->v_dc;
  s->v_star = (float)a->v_star;
  double th = a->enc_angle + enc_error;
  if (!(th >= 0.0 && th < 2.0 * SIL_PI)) { /* fmod is the identity on [0, 2 pi) */
    th = fmod(th, 2.0 * SIL_PI);
  }
  s->enc_angle = (float)(th < 0.0 ? th + 2.0 * SIL_PI : th);
  s->enc_valid = true;
}

static void command_references(drive_t *drv, const scenario_t *sc, double t) {
  bool on = t >= sc->enable_at && !(sc->disable_at > sc->enable_at && t >= sc->disable_at);
  drive_cmd_enable(drv, on);
  drive_cmd_torque(drv, (float)profile_eval(&sc->ref.torque, t));
  drive_cmd_speed(drv, (float)profile_eval(&sc->ref.speed, t));
  drive_cmd_current(drv, (float)profile_eval(&sc->ref.id, t), (float)profile_eval(&sc->ref.iq, t));
  drive_cmd_flux(drv, (float)profile_eval(&sc->ref.flux, t));
}

static void sleep_s(double s) {
  if (s <= 0.0) {
    return;
  }
  struct timespec ts;
  ts.tv_sec = (time_t)s;
  ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
  nanosleep(&ts, NULL);
}

int sil_run(const scenario_t *sc, sil_observer_fn obs, void *user, sil_result_t *res, char *err,
            size_t errlen) {
  return sil_run_ex(sc, NULL, obs, user, res, err, errlen);
}

int sil_run_ex(const scenario_t *sc, const sil_opts_t *opts, sil_observer_fn obs, void *user,
               sil_result_t *res, char *err, size_t errlen) {
  static const sil_opts_t no_opts = {0};
  static can_proto_t proto;
  static plant_t plant; /* large: keep off the stack; one run at a time */
  static drive_t drv;
  static hal_sil_t hal;
  const char *field = "";
  memset(res, 0, sizeof *res);

  if (plant_init(&plant, &sc->plant, &field) != 0) {
    snprintf(err, errlen, "plant: invalid parameter %s", field);
    return -1;
  }
  hal_sil_init(&hal);
  hal_sil_bind(&hal);
  if (drive_init(&drv, &sc->drive, &field) != 0) {
    snprintf(err, errlen, "controller: invalid parameter %s", field);
    return -1;
  }
  drive_cmd_set_law(&drv, sc->drive.law);
  drive_cmd_set_mode(&drv, sc->drive.mode);
  if (opts == NULL) {
    opts = &no_opts;
  }
  const bool can = opts->can != NULL;
  if (can && can_proto_init(&proto, opts->can) != 0) {
    snprintf(err, errlen, "CAN: invalid node %u (0..%u)", (unsigned)opts->can->node, CAN_NODE_MAX);
    return -1;
  }
  if (can && opts->can_ready != NULL) {
    while (!opts->can_ready(opts->can_user) && !(opts->stop != NULL && *opts->stop)) {
      if (opts->can_io != NULL) {
        opts->can_io(opts->can_user, &hal, 0.0);
      }
      sleep_s(0.01);
    }
  }

  const double ts = sc->plant.ts;
  uint64_t n = (uint64_t)llround(sc->duration / ts);
  const uint64_t tail = n - n / 20;
  float duty_active[3] = {0.5f, 0.5f, 0.5f};
  double torque_tail = 0.0;
  res->v_dc_min = INFINITY;
  res->v_dc_max = -INFINITY;
  res->max_speed = -INFINITY;
  res->min_speed = INFINITY;
  res->first_fault_t = -1.0;

  plant_adc_t adc;
  plant_state_t st;
  plant_brief_t br; /* what the metrics need: cheaper than plant_state_t */
  /* encoder error and source voltage profiles, each constant until *_end */
  double enc_err = 0.0, enc_err_end = -INFINITY, v_src = 0.0, v_src_end = -INFINITY;
  const double t_start = wall_now();
  uint64_t k = 0;
  for (; k < n; ++k) {
    const double t = (double)k * ts;
    hal.time_us = (uint32_t)(uint64_t)(t * 1e6);
    if (k % sc->drive.slow_div == 0) {
      if (opts->stop != NULL && *opts->stop) {
        res->stopped = true;
        break;
      }
      if (can) {
        if (opts->can_io != NULL) {
          opts->can_io(opts->can_user, &hal, t);
        }
        can_proto_poll(&proto, &drv, hal.time_us);
        drive_slow_loop(&drv);
        if (opts->can_io != NULL) {
          opts->can_io(opts->can_user, &hal, t);
        }
      } else {
        command_references(&drv, sc, t);
        drive_slow_loop(&drv);
      }
      if (opts->realtime) {
        sleep_s(t - (wall_now() - t_start));
      }
    }
    /* 1. sample */
    plant_sample(&plant, &adc);
    if (!(t < enc_err_end)) {
      enc_err = profile_eval_span(&sc->encoder_error, t, &enc_err_end);
    }
    to_hal_sample(&adc, enc_err, &hal.sample); /* in place: no copy of a just-written struct */
    /* 2. ISR */
    drive_isr(&drv);
    /* 3. observe */
    plant_get_brief(&plant, &br);
    for (int x = 0; x < 3; ++x) {
      double a = fabs(br.i_abc[x]);
      if (a > res->max_phase_current) {
        res->max_phase_current = a;
        res->max_phase_current_t = t;
      }
    }
    /* fmin/fmax semantics (a NaN sample is ignored), without the calls */
    res->v_dc_min = br.v_dc < res->v_dc_min ? br.v_dc : res->v_dc_min;
    res->v_dc_max = br.v_dc > res->v_dc_max ? br.v_dc : res->v_dc_max;
    res->max_speed = br.omega_m > res->max_speed ? br.omega_m : res->max_speed;
    res->min_speed = br.omega_m < res->min_speed ? br.omega_m : res->min_speed;
    if (k >= tail) {
      torque_tail += br.torque;
    }
    res->faults_seen |= drv.faults;
    if (drv.faults != 0u && res->first_fault_t < 0.0) {
      res->first_fault_t = t;
    }
    if (obs != NULL) {
      plant_get_state(&plant, &st);
      sil_step_t s = {k, t, &st, &hal.sample, &drv, sc, duty_active, hal.gates_on};
      obs(user, &s);
    }
    /* 4. plant over [t_k, t_k+1) */
    if (!(t < v_src_end)) {
      v_src = profile_eval_span(&sc->v_source, t, &v_src_end);
    }
    plant.p.dclink.v_source = v_src;
    const double d[3] = {duty_active[0], duty_active[1], duty_active[2]};
    plant_step(&plant, d, hal.gates_on);
    memcpy(duty_active, hal.duty, sizeof duty_active);
    /* hardware comparator: gates off in hardware, latched */
    if (sc->hw_trip > 0.0 && hal.gates_on) {
      plant_get_brief(&plant, &br);
      if (fabs(br.i_abc[0]) > sc->hw_trip || fabs(br.i_abc[1]) > sc->hw_trip ||
          fabs(br.i_abc[2]) > sc->hw_trip) {
        hal.hw_tripped = true;
        hal.gates_on = false;
      }
    }
  }
  res->wall_time = wall_now() - t_start;
  plant_get_state(&plant, &st);
  if (k < n) { /* stopped early */
    n = k;
  }
  res->steps = n;
  res->sim_time = (double)n * ts;
  if (can) {
    res->can = proto.stats;
  }
  res->real_time_factor = res->wall_time > 0.0 ? res->sim_time / res->wall_time : 0.0;
  res->final_speed = st.omega_m;
  res->final_speed_ref = profile_eval(&sc->ref.speed, res->sim_time);
  res->final_torque = n > tail ? torque_tail / (double)(n - tail) : st.torque;
  res->faults = drv.faults;
  res->final_state = drv.state;
  res->watchdog_kicks = hal.watchdog_kicks;
  return 0;
}
