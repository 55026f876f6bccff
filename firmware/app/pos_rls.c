/*
 * pos_rls.c - the identification column of the star-point sources
 * (pos_star.h): a, b of the star-point model identified online by the RLS
 * of (4.51)-(4.57) (estimation/rls_ab.h), the loop of Fig. 4.4 (Fabbri
 * 2022): the IVD uses the identified a, b (held in the IVD's convergence
 * region |b/a| <= 0.45 and within a factor 4 of dfc_a) and, once aligned,
 * starts its iterations from the tracker's prediction (from the raw
 * estimate their residual error biased b: issue 23 point 5); the RLS
 * regressor is the filter's predicted angle (a priori: free of this
 * period's signal noise, which the IVD angle carries - no errors-in-variables
 * bias); it identifies only above rls_w_min, where the 2theta and 4theta
 * columns are separable, and never with the EKF: the EKF's angle is itself
 * a function of a and b, the thesis's non-observable combination (5.1.3),
 * so no row combines them (pos_sources.c).
 */
#include <stddef.h>

#include "math/fd_math.h"
#include "pos_star.h"

static rls_ab_cfg_t rls_cfg_of(const drive_config_t *cfg) {
  const rls_ab_cfg_t r = {cfg->rls_lambda, cfg->dfc_sigma * cfg->dfc_sigma, cfg->rls_p_min,
                          cfg->rls_p_max};
  return r;
}

#define POS_DFC_P_MAX 0.45f /* |b/a| the IVD is given at most (Theorem 1: < 1/2) */
/* The IVD's a, b: the RLS's within the guards (header). */
static void rls_guarded(const rls_ab_t *r, const drive_config_t *cfg, dfc_cfg_t *dc) {
  const float a0 = fabsf(cfg->dfc_a);
  const float am = fd_clampf(fabsf(r->x[0]), 0.25f * a0, 4.0f * a0);
  dc->a = cfg->dfc_a < 0.0f ? -am : am;
  dc->b = fd_clampf(r->x[1], -POS_DFC_P_MAX * am, POS_DFC_P_MAX * am);
}

FD_COLD static void rls_init(pos_state_t *s, const drive_config_t *cfg) {
  const rls_ab_cfg_t rc = rls_cfg_of(cfg);
  (void)rls_ab_init(&s->star.id.rls, &rc);
  rls_ab_reset(&s->star.id.rls, cfg->dfc_a, cfg->dfc_b, cfg->rls_p_max);
  s->star.id.avg[0] = 0.0f; /* not settled before its updates (rls_health) */
  s->star.id.avg[1] = 0.0f;
  s->star.id.warm2 = 1.0f;
  s->star.id.health_due = false;
  s->star.id.upd_due = false;
  rls_guarded(&s->star.id.rls, cfg, &s->star.meas.dc); /* the RLS's start, guarded */
}

/* (2|p|)^2n: the warm-started IVD's n iterations contract the
 * prediction's error of 2theta by (2|p|)^n (Theorem 1, (3.81)); its
 * square scales the prediction's variance into the measurement's
 * (pos_track.c, meas_r). Taken when the RLS moves a, b (every third period
 * at most) and at the end of the alignment. */
static void warm_gain(pos_state_t *s) {
  const dfc_cfg_t *dc = &s->star.meas.dc;
  const float p = fd_minf(fabsf(dc->b) / fd_maxf(fabsf(dc->a), 1e-12f), 0.5f);
  float c = 1.0f;
  for (unsigned k = 0u; k < dc->iterations && k < DFC_ITER_MAX; ++k) {
    c *= 2.0f * p;
  }
  s->star.id.warm2 = c * c;
}

/* Whether this period refreshes the RLS: one update per refresh of the
 * whole vector (when component a is the newest: every third period, 5.3
 * kHz, the thesis's DFC rate), so that successive updates share no sample,
 * as the RLS's independent noise assumes; aligned and above rls_w_min. */
static bool rls_refresh(const pos_state_t *s, const drive_config_t *cfg) {
  bool due = false;
  if (s->star.meas.miss == 0u && s->star.meas.sig.last == 0u && s->star.pol.aligned &&
      /* mut: rls_never_updates */
      fabsf(pos_track_omega(s)) > cfg->rls_w_min) {
    due = true;
  }
  return due;
}

/* The RLS of a, b (4.51)-(4.57) on a refresh's vector (al, be; km its
 * map of the 4theta term) at the filter's predicted angle (c, s: e^{j 2
 * theta}); the IVD's a, b from it in a later period (rls_step). */
static void rls_update(pos_state_t *s, const drive_config_t *cfg, float al, float be, float c,
                       float sn, const float *km) {
  pos_ident_state_t *id = &s->star.id;
  id->upd_due = false;
  id->rls.cfg = rls_cfg_of(cfg); /* the live tuning, for this update and rls_health */
  id->health_due = rls_ab_update(&id->rls, al, be, c, sn, km);
}

static void rls_update_held(pos_state_t *s, const drive_config_t *cfg) {
  const pos_ident_state_t *id = &s->star.id;
  rls_update(s, cfg, id->held.al, id->held.be, id->held.c, id->held.s, id->held.k);
}

