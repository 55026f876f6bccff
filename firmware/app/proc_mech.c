/*
 * proc_mech.c - identification of the inertia J and the friction (Coulomb
 * T_c and viscous B) with an encoder (issue 25 g): the current loop on the
 * encoder (offset, pole pairs and lambda_m identified, in force) applies
 * torque steps, T = 1.5 p lambda_m i_q (i_d = 0), the q current +-i
 * (i = id_i_test) or zero:
 *   accelerate +T to 0.8 id_speed_max, coast (T = 0) to 0.4 of it, brake
 *   -T through standstill to -0.8 id_speed_max, coast to -0.4, and +T
 *   back to standstill,
 * each step bounded in time (PROC_MECH_T_STEP; a coast PROC_MECH_T_COAST).
 * The rotor's equation T - T_c sgn(w) - B w = J dw/dt, integrated over
 * windows of PROC_MECH_NW blocks, gives one row per window
 *   J (w1 - w0) + T_c int sgn(w) dt + B int w dt = int T dt,
 * solved by least squares over the run (core/estimation/ident_mech.h).
 * The coasts measure the friction alone (T_c + B w = -J dw/dt), the steps
 * J against it; the speed span separates T_c from B. The equation is
 * linear: it holds as well for the signals' moving means over
 * PROC_MECH_NB blocks of PROC_MECH_D periods (32 ms), and the speed's mean
 * is exact from the encoder, (theta_k - theta_{k-M}) / (M ts): one count
 * over 32 ms (0.05 rad/s at 4096 counts) where the speed's per period
 * would be 500 times coarser. (PMC, rombrew/phobia pm_probe "J": the
 * inertia from a speed change under a known torque; ODrive and VESC have
 * none; learnt from, not copied.) Cogging averages out over whole turns.
 * Error: the torque constant's (lambda_m's) error scales J, T_c and B
 * alike; the encoder's count (2 pi / cpr over 32 ms) is noise the fit
 * averages; sgn(w) is the sign of the block's movement (0 at rest: the
 * friction that holds a resting rotor is not T_c).
 * Bounds: |i| <= i (tripped above PROC_ID_TRIP i + 5 % i_max), the speed
 * 0.8 id_speed_max (tripped overspeed above 1.2 of it), voltage v_max.
 */
#include <math.h>
#include <stddef.h>

#include "estimation/ident_mech.h"
#include "math/fd_math.h"
#include "math/frames.h"
#include "proc.h"

#define PROC_MECH_NW      16u  /* blocks per window (a least squares row) */
#define PROC_MECH_T_STEP  4.0f /* a torque step's longest [s] */
#define PROC_MECH_T_COAST 1.5f /* a coast's longest [s] */
#define PROC_MECH_HI      0.8f /* accelerate to this x id_speed_max ... */
#define PROC_MECH_LO      0.4f /* ... coast to this */
#define PROC_MECH_TRIP    1.3f

/* The friction's plateaus: speeds (x w_hi), the speed loop's bandwidth
 * [rad/s], the settling (at least, at most) and the measurement [s]. */
#define PROC_MECH_NP      6u
#define PROC_MECH_BW      20.0f
#define PROC_MECH_T_SET   0.6f
#define PROC_MECH_T_PLAT  1.0f
#define PROC_MECH_SET_TOL 0.02f /* settled: within this of the plateau's speed */
static const float mech_plat[PROC_MECH_NP] = {0.2f, 0.5f, 1.0f, -0.2f, -0.5f, -1.0f};

/* The steps: q current sign and the speed that ends each (x w_hi); then
 * the plateaus. */
enum {
  PH_ACC = 0,
  PH_COAST = 1,
  PH_BRAKE = 2,
  PH_COAST_B = 3,
  PH_BACK = 4,
  PH_PLAT = 5,
  PH_END = 6
};

