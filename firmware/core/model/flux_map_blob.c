/*
 * flux_map_blob.c - parsing and validation of a .fdmap blob, version 1
 * (layout: docs/flux-maps.md). The checks repeat those of the tool that
 * wrote the blob (tools/src/fluxdrive/fluxmap/) where a wrong blob would
 * make a wrong machine: a blob may come from elsewhere than the tool.
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "math/fd_math.h"
#include "model/flux_map.h"

/* Header words (docs/flux-maps.md). */
enum {
  W_MAGIC,
  W_VERSION,
  W_SIZE,
  W_ND,
  W_NQ,
  W_NLUT,
  W_FLAGS,
  W_POLES,
  W_ID0,
  W_DID,
  W_IQ0,
  W_DIQ,
  W_HEADER
};

static float word_f32(const uint32_t *w, uint32_t i) {
  float f;
  memcpy(&f, &w[i], sizeof f);
  return f;
}

/* CRC-32, reflected polynomial 0xEDB88320, four bits a step from a 16-entry
 * table (64 bytes of flash; a bit at a time cost 0.6 M instructions on a
 * 10 KB blob, this a quarter of that). */
uint32_t flux_map_crc32(const uint32_t *words, uint32_t n_bytes) {
  static const uint32_t nib[16] = {0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
                                   0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
                                   0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
                                   0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};
  uint32_t crc = 0xFFFFFFFFu;
  for (uint32_t b = 0u; b < n_bytes; ++b) {
    crc ^= (words[b >> 2u] >> (8u * (b & 3u))) & 0xFFu; /* little-endian byte order */
    crc = (crc >> 4u) ^ nib[crc & 15u];
    crc = (crc >> 4u) ^ nib[crc & 15u];
  }
  return ~crc;
}

const char *flux_map_err_str(flux_map_err_t e) {
  static const char *const s[FLUX_MAP_E_COUNT] = {
      "valid",
      "no blob",
      "not a flux map (magic)",
      "unsupported version",
      "size does not match the header",
      "grid points outside 2..64",
      "table points outside 2..128",
      "unknown flags",
      "CRC mismatch",
      "grid axes or pole pairs not finite and positive, or beyond 1e5 A or 100 pole pairs",
      "grid does not cover both signs of i_q",
      "flux value not finite or beyond 1000 Vs",
      "incremental self-inductance not positive",
      "incremental inductance matrix not positive definite",
      "MTPA/MTPV tables not finite, negative or not increasing",
  };
  return (unsigned)e < (unsigned)FLUX_MAP_E_COUNT ? s[e] : "unknown error";
}

static int fail(flux_map_status_t *st, flux_map_err_t code, int j, int k) {
  st->code = code;
  st->j = j;
  st->k = k;
  return -1;
}

/* Finite values, positive self-inductances and a positive-definite
 * (symmetric part of the) incremental inductance matrix in every cell, by
 * the cell's mean differences. */
static int check_cells(const flux_map_t *m, flux_map_status_t *st) {
  const uint32_t n = m->nd * m->nq;
  for (uint32_t o = 0u; o < n; ++o) {
    if (!(fabsf(word_f32(m->psi_d, o)) <= FLUX_MAP_PSI_MAX &&
          fabsf(word_f32(m->psi_q, o)) <= FLUX_MAP_PSI_MAX)) {
      return fail(st, FLUX_MAP_E_FINITE, (int)(o % m->nd), (int)(o / m->nd));
    }
  }
  for (uint32_t k = 0u; k + 1u < m->nq; ++k) {
    for (uint32_t j = 0u; j + 1u < m->nd; ++j) {
      const uint32_t o = k * m->nd + j, nd = m->nd;
      const float ld = word_f32(m->psi_d, o), ld10 = word_f32(m->psi_d, o + 1u);
      const float ld01 = word_f32(m->psi_d, o + nd), ld11 = word_f32(m->psi_d, o + nd + 1u);
      const float lq = word_f32(m->psi_q, o), lq10 = word_f32(m->psi_q, o + 1u);
      const float lq01 = word_f32(m->psi_q, o + nd), lq11 = word_f32(m->psi_q, o + nd + 1u);
      const float dd = 0.5f * (ld10 - ld + ld11 - ld01) * m->inv_did;
      const float qq = 0.5f * (lq01 - lq + lq11 - lq10) * m->inv_diq;
      const float dq = 0.5f * (ld01 - ld + ld11 - ld10) * m->inv_diq;
      const float qd = 0.5f * (lq10 - lq + lq11 - lq01) * m->inv_did;
      const float c = 0.5f * (dq + qd);
      if (!(dd > 0.0f && qq > 0.0f)) {
        return fail(st, FLUX_MAP_E_SELF_L, (int)j, (int)k);
      }
      if (!(dd * qq - c * c > 0.0f)) {
        return fail(st, FLUX_MAP_E_NOT_PD, (int)j, (int)k);
      }
    }
  }
  return 0;
}

