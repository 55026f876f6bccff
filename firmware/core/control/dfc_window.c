/*
 * dfc_window.c - the DFC measurement window in the PWM pattern (see
 * dfc_window.h).
 */
#include "dfc_window.h"

void dfc_window_range(float t0, float tw, float d_min, float d_max, float *lo, float *hi) {
  /* every pulse rises in the first half and falls in the second: leg X
   * (each leg in turn) needs t0 + d >= 1/2, the others t0 + tw + d <= 1 */
  const float bottom = 0.5f - t0;
  *lo = d_min > bottom ? d_min : bottom;
  const float top = 1.0f - t0 - tw;
  *hi = d_max < top ? d_max : top;
}

void dfc_window_pattern(const float d[3], unsigned leg, float t0, float tw, float on[3],
                        float off[3]) {
  for (unsigned x = 0u; x < 3u; ++x) {
    /* v0 -> v_X from t0, then v7 from t0 + tw: the rising edges fixed by
     * the window, the falling ones by the duties */
    const float o = x == leg ? t0 : t0 + tw;
    on[x] = o;
    off[x] = o + d[x];
  }
}

void dfc_window_moments(const float on[3], const float off[3], float m[3]) {
  float mean = 0.0f;
  for (unsigned x = 0u; x < 3u; ++x) {
    const float d = off[x] - on[x];
    m[x] = 0.5f * d * (1.0f - on[x] - off[x]);
    mean += m[x];
  }
  mean *= 1.0f / 3.0f;
  for (unsigned x = 0u; x < 3u; ++x) {
    m[x] -= mean;
  }
}
