/*
 * The core's flux map (float, bilinear: firmware/core/model/flux_map.c)
 * against the plant's (double, C2 spline: sil/plant/plant_fluxmap.c), both
 * built from the same committed blob maps/syr_1k1.fdmap through the SIL's
 * loader (map_load.c): equal at the grid points to float resolution;
 * between them apart by the bilinear interpolation's error only; the
 * incremental inductances and the inverse alike. And the map-file preset
 * (an NPZ in the SyR convention, through the map tool at start-up) drives.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <string.h>

#include "map_load.h"
#include "sil_test_util.h"

static const map_load_t *syr(void) {
  char err[512];
  const map_load_t *e = map_load("maps/syr_1k1.fdmap", "test", 0, err, sizeof err);
  if (e == NULL) {
    fail_msg("%s", err);
  }
  return e;
}

static void core_vs_plant(void **state) {
  (void)state;
  const map_load_t *e = syr();
  const flux_map_t *m = &e->map;
  double node = 0.0, mid = 0.0, scale = 0.0, lmid = 0.0, inv = 0.0, d2 = 0.0;
  /* the bilinear interpolation's error bound at a cell centre, from the
   * map's own second differences: (|D2_d f| + |D2_q f|) / 8 */
  for (uint32_t k = 1; k + 1 < m->nq; ++k) {
    for (uint32_t j = 1; j + 1 < m->nd; ++j) {
      for (int c = 0; c < 2; ++c) {
        const uint32_t *t = c == 0 ? m->psi_d : m->psi_q;
        float f[5];
        const uint32_t o[5] = {k * m->nd + j, k * m->nd + j - 1, k * m->nd + j + 1,
                               (k - 1) * m->nd + j, (k + 1) * m->nd + j};
        for (int n = 0; n < 5; ++n) {
          memcpy(&f[n], &t[o[n]], sizeof f[n]);
        }
        d2 = fmax(d2, (fabs(f[1] - 2.0 * f[0] + f[2]) + fabs(f[3] - 2.0 * f[0] + f[4])) / 8.0);
      }
    }
  }
  for (uint32_t k = 0; k < m->nq; ++k) {
    for (uint32_t j = 0; j < m->nd; ++j) {
      const double id = m->id0 + j * (double)m->did, iq = m->iq0 + k * (double)m->diq;
      double pd, pq;
      plant_fluxmap_flux(e->plant, id, iq, &pd, &pq);
      const dq_t c = flux_map_flux(m, (dq_t){(float)id, (float)iq});
      node = fmax(node, fmax(fabs(c.d - pd), fabs(c.q - pq)));
      scale = fmax(scale, hypot(pd, pq));
      if (j + 1 < m->nd && k + 1 < m->nq) {
        /* the cell centre: the bilinear interpolation's largest error */
        const double xd = id + 0.5 * m->did, xq = iq + 0.5 * m->diq;
        plant_fluxmap_flux(e->plant, xd, xq, &pd, &pq);
        const dq_t cm = flux_map_flux(m, (dq_t){(float)xd, (float)xq});
        mid = fmax(mid, fmax(fabs(cm.d - pd), fabs(cm.q - pq)));
        /* the incremental inductance: (25) centred on the bilinear map
         * against the spline's Jacobian (inverted) */
        double g[2][2];
        plant_fluxmap_jacobian(e->plant, pd, pq, g);
        const double det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
        const double lqq = g[0][0] / det, ldd = g[1][1] / det;
        const flux_map_ldq_t l = flux_map_inductance(m, (dq_t){(float)xd, (float)xq});
        lmid = fmax(lmid, fmax(fabs(l.dd - ldd) / ldd, fabs(l.qq - lqq) / lqq));
        /* the inverse: the core's Newton on its own map, from the core's flux */
        const dq_t back = flux_map_current(m, cm);
        inv = fmax(inv, hypot(back.d - xd, back.q - xq));
      }
    }
  }
  printf("syr_1k1, core vs plant: grid points %.2e Vs, cell centres %.2e Vs (%.3f %% of the "
         "largest flux %.3f Vs; the bilinear bound from the map's second differences %.2e Vs); "
         "incremental self-inductances at the cell centres %.2f %% apart; core inverse %.2e A\n",
         node, mid, 100.0 * mid / scale, scale, d2, 100.0 * lmid, inv);
  assert_true(node < 2e-7 * scale);
  assert_true(mid < 1.5 * d2);     /* bilinear error h^2/8 |f''|, with the spline's own curvature */
  assert_true(mid > 1e-6 * scale); /* and not the same interpolant */
  assert_true(lmid < 0.25);        /* a bilinear map's slope is a cell's mean */
  assert_true(inv < 1e-4);
}

static void file_preset_drives(void **state) {
  (void)state;
  scenario_t sc;
  trace_t tr;
  sil_result_t res;
  run_json("{\"name\": \"pmasyr file\", \"duration\": 0.25, \"machine\": {\"preset\": "
           "\"pmasyr_file\"}, \"mechanics\": {\"mode\": \"imposed\", \"speed\": {\"unit\": "
           "\"rpm\", \"terms\": [{\"type\": \"const\", \"value\": 500}]}}, \"controller\": "
           "{\"law\": \"foc\", \"mode\": \"torque\"}, \"references\": {\"torque\": [{\"type\": "
           "\"step\", \"t\": 0.05, \"value\": 8}]}}",
           &sc, &tr, &res);
  double t = 0.0;
  const size_t k0 = idx_at(&tr, 0.15);
  for (size_t k = k0; k < tr.n; ++k) {
    t += tr.torque[k];
  }
  t /= (double)(tr.n - k0);
  printf("pmasyr_file (NPZ, SyR convention, through the map tool): T* = 8 N m gives %.4f N m\n", t);
  assert_true(fabs(t - 8.0) < 0.03 * 8.0);
  assert_int_equal(res.faults, 0);
  assert_true(strstr(sc.map_file, "pmasyr_file.npz") != NULL);
  trace_free(&tr);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(core_vs_plant),
                                     cmocka_unit_test(file_preset_drives)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
