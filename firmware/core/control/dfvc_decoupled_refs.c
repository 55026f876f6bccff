/*
 * dfvc_decoupled_refs.c - references of the DFVC of a saturated machine,
 * Varatharajan 2022, eqs. (29)-(34).
 */
#include "control/dfvc_decoupled_refs.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

/* the online MTPA integrates while the observed flux is within this
 * fraction of the last lambda* (dfvc_decoupled_refs.h) */
/* ... and the torque current is above this fraction of i_max: at zero
 * torque (7) is degenerate (both axes satisfy it; on a PM machine held at
 * lambda_min > lambda_m by a d current its sign says "more flux" and the
 * flux ran to its cap) */
#define DFVC_DECOUPLED_REFS_LOADED 0.03f
#ifndef DFVC_DECOUPLED_REFS_SETTLED
#define DFVC_DECOUPLED_REFS_SETTLED 0.05f
#endif
/* time constant of the current amplitude in the resistive drop of (30) [s] */
#define DFVC_DECOUPLED_REFS_IDROP_TAU 0.01f
#define DFVC_DECOUPLED_REFS_W_MIN     1.0f /* floor of |omega_r| in (30) [rad/s] */

static int dfvc_decoupled_refs_frac(float x) {
  return fd_isfinite(x) && x > 0.0f && x <= 1.0f;
}

FD_COLD int dfvc_decoupled_refs_init(dfvc_decoupled_refs_t *r,
                                     const dfvc_decoupled_refs_cfg_t *cfg) {
  memset(r, 0, sizeof(*r));
  const dfvc_decoupled_refs_cfg_t *c = cfg;
  if (!(c->machine != NULL &&
        (c->mode == DFVC_DECOUPLED_REFS_ONLINE ||
         (c->mode == DFVC_DECOUPLED_REFS_LUT && c->machine->map != NULL)) &&
        fd_isfinite(c->ts) && c->ts > 0.0f && fd_isfinite(c->i_max) && c->i_max > 0.0f &&
        fd_isfinite(c->lambda_min) && c->lambda_min > 0.0f && dfvc_decoupled_refs_frac(c->k_v) &&
        dfvc_decoupled_refs_frac(c->k_t) && fd_isfinite(c->k_a) && c->k_a >= 0.0f &&
        fd_isfinite(c->lambda_cap) && c->lambda_cap >= c->lambda_min && fd_isfinite(c->lambda_0) &&
        c->lambda_0 >= 0.0f)) {
    return -1;
  }
  r->cfg = *cfg;
  r->kt = 1.5f * c->machine->pole_pairs;
  dfvc_decoupled_refs_reset(r);
  return 0;
}

void dfvc_decoupled_refs_reset(dfvc_decoupled_refs_t *r) {
  r->lambda_mtpa = fd_maxf(r->cfg.lambda_min, r->cfg.lambda_0);
  r->lambda_ref = r->lambda_mtpa;
  r->i_amp_f = 0.0f;
  r->i_alpha = r->cfg.ts / (r->cfg.ts + DFVC_DECOUPLED_REFS_IDROP_TAU);
}

void dfvc_decoupled_refs_update(dfvc_decoupled_refs_t *r, const dfvc_decoupled_refs_in_t *in,
                                dfvc_decoupled_refs_out_t *out) {
  const dfvc_decoupled_refs_cfg_t *c = &r->cfg;
  const float kt = r->kt;
  unsigned lim = 0u;
  /* Varatharajan 2022, eq. (30), less the resistive drop at the filtered
   * current amplitude (see the header) */
  r->i_amp_f += r->i_alpha * (in->i_amp - r->i_amp_f);
  const float lmax =
      fd_maxf(c->k_v * fd_maxf(in->v_lin, 0.0f) - c->machine->rs * r->i_amp_f, 0.0f) /
      fd_maxf(fabsf(in->omega_r), DFVC_DECOUPLED_REFS_W_MIN);
  float lmtpa;
  if (in->lambda_override > 0.0f) {
    lmtpa = in->lambda_override;
  } else if (c->mode == DFVC_DECOUPLED_REFS_LUT) {
    lmtpa = flux_map_mtpa_flux(c->machine->map, in->torque_ref); /* (29) */
  } else {
    /* eq. (32), held in flux weakening and bounded; the sign: see the header */
    const int settled =
        fabsf(in->lambda_hat - r->lambda_ref) <= DFVC_DECOUPLED_REFS_SETTLED * r->lambda_ref;
    const int loaded = fabsf(in->i_tau) > DFVC_DECOUPLED_REFS_LOADED * c->i_max;
    if (in->adapt && settled && loaded && r->lambda_mtpa < lmax) {
      /* mut: mtpa_adaptation_printed_sign */
      r->lambda_mtpa -= c->ts * c->k_a * in->mtpa_cross;
    }
    r->lambda_mtpa = fd_clampf(r->lambda_mtpa, c->lambda_min,
                               fd_maxf(fd_minf(lmax, c->lambda_cap), c->lambda_min));
    lmtpa = r->lambda_mtpa;
  }
  float lref = lmtpa;
  if (lmax < lref) {
    lref = lmax;
    lim |= DFVC_DECOUPLED_REFS_FLUX_VLIM;
  }
  if (lref < c->lambda_min) {
    lref = c->lambda_min;
    lim |= DFVC_DECOUPLED_REFS_FLUX_MIN;
  }
  /* MTPV limit: (31) from the table, or (34) online */
  float tmax;
  if (c->mode == DFVC_DECOUPLED_REFS_LUT) {
    tmax = c->k_t * flux_map_mtpv_torque(c->machine->map, lref);
  } else {
    /* mut: mtpv_no_margin_term */
    const float margin = kt * in->mtpv_cross * in->mtpv_angle;
    tmax = c->k_t * (fabsf(in->torque_est) + (fd_isfinite(margin) ? fd_maxf(margin, 0.0f) : 0.0f));
  }
  float t = in->torque_ref;
  if (fabsf(t) > tmax) {
    t = copysignf(tmax, t);
    lim |= DFVC_DECOUPLED_REFS_TMAX;
  }
  /* eq. (13) and the current limit */
  const float rad = c->i_max * c->i_max - in->i_f * in->i_f;
  const float itau_max = (rad > 0.0f) ? sqrtf(rad) : 0.0f;
  float itau = t / (kt * lref);
  if (fabsf(itau) > itau_max) {
    itau = copysignf(itau_max, itau);
    lim |= DFVC_DECOUPLED_REFS_IMAX;
  }
  out->lambda_mtpa = lmtpa;
  out->lambda_max = lmax;
  out->lambda_ref = lref;
  r->lambda_ref = lref;
  out->torque_mtpv = tmax;
  out->itau_ref = itau;
  out->torque_max = fd_minf(tmax, kt * lref * itau_max);
  out->limits = lim;
}
