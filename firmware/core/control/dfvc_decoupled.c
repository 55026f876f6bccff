/*
 * dfvc_decoupled.c - decoupled DFVC of saturated machines with LUT or online
 * MTPA / MTPV references, Varatharajan 2022, Figs. 1, 7, 8.
 */
#include "control/dfvc_decoupled.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

#define DFVC_DECOUPLED_2PI 6.28318530717959f
#define DFVC_DECOUPLED_I_APP_MIN                                                                   \
  0.05f /* below: apparent inductance from the unsaturated one [A]                                 \
         */

FD_COLD void dfvc_decoupled_cfg_defaults(dfvc_decoupled_cfg_t *cfg, const machine_t *machine) {
  memset(cfg, 0, sizeof(*cfg));
  cfg->machine = machine;
  cfg->ts = 2e-4f;                          /* Varatharajan 2022, section VI: 5 kHz */
  cfg->g = DFVC_DECOUPLED_2PI * 5.0f;       /* section VI */
  cfg->omega = DFVC_DECOUPLED_2PI * 100.0f; /* section VI.A: 2 pi 100 and 2 pi 200 */
  cfg->k_a = 60.0f;                         /* section VI */
  cfg->k_v = 0.9f;                          /* section V.A: ~10 % margins */
  cfg->k_t = 0.9f;
  /* open in the paper */
  cfg->v_f_max = 1e4f;
  cfg->rot_advance = 0.5f;
  cfg->b_floor_frac = 0.1f;
  cfg->gains = DFVC_DECOUPLED_GAINS_PROPOSED;
  cfg->refs_mode = DFVC_DECOUPLED_REFS_ONLINE;
  cfg->i_max = 1.0f;
  cfg->lambda_min = 0.1f;
}

/* The step's blocks inlined into it at -Os too (as calls their arguments
 * and results went through the stack: PIL). */
#if defined(__GNUC__)
#define DD_INLINE static inline __attribute__((always_inline))
#else
#define DD_INLINE static inline
#endif

/* The model quantities with the controller's map scaled (dfvc_decoupled.h) at the
 * current-model flux li and inductances l. sota 0 skips the gains of (17);
 * angles 0: no MTPV angle (LUT references), 1: the MTPV angle of (34), 2:
 * also the MTPA angle (below 2 it is not computed: the ISR's telemetry
 * takes its sine from lambda^a and i where it is read,
 * dfvc_decoupled_tm_mtpa_angle; no atan2 and no root in the ISR). */
DD_INLINE void dfvc_decoupled_model_at(const machine_t *m, dq_t s, dq_t lambda, dq_t i, dq_t li,
                                       machine_ldq_t l, int sota, int angles,
                                       dfvc_decoupled_model_t *q) {
  q->lambda_i = li;
  q->l = l;
  const float l2 = lambda.d * lambda.d + lambda.q * lambda.q;
  const dq_t la = sfo_aux_flux(lambda, i, l);    /* (6) */
  const dq_t ia = sfo_aux_current(lambda, i, l); /* (9) */
  q->lambda_a = la;
  q->mtpa_cross = sfo_mtpa_cross(la, i);      /* (7) */
  q->mtpv_cross = sfo_mtpv_cross(lambda, ia); /* (10) */
  q->mtpa_angle = (angles == 2) ? sfo_line_angle(i, la) : 0.0f;
  /* sfo_line_angle(lambda, i^a): its sine term is -mtpv_cross, whose
   * magnitude it takes (the same float, negated exactly) */
  q->mtpv_angle =
      angles ? fd_atan2f(fabsf(q->mtpv_cross), fabsf(lambda.d * ia.d + lambda.q * ia.q)) : 0.0f;
  q->prop.a = sfo_gain_a(lambda, l); /* (22) */
  q->prop.b = (l2 > 1e-12f) ? q->mtpv_cross / l2 : 0.0f;
  q->sota = (sfo_gains_t){0.0f, 0.0f};
  if (sota) {
    float lad;
    float laq;
    sfo_apparent(li, i, machine_pm_flux(m) * s.d, DFVC_DECOUPLED_I_APP_MIN, m->ld * s.d,
                 m->lq * s.q, &lad, &laq);
    const float lam = sqrtf(l2);
    const sincos_t scd =
        (lam > 1e-6f) ? (sincos_t){lambda.q / lam, lambda.d / lam} : (sincos_t){0.0f, 1.0f};
    q->sota = sfo_gains_sota(lam, scd, lad, laq, machine_pm_flux(m) * s.d); /* (17) */
  }
}

