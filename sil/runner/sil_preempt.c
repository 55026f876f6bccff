/*
 * sil_preempt.c - the SIL under random preemption (see sil_preempt.h).
 */
#define _GNU_SOURCE /* pthread_kill, clock_gettime */
#include "sil_preempt.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "drive_params.h"
#include "sil_run.h"

/* Shared by the handler ("the ISR") and the main thread; each field of the
 * result has one writer. */
static sil_ctx_t g_x;
static const scenario_t *g_sc;
static sil_preempt_result_t *g_r;
static volatile sig_atomic_t g_running;
static _Atomic uint64_t g_k; /* periods done (written by the handler) */
static atomic_bool g_stop;
static pthread_t g_main;
static double g_max_gap_us;
static bool g_need_enable;   /* handler: a trip or a clear disarmed, no enable command since */
static uint32_t g_need_mark; /* the enable count at that disarm */
/* What the ISR owns, as the last ISR left it: nobody else may change it. */
static struct {
  bool valid;
  drive_state_t state;
  uint32_t faults;
  bool armed;
  drive_cmd_t cmd;
} g_owned;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Handler side: records the first violation (static text only). */
static void violation(const char *what) {
  if (g_r->violations++ == 0u) {
    size_t n = strlen(what);
    n = n < sizeof g_r->first_violation - 1u ? n : sizeof g_r->first_violation - 1u;
    memcpy(g_r->first_violation, what, n);
    g_r->first_violation[n] = '\0';
  }
}

static bool gates_state(drive_state_t s) {
  return s == DRIVE_STATE_RUN || s == DRIVE_STATE_ALIGN;
}

/* The command block the ISR holds equals the one published (seq aside). */
static bool same_block(const drive_cmd_t *a, const drive_cmd_t *b) {
  return a->enable == b->enable && a->law == b->law && a->mode == b->mode &&
         !(a->torque < b->torque || a->torque > b->torque) &&
         !(a->speed < b->speed || a->speed > b->speed) && !(a->id < b->id || a->id > b->id) &&
         !(a->iq < b->iq || a->iq > b->iq) && !(a->flux < b->flux || a->flux > b->flux) &&
         a->clear_count == b->clear_count && a->enable_count == b->enable_count &&
         a->clear_enable_mark == b->clear_enable_mark &&
         memcmp(a->fault_count, b->fault_count, sizeof a->fault_count) == 0;
}

/* One PWM period, on top of whatever the main thread is doing. */
static void on_interrupt(int sig) {
  (void)sig;
  if (!g_running) {
    return;
  }
  const int saved_errno = errno;
  drive_t *d = &g_x.drv;
  const uint64_t k = atomic_load(&g_k);
  const double t = (double)k * g_sc->plant.ts;
  g_x.hal.time_us = (uint32_t)(uint64_t)(t * 1e6);
  sil_sample(&g_x, g_sc, t);

  if (g_owned.valid && (d->state != g_owned.state || d->faults != g_owned.faults ||
                        d->armed != g_owned.armed || !same_block(&d->cmd, &g_owned.cmd))) {
    violation("the main loop wrote drive state the ISR owns (state, faults, armed, commands)");
  }
  const drive_state_t st0 = d->state;
  const uint32_t faults0 = d->faults;
  const uint32_t clear0 = d->clear_seen;
  uint32_t seen0[DRIVE_FAULT_COUNT];
  memcpy(seen0, d->fault_seen, sizeof seen0);
  const uint32_t seq = d->req.seq; /* the main thread is frozen while we run */
  g_r->cfg_in_publication += (d->creq.seq & 1u) != 0u ? 1u : 0u;
  const drive_cmd_t cmd0 = d->cmd;
  drive_isr(d);

  const drive_state_t st = d->state;
  if (st == DRIVE_STATE_FAULT) {
    if (d->faults == 0u) {
      violation("fault state with no fault latched");
    }
    if (g_x.hal.gates_on) {
      violation("gates on in the fault state");
    }
  } else if (d->faults != 0u) {
    violation("faults latched outside the fault state (e.g. idle after a racing clear)");
  }
  if (g_x.hal.gates_on && !gates_state(st)) {
    violation("gates on outside run and alignment");
  }
  if (drive_config_check(&d->cfg, NULL) != 0) {
    violation("the parameter set in force is not a valid set (torn request)");
  }
  if ((d->faults & DRIVE_FAULT_CONFIG) != 0u) {
    violation("the ISR refused a parameter set the main loop had validated (torn request)");
  }
  if ((seq & 1u) != 0u) {
    g_r->in_publication++;
    if (!same_block(&d->cmd, &cmd0)) {
      violation("the ISR took a half-written command block");
    }
  } else if (!same_block(&d->cmd, &d->req.cmd)) {
    violation("the ISR's command block differs from the published one");
  }
  /* a clear clears only what was latched before it: every request taken
   * latches, even one posted in the same period as a clear */
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    if (d->fault_seen[b] != seen0[b] && (d->faults & (1u << b)) == 0u) {
      violation("a fault request was taken but not latched");
    }
  }
  if (d->clear_seen != clear0 && st0 == DRIVE_STATE_FAULT) {
    /* a clear that found a fault needs an enable command posted after it */
    g_need_enable = true;
    g_need_mark = d->cmd.clear_enable_mark;
  }
  if (st0 != DRIVE_STATE_FAULT && st == DRIVE_STATE_FAULT) {
    g_r->trips++;
  }
  if (st == DRIVE_STATE_FAULT && d->faults != faults0) {
    g_need_enable = true; /* a trip: enables posted before it do not count */
    g_need_mark = d->cmd.enable_count;
  }
  if (g_need_enable && d->cmd.enable_count != g_need_mark) {
    g_need_enable = false;
  }
  if (st0 == DRIVE_STATE_IDLE && st == DRIVE_STATE_OFFSET_CAL) {
    g_r->starts++;
    if (d->cmd.enable == 0u || g_need_enable) {
      violation("started without an enable command after a trip or a clear");
    }
  }
  g_owned.state = d->state;
  g_owned.faults = d->faults;
  g_owned.armed = d->armed;
  g_owned.cmd = d->cmd;
  g_owned.valid = true;
  sil_advance(&g_x, g_sc, t);
  g_r->periods++;
  atomic_store(&g_k, k + 1u);
  errno = saved_errno;
}

