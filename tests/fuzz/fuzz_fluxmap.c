/*
 * fuzz_fluxmap.c - libFuzzer harness: a flux-map file's contents through
 * the SIL's loader (sil/runner/map_load.c: size checks, the core's
 * flux_map_parse, the plant's inverse map) and the lookups of an accepted
 * map (firmware/core/model/flux_map.c, sil/plant/plant_fluxmap.c).
 *
 * Each input is loaded twice: as it is (most fail the size or CRC check),
 * and with its size word and CRC made right (whole words only), so that
 * inputs reach the grid, cell and table checks and the accepted maps.
 * Checked (docs/fuzzing.md), __builtin_trap() on a violation:
 *   - a refusal comes with a message, NUL-terminated, naming the file;
 *   - an accepted map's lookups are finite over a grid spanning the map's
 *     current range and half of it again on every side (flux, incremental
 *     inductance, the current from a flux (Newton), torque, MTPA current,
 *     flux and torque, MTPV torque; the plant's flux, current and
 *     Jacobian);
 *   - the core's flux equals the blob's value at every grid point (that
 *     floats can address: a step far below the origin's resolution has
 *     none).
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "map_load.h"
#include "model/flux_map.h"
#include "plant_fluxmap.h"

#define SHOWN    "fuzz.fdmap"
#define N_SAMPLE 9 /* lookups per axis */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void violated(const char *what, double a, double b) {
  fprintf(stderr, "fuzz_fluxmap: invariant violated: %s (%g, %g)\n", what, a, b);
  __builtin_trap();
}

static void finite2(const char *what, double a, double b, double at_d, double at_q) {
  if (!isfinite(a) || !isfinite(b)) {
    fprintf(stderr, "fuzz_fluxmap: at (%g, %g): %g, %g\n", at_d, at_q, a, b);
    violated(what, at_d, at_q);
  }
}

static float word_f32(const uint32_t *w, size_t i) {
  float f;
  memcpy(&f, &w[i], sizeof f);
  return f;
}

static void check_map(const map_load_t *e) {
  const flux_map_t *m = &e->map;
  /* grid values back at the grid points (to the rounding of the weights,
   * on the scale of the largest value) */
  float big = 0.0f;
  for (uint32_t o = 0; o < m->nd * m->nq; ++o) {
    big = fmaxf(big, fmaxf(fabsf(word_f32(m->psi_d, o)), fabsf(word_f32(m->psi_q, o))));
  }
  for (uint32_t k = 0; k < m->nq; ++k) {
    for (uint32_t j = 0; j < m->nd; ++j) {
      const dq_t i = {m->id0 + (float)j * m->did, m->iq0 + (float)k * m->diq};
      if (!(fabsf((i.d - m->id0) * m->inv_did - (float)j) <= 1e-5f * (float)(j + 1u) &&
            fabsf((i.q - m->iq0) * m->inv_diq - (float)k) <= 1e-5f * (float)(k + 1u))) {
        continue; /* a step below the float resolution of the origin: no grid point */
      }
      const dq_t l = flux_map_flux(m, i);
      const float ld = word_f32(m->psi_d, k * m->nd + j), lq = word_f32(m->psi_q, k * m->nd + j);
      const float tol = 1e-4f * big + 1e-6f;
      if (!(fabsf(l.d - ld) <= tol && fabsf(l.q - lq) <= tol)) {
        violated("flux at a grid point differs from the blob", (double)j, (double)k);
      }
    }
  }
  const float span_d = (float)(m->nd - 1u) * m->did, span_q = (float)(m->nq - 1u) * m->diq;
  for (int a = 0; a < N_SAMPLE; ++a) {
    for (int b = 0; b < N_SAMPLE; ++b) {
      const float fd = -0.5f + 2.0f * (float)a / (N_SAMPLE - 1);
      const float fq = -0.5f + 2.0f * (float)b / (N_SAMPLE - 1);
      const dq_t i = {m->id0 + fd * span_d, m->iq0 + fq * span_q};
      const dq_t l = flux_map_flux(m, i);
      finite2("flux_map_flux", (double)l.d, (double)l.q, (double)i.d, (double)i.q);
      const flux_map_ldq_t L = flux_map_inductance(m, i);
      finite2("flux_map_inductance", (double)(L.dd + L.qq), (double)(L.dq + L.qd), (double)i.d,
              (double)i.q);
      flux_map_ldq_t L2;
      const dq_t l2 = flux_map_flux_inductance(m, i, &L2);
      finite2("flux_map_flux_inductance", (double)(l2.d + l2.q),
              (double)(L2.dd + L2.qq + L2.dq + L2.qd), (double)i.d, (double)i.q);
      const dq_t ii = flux_map_current(m, l);
      finite2("flux_map_current", (double)ii.d, (double)ii.q, (double)l.d, (double)l.q);
      const float t = flux_map_torque(m, m->pole_pairs, i);
      finite2("flux_map_torque", (double)t, 0.0, (double)i.d, (double)i.q);
      const float tr = (fd - 0.25f) * 2.0f * m->mtpa_t_max;
      const dq_t im = flux_map_mtpa_current(m, tr);
      finite2("flux_map_mtpa_current", (double)im.d, (double)im.q, (double)tr, 0.0);
      finite2("flux_map_mtpa_flux / torque", (double)flux_map_mtpa_flux(m, tr),
              (double)flux_map_mtpa_torque(m, fabsf(i.q)), (double)tr, (double)i.q);
      finite2("flux_map_mtpv_torque", (double)flux_map_mtpv_torque(m, fq * m->mtpv_flux_max), 0.0,
              (double)fq, 0.0);
      double pd, pq, cd, cq, jac[2][2];
      plant_fluxmap_flux(e->plant, (double)i.d, (double)i.q, &pd, &pq);
      finite2("plant_fluxmap_flux", pd, pq, (double)i.d, (double)i.q);
      plant_fluxmap_current(e->plant, pd, pq, &cd, &cq);
      finite2("plant_fluxmap_current", cd, cq, pd, pq);
      plant_fluxmap_jacobian(e->plant, pd, pq, jac);
      finite2("plant_fluxmap_jacobian", jac[0][0] + jac[1][1], jac[0][1] + jac[1][0], pd, pq);
    }
  }
}

static void load(const void *bytes, size_t n) {
  map_load_t e;
  char err[512];
  memset(err, 'x', sizeof err);
  if (map_load_bytes(bytes, n, SHOWN, &e, err, sizeof err) != 0) {
    if (memchr(err, '\0', sizeof err) == NULL) {
      violated("error message not NUL-terminated", 0.0, 0.0);
    }
    if (strncmp(err, SHOWN ": ", sizeof SHOWN + 1u) != 0 || strlen(err) <= sizeof SHOWN + 1u) {
      fprintf(stderr, "fuzz_fluxmap: message: \"%s\"\n", err);
      violated("error message does not name the file and the reason", 0.0, 0.0);
    }
    return;
  }
  check_map(&e);
  map_load_release(&e);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  load(data, size);
  /* the same with the size word and the CRC made right */
  const size_t n = size & ~(size_t)3u;
  if (n < 16u || n > 4u * (12u + 2u * 64u * 64u + 2u + 4u * 128u + 1u)) {
    return 0;
  }
  uint32_t *w = malloc(n);
  if (w == NULL) {
    return 0;
  }
  memcpy(w, data, n);
  w[2] = (uint32_t)n;
  w[n / 4u - 1u] = flux_map_crc32(w, (uint32_t)n - 4u);
  load(w, n);
  free(w);
  return 0;
}
