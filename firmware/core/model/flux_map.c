/*
 * flux_map.c - lookups on a parsed flux map (flux_map.h): flux, incremental
 * inductance, inverse, torque and the MTPA / MTPV tables.
 */
#include "model/flux_map.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

/* The lookups' small helpers inlined at -Os too (a call each cost more
 * than its body: 136 instructions a lookup as calls, PIL). */
#if defined(__GNUC__)
#define FM_INLINE static inline __attribute__((always_inline))
#else
#define FM_INLINE static inline
#endif

FM_INLINE float word_f32(const uint32_t *w, uint32_t i) {
  float f;
  memcpy(&f, &w[i], sizeof f);
  return f;
}

/* The grid cell used for i: its first point (offset k nd + j, clamped so
 * that the cell exists), its column j and row k, and the position (u, v)
 * inside it in steps, not clamped (linear extrapolation outside the grid). */
typedef struct {
  uint32_t o, j, k;
  float u, v;
} cell_t;

FM_INLINE cell_t cell_of(const flux_map_t *m, dq_t i) {
  const float x = (i.d - m->id0) * m->inv_did;
  const float y = (i.q - m->iq0) * m->inv_diq;
  const uint32_t j = (uint32_t)fd_clampf(x, 0.0f, (float)(m->nd - 2u)); /* >= 0: trunc = floor */
  const uint32_t k = (uint32_t)fd_clampf(y, 0.0f, (float)(m->nq - 2u));
  return (cell_t){k * m->nd + j, j, k, x - (float)j, y - (float)k};
}

/* The four corners of one table in a cell: f00 (j, k), f10 (j+1, k),
 * f01 (j, k+1), f11 (j+1, k+1). */
typedef struct {
  float f00, f10, f01, f11;
} corners_t;

FM_INLINE corners_t corners(const flux_map_t *m, const uint32_t *t, uint32_t o) {
  return (corners_t){word_f32(t, o), word_f32(t, o + 1u), word_f32(t, o + m->nd),
                     word_f32(t, o + m->nd + 1u)};
}

FM_INLINE float bilinear(const corners_t *c, float u, float v) {
  const float a = c->f00 + u * (c->f10 - c->f00);
  const float b = c->f01 + u * (c->f11 - c->f01);
  return a + v * (b - a);
}

dq_t flux_map_flux(const flux_map_t *m, dq_t i) {
  const cell_t c = cell_of(m, i);
  const corners_t d = corners(m, m->psi_d, c.o);
  const corners_t q = corners(m, m->psi_q, c.o);
  return (dq_t){bilinear(&d, c.u, c.v), bilinear(&q, c.u, c.v)};
}

flux_map_ldq_t flux_map_inductance(const flux_map_t *m, dq_t i) {
  /* mut: flux_map_inductance_step */
  const float hd = 0.5f * m->did, hq = 0.5f * m->diq;
  const dq_t dp = flux_map_flux(m, (dq_t){i.d + hd, i.q});
  const dq_t dm = flux_map_flux(m, (dq_t){i.d - hd, i.q});
  const dq_t qp = flux_map_flux(m, (dq_t){i.d, i.q + hq});
  const dq_t qm = flux_map_flux(m, (dq_t){i.d, i.q - hq});
  return (flux_map_ldq_t){(dp.d - dm.d) * m->inv_did, (qp.d - qm.d) * m->inv_diq,
                          (dp.q - dm.q) * m->inv_did, (qp.q - qm.q) * m->inv_diq};
}

/* The centred (25) over one step (flux_map.h) needs, per axis, the slope
 * of the cell next to c that the window [x - 1/2, x + 1/2] (steps) reaches
 * into: the one after (fraction >= 1/2) or before it; at the grid's edge
 * the cell's plane continues (the neighbour is the cell itself). Which
 * neighbour, and the window's share in it, are the same for both tables. */
typedef struct {
  int nd_dir, nq_dir; /* +1 the next cell, -1 the previous one, 0 none */
  float w, z;         /* the window's share in it along d, along q */
} window_t;