/* The interrupt source: SIGUSR1 to the main thread after random gaps. */
static void *interrupter(void *arg) {
  uint64_t s = *(const uint64_t *)arg | 1u;
  while (!atomic_load(&g_stop)) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    const double gap = g_max_gap_us * 1e-6 * (double)(s % 1000u) / 1000.0;
    const double until = now_s() + gap;
    while (now_s() < until) {
    }
    pthread_kill(g_main, SIGUSR1);
  }
  return NULL;
}

typedef struct {
  uint64_t s;
} rng_t;

static uint32_t rnd(rng_t *r, uint32_t n) {
  r->s ^= r->s << 13;
  r->s ^= r->s >> 7;
  r->s ^= r->s << 17;
  return (uint32_t)(r->s % n);
}

static float rnd_f(rng_t *r, float lo, float hi) {
  return lo + (hi - lo) * (float)rnd(r, 100001u) / 100000.0f;
}

/* A parameter write: LIVE ones (run or not), IDLE ones (refused while
 * running), and pairs whose intermediate sets stay valid only in order. */
static void random_param(rng_t *r, sil_preempt_result_t *res) {
  static const char *const live[] = {"i_trip", "torque_max", "speed_bw", "v_dc_min", "lc_time"};
  static const float live_lo[] = {7.5f, 10.0f, 30.0f, 100.0f, 0.002f};
  static const float live_hi[] = {9.0f, 20.0f, 60.0f, 150.0f, 0.004f};
  static const char *const idle[] = {"rs", "current_bw", "flux_obs_wc", "i_max"};
  static const float idle_lo[] = {6.5f, 1500.0f, 100.0f, 3.0f};
  static const float idle_hi[] = {7.7f, 2500.0f, 150.0f, 3.7f};
  const bool is_live = rnd(r, 2u) == 0u;
  const unsigned j = rnd(r, is_live ? 5u : 4u);
  const drive_param_t *p = drive_params_by_name(is_live ? live[j] : idle[j]);
  const float v = is_live ? rnd_f(r, live_lo[j], live_hi[j]) : rnd_f(r, idle_lo[j], idle_hi[j]);
  res->param_writes++;
  if (drive_params_set(&g_x.drv, p->id, v, NULL) != DRIVE_PARAM_OK) {
    res->param_refused++;
  }
}

/* A whole parameter set, A or B, requested at once: a copy that mixed them
 * would be invalid - i_max (early in the struct) of A with align_current
 * (late) of B, or i_trip of A with i_max of B - which the handler sees. */
static void random_set(rng_t *r, sil_preempt_result_t *res) {
  drive_config_t c = *drive_requested_config(&g_x.drv);
  const bool a = rnd(r, 2u) == 0u;
  c.i_max = a ? 3.0f : 3.7f;
  c.i_trip = a ? 3.2f : 7.5f;
  c.align_current = a ? 2.9f : 3.6f;
  c.current_bw = a ? 1800.0f : 2200.0f;
  c.speed_bw = a ? 40.0f : 60.0f;
  res->param_writes++;
  const drive_state_t st = g_x.drv.state;
  /* not LIVE: only with the gates off */
  const bool off = st == DRIVE_STATE_IDLE || st == DRIVE_STATE_FAULT;
  if (!off || drive_request_config(&g_x.drv, &c, NULL) != 0) {
    res->param_refused++;
  }
}

