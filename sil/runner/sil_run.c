/*
 * sil_run.c - the lock-step loop (see sil_run.h for the timing).
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "sil_run.h"

#include <math.h>
#include <stdio.h>
#include <stddef.h>
#include <string.h>
#include <time.h>

#define SIL_PI 3.14159265358979323846

static double wall_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The plant's sensors at the valley as the board's sample set. */
static void to_hal_sample(const plant_adc_t *a, const sil_ctx_t *x, double enc_error, bool enc_ok,
                          hal_sample_t *s) {
  for (int k = 0; k < 3; ++k) {
    s->i_abc[k] = (float)a->i_abc[k];
  }
  s->v_dc = (float)a->v_dc;
  s->t_i = 0.0f;
  if (x->star_got > 0) { /* the DFC window of the last period */
    s->n_star = (uint8_t)x->star_got;
    for (int k = 0; k < HAL_STAR_MAX; ++k) {
      s->v_star[k] = k < x->star_got ? (float)x->star_v[k] : 0.0f;
      s->t_star[k] = k < x->star_got ? (float)x->star_tt[k] : 0.0f;
    }
    s->test_vector = x->star_got_tv;
  } else { /* the star point at the valley */
    s->n_star = 1u;
    s->v_star[0] = (float)a->v_star;
    s->t_star[0] = 0.0f;
    s->v_star[1] = 0.0f;
    s->t_star[1] = 0.0f;
    s->test_vector = 0u;
  }
  double th = a->enc_angle + enc_error;
  if (!(th >= 0.0 && th < 2.0 * SIL_PI)) { /* fmod is the identity on [0, 2 pi) */
    th = fmod(th, 2.0 * SIL_PI);
  }
  s->enc_angle = (float)(th < 0.0 ? th + 2.0 * SIL_PI : th);
  s->t_enc = 0.0f;
  s->enc_valid = enc_ok;
  s->valid = true;
}

void sil_command_references(drive_t *drv, const scenario_t *sc, double t) {
  bool on = t >= sc->enable_at && !(sc->disable_at > sc->enable_at && t >= sc->disable_at);
  drive_cmd_enable(drv, on);
  drive_cmd_torque(drv, (float)profile_eval(&sc->ref.torque, t));
  drive_cmd_speed(drv, (float)profile_eval(&sc->ref.speed, t));
  drive_cmd_current(drv, (float)profile_eval(&sc->ref.id, t), (float)profile_eval(&sc->ref.iq, t));
  drive_cmd_flux(drv, (float)profile_eval(&sc->ref.flux, t));
}