/* Tables: finite and within the map's physical bounds (currents within
 * FLUX_MAP_I_MAX, flux within FLUX_MAP_PSI_MAX, torque within FLUX_MAP_T_MAX:
 * finite values near FLT_MAX would overflow the interpolation's difference,
 * b - a, to infinity and 0 * inf to NaN; the flux-map fuzzer found one);
 * MTPA current i_q >= 0; flux, torque and current amplitude not decreasing
 * along the tables (monotonic references). */
static int check_tables(const flux_map_t *m, flux_map_status_t *st) {
  float prev_flux = 0.0f, prev_amp = 0.0f, prev_t = 0.0f;
  for (uint32_t j = 0u; j < m->n_lut; ++j) {
    const float id = word_f32(m->mtpa_id, j), iq = word_f32(m->mtpa_iq, j);
    const float fl = word_f32(m->mtpa_flux, j), t = word_f32(m->mtpv_torque, j);
    const float amp = id * id + iq * iq;
    const float z = fd_zero_if_finite(id) + fd_zero_if_finite(iq) + fd_zero_if_finite(fl) +
                    fd_zero_if_finite(t);
    const int bounded = fabsf(id) <= FLUX_MAP_I_MAX && iq <= FLUX_MAP_I_MAX &&
                        fabsf(fl) <= FLUX_MAP_PSI_MAX && fabsf(t) <= FLUX_MAP_T_MAX;
    if (!(fd_isfinite(z) && bounded && iq >= 0.0f && fl >= prev_flux && amp >= prev_amp &&
          t >= prev_t)) {
      return fail(st, FLUX_MAP_E_TABLES, (int)j, -1);
    }
    prev_flux = fl;
    prev_amp = amp;
    prev_t = t;
  }
  return 0;
}

