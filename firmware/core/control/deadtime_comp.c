/*
 * deadtime_comp.c - predictive dead-time compensation, Rubino 2020, Fig. 8.
 */
#include "control/deadtime_comp.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

FD_COLD int deadtime_comp_init(deadtime_comp_t *d, const deadtime_comp_cfg_t *cfg) {
  memset(d, 0, sizeof(*d));
  if (!(fd_isfinite(cfg->td) && cfg->td >= 0.0f && fd_isfinite(cfg->ts) && cfg->ts > 0.0f &&
        cfg->td < cfg->ts && fd_isfinite(cfg->i_band) && cfg->i_band >= 0.0f)) {
    return -1;
  }
  d->cfg = *cfg;
  deadtime_comp_reset(d);
  return 0;
}

void deadtime_comp_reset(deadtime_comp_t *d) {
  d->dt_ratio = d->cfg.td / d->cfg.ts;
}

void deadtime_comp_apply(const deadtime_comp_t *d, const float duty_in[3], abc_t i_pred,
                         float duty_out[3]) {
  const float ix[3] = {i_pred.a, i_pred.b, i_pred.c};
  for (int k = 0; k < 3; ++k) {
    /* Rubino 2020, Fig. 8: feed-forward of the dead-time error over [tau+1, tau+2) */
    float y = duty_in[k] + d->dt_ratio * deadtime_comp_sign(d, ix[k]);
    if (!(y >= 0.0f)) { /* also catches NaN */
      y = 0.0f;
    }
    if (y > 1.0f) {
      y = 1.0f;
    }
    duty_out[k] = y;
  }
}