static void main_loop(rng_t *r, const sil_preempt_opts_t *o, sil_preempt_result_t *res) {
  drive_t *d = &g_x.drv;
  const double t0 = now_s(), t_end = t0 + o->wall_max_s;
  uint64_t next = 0u;
  unsigned turn = 0u;
  float torque = 0.0f;
  for (;;) {
    const uint64_t k = atomic_load(&g_k);
    if (k >= o->periods || ((res->main_iterations & 1023u) == 0u && now_s() > t_end)) {
      break;
    }
    res->main_iterations++;
    if (k < next) {
      /* between actions: telemetry copies, the background service, the
       * last torque command posted again (the ISR copies every block) and,
       * with the gates off, a whole parameter set requested again */
      turn = (turn + 1u) % 4u;
      if (turn == 0u) {
        drive_telemetry_t tm;
        res->tm_reads++;
        if (drive_telemetry_read(d, &tm)) {
          res->tm_torn += tm.isr_count != tm.isr_count_end ? 1u : 0u;
        } else {
          res->tm_failed++;
        }
      } else if (turn == 1u) {
        drive_background(d);
      } else if (turn == 2u) {
        drive_cmd_torque(d, torque);
      } else if (d->state == DRIVE_STATE_IDLE || d->state == DRIVE_STATE_FAULT) {
        random_set(r, res);
      }
      continue;
    }
    next = k + 1u + rnd(r, 40u);
    const uint32_t a = rnd(r, 100u);
    res->commands++;
    if (a < 25u) {
      drive_cmd_enable(d, rnd(r, 10u) < 8u);
    } else if (a < 45u) {
      torque = rnd_f(r, -15.0f, 15.0f);
      drive_cmd_torque(d, torque);
    } else if (a < 55u) {
      drive_cmd_speed(d, rnd_f(r, -60.0f, 60.0f));
    } else if (a < 60u) {
      (void)drive_cmd_set_mode(d, rnd(r, 2u) == 0u ? DRIVE_MODE_TORQUE : DRIVE_MODE_SPEED);
    } else if (a < 64u) {
      (void)drive_cmd_set_law(d, (drive_law_t)rnd(r, (uint32_t)DRIVE_LAW_COUNT));
    } else if (a < 70u) {
      drive_cmd_clear_fault(d);
      res->clears++;
    } else if (a < 73u) {
      drive_request_fault(d, DRIVE_FAULT_CMD_TIMEOUT);
      res->fault_requests++;
    } else if (a < 82u) {
      random_param(r, res);
    } else if (a < 85u) {
      random_set(r, res);
    } else {
      drive_cmd_flux(d, 0.0f);
    }
  }
  res->tm_retries = d->host.tm_retries;
  res->wall_s = now_s() - t0;
}

int sil_preempt_run(const scenario_t *sc, const sil_preempt_opts_t *opts, sil_preempt_result_t *r,
                    char *err, size_t errlen) {
  memset(r, 0, sizeof *r);
  if (sil_setup(&g_x, sc, err, errlen) != 0) {
    return -1;
  }
  g_sc = sc;
  g_r = r;
  g_max_gap_us = opts->max_gap_us;
  g_need_enable = false;
  g_need_mark = 0u;
  g_owned.valid = false;
  atomic_store(&g_k, 0u);
  atomic_store(&g_stop, false);
  g_main = pthread_self();
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  if (sigaction(SIGUSR1, &sa, NULL) != 0) {
    snprintf(err, errlen, "sigaction: %s", strerror(errno));
    return -1;
  }
  g_running = 1;
  pthread_t th;
  static uint64_t seed_box;
  seed_box = (uint64_t)opts->seed * 2654435761u;
  if (pthread_create(&th, NULL, interrupter, &seed_box) != 0) {
    snprintf(err, errlen, "cannot start the interrupter thread");
    return -1;
  }
  rng_t rng = {(uint64_t)opts->seed * 0x9E3779B97F4A7C15ull | 1u};
  main_loop(&rng, opts, r);
  atomic_store(&g_stop, true);
  pthread_join(th, NULL);
  g_running = 0;
  /* quiet: a few ISRs in sequence take the last command block; every
   * fault request must then have been taken */
  for (int n = 0; n < 4; ++n) {
    g_running = 1;
    on_interrupt(SIGUSR1);
    g_running = 0;
  }
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    if (g_x.drv.fault_seen[b] != g_x.drv.req.cmd.fault_count[b]) {
      violation("a fault request was never taken");
    }
  }
  signal(SIGUSR1, SIG_DFL);
  return 0;
}