FD_COLD static void mech_init(proc_state_t *st, const proc_setup_t *su) {
  proc_mech_t *m = &st->mech;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&m->cc, &ccfg);
  proc_enc_unwrap_reset(&m->u);
  m->n = m->n_all = 0u;
  m->phase = PH_ACC;
  m->rows = 0u;
  m->bk = 0u;
  for (unsigned k = 0; k < PROC_MECH_NB; ++k) {
    m->r_th[k] = m->r_t[k] = m->r_s[k] = 0.0f;
  }
  m->b_t = m->b_th0 = 0.0f;
  m->x_prev[0] = m->x_prev[1] = m->x_prev[2] = 0.0f;
  m->w0 = 0.0f;
  m->win[0] = m->win[1] = m->win[2] = 0.0f;
  m->win_n = 0u;
  ident_mech_reset(m->ls);
  m->res[0] = m->res[1] = m->res[2] = m->res[3] = 0.0f;
  m->w = 0.0f;
  m->plat = 0u;
  m->plat_meas = false;
}

/* The friction from the plateaus: the least squares of T_k = T_c s_k + B
 * w_k (s_k = sgn(w_k)) over the plateaus' mean torque T_k and speed w_k
 * (the angle over the plateau: a count over PROC_MECH_T_PLAT), the normal
 * equations solved by Cramer's rule. false: singular. */
FD_COLD static bool mech_plat_solve(proc_mech_t *m) {
  const float *p = m->pl.ps;
  const float det = p[0] * p[2] - p[1] * p[1];
  if (!(fabsf(det) > 1e-6f * p[0] * p[2])) {
    return false;
  }
  m->res[1] = (p[2] * p[3] - p[1] * p[4]) / det;
  m->res[2] = (p[0] * p[4] - p[1] * p[3]) / det;
  return true;
}

/* The scales of the least squares' columns (ident_mech.h): speed w_s,
 * torque t_s, window t_w. */
typedef struct {
  float w_s, t_s, t_w;
} mech_scale_t;

FD_COLD static mech_scale_t mech_scale(const drive_config_t *c) {
  const float kt = 1.5f * c->pole_pairs * c->lambda_m;
  return (mech_scale_t){PROC_MECH_HI * proc_id_speed_max(c), kt * proc_id_current(c),
                        (float)(PROC_MECH_NW * PROC_MECH_D) * c->ts};
}

FD_COLD static void mech_solve(proc_mech_t *m, const drive_config_t *c) {
  const mech_scale_t k = mech_scale(c);
  float x[3], rms;
  (void)ident_mech_solve(m->ls, m->rows, x, &rms);
  /* x = (J w_s / (t_s t_w), T_c / t_s, B w_s / t_s) */
  m->res[0] = x[0] * k.t_s * k.t_w / k.w_s;
  m->res[1] = x[1] * k.t_s;
  m->res[2] = x[2] * k.t_s / k.w_s;
  m->res[3] = rms;
}

/* A block's end: the moving means (the filtered speed, sgn(w), torque: the
 * rotor's equation holds for them as for the signals, it is linear in
 * them), integrated over the window (trapezoid), a row per window. */
FD_COLD static void mech_block(proc_mech_t *m, const drive_config_t *c, float th) {
  const float tb = (float)PROC_MECH_D * c->ts;
  const float dth = th - m->b_th0;
  const unsigned j = m->bk % PROC_MECH_NB;
  const float th_old = m->r_th[j];
  m->r_th[j] = th;
  m->r_t[j] = m->b_t;
  m->r_s[j] = (dth > 0.0f ? 1.0f : (dth < 0.0f ? -1.0f : 0.0f)) * tb;
  m->b_t = 0.0f;
  m->b_th0 = th;
  if (++m->bk <= PROC_MECH_NB) {
    return; /* the mean's span not yet filled */
  }
  const float span = (float)PROC_MECH_NB * tb;
  float st = 0.0f, ss = 0.0f;
  for (unsigned k = 0; k < PROC_MECH_NB; ++k) {
    st += m->r_t[k];
    ss += m->r_s[k];
  }
  const float x[3] = {ss / span, (th - th_old) / span, st / span}; /* sgn(w), w, T */
  if (m->bk == PROC_MECH_NB + 1u) {
    m->w0 = x[1];
  } else {
    for (unsigned k = 0; k < 3u; ++k) {
      m->win[k] += 0.5f * (m->x_prev[k] + x[k]) * tb;
    }
    if (++m->win_n >= PROC_MECH_NW) {
      const mech_scale_t s = mech_scale(c);
      /* mut: mech_coulomb_column */
      const float a[3] = {(x[1] - m->w0) / s.w_s, m->win[0] / s.t_w, m->win[1] / (s.w_s * s.t_w)};
      ident_mech_add(m->ls, a, m->win[2] / (s.t_s * s.t_w));
      m->rows++;
      m->win[0] = m->win[1] = m->win[2] = 0.0f;
      m->win_n = 0u;
      m->w0 = x[1];
    }
  }
  m->x_prev[0] = x[0];
  m->x_prev[1] = x[1];
  m->x_prev[2] = x[2];
}