FM_INLINE window_t window_of(const flux_map_t *m, const cell_t *c) {
  window_t s;
  s.w = c->u - 0.5f;
  if (s.w >= 0.0f) {
    s.nd_dir = (c->j + 1u <= m->nd - 2u) ? 1 : 0;
  } else {
    s.nd_dir = (c->j >= 1u) ? -1 : 0;
    s.w = -s.w;
  }
  s.z = c->v - 0.5f;
  if (s.z >= 0.0f) {
    s.nq_dir = (c->k + 1u <= m->nq - 2u) ? 1 : 0;
  } else {
    s.nq_dir = (c->k >= 1u) ? -1 : 0;
    s.z = -s.z;
  }
  return s;
}

/* The centred (25) of table t at cell c with the cell's corners f and the
 * window s: the slope along d, (1 - v) of the lower row plus v of the
 * upper, blended with the neighbour's by the share w, and alike along q.
 * The neighbour shares two corners with the cell (f): two table words
 * each (a cell and its neighbours are 8 words of a table, not 12). */
FM_INLINE void centred(const flux_map_t *m, const uint32_t *t, const cell_t *c, const corners_t *f,
                       const window_t *s, float *l_d, float *l_q) {
  const uint32_t o = c->o, nd = m->nd;
  const float sd = (1.0f - c->v) * (f->f10 - f->f00) + c->v * (f->f11 - f->f01);
  const float sq = (1.0f - c->u) * (f->f01 - f->f00) + c->u * (f->f11 - f->f10);
  float nd_s = sd; /* the neighbour's slope along d */
  if (s->nd_dir > 0) {
    nd_s =
        (1.0f - c->v) * (word_f32(t, o + 2u) - f->f10) + c->v * (word_f32(t, o + nd + 2u) - f->f11);
  } else if (s->nd_dir < 0) {
    nd_s =
        (1.0f - c->v) * (f->f00 - word_f32(t, o - 1u)) + c->v * (f->f01 - word_f32(t, o + nd - 1u));
  }
  *l_d = (sd + s->w * (nd_s - sd)) * m->inv_did;
  float nq_s = sq; /* along q */
  if (s->nq_dir > 0) {
    nq_s = (1.0f - c->u) * (word_f32(t, o + 2u * nd) - f->f01) +
           c->u * (word_f32(t, o + 2u * nd + 1u) - f->f11);
  } else if (s->nq_dir < 0) {
    nq_s =
        (1.0f - c->u) * (f->f00 - word_f32(t, o - nd)) + c->u * (f->f10 - word_f32(t, o - nd + 1u));
  }
  *l_q = (sq + s->z * (nq_s - sq)) * m->inv_diq;
}

dq_t flux_map_flux_inductance(const flux_map_t *m, dq_t i, flux_map_ldq_t *l) {
  const cell_t c = cell_of(m, i);
  const window_t s = window_of(m, &c);
  const corners_t d = corners(m, m->psi_d, c.o);
  const corners_t q = corners(m, m->psi_q, c.o);
  centred(m, m->psi_d, &c, &d, &s, &l->dd, &l->dq);
  centred(m, m->psi_q, &c, &q, &s, &l->qd, &l->qq);
  return (dq_t){bilinear(&d, c.u, c.v), bilinear(&q, c.u, c.v)};
}

/* Flux and the bilinear interpolant's own Jacobian at i (Newton). */
static dq_t flux_jac(const flux_map_t *m, dq_t i, flux_map_ldq_t *l) {
  const cell_t c = cell_of(m, i);
  const corners_t d = corners(m, m->psi_d, c.o);
  const corners_t q = corners(m, m->psi_q, c.o);
  const float u = c.u, v = c.v;
  l->dd = ((1.0f - v) * (d.f10 - d.f00) + v * (d.f11 - d.f01)) * m->inv_did;
  l->dq = ((1.0f - u) * (d.f01 - d.f00) + u * (d.f11 - d.f10)) * m->inv_diq;
  l->qd = ((1.0f - v) * (q.f10 - q.f00) + v * (q.f11 - q.f01)) * m->inv_did;
  l->qq = ((1.0f - u) * (q.f01 - q.f00) + u * (q.f11 - q.f10)) * m->inv_diq;
  return (dq_t){bilinear(&d, u, v), bilinear(&q, u, v)};
}

