/*
 * modulation.c - min-max zero-sequence injection (equivalent to centred
 * SVPWM) normalised by the measured DC-link voltage, inside the duty range
 * [d_min, d_max] the board publishes (hal_caps_t).
 *
 * v0 = -(max + min)/2, duty_x = (d_min + d_max)/2 + (v_x + v0) / v_dc. The
 * linear range is the circle inscribed in the hexagon the duty range
 * allows, |v| <= (d_max - d_min) v_dc/sqrt(3); beyond it the request is
 * scaled onto that circle keeping its angle. The applied vector is
 * reconstructed from the duties (Clarke of duty*v_dc; the common mode drops
 * out), so rounding and clamping are reported honestly.
 */
#include "control/modulation.h"

#include <math.h>

#include "math/fd_math.h"

#define MOD_INV_SQRT3 0.577350269189626f

/* modulation_v_max(), inline in the ISR's modulation (no call) */
static inline float mod_v_max(float v_dc, float d_min, float d_max) {
  const float span = d_max - d_min;
  return (v_dc > 0.0f && fd_isfinite(v_dc) && span > 0.0f) ? span * v_dc * MOD_INV_SQRT3 : 0.0f;
}

float modulation_v_max(float v_dc, float d_min, float d_max) {
  return mod_v_max(v_dc, d_min, d_max);
}

static float mod_clamp(float x, float lo, float hi) {
  return (x > hi) ? hi : ((x < lo) ? lo : x);
}

static float mod_max3(float a, float b, float c) {
  const float m = (a > b) ? a : b;
  return (m > c) ? m : c;
}

static float mod_min3(float a, float b, float c) {
  const float m = (a < b) ? a : b;
  return (m < c) ? m : c;
}

int modulation_minmax_duty(ab_t v_ref, float v_dc, float d_min, float d_max, float duty[3]) {
  const float mid = 0.5f * (d_min + d_max);
  duty[0] = duty[1] = duty[2] = mid; /* the safe output until the duties below */
  const float v_max = mod_v_max(v_dc, d_min, d_max);
  if (!(v_max > 0.0f) || !fd_isfinite(v_ref.alpha) || !fd_isfinite(v_ref.beta)) {
    return MODULATION_SAFE; /* zero average voltage, flagged */
  }
  const float mag = sqrtf(v_ref.alpha * v_ref.alpha + v_ref.beta * v_ref.beta);
  if (!fd_isfinite(mag)) {
    return MODULATION_SAFE; /* finite but huge components overflowed */
  }
  int r = MODULATION_LINEAR;
  if (mag > v_max) {
    const float k = v_max / mag;
    v_ref.alpha *= k;
    v_ref.beta *= k;
    r = MODULATION_SCALED;
  }
  const abc_t v = frames_clarke_inv(v_ref);
  const float v_cm = -0.5f * (mod_max3(v.a, v.b, v.c) + mod_min3(v.a, v.b, v.c));
  const float inv_vdc = 1.0f / v_dc;
  duty[0] = mod_clamp(mid + (v.a + v_cm) * inv_vdc, d_min, d_max);
  duty[1] = mod_clamp(mid + (v.b + v_cm) * inv_vdc, d_min, d_max);
  duty[2] = mod_clamp(mid + (v.c + v_cm) * inv_vdc, d_min, d_max);
  return r;
}

modulation_out_t modulation_minmax(ab_t v_ref, float v_dc, float d_min, float d_max) {
  modulation_out_t out;
  const int r = modulation_minmax_duty(v_ref, v_dc, d_min, d_max, out.duty);
  out.saturated = r != MODULATION_LINEAR;
  out.v_applied = (ab_t){0.0f, 0.0f};
  if (r != MODULATION_SAFE) {
    const abc_t v_pole = {out.duty[0] * v_dc, out.duty[1] * v_dc, out.duty[2] * v_dc};
    out.v_applied = frames_clarke(v_pole);
  }
  return out;
}
