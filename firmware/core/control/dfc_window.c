/*
 * dfc_window.c - the DFC measurement window in the PWM pattern (see
 * dfc_window.h).
 */
#include "dfc_window.h"

void dfc_window_range(float t0, float tw, float d_min, float d_max, float *lo, float *hi) {
  *lo = d_min > tw ? d_min : tw;
  const float top = 1.0f - t0 - tw;
  *hi = d_max < top ? d_max : top;
}

void dfc_window_pattern(const float d[3], unsigned leg, float t0, float tw, float on[3],
                        float off[3]) {
  for (unsigned x = 0u; x < 3u; ++x) {
    float o;
    if (x == leg) {
      o = t0; /* the test vector: leg X alone from t0 */
    } else {
      o = 0.5f * (1.0f - d[x]);
      o = o > t0 + tw ? o : t0 + tw; /* not before the window closes */
    }
    on[x] = o;
    off[x] = o + d[x];
  }
}