FD_COLD float dfvc_decoupled_tm_mtpa_angle(const dfvc_decoupled_tm_t *tm) {
  const dq_t la = tm->mtpa_la;
  const dq_t i = tm->mtpa_i;
  const float n = sqrtf((la.d * la.d + la.q * la.q) * (i.d * i.d + i.q * i.q));
  return (n > 1e-12f) ? fabsf(sfo_mtpa_cross(la, i)) / n : 0.0f;
}

/* The controller's map at i: flux and L_d (25), rows scaled by s
 * (machine_flux_inductance: one cell and its neighbours, where a flux
 * lookup and flux_map_inductance cost five lookups, 410 instructions of a
 * 2818-instruction ISR in the PIL) */
static void dfvc_decoupled_map(const machine_t *m, dq_t s, dq_t i, dq_t *li, machine_ldq_t *l) {
  machine_ldq_t k;
  const dq_t f = machine_flux_inductance(m, i, &k);
  /* mut: cm_scale_ignored */
  *li = (dq_t){s.d * f.d, s.q * f.q};
  *l = (machine_ldq_t){s.d * k.dd, s.d * k.dq, s.q * k.qd, s.q * k.qq};
}

/* init, tests and tools (the step inlines its own dfvc_decoupled_model_at) */
FD_COLD void dfvc_decoupled_model(const machine_t *m, dq_t cm_scale, dq_t lambda, dq_t i,
                                  dfvc_decoupled_model_t *q) {
  dq_t li;
  machine_ldq_t l;
  dfvc_decoupled_map(m, cm_scale, i, &li, &l);
  dfvc_decoupled_model_at(m, cm_scale, lambda, i, li, l, 1, 2, q);
}

FD_COLD float dfvc_decoupled_flux_cap(const machine_t *m, float i_max) {
  /* the largest flux amplitude on the current-limit circle (bounded loop) */
  float cap2 = 0.0f;
  for (int n = 0; n < 32; ++n) {
    const sincos_t sc = frames_sincos(0.19634954f * (float)n); /* 2 pi / 32 */
    const dq_t f = machine_flux(m, (dq_t){i_max * sc.c, i_max * sc.s});
    cap2 = fd_maxf(cap2, f.d * f.d + f.q * f.q);
  }
  return sqrtf(cap2);
}

FD_COLD int dfvc_decoupled_init(dfvc_decoupled_t *c, const dfvc_decoupled_cfg_t *cfg) {
  memset(c, 0, sizeof(*c));
  c->cfg = *cfg;
  const dfvc_decoupled_cfg_t *k = cfg;
  if (!(k->machine != NULL && fd_isfinite(k->rot_advance) && k->rot_advance >= 0.0f &&
        k->rot_advance <= 1.0f && fd_isfinite(k->b_floor_frac) && k->b_floor_frac > 0.0f &&
        k->b_floor_frac < 1.0f && (unsigned)k->gains < (unsigned)DFVC_DECOUPLED_GAINS_COUNT)) {
    return -1;
  }
  const flux_observer_cfg_t oc = {k->machine, k->ts, k->g, 1000.0f};
  /* the magnetising axis (the larger unsaturated inductance, or the PM's) */
  const machine_t *m = k->machine;
  const dq_t mag =
      (m->lq > m->ld && !(m->lambda_m > 0.0f)) ? (dq_t){0.0f, 1.0f} : (dq_t){1.0f, 0.0f};
  const dq_t f0 = machine_flux(m, (dq_t){0.0f, 0.0f});
  const dfvc_decoupled_refs_cfg_t rc = {.machine = m,
                                        .mode = k->refs_mode,
                                        .ts = k->ts,
                                        .i_max = k->i_max,
                                        .lambda_min = k->lambda_min,
                                        .k_v = k->k_v,
                                        .k_t = k->k_t,
                                        .k_a = k->k_a,
                                        .lambda_0 = sqrtf(f0.d * f0.d + f0.q * f0.q),
                                        .lambda_cap = dfvc_decoupled_flux_cap(m, k->i_max)};
  const dfvc_decoupled_pi_cfg_t pc = {k->ts, k->omega, k->v_f_max};
  if (flux_observer_init(&c->obs, &oc) != 0 || dfvc_decoupled_refs_init(&c->refs, &rc) != 0 ||
      dfvc_decoupled_pi_init(&c->pi, &pc) != 0) {
    return -1;
  }
  /* the design point of the constant-gain law and of the floor of b_hat:
   * MTPA at half the current limit */
  const dq_t i0 = machine_mtpa_current(m, machine_mtpa_torque(m, 0.5f * k->i_max));
  dfvc_decoupled_model_t q;
  dfvc_decoupled_model(m, (dq_t){1.0f, 1.0f}, machine_flux(m, i0), i0, &q);
  c->b0 = q.prop.b;
  if (!(fd_isfinite(c->b0) && c->b0 > 0.0f)) {
    return -1;
  }
  c->b_floor = k->b_floor_frac * c->b0;
  c->seed = 0.01f * k->lambda_min;
  c->seed_dq = (dq_t){c->seed * mag.d, c->seed * mag.q};
  return 0;
}

