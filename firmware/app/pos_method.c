/*
 * pos_method.c - the method column of the star-point sources (pos_star.h):
 * how the angle is measured from the DFC signal vector (Fabbri 2022
 * chapter 3, estimation/dfc.h):
 *   dfc      standard Direct Flux Control (3.8)-(3.10)
 *   dfc_inv  inverse DFC (3.15)-(3.16)
 *   ivd      Iterative Vector Decoupling (3.76), the Full IVD (3.100)
 *            when the phase shifts dfc_phi_a, dfc_phi_b are not zero
 */
#include "math/fd_math.h"
#include "pos_star.h"

const pos_method_t pos_method_dfc = {DFC_STANDARD, DFC_STANDARD, false};
const pos_method_t pos_method_dfc_inv = {DFC_INVERSE, DFC_INVERSE, false};
const pos_method_t pos_method_ivd = {DFC_IVD, DFC_FULL_IVD, true};

dfc_cfg_t pos_method_cfg(const pos_method_t *m, const drive_config_t *cfg) {
  const bool shifted = fabsf(cfg->dfc_phi_a) > 0.0f || fabsf(cfg->dfc_phi_b) > 0.0f;
  const dfc_cfg_t d = {shifted ? m->shifted : m->plain,
                       cfg->dfc_a,
                       cfg->dfc_b,
                       cfg->dfc_phi_a,
                       cfg->dfc_phi_b,
                       cfg->dfc_iter};
  return d;
}