void sil_main_injections(sil_ctx_t *x, const scenario_t *sc, double t) {
  /* the injected trip, once, at the first main-loop period at or after
   * trip_at (a flag, not a window: any trip_at fires, a denormal one at
   * the first period after t = 0) */
  if (sc->trip_cause != 0u && !x->trip_posted && t >= sc->trip_at) {
    drive_request_fault(&x->drv, sc->trip_cause);
    x->trip_posted = true;
  }
  /* the controller's map error: a parameter write when the profile's value
   * changes (the first time: when it differs from the set requested), so a
   * CAN client's own write holds until the profile moves again */
  if (sc->cm_scale_d.n > 0 || sc->cm_scale_q.n > 0) {
    drive_config_t cfg = *drive_requested_config(&x->drv);
    const float sd =
        sc->cm_scale_d.n > 0 ? (float)profile_eval(&sc->cm_scale_d, t) : cfg.cm_scale_d;
    const float sq =
        sc->cm_scale_q.n > 0 ? (float)profile_eval(&sc->cm_scale_q, t) : cfg.cm_scale_q;
    const float ld = x->cm_written ? x->cm_last[0] : cfg.cm_scale_d;
    const float lq = x->cm_written ? x->cm_last[1] : cfg.cm_scale_q;
    if (sd < ld || sd > ld || sq < lq || sq > lq) {
      cfg.cm_scale_d = sd;
      cfg.cm_scale_q = sq;
      (void)drive_request_config(&x->drv, &cfg, NULL); /* out of range: refused, the last holds */
      x->cm_last[0] = sd;
      x->cm_last[1] = sq;
      x->cm_written = true;
    }
  }
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

/* A profile used as an on/off injection: active while > 0.5. */
static bool injected(const profile_t *p, double t) {
  return p->n > 0 && profile_eval(p, t) > 0.5;
}

int sil_run(const scenario_t *sc, sil_observer_fn obs, void *user, sil_result_t *res, char *err,
            size_t errlen) {
  return sil_run_ex(sc, NULL, obs, user, res, err, errlen);
}

/* The firmware's start: drive_init with the scenario's parameter set. */
static int sil_start_firmware(sil_ctx_t *x, const scenario_t *sc, char *err, size_t errlen) {
  drive_config_err_t e;
  if (drive_init(&x->drv, &sc->drive, &e) != 0) {
    snprintf(err, errlen, "controller: %s: %s", e.field, e.reason);
    return -1;
  }
  return 0;
}

/* The MCU restarts after a watchdog reset: gates off at once (the timer's
 * outputs go idle), the firmware starts again from drive_init. */
static int sil_reset_mcu(sil_ctx_t *x, const scenario_t *sc, char *err, size_t errlen) {
  x->hal.gates_on = false;
  x->hal.asc = false;
  x->hal.reset_by_watchdog = true;
  x->hal.isr_overruns = 0u; /* the board's counter restarts with the MCU */
  x->hal.watchdog_last_us = x->hal.time_us;
  return sil_start_firmware(x, sc, err, errlen);
}

int sil_setup(sil_ctx_t *x, const scenario_t *sc, char *err, size_t errlen) {
  const char *field = "";
  if (plant_init(&x->plant, &sc->plant, &field) != 0) {
    snprintf(err, errlen, "plant: invalid parameter %s", field);
    return -1;
  }
  hal_sil_init(&x->hal, &sc->board);
  hal_sil_bind(&x->hal);
  if (sil_start_firmware(x, sc, err, errlen) != 0) {
    return -1;
  }
  for (int j = 0; j < 3; ++j) {
    x->pwm_on[j] = 0.25;
    x->pwm_off[j] = 0.75;
  }
  x->star_n = 0;
  x->star_got = 0;
  x->enc_err = 0.0;
  x->enc_err_end = -INFINITY;
  x->v_src = 0.0;
  x->v_src_end = -INFINITY;
  x->isr_late = false;
  x->trip_posted = false;
  x->cm_written = false;
  x->cm_last[0] = 0.0f;
  x->cm_last[1] = 0.0f;
  sil_adc_faults_reset(&x->adc_faults);
  sil_enc_faults_reset(&x->enc_faults, &sc->encoder_faults);
  const sil_enc_faults_t *ef = &sc->encoder_faults;
  x->enc_faults_on =
      ef->frozen.n > 0 || ef->reversed.n > 0 || ef->jitter > 0.0 || ef->missing > 0.0;
  x->rare = sc->encoder_invalid.n > 0 || x->enc_faults_on || sc->current_faults.n > 0 ||
            sc->isr_stall.n > 0 || sc->isr_overrun.n > 0 || sc->gate_driver.n > 0 ||
            sc->power_faults || sc->hw_trip > 0.0;
  return 0;
}

void sil_sample(sil_ctx_t *x, const scenario_t *sc, double t) {
  plant_adc_t adc;
  plant_sample_brief(&x->plant, &adc, &x->br);
  if (!(t < x->enc_err_end)) {
    x->enc_err = profile_eval_span(&sc->encoder_error, t, &x->enc_err_end);
  }
  to_hal_sample(&adc, x, x->enc_err, true, &x->hal.sample);
  if (!x->rare) {
    return;
  }
  x->hal.sample.enc_valid = !injected(&sc->encoder_invalid, t);
  if (x->enc_faults_on) {
    const sil_enc_faults_t *ef = &sc->encoder_faults;
    const int cpr = sc->plant.sensors.encoder_cpr;
    x->hal.sample.enc_angle =
        (float)sil_enc_faults_apply(ef, &x->enc_faults, t, adc.enc_angle + x->enc_err,
                                    x->plant.omega_m, cpr > 0 ? 2.0 * SIL_PI / cpr : 0.0);
  }
  if (sc->current_faults.n > 0) {
    sil_adc_faults_apply(&sc->current_faults, &x->adc_faults, t, sc->plant.sensors.i_full_scale,
                         &x->hal.sample);
  }
}

/* A break input latched: gates off in hardware (hal_sil_t, like TIM1 MOE). */
static void hw_break(sil_ctx_t *x, uint32_t source) {
  x->hal.hw_tripped = true;
  x->hal.hw_source |= source;
  x->hal.gates_on = false;
  x->hal.asc = false; /* MOE cleared: the short too */
}

/* The power-stage faults in force at t, into the plant. */
static void set_power_faults(sil_ctx_t *x, const scenario_t *sc, double t) {
  plant_power_fault_t f = {0u, 0u, 0u, 0u, 0u};
  if (injected(&sc->switch_open.active, t)) {
    f.open |= 1u << sc->switch_open.target;
  }
  if (injected(&sc->phase_lost.active, t)) {
    f.open |= PLANT_SW_LOW(sc->phase_lost.target) | PLANT_SW_HIGH(sc->phase_lost.target);
  }
  if (injected(&sc->switch_closed.active, t)) {
    f.closed |= 1u << sc->switch_closed.target;
  }
  if (injected(&sc->phase_open.active, t)) {
    f.phase_open |= 1u << sc->phase_open.target;
  }
  if (injected(&sc->ground_short.active, t)) {
    f.ground |= 1u << sc->ground_short.target;
  }
  if (injected(&sc->phase_short.active, t)) {
    const unsigned p0 = (unsigned)sc->phase_short.target;
    f.shorted = (1u << p0) | (1u << ((p0 + 1u) % 3u));
  }
  /* one stuck-closed switch, one short pair never on an open lead (the
   * parser): never refused */
  (void)plant_set_power_faults(&x->plant, &f);
}

/* The injections before the plant's period (x->rare only): nFAULT, the
 * power-stage faults in force. */
static void advance_faults_before(sil_ctx_t *x, const scenario_t *sc, double t) {
  if (injected(&sc->gate_driver, t)) {
    hw_break(x, HAL_BREAK_GATE_DRIVER); /* nFAULT: gates off at once, latched */
  }
  if (sc->power_faults) {
    set_power_faults(x, sc, t);
  }
}
/* The hardware's reactions after it (x->rare only): the desaturation
 * detection, the overcurrent comparator. */
static void advance_faults_after(sil_ctx_t *x, const scenario_t *sc) {
  if (sc->power_faults && plant_take_desat(&x->plant)) {
    hw_break(x, HAL_BREAK_GATE_DRIVER); /* desaturation: the driver's nFAULT */
  }
  /* hardware comparator: gates off in hardware, latched */
  if (sc->hw_trip > 0.0 && (x->hal.gates_on || x->hal.asc)) {
    plant_brief_t br;
    plant_get_brief(&x->plant, &br);
    if (fabs(br.i_abc[0]) > sc->hw_trip || fabs(br.i_abc[1]) > sc->hw_trip ||
        fabs(br.i_abc[2]) > sc->hw_trip) {
      hw_break(x, HAL_BREAK_OVERCURRENT);
    }
  }
}
void sil_advance(sil_ctx_t *x, const scenario_t *sc, double t) {
  if (x->rare) {
    advance_faults_before(x, sc, t);
  }
  if (!(t < x->v_src_end)) {
    x->v_src = profile_eval_span(&sc->v_source, t, &x->v_src_end);
  }
  x->plant.p.dclink.v_source = x->v_src;
  /* the pattern preloaded by the previous ISR acts over this period,
   * with its star-point samples (gates on only) */
  const int n_star = x->hal.gates_on ? x->star_n : 0;
  plant_star_request(&x->plant, n_star, x->star_t);
  if (x->hal.asc) { /* all low sides on for the whole period */
    static const double low[3] = {0.0, 0.0, 0.0};
    plant_step_pattern(&x->plant, low, low, true);
  } else {
    plant_step_pattern(&x->plant, x->pwm_on, x->pwm_off, x->hal.gates_on);
  }
  if (x->rare) {
    /* the desaturation at once; the comparator sees the period's end state
     * (nothing between reads the flag or the gates: the same order) */
    advance_faults_after(x, sc);
  }
  double v[PLANT_STAR_MAX];
  x->star_got = plant_star_read(&x->plant, v);
  x->star_got_tv = x->star_tv;
  for (int k = 0; k < x->star_got && k < HAL_STAR_MAX; ++k) {
    x->star_v[k] = v[k];
    x->star_tt[k] = x->plant.aux.star_t[k] - sc->plant.ts;
  }
  /* the pattern loaded at t_{k+1}: the ISR's, or, if it overran, the one
   * written before it */
  const hal_pwm_t *next = x->isr_late ? &x->pwm_before : &x->hal.pwm;
  x->isr_late = false;
  for (int j = 0; j < 3; ++j) {
    x->pwm_on[j] = next->on[j];
    x->pwm_off[j] = next->off[j];
  }
  x->star_n = next->n_star;
  for (int k = 0; k < HAL_STAR_MAX; ++k) {
    x->star_t[k] = next->t_star_req[k];
  }
  x->star_tv = next->test_vector;
}

int sil_run_ex(const scenario_t *sc, const sil_opts_t *opts, sil_observer_fn obs, void *user,
               sil_result_t *res, char *err, size_t errlen) {
  static const sil_opts_t no_opts = {0};
  static can_proto_t proto;
  static sil_ctx_t x; /* large: keep off the stack; one run at a time */
  /* the commission record clears its own (sil_commission_init): its
   * points' storage is left as it is */
  memset(res, 0, offsetof(sil_result_t, commission));
  if (sil_setup(&x, sc, err, errlen) != 0) {
    return -1;
  }
  /* the plant's period averages are the observer's (the log) alone */
  plant_set_averages(&x.plant, obs != NULL);
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
        opts->can_io(opts->can_user, &x.hal, 0.0);
      }
      sleep_s(0.01);
    }
  }

  const double ts = sc->plant.ts;
  uint64_t n = (uint64_t)llround(sc->duration / ts);
  const uint64_t tail = n - n / 20;
  double torque_tail = 0.0;
  res->v_dc_min = INFINITY;
  res->v_dc_max = -INFINITY;
  res->max_speed = -INFINITY;
  res->min_speed = INFINITY;
  res->first_fault_t = -1.0;
  res->first_watchdog_t = -1.0;
  sil_commission_init(&res->commission, &sc->commission);

  plant_state_t st;
  const double t_start = wall_now();
  uint64_t k = 0;
  unsigned slow_left = 0u; /* periods to the next main-loop period (k % slow_div == 0) */
  for (; k < n; ++k) {
    const double t = (double)k * ts;
    /* t * 1e6 < 2^63 (a run of 292,000 years): the signed conversion, one
     * instruction, gives what the unsigned one (a branch and two) gives */
    x.hal.time_us = (uint32_t)(int64_t)(t * 1e6);
    if (slow_left == 0u) {
      slow_left = sc->drive.slow_div;
      if (opts->stop != NULL && *opts->stop) {
        res->stopped = true;
        break;
      }
      /* the main loop: commands (scenario or CAN), then the background
       * service (telemetry copy, watchdog) - unless it is hung */
      if (!injected(&sc->main_stall, t)) {
        if (can) {
          if (opts->can_io != NULL) {
            opts->can_io(opts->can_user, &x.hal, t);
          }
          drive_background(&x.drv); /* fresh telemetry for the protocol */
          can_proto_poll(&proto, &x.drv, x.hal.time_us);
          sil_main_injections(&x, sc, t); /* the scenario's faults, as without CAN */
          if (opts->can_io != NULL) {
            opts->can_io(opts->can_user, &x.hal, t);
          }
        } else {
          if (!sil_commission_main(&res->commission, &sc->commission, &x.drv, t, x.plant.theta_m)) {
            sil_command_references(&x.drv, sc, t);
          }
          sil_main_injections(&x, sc, t);
          drive_background(&x.drv);
        }
      }
      if (opts->realtime) {
        sleep_s(t - (wall_now() - t_start));
      }
    }
    slow_left--;
    /* 1. sample */
    sil_sample(&x, sc, t);
    /* 2. ISR (unless the interrupt is stuck) */
    const bool hw_in = x.hal.hw_tripped;
    const uint32_t hw_src = x.hal.hw_source;
    if (!(x.rare && injected(&sc->isr_stall, t))) {
      /* it ends after the next valley */
      x.isr_late = x.rare && injected(&sc->isr_overrun, t);
      if (x.isr_late) {
        x.pwm_before = x.hal.pwm;
      }
      drive_isr(&x.drv);
      if (x.isr_late) { /* counted at its exit: the update already pending */
        x.hal.isr_overruns++;
      }
    }
    if (hal_sil_watchdog_expired(&x.hal, x.hal.time_us)) {
      res->watchdog_resets++;
      if (res->first_watchdog_t < 0.0) {
        res->first_watchdog_t = t;
      }
      if (sil_reset_mcu(&x, sc, err, errlen) != 0) {
        return -1;
      }
    }
    /* 3. observe */
    const plant_brief_t br = x.br; /* the state sampled at t (sil_sample) */
    for (int j = 0; j < 3; ++j) {
      double a = fabs(br.i_abc[j]);
      if (a > res->max_phase_current) {
        res->max_phase_current = a;
        res->max_phase_current_t = t;
      }
    }
    if (!res->commission.done) {
      sil_commission_observe(&res->commission, br.i_abc, x.plant.theta_m);
    }
    /* fmin/fmax semantics (a NaN sample is ignored), without the calls */
    res->v_dc_min = br.v_dc < res->v_dc_min ? br.v_dc : res->v_dc_min;
    res->v_dc_max = br.v_dc > res->v_dc_max ? br.v_dc : res->v_dc_max;
    res->max_speed = br.omega_m > res->max_speed ? br.omega_m : res->max_speed;
    res->min_speed = br.omega_m < res->min_speed ? br.omega_m : res->min_speed;
    if (k >= tail) {
      torque_tail += plant_get_torque(&x.plant);
    }
    res->faults_seen |= x.drv.faults;
    if (x.drv.faults != 0u && res->first_fault_t < 0.0) {
      res->first_fault_t = t;
    }
    if (obs != NULL) {
      plant_get_state(&x.plant, &st);
      const float duty_active[3] = {(float)(x.pwm_off[0] - x.pwm_on[0]),
                                    (float)(x.pwm_off[1] - x.pwm_on[1]),
                                    (float)(x.pwm_off[2] - x.pwm_on[2])};
      sil_step_t s = {k,
                      t,
                      &st,
                      &x.hal.sample,
                      &x.drv,
                      sc,
                      duty_active,
                      x.hal.gates_on,
                      x.hal.asc,
                      hw_in,
                      x.hal.timer_counts,
                      hw_src};
      obs(user, &s);
    }
    /* 4. plant over [t_k, t_k+1) */
    sil_advance(&x, sc, t);
    if (plant_too_fast(&x.plant)) { /* beyond what its steps cover: end, named */
      snprintf(err, errlen,
               "mechanics: at t = %.6g s the rotor turns at %.4g rpm: beyond what the plant "
               "integrates at this PWM period (%.4g rpm: %d steps of %g electrical rad per "
               "period); a load (mechanics.load_torque) or an inertia (mechanics.j) that lets "
               "the rotor run away",
               t, x.plant.omega_m * 30.0 / SIL_PI,
               plant_speed_limit_e(&x.plant) / sc->plant.machine.pole_pairs * 30.0 / SIL_PI,
               PLANT_STEPS_SPEED_MAX, PLANT_HW_MAX);
      return -1;
    }
  }
  res->wall_time = wall_now() - t_start;
  plant_get_state(&x.plant, &st);
  if (k < n) { /* stopped early */
    n = k;
  }
  res->steps = n;
  res->sim_time = (double)n * ts;
  res->pwm_clamped = x.hal.pwm_clamped;
  res->voltage_balance_max = (double)x.drv.host.ph.vdef_max;
  if (can) {
    res->can = proto.stats;
  }
  res->real_time_factor = res->wall_time > 0.0 ? res->sim_time / res->wall_time : 0.0;
  res->final_speed = st.omega_m;
  res->final_speed_ref = profile_eval(&sc->ref.speed, res->sim_time);
  res->final_torque = n > tail ? torque_tail / (double)(n - tail) : st.torque;
  res->faults = x.drv.faults;
  res->final_state = x.drv.state;
  res->watchdog_kicks = x.hal.watchdog_kicks;
  return 0;
}