FD_COLD static int mech_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                             proc_out_t *out) {
  proc_mech_t *m = &st->mech;
  const drive_config_t *c = su->cfg;
  const float i = proc_id_current(c);
  const float w_max = proc_id_speed_max(c), w_hi = PROC_MECH_HI * w_max;
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  if (!in->pos->valid || !in->s->enc_valid || !fd_isfinite(in->s->enc_angle)) {
    out->fault = DRIVE_FAULT_POSITION;
    return PROC_FAILED;
  }
  const float lim = PROC_MECH_TRIP * i + 0.05f * c->i_max;
  if (!(in->i_ab.alpha * in->i_ab.alpha + in->i_ab.beta * in->i_ab.beta <= lim * lim)) {
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  const float th = proc_enc_unwrap(&m->u, in->s->enc_angle);
  const float we = in->pos->omega, w = we / c->pole_pairs;
  m->w = w;
  if (!(fabsf(w) <= 1.2f * w_max)) {
    out->fault = DRIVE_FAULT_OVERSPEED;
    return PROC_FAILED;
  }
  const sincos_t sc = frames_sincos(in->pos->theta);
  const dq_t idq = frames_park(in->i_ab, sc);
  const machine_t *mm = su->machine;
  /* the torque of the sampled current (i_d = 0: 1.5 p lambda_m i_q) */
  m->b_t += 1.5f * mm->pole_pairs * (mm->lambda_m + (mm->ld - mm->lq) * idq.d) * idq.q * c->ts;
  if (m->n_all == 0u) {
    m->b_th0 = th;
  }
  /* the steps' rows (not on the plateaus: J is solved, ls taken) */
  if (++m->n_all % PROC_MECH_D == 0u && m->phase < PH_PLAT) {
    mech_block(m, c, th);
  }
  /* the steps */
  const float t = (float)(++m->n) * c->ts;
  bool next;
  switch (m->phase) {
  case PH_ACC:
    next = w >= w_hi || t >= PROC_MECH_T_STEP;
    break;
  case PH_COAST:
    next = w <= PROC_MECH_LO * w_hi || t >= PROC_MECH_T_COAST;
    break;
  case PH_BRAKE:
    next = w <= -w_hi || t >= 2.0f * PROC_MECH_T_STEP;
    break;
  case PH_COAST_B:
    next = w >= -PROC_MECH_LO * w_hi || t >= PROC_MECH_T_COAST;
    break;
  case PH_BACK:
    next = w >= 0.0f || t >= PROC_MECH_T_STEP;
    break;
  default: /* PH_PLAT: settle, then measure over PROC_MECH_T_PLAT */
    next = false;
    if (!m->plat_meas) {
      const float wr = mech_plat[m->plat] * w_hi;
      if ((t >= PROC_MECH_T_SET && fabsf(w - wr) <= PROC_MECH_SET_TOL * fabsf(wr)) ||
          t >= PROC_MECH_T_STEP) {
        m->plat_meas = true;
        m->n = 0u;
        m->pl.p_t = 0.0f;
        m->pl.p_th0 = th;
      }
    } else {
      m->pl.p_t +=
          1.5f * mm->pole_pairs * (mm->lambda_m + (mm->ld - mm->lq) * idq.d) * idq.q * c->ts;
      if (t >= PROC_MECH_T_PLAT) { /* the plateau's mean torque and speed */
        const float wk = (th - m->pl.p_th0) / t, tk = m->pl.p_t / t;
        /* mut: mech_plateau_sign_ignored */
        const float sk = wk > 0.0f ? 1.0f : -1.0f;
        m->pl.ps[0] += sk * sk;
        m->pl.ps[1] += sk * wk;
        m->pl.ps[2] += wk * wk;
        m->pl.ps[3] += sk * tk;
        m->pl.ps[4] += wk * tk;
        m->plat_meas = false;
        m->n = 0u;
        next = ++m->plat >= PROC_MECH_NP;
      }
    }
    break;
  }
  if (next) {
    m->phase++;
    m->n = 0u;
    if (m->phase == PH_PLAT) {
      /* J (and a first T_c, B) from the steps: the speed loop's gain */
      mech_solve(m, c);
      if (!(m->res[0] > 0.0f) || !fd_isfinite(m->res[0])) {
        out->fault = DRIVE_FAULT_CONTROL; /* no fit: the rotor did not move as a free inertia */
        return PROC_FAILED;
      }
      /* the normal equations' place taken by the plateaus' */
      m->pl.integ = 0.0f;
      m->pl.p_t = m->pl.p_th0 = 0.0f;
      for (unsigned k = 0; k < 5u; ++k) {
        m->pl.ps[k] = 0.0f;
      }
    }
    if (m->phase == PH_END) {
      out->apply = false;
      if (!mech_plat_solve(m) || !fd_isfinite(m->res[1]) || !fd_isfinite(m->res[2])) {
        out->fault = DRIVE_FAULT_CONTROL; /* the plateaus carry no friction fit */
        return PROC_FAILED;
      }
      return PROC_DONE;
    }
  }
  float iq = m->phase == PH_ACC || m->phase == PH_BACK ? i : m->phase == PH_BRAKE ? -i : 0.0f;
  if (m->phase == PH_PLAT) {
    /* the speed loop: PI on the source's speed, T = J bw e, the integral
     * zero at bw / 2 (settled to e^-6 in PROC_MECH_T_SET: no J dw/dt
     * left in the plateau's torque), within +-i (the integral held) */
    const float kt = 1.5f * mm->pole_pairs * mm->lambda_m;
    const float kp = kt > 0.0f ? m->res[0] * PROC_MECH_BW / kt : 0.0f;
    const float e = mech_plat[m->plat] * w_hi - w;
    m->pl.integ = fd_clampf(m->pl.integ + 0.5f * PROC_MECH_BW * kp * e * c->ts, -i, i);
    iq = fd_clampf(kp * e + m->pl.integ, -i, i);
  }
  const dq_t v = current_ctrl_update(&m->cc, (dq_t){0.0f, iq}, idq, we, in->v_max);
  const sincos_t sc_out = frames_sincos(frames_wrap_pi(in->pos->theta + we * 1.5f * c->ts));
  out->v_ab = frames_park_inv(v, sc_out);
  return PROC_RUNNING;
}

/* result: [0] J [kg m^2], [1] T_c [N m], [2] B [N m s/rad], [3] the fit's
 * rms residual (relative), [4] the speed [rad/s mechanical]; J, T_c, B
 * once done (the fit at the end) */
FD_COLD static void mech_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_mech_t *m = &st->mech;
  tm->phase = m->phase;
  tm->n = m->n_all;
  tm->result[0] = m->res[0];
  tm->result[1] = m->res[1];
  tm->result[2] = m->res[2];
  tm->result[3] = m->res[3];
  tm->result[4] = m->w;
}

FD_COLD static const char *mech_check(const proc_setup_t *su, const char **field) {
  const char *why = proc_id_encoder_check(su, field);
  if (why == NULL && !(proc_id_speed_max(su->cfg) > 0.0f)) {
    *field = "id_speed_max";
    why = "needs a speed bound (id_speed_max, or speed_max > 0)";
  }
  if (why == NULL && !(su->cfg->lambda_m > 0.0f)) {
    *field = "lambda_m";
    why = "needs the PM flux (the torque constant): a PM machine";
  }
  return why;
}

const proc_row_t proc_mech = {
    .name = "mech",
    .id = PROC_MECH,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = mech_check,
    .wanted = NULL,
    .init = mech_init,
    .step = mech_step,
    .abort = NULL,
    .publish = mech_publish,
};