void dfvc_decoupled_reset(dfvc_decoupled_t *c) {
  flux_observer_reset(&c->obs);
  dfvc_decoupled_refs_reset(&c->refs);
  dfvc_decoupled_pi_reset(&c->pi);
}

/* e^{jx} for the small rotation over part of a period (|x| <= omega Ts,
 * 0.06 rad at 2625 rpm and 5 kHz): Taylor to x^4, error below x^5/120
 * (7e-9 there) */
static inline sincos_t dfvc_decoupled_small_rot(float x) {
  const float x2 = x * x;
  return (sincos_t){x * (1.0f - x2 * (1.0f / 6.0f)), 1.0f - x2 * (0.5f - x2 * (1.0f / 24.0f))};
}

/* The flux-axis current of the reference: the current model's current at
 * the flux lambda_ref along the current model's flux lambda^i (at the
 * measured current i, from the controller's map), linearised with the
 * incremental inductance (25): u . (i + L_d^-1 (lambda_ref - |lambda^i|) u),
 * u = lambda^i / |lambda^i|: u . i + (lambda_ref - |lambda^i|) u^T adj(L_d)
 * u / det L_d. For a linear machine it is exact and does not depend on i;
 * on a map i enters through the map's curvature only. Along the current
 * model's flux, not the observer's: through the observer's flux the
 * compensation closed a loop of its own (a flux error moved the
 * compensation, whose voltage error moved the observer): on the star-point
 * position the decoupled DFVC's observed flux sat 11 % high and its torque
 * 15 % low (python/pytest, test_fabbri2022 test_the_other_laws_run_on_the_star_point). */
static float dfvc_decoupled_ref_if(dq_t i, dq_t li, machine_ldq_t l, float lambda_ref) {
  const float n2 = li.d * li.d + li.q * li.q;
  const float det = l.dd * l.qq - l.dq * l.qd;
  if (!(n2 > 0.0f && det > 0.0f)) {
    return 0.0f;
  }
  const float amp = sqrtf(n2);
  const float quad = li.d * (l.qq * li.d - l.dq * li.q) + li.q * (l.dd * li.q - l.qd * li.d);
  /* mut: dfvc_ref_if_no_current_model */
  return (li.d * i.d + li.q * i.q) / amp + (lambda_ref - amp) * quad / (n2 * det);
}

static inline float dfvc_decoupled_zf(ab_t x) {
  return fd_zero_if_finite(x.alpha) + fd_zero_if_finite(x.beta);
}