int flux_map_parse(flux_map_t *m, const uint32_t *w, uint32_t size, flux_map_status_t *st) {
  flux_map_status_t dummy = {FLUX_MAP_OK, -1, -1};
  st = st != NULL ? st : &dummy;
  *st = (flux_map_status_t){FLUX_MAP_OK, -1, -1};
  if (w == NULL || m == NULL) {
    return fail(st, FLUX_MAP_E_NULL, -1, -1);
  }
  if (size < 4u * (W_HEADER + 1u) || (size & 3u) != 0u) {
    return fail(st, FLUX_MAP_E_SIZE, -1, -1);
  }
  if (w[W_MAGIC] != FLUX_MAP_MAGIC) {
    return fail(st, FLUX_MAP_E_MAGIC, -1, -1);
  }
  if (w[W_VERSION] != FLUX_MAP_VERSION) {
    return fail(st, FLUX_MAP_E_VERSION, -1, -1);
  }
  if (w[W_SIZE] != size) {
    return fail(st, FLUX_MAP_E_SIZE, -1, -1);
  }
  const uint32_t nd = w[W_ND], nq = w[W_NQ], nl = w[W_NLUT];
  if (nd < 2u || nq < 2u || nd > FLUX_MAP_GRID_MAX || nq > FLUX_MAP_GRID_MAX) {
    return fail(st, FLUX_MAP_E_GRID, (int)nd, (int)nq);
  }
  if (nl < 2u || nl > FLUX_MAP_LUT_MAX) {
    return fail(st, FLUX_MAP_E_LUT, (int)nl, -1);
  }
  if ((w[W_FLAGS] & ~FLUX_MAP_FLAG_PM) != 0u) {
    return fail(st, FLUX_MAP_E_FLAGS, -1, -1);
  }
  const uint32_t n_words = W_HEADER + 2u * nd * nq + 1u + 3u * nl + 1u + nl + 1u;
  if (size != 4u * n_words) {
    return fail(st, FLUX_MAP_E_SIZE, -1, -1);
  }
  const uint32_t crc = flux_map_crc32(w, size - 4u);
  if (crc != w[n_words - 1u]) {
    return fail(st, FLUX_MAP_E_CRC, -1, -1);
  }
  const float pp = word_f32(w, W_POLES), id0 = word_f32(w, W_ID0), did = word_f32(w, W_DID);
  const float iq0 = word_f32(w, W_IQ0), diq = word_f32(w, W_DIQ);
  const float z = fd_zero_if_finite(pp) + fd_zero_if_finite(id0) + fd_zero_if_finite(did) +
                  fd_zero_if_finite(iq0) + fd_zero_if_finite(diq);
  const float id1 = id0 + (float)(nd - 1u) * did, iq1 = iq0 + (float)(nq - 1u) * diq;
  if (!(fd_isfinite(z) && pp >= 1.0f && pp <= FLUX_MAP_POLES_MAX && did > 0.0f && diq > 0.0f &&
        fabsf(id0) <= FLUX_MAP_I_MAX && fabsf(id1) <= FLUX_MAP_I_MAX &&
        fabsf(iq0) <= FLUX_MAP_I_MAX && fabsf(iq1) <= FLUX_MAP_I_MAX)) {
    return fail(st, FLUX_MAP_E_AXES, -1, -1);
  }
  if (!(iq0 < 0.0f && iq1 > 0.0f)) {
    return fail(st, FLUX_MAP_E_IQ_SIGNS, -1, -1);
  }
  const uint32_t *p = w + W_HEADER;
  flux_map_t t = {0};
  t.nd = nd;
  t.nq = nq;
  t.n_lut = nl;
  t.flags = w[W_FLAGS];
  t.crc = crc;
  t.pole_pairs = pp;
  t.id0 = id0;
  t.did = did;
  t.iq0 = iq0;
  t.diq = diq;
  t.inv_did = 1.0f / did;
  t.inv_diq = 1.0f / diq;
  t.psi_d = p;
  t.psi_q = p + (size_t)nd * nq;
  p += (size_t)2u * nd * nq;
  t.mtpa_t_max = word_f32(p, 0u);
  t.mtpa_id = p + 1u;
  t.mtpa_iq = p + 1u + nl;
  t.mtpa_flux = p + 1u + (size_t)2u * nl;
  p += 1u + (size_t)3u * nl;
  t.mtpv_flux_max = word_f32(p, 0u);
  t.mtpv_torque = p + 1u;
  if (!(t.mtpa_t_max > 0.0f && t.mtpv_flux_max > 0.0f && t.mtpa_t_max <= FLUX_MAP_T_MAX &&
        t.mtpv_flux_max <= FLUX_MAP_PSI_MAX)) {
    return fail(st, FLUX_MAP_E_TABLES, -1, -1);
  }
  t.mtpa_inv = (float)(nl - 1u) / t.mtpa_t_max;
  t.mtpv_inv = (float)(nl - 1u) / t.mtpv_flux_max;
  if (!fd_isfinite(t.mtpa_inv + t.mtpv_inv)) { /* a range too small to invert */
    return fail(st, FLUX_MAP_E_TABLES, -1, -1);
  }
  if (check_cells(&t, st) != 0 || check_tables(&t, st) != 0) {
    return -1;
  }
  *m = t;
  return 0;
}
