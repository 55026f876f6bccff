/*
 * proc_poles.c - identification of the pole pairs and the magnet's
 * polarity with an encoder (issue 25 d), and what the encoder
 * identifications share (proc_id_*, the encoder unwrapped).
 *
 * A current vector of amplitude i = id_i_test turned slowly in open loop
 * (I-f: the current loop in the alpha-beta frame, the reference
 * i e^{j theta_v}, theta_v = w_v t), the rotor follows it (the PM torque
 * 1.5 p lambda_m i sin(theta_v - theta_e) pulls its d axis to the vector).
 * After PROC_POLES_TURNS electrical turns the rotor has turned
 * PROC_POLES_TURNS / p mechanical turns: the encoder's change Delta theta_m
 * gives p = 2 pi PROC_POLES_TURNS / |Delta theta_m|, rounded, with the
 * residue checked, and the sign of Delta theta_m the polarity (+1: the
 * encoder counts up as the vector turns forward). The rest angles before
 * and after are means over a hold (a light free rotor swings about the
 * vector: the mean is its axis). As moteus's calibration (moteus_tool.py,
 * "find_pole_count"-like: it turns the vector and reads the encoder's
 * change), learnt from, not copied.
 *
 * Bounds: the current i (clamped to i_max; tripped above
 * PROC_ID_TRIP i + 5 % i_max), the voltage v_max; the rotor turns
 * PROC_POLES_TURNS electrical turns (PROC_POLES_TURNS / p mechanical), from
 * rest to rest (a raised-sine acceleration: poles_turn_time), at 4 pi
 * PROC_POLES_HZ rad/s electrical at most.
 * Error: the rest angles' bias e (Coulomb friction: asin(T_c / (1.5 p
 * lambda_m i)) electrical, both ends the same way after the turn) and the
 * encoder's count give p PROC_POLES_TURNS / (PROC_POLES_TURNS + e / 2 pi):
 * exact after rounding while |e| < pi PROC_POLES_TURNS / p (p = 21: 0.6 rad
 * electrical); the residue check (PROC_POLES_RESIDUE) fails a slipped turn.
 */
#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"
#include "proc.h"

#define PROC_POLES_TURNS   4.0f  /* electrical turns */
#define PROC_POLES_HZ      2.0f  /* the vector's mean speed, at most [Hz electrical] */
#define PROC_POLES_ACC     0.3f  /* the vector's acceleration: this fraction of the torque's */
#define PROC_POLES_T_MAX   8.0f  /* the turns' longest [s] */
#define PROC_POLES_HOLD    0.4f  /* each hold [s]; the rest angle: its second half's mean */
#define PROC_POLES_RESIDUE 0.25f /* |p measured - round(p)| beyond: failed */
#define PROC_ID_TRIP       1.3f  /* the current's bound: PROC_ID_TRIP x the test current */

enum { PH_HOLD0 = 0, PH_TURN = 1, PH_HOLD1 = 2, PH_DONE = 3 };

/* ------------------------------------------------- shared (proc.h) */

FD_COLD float proc_id_current(const drive_config_t *c) {
  const float i = c->id_i_test > 0.0f ? c->id_i_test : 0.3f * c->i_max;
  return fminf(i, c->i_max);
}

FD_COLD float proc_id_speed_max(const drive_config_t *c) {
  return c->id_speed_max > 0.0f ? c->id_speed_max : 0.3f * c->speed_max;
}

FD_COLD float proc_id_speed(const drive_config_t *c) {
  const float w = c->id_speed > 0.0f ? c->id_speed : 0.2f * c->speed_max;
  return fminf(w, proc_id_speed_max(c));
}

FD_COLD void proc_enc_unwrap_reset(proc_enc_unwrap_t *u) {
  u->prev = 0.0f;
  u->theta = 0.0f;
  u->started = false;
}

FD_COLD float proc_enc_unwrap(proc_enc_unwrap_t *u, float enc_angle) {
  if (!u->started) {
    u->prev = enc_angle;
    u->started = true;
  }
  u->theta += frames_wrap_pi(enc_angle - u->prev);
  u->prev = enc_angle;
  return u->theta;
}

FD_COLD const char *proc_id_encoder_check(const proc_setup_t *su, const char **field) {
  if (su->cfg->pos_source != POS_SOURCE_ENCODER) {
    *field = "pos_source";
    return "needs the encoder (pos_source encoder)";
  }
  return NULL;
}

/* The current's bound: PROC_ID_TRIP the test current + 5 % i_max (noise). */
FD_COLD static bool poles_overcurrent(const drive_config_t *c, ab_t i, float i_test) {
  const float lim = PROC_ID_TRIP * i_test + 0.05f * c->i_max;
  return !(i.alpha * i.alpha + i.beta * i.beta <= lim * lim);
}

/* ------------------------------------------------------ the procedure */

/* The turns' duration: the vector's acceleration (peak 4 pi^2 N / t^2
 * electrical) at most PROC_POLES_ACC of the torque 1.5 p lambda_m i over
 * the inertia with p = 1 (the pole pairs unknown: the slowest machine's
 * electrical acceleration, 1.5 p^2 lambda_m i / J, is p = 1's), J and
 * lambda_m the parameters' (rough values suffice), and the speed at most
 * 2 pi PROC_POLES_HZ on average; at most PROC_POLES_T_MAX. */
