/*
 * pos_method.c - the method column of the star-point sources (pos_star.h):
 * how the angle is measured from the DFC signal vector (Fabbri 2022
 * chapter 3, estimation/dfc.h):
 *   dfc      standard Direct Flux Control (3.8)-(3.10)
 *   dfc_inv  inverse DFC (3.15)-(3.16)
 *   ivd      Iterative Vector Decoupling (3.76), the Full IVD (3.100)
 *            when the phase shifts dfc_phi_a, dfc_phi_b are not zero
 * (the configuration from them: pos_star.h, pos_method_cfg)
 */
#include "pos_star.h"

const pos_method_t pos_method_dfc = {DFC_STANDARD, DFC_STANDARD, false};
const pos_method_t pos_method_dfc_inv = {DFC_INVERSE, DFC_INVERSE, false};
const pos_method_t pos_method_ivd = {DFC_IVD, DFC_FULL_IVD, true};
