/*
 * ident_mech.c - the mechanical equation's least squares (ident_mech.h).
 */
#include "estimation/ident_mech.h"

#include <math.h>

#include "math/fd_math.h"

FD_COLD void ident_mech_reset(float ls[IDENT_MECH_LS]) {
  for (unsigned k = 0; k < IDENT_MECH_LS; ++k) {
    ls[k] = 0.0f;
  }
}

FD_COLD void ident_mech_add(float ls[IDENT_MECH_LS], const float a[3], float y) {
  ls[0] += a[0] * a[0];
  ls[1] += a[0] * a[1];
  ls[2] += a[0] * a[2];
  ls[3] += a[1] * a[1];
  ls[4] += a[1] * a[2];
  ls[5] += a[2] * a[2];
  ls[6] += a[0] * y;
  ls[7] += a[1] * y;
  ls[8] += a[2] * y;
  ls[9] += y * y;
}

/* det of the 3x3 [c0 c1 c2] (columns) */
FD_COLD static float det3(const float c0[3], const float c1[3], const float c2[3]) {
  return c0[0] * (c1[1] * c2[2] - c2[1] * c1[2]) - c1[0] * (c0[1] * c2[2] - c2[1] * c0[2]) +
         c2[0] * (c0[1] * c1[2] - c1[1] * c0[2]);
}

FD_COLD int ident_mech_solve(const float ls[IDENT_MECH_LS], unsigned rows, float x[3], float *rms) {
  const float c0[3] = {ls[0], ls[1], ls[2]};
  const float c1[3] = {ls[1], ls[3], ls[4]};
  const float c2[3] = {ls[2], ls[4], ls[5]};
  const float b[3] = {ls[6], ls[7], ls[8]};
  const float d = det3(c0, c1, c2);
  /* singular: relative to the diagonal's product (Cramer's rule, a 3x3
   * well scaled by the caller) */
  const float scale = ls[0] * ls[3] * ls[5];
  if (rows < 3u || !(scale > 0.0f) || !(fabsf(d) > 1e-6f * scale)) {
    x[0] = x[1] = x[2] = 0.0f;
    *rms = 1.0f;
    return -1;
  }
  x[0] = det3(b, c1, c2) / d;
  x[1] = det3(c0, b, c2) / d;
  x[2] = det3(c0, c1, b) / d;
  /* |y - A x|^2 = y'y - 2 x'A'y + x'A'A x */
  const float xay = x[0] * b[0] + x[1] * b[1] + x[2] * b[2];
  const float xaax = x[0] * (c0[0] * x[0] + c1[0] * x[1] + c2[0] * x[2]) +
                     x[1] * (c0[1] * x[0] + c1[1] * x[1] + c2[1] * x[2]) +
                     x[2] * (c0[2] * x[0] + c1[2] * x[1] + c2[2] * x[2]);
  const float e2 = fmaxf(ls[9] - 2.0f * xay + xaax, 0.0f);
  *rms = ls[9] > 0.0f ? sqrtf(e2 / ls[9]) : 1.0f;
  return 0;
}