/* The RLS's health (rls_ok), after each update: its a and b have settled
 * within the band, each of them
 *   steady: the distance it still has to go within POS_DFC_RLS_BAND:
 *     its distance from its own low-pass over the updates (1 /
 *     POS_DFC_RLS_AVG updates; from 0 at the start: no update, no
 *     information, not settled) is the rate it moves at times that lag,
 *     and an RLS at its covariance P converges with a time constant of
 *     about 1 + R / P updates (gain P / (P + R)): the distance left is the
 *     rate times that time constant when it is the longer,
 *   known: twice the standard deviation its covariance states, sqrt(2 P)
 *     (the floor-limited RLS's estimate has a variance of about P / 2),
 *     within the band (a small b against the floor: p too small),
 * and neither held at the IVD's guards (rls_guarded). A bias the model
 * itself carries is not seen (docs/dfc.md). */
#define POS_DFC_RLS_BAND 0.05f       /* issue 23 point 5: the 5 % band */
#define POS_DFC_RLS_AVG  0.00390625f /* 1/256 per update: 48 ms at 5.3 kHz */
static bool rls_health(pos_state_t *s, const drive_config_t *cfg) {
  const rls_ab_t *r = &s->star.id.rls;
  bool ok = true;
  for (unsigned j = 0u; j < 2u; ++j) {
    s->star.id.avg[j] += POS_DFC_RLS_AVG * (r->x[j] - s->star.id.avg[j]);
    const float tol = POS_DFC_RLS_BAND * fabsf(r->x[j]);
    const float pjj = r->p[(size_t)2u * j];
    const float t_rls = 1.0f + r->cfg.r / pjj; /* updates; P >= p_min > 0 */
    const float go = fabsf(r->x[j] - s->star.id.avg[j]) * fd_maxf(1.0f, POS_DFC_RLS_AVG * t_rls);
    /* mut: rls_ok_no_covariance */
    ok = ok && go <= tol && 2.0f * pjj <= tol * tol;
  }
  const float a0 = fabsf(cfg->dfc_a), am = fabsf(r->x[0]);
  return ok && am > 0.25f * a0 && am < 4.0f * a0 && fabsf(r->x[1]) < POS_DFC_P_MAX * am;
}

/* The last update's a, b into the IVD (within the guards; they move only
 * here, pos_star_update keeps them), the warm gain and the health
 * (rls_ok), on that update's a, b and covariance. */
static void rls_settle(pos_state_t *s, const drive_config_t *cfg, pos_estimate_t *out) {
  s->star.id.health_due = false;
  rls_guarded(&s->star.id.rls, cfg, &s->star.meas.dc);
  warm_gain(s);
  out->rls_ok = rls_health(s, cfg);
}

/* One period. A refresh's work comes in two halves of about 150
 * instructions each, the update (rls_update) and its settling
 * (rls_settle), each in a period of its own, in order, and not in a
 * period that carries the drive's heavier slow-rate work (busy: the slow
 * period's first three ISRs, the current-sum check and the main loop's
 * commands, the speed loop, the law's work on the loop's new torque;
 * drive.c, drive_schedule): one half per free period, the older first
 * (issue 24 point 8: the ISR's worst case was where an RLS half met the
 * speed loop and the law's MTPA current). Unbusy, a refresh is updated in
 * its own period and settled in the next, the IVD taking the new a, b a
 * period (62.5 us) after the update; after the busy periods the halves
 * catch up within a few periods (two per three periods, one a period).
 * The regressor of a refresh that cannot be updated at once is held
 * (pos_ident_state_t.held); should the next refresh come before its update
 * ran (slow_div < 9: fewer free periods than halves), that update, and the settling
 * before it, run first, busy or not: every update runs, on its own
 * regressor, in order, at most two halves a period. */
static void rls_step(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v,
                     const sincos_t *u, bool busy, pos_estimate_t *out) {
  pos_ident_state_t *id = &s->star.id;
  bool refresh = rls_refresh(s, cfg);
  if (!busy) { /* one half, the older first */
    if (id->health_due) {
      rls_settle(s, cfg, out);
    } else if (id->upd_due) {
      rls_update_held(s, cfg);
    } else if (refresh) {
      rls_update(s, cfg, v->al, v->be, u->c, u->s, v->k);
      refresh = false;
    }
  }
  if (refresh) {
    if (id->upd_due) { /* the held regressor has found no free period */
      if (id->health_due) {
        rls_settle(s, cfg, out);
      }
      rls_update_held(s, cfg);
    }
    id->held.al = v->al; /* this one's, until its update */
    id->held.be = v->be;
    id->held.c = u->c;
    id->held.s = u->s;
    for (unsigned j = 0u; j < 4u; ++j) {
      id->held.k[j] = v->k[j];
    }
    id->upd_due = true;
  }
}

/* the warm start's gain at the a, b in force (pos_star_align: once per start) */
FD_COLD static void rls_aligned(pos_state_t *s) {
  warm_gain(s);
}

FD_COLD static const char *rls_check(const drive_config_t *cfg, const char **field) {
  if (!(cfg->rls_p_min <= cfg->rls_p_max)) {
    *field = "rls_p_min";
    return "the RLS covariance limits need rls_p_min <= rls_p_max";
  }
  return NULL;
}

const pos_ident_t pos_ident_rls = {rls_init, rls_step, rls_aligned, rls_check};