void dfvc_decoupled_step(dfvc_decoupled_t *c, const dfvc_decoupled_in_t *in,
                         dfvc_decoupled_out_t *out) {
  const dfvc_decoupled_cfg_t *k = &c->cfg;
  const machine_t *m = k->machine;
  const float zin = dfvc_decoupled_zf(in->i_ab) + dfvc_decoupled_zf(in->v_ab_applied) +
                    fd_zero_if_finite(in->theta_r) + fd_zero_if_finite(in->omega_r) +
                    fd_zero_if_finite(in->v_lin) + fd_zero_if_finite(in->torque_ref) +
                    fd_zero_if_finite(in->lambda_ref) + fd_zero_if_finite(in->cm_scale.d) +
                    fd_zero_if_finite(in->cm_scale.q);
  if (!fd_isfinite(zin) || !(in->cm_scale.d > 0.0f) || !(in->cm_scale.q > 0.0f)) {
    memset(out, 0, sizeof(*out));
    out->fault = DFVC_DECOUPLED_FAULT_INPUT;
    return;
  }
  const sincos_t scr = frames_sincos(in->theta_r);
  const dq_t i = frames_park(in->i_ab, scr);

  /* the current model lambda^i = Lambda(i) and L_d (25) of the controller's map */
  dq_t li;
  machine_ldq_t l;
  dfvc_decoupled_map(m, in->cm_scale, i, &li, &l);

  /* hybrid observer, Varatharajan 2022, eq. (24) (the paper's resistive
   * drop at tau: i_next = i) */
  ab_t lcm = frames_park_inv(li, scr);
  if (!c->obs.started && li.d * li.d + li.q * li.q < c->seed * c->seed) {
    /* start-up of an unmagnetised machine (no PM flux): the observer starts
     * from a small flux along the magnetising axis (the larger unsaturated
     * inductance), so that the flux is built there and not on the other
     * axis, where b < 0 (beyond MTPV: the reluctance torque is unstable) */
    const ab_t sd = frames_park_inv(c->seed_dq, scr);
    lcm.alpha += sd.alpha;
    lcm.beta += sd.beta;
  }
  flux_observer_out_t o;
  flux_observer_update_cm(&c->obs, in->i_ab, in->i_ab, in->v_ab_applied, lcm, &o);
  const dq_t lam = frames_park(o.lambda, scr);

  /* (6), (7), (9), (10), (17), (22) with the observed flux */
  dfvc_decoupled_model_t q;
  dfvc_decoupled_model_at(m, in->cm_scale, lam, i, li, l, k->gains == DFVC_DECOUPLED_GAINS_SOTA,
                          k->refs_mode == DFVC_DECOUPLED_REFS_ONLINE, &q);
  sfo_gains_t g;
  switch (k->gains) {
  case DFVC_DECOUPLED_GAINS_SOTA:
    g = q.sota;
    break;
  case DFVC_DECOUPLED_GAINS_CONSTANT:
    g = (sfo_gains_t){0.0f, c->b0};
    break;
  default:
    /* mut: dfvc_decoupled_no_decoupling_a */
    g = q.prop;
    break;
  }
  if (!(g.b >= c->b_floor)) {
    g.b = c->b_floor; /* the MTPV singularity b = 0 (also a NaN b) */
  }

  /* references, (29)-(34) */
  const dfvc_decoupled_refs_in_t ri = {.torque_ref = in->torque_ref,
                                       .lambda_override = in->lambda_ref,
                                       .omega_r = in->omega_r,
                                       .v_lin = in->v_lin,
                                       .i_f = o.i_dqs.d,
                                       .i_tau = o.i_dqs.q,
                                       .i_amp = sqrtf(i.d * i.d + i.q * i.q),
                                       .lambda_hat = o.lambda_s,
                                       .torque_est = o.torque,
                                       .mtpa_cross = q.mtpa_cross,
                                       .mtpv_cross = q.mtpv_cross,
                                       .mtpv_angle = q.mtpv_angle,
                                       .adapt = 1};
  /* into the output (no copy; the fault paths below clear it) */
  dfvc_decoupled_refs_update(&c->refs, &ri, &out->r);
  const dfvc_decoupled_refs_out_t *r = &out->r;

  /* regulators (26)-(28) */
  const dfvc_decoupled_pi_in_t pin = {
      r->lambda_ref, r->itau_ref, o.lambda_s_next, o.i_dqs, in->omega_r, m->rs, g, in->v_lin};
  dfvc_decoupled_pi_out_t po;
  dfvc_decoupled_pi_step(&c->pi, &pin, &po);

  /* (f, tau) -> (alpha, beta) at the predicted flux angle, advanced into
   * the interval the voltage acts (dfvc.h, rot_advance) */
  const sincos_t scv = frames_sincos_add(
      o.sc_s_next, dfvc_decoupled_small_rot(k->rot_advance * in->omega_r * k->ts));
  const ab_t v_ab = frames_park_inv(po.v_ft, scv);

  const float z = dfvc_decoupled_zf(v_ab) + fd_zero_if_finite(r->lambda_ref) +
                  fd_zero_if_finite(r->itau_ref) + dfvc_decoupled_zf(o.lambda_next);
  if (!fd_isfinite(z)) {
    dfvc_decoupled_reset(c);
    memset(out, 0, sizeof(*out));
    out->fault = DFVC_DECOUPLED_FAULT_STATE;
    return;
  }
  out->v_ab_ref = v_ab;
  /* the dead-time compensation's current: the references' (the flux
   * reference's current and i_tau_ref), as FOC's is its reference current;
   * not the measured one, whose sign near zero current would feed back
   * through the compensation (docs/faults.md, issue 23 point 17) */
  out->i_ab_mid =
      /* mut: dfvc_dt_current_measured */
      /* mut: dfvc_dt_current_measured_flux_axis */
      frames_park_inv((dq_t){dfvc_decoupled_ref_if(i, li, l, r->lambda_ref), r->itau_ref}, scv);
  out->i_dq = i;
  out->lambda_s = o.lambda_s;
  out->lambda_dq = lam; /* the load angle's, telemetry */
  out->i_ft = o.i_dqs;
  out->torque = o.torque;
  {
    const float ea = o.lambda.alpha - o.lambda_cm.alpha;
    const float eb = o.lambda.beta - o.lambda_cm.beta;
    out->obs_err = sqrtf(ea * ea + eb * eb);
  }
  out->v_ft = po.v_ft;
  out->sat = po.sat;
  out->fault = 0u;
  c->tm =
      (dfvc_decoupled_tm_t){r->lambda_mtpa, r->torque_mtpv, g.a, g.b, q.lambda_a, i, q.mtpv_angle};
}