FD_COLD static float poles_turn_time(const drive_config_t *c, float lambda_m, float i) {
  const float a = PROC_POLES_ACC * 1.5f * lambda_m * i / c->inertia;
  const float t_acc =
      a > 0.0f ? sqrtf(4.0f * FRAMES_PI * FRAMES_PI * PROC_POLES_TURNS / a) : PROC_POLES_T_MAX;
  return fminf(fmaxf(t_acc, PROC_POLES_TURNS / PROC_POLES_HZ), PROC_POLES_T_MAX);
}

FD_COLD static void poles_init(proc_state_t *st, const proc_setup_t *su) {
  proc_poles_t *p = &st->poles;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&p->cc, &ccfg);
  proc_enc_unwrap_reset(&p->u);
  p->n = 0u;
  p->n_all = 0u;
  p->phase = PH_HOLD0;
  p->theta_v = 0.0f;
  p->acc = 0.0f;
  p->acc_n = 0u;
  p->th0 = 0.0f;
  p->th1 = 0.0f;
  p->pp = 0.0f;
}

FD_COLD static int poles_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                              proc_out_t *out) {
  proc_poles_t *p = &st->poles;
  const drive_config_t *c = su->cfg;
  const float i = proc_id_current(c);
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  if (!in->s->enc_valid || !fd_isfinite(in->s->enc_angle)) {
    out->fault = DRIVE_FAULT_POSITION;
    return PROC_FAILED;
  }
  if (poles_overcurrent(c, in->i_ab, i)) {
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  const float th = proc_enc_unwrap(&p->u, in->s->enc_angle);
  const uint32_t n_hold = (uint32_t)(PROC_POLES_HOLD / c->ts) + 1u;
  const float t_turn = poles_turn_time(c, su->machine->lambda_m, i);
  const uint32_t n_turn = (uint32_t)(t_turn / c->ts) + 1u;
  p->n_all++;
  p->n++;
  if (p->phase == PH_HOLD0 || p->phase == PH_HOLD1) {
    if (p->n > n_hold / 2u) { /* the second half: the rest angle's mean */
      p->acc += th;
      p->acc_n++;
    }
    if (p->n >= n_hold) {
      const float mean = p->acc / (float)p->acc_n;
      p->acc = 0.0f;
      p->acc_n = 0u;
      p->n = 0u;
      if (p->phase == PH_HOLD0) {
        p->th0 = mean;
        p->phase = PH_TURN;
      } else {
        p->th1 = mean;
        p->phase = PH_DONE;
      }
    }
  } else if (p->phase == PH_TURN) {
    /* theta_v = 2 pi N (x - sin(2 pi x) / 2 pi), x = t / t_turn: from rest
     * to rest, the acceleration a raised sine (the core's sine, not libm's:
     * the PIL's duties equal the host's, docs/pil.md) */
    const float x = (float)p->n / (float)n_turn;
    const float s2 = frames_sincos(2.0f * FRAMES_PI * x).s;
    p->theta_v = 2.0f * FRAMES_PI * PROC_POLES_TURNS * (x - s2 / (2.0f * FRAMES_PI));
    if (p->n >= n_turn) {
      p->theta_v = 2.0f * FRAMES_PI * PROC_POLES_TURNS;
      p->n = 0u;
      p->phase = PH_HOLD1;
    }
  }
  if (p->phase == PH_DONE) {
    out->apply = false;
    const float d = p->th1 - p->th0;
    /* mut: poles_count_formula */
    p->pp = fabsf(d) > 1e-6f ? 2.0f * FRAMES_PI * PROC_POLES_TURNS / d : 0.0f;
    const float a = fabsf(p->pp);
    const float r = a - roundf(a);
    if (!(a >= 0.5f && a < 200.5f) || fabsf(r) > PROC_POLES_RESIDUE) {
      out->fault = DRIVE_FAULT_POSITION; /* slipped, stuck, or no encoder movement */
      return PROC_FAILED;
    }
    return PROC_DONE;
  }
  const sincos_t sc = frames_sincos(frames_wrap_pi(p->theta_v));
  const dq_t v = current_ctrl_update(&p->cc, (dq_t){i * sc.c, i * sc.s},
                                     (dq_t){in->i_ab.alpha, in->i_ab.beta}, 0.0f, in->v_max);
  out->v_ab = (ab_t){v.d, v.q};
  return PROC_RUNNING;
}

/* result: [0] pole pairs (rounded), [1] polarity (+1 the encoder counts
 * with the vector, -1 against), [2] the measured (unrounded, unsigned) pole
 * pairs, [3] the residue, [4] the rotor's movement over the turns [rad
 * mechanical], [5] the vector's angle [rad electrical, unwrapped] */
FD_COLD static void poles_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_poles_t *p = &st->poles;
  const float a = fabsf(p->pp);
  tm->phase = p->phase;
  tm->n = p->n_all;
  tm->result[0] = roundf(a);
  tm->result[1] = p->pp > 0.0f ? 1.0f : (p->pp < 0.0f ? -1.0f : 0.0f);
  tm->result[2] = a;
  tm->result[3] = a - roundf(a);
  tm->result[4] = p->th1 - p->th0;
  tm->result[5] = p->theta_v;
}

FD_COLD static const char *poles_check(const proc_setup_t *su, const char **field) {
  return proc_id_encoder_check(su, field);
}

const proc_row_t proc_poles = {
    .name = "poles",
    .id = PROC_POLES,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = poles_check,
    .wanted = NULL,
    .init = poles_init,
    .step = poles_step,
    .abort = NULL,
    .publish = poles_publish,
};