/* x = L^-1 r; 0 when L is singular (no step). */
static dq_t solve(const flux_map_ldq_t *l, dq_t r) {
  const float det = l->dd * l->qq - l->dq * l->qd;
  if (!(fabsf(det) > 0.0f)) {
    return (dq_t){0.0f, 0.0f};
  }
  const float inv = 1.0f / det;
  return (dq_t){(l->qq * r.d - l->dq * r.q) * inv, (l->dd * r.q - l->qd * r.d) * inv};
}

dq_t flux_map_current(const flux_map_t *m, dq_t lambda) {
  /* from the zero-current linearisation (the first step from i = 0), then
   * FLUX_MAP_NEWTON steps. A step that leaves the floats ends the iteration
   * at the last finite iterate: the parser checks each cell's mean
   * inductance matrix, not the interpolant's at every point, and a
   * Jacobian near singular inside a cell or far outside the grid gave
   * inf, then NaN (found by tests/fuzz fuzz_fluxmap) */
  flux_map_ldq_t l;
  dq_t i = {0.0f, 0.0f};
  for (int n = 0; n <= FLUX_MAP_NEWTON; ++n) {
    const dq_t f = flux_jac(m, i, &l);
    const dq_t s = solve(&l, (dq_t){lambda.d - f.d, lambda.q - f.q});
    const dq_t next = {i.d + s.d, i.q + s.q};
    if (!fd_isfinite(next.d + next.q)) {
      break;
    }
    i = next;
  }
  return i;
}

float flux_map_torque(const flux_map_t *m, float pole_pairs, dq_t i) {
  const dq_t l = flux_map_flux(m, i);
  /* mut: flux_map_torque_sign */
  return 1.5f * pole_pairs * (l.d * i.q - l.q * i.d);
}

/* Index and fraction of x (in table steps) on a table of n points, clamped
 * to the table (no extrapolation). */
static uint32_t lut_pos(float x, uint32_t n, float *frac) {
  const float xc = fd_clampf(x, 0.0f, (float)(n - 1u));
  uint32_t j = (uint32_t)xc;
  j = j > n - 2u ? n - 2u : j;
  *frac = xc - (float)j;
  return j;
}

static float lut(const uint32_t *t, uint32_t j, float f) {
  const float a = word_f32(t, j);
  return a + f * (word_f32(t, j + 1u) - a);
}

dq_t flux_map_mtpa_current(const flux_map_t *m, float t) {
  float f;
  const uint32_t j = lut_pos(fabsf(t) * m->mtpa_inv, m->n_lut, &f);
  const float iq = lut(m->mtpa_iq, j, f);
  return (dq_t){lut(m->mtpa_id, j, f), t < 0.0f ? -iq : iq};
}

float flux_map_mtpa_flux(const flux_map_t *m, float t) {
  float f;
  const uint32_t j = lut_pos(fabsf(t) * m->mtpa_inv, m->n_lut, &f);
  return lut(m->mtpa_flux, j, f);
}

static float mtpa_amp(const flux_map_t *m, uint32_t j) {
  const float d = word_f32(m->mtpa_id, j), q = word_f32(m->mtpa_iq, j);
  return sqrtf(d * d + q * q);
}

float flux_map_mtpa_torque(const flux_map_t *m, float i_amp) {
  const float dt = m->mtpa_t_max / (float)(m->n_lut - 1u);
  float a0 = mtpa_amp(m, 0u);
  for (uint32_t j = 1u; j < m->n_lut; ++j) {
    const float a1 = mtpa_amp(m, j);
    if (a1 >= i_amp) {
      const float f = a1 > a0 ? fd_clampf((i_amp - a0) / (a1 - a0), 0.0f, 1.0f) : 1.0f;
      return ((float)(j - 1u) + f) * dt;
    }
    a0 = a1;
  }
  return m->mtpa_t_max;
}

float flux_map_mtpv_torque(const flux_map_t *m, float flux) {
  float f;
  const uint32_t j = lut_pos(flux * m->mtpv_inv, m->n_lut, &f);
  return lut(m->mtpv_torque, j, f);
}
