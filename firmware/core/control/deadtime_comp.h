/*
 * deadtime_comp.h - predictive dead-time compensation (Rubino 2020, Fig. 8,
 * after Bojoi et al. 2012, ref. [16]): each phase duty is corrected by the
 * dead-time voltage error expected over the interval in which the duties
 * are applied, using the phase currents predicted for that interval (not
 * the currents sampled one period earlier):
 *   d_x' = clamp(d_x + (td / Ts) sgn_b(i_x_pred), 0, 1),  x = a, b, c
 * sgn_b is a saturated-linear sign, i / i_band clamped to [-1, 1], so the
 * correction fades through zero current instead of chattering (i_band = 0
 * gives the hard sign). Positive current flows from the inverter into the
 * machine; with it, the dead time loses volts, so the duty is raised.
 * With dfvc.h, i_pred is frames_clarke_inv(out.i_ab_mid), the mean of the
 * currents predicted at tau+1 and tau+2; with dfvc_decoupled.h, the references'
 * current (a compensation on the measured current feeds back through its
 * sign near zero current: docs/faults.md, issue 23 point 17).
 */
#ifndef FD_CONTROL_DEADTIME_COMP_H
#define FD_CONTROL_DEADTIME_COMP_H

#include "math/fd_math.h"
#include "math/frames.h"

#if defined(__GNUC__)
#define DTC_INLINE static inline __attribute__((always_inline))
#else
#define DTC_INLINE static inline
#endif

typedef struct {
  float td;     /* dead time [s] (plus switch delays if identified), >= 0 */
  float ts;     /* PWM period [s], > 0 */
  float i_band; /* current of full correction [A], >= 0; 0 = hard sign */
} deadtime_comp_cfg_t;

typedef struct {
  deadtime_comp_cfg_t cfg;
  float dt_ratio; /* td / Ts */
} deadtime_comp_t;

/* Returns 0, or -1 for invalid parameters (td < Ts required). */
int deadtime_comp_init(deadtime_comp_t *d, const deadtime_comp_cfg_t *cfg);
/* No dynamic state: recomputes td/Ts. */
void deadtime_comp_reset(deadtime_comp_t *d);
/* Saturated-linear sign in [-1, 1]; 0 for a non-finite current. Inline:
 * the ISR calls it once per phase (as calls, 19 instructions each in the
 * PIL). */
DTC_INLINE float deadtime_comp_sign(const deadtime_comp_t *d, float i) {
  if (!fd_isfinite(i)) {
    return 0.0f;
  }
  if (i >= d->cfg.i_band) {
    return (i > 0.0f) ? 1.0f : 0.0f; /* i_band = 0 and i = 0: no correction */
  }
  if (i <= -d->cfg.i_band) {
    return (i < 0.0f) ? -1.0f : 0.0f;
  }
  return i / d->cfg.i_band; /* |i| < i_band implies i_band > 0 */
}
/* duty_in: modulator duties [0, 1]; i_pred: phase currents predicted over the
 * application interval [A]. duty_out may alias duty_in. Rubino 2020, Fig. 8. */
void deadtime_comp_apply(const deadtime_comp_t *d, const float duty_in[3], abc_t i_pred,
                         float duty_out[3]);

#endif
