/*
 * pos_dfc_signals.c - what the star-point sources (pos_dfc.c) expose for
 * logs: the last estimate's instant, the DFC signals, 2 theta after each
 * IVD step, the a, b the IVD used and the Kalman filter's measurement
 * variance; getters on pos_state_t (signal_row.h), run after the ISR (FD_COLD:
 * left in flash on the boards).
 */
#include "pos_dfc_signals.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

#define STAR(owner)      (&((const pos_state_t *)(owner))->star)
#define DFC_STATE(owner) (&STAR(owner)->meas)

FD_COLD static double sig_t(const void *o) {
  return (double)DFC_STATE(o)->t;
}
FD_COLD static double sig_ga(const void *o) {
  return (double)DFC_STATE(o)->sig.g[0];
}
FD_COLD static double sig_gb(const void *o) {
  return (double)DFC_STATE(o)->sig.g[1];
}
FD_COLD static double sig_gc(const void *o) {
  return (double)DFC_STATE(o)->sig.g[2];
}

/* 2 theta after IVD step k, from its unit vector (cos, sin) in the trace */
#define DFC_K(k)                                                                                   \
  FD_COLD static double sig_k##k(const void *o) {                                                  \
    const float *tr = DFC_STATE(o)->trace;                                                         \
    return atan2((double)tr[(size_t)2 * (k) + 1u], (double)tr[(size_t)2 * (k)]);                   \
  }
DFC_K(0)
DFC_K(1)
DFC_K(2)
DFC_K(3)
DFC_K(4)
DFC_K(5)
DFC_K(6)
DFC_K(7)
DFC_K(8)
#undef DFC_K
_Static_assert(DFC_ITER_MAX == 8u, "one dfc_k signal per IVD step");

/* the a, b the IVD used this period: identified (a row with an
 * identification: ivd+kf+rls), else 0 */
FD_COLD static double sig_rls_a(const void *o) {
  return (double)(STAR(o)->ident != NULL ? DFC_STATE(o)->dc.a : 0.0f);
}
FD_COLD static double sig_rls_b(const void *o) {
  return (double)(STAR(o)->ident != NULL ? DFC_STATE(o)->dc.b : 0.0f);
}
FD_COLD static double sig_kf_r(const void *o) {
  return (double)STAR(o)->trk.r;
}

#define K_ROW(k)                                                                                   \
  {                                                                                                \
    "dfc_k" #k, SIGNAL_F32, "rad", "2 theta_e after IVD step " #k " (stale beyond dfc_iter)",      \
        sig_k##k                                                                                   \
  }

const signal_row_t pos_dfc_signals[POS_DFC_N_SIGNALS] = {
    {"dfc_t", SIGNAL_F32, "s",
     "instant of the source's last estimate relative to t (negative: taken in the previous "
     "period)",
     sig_t},
    {"dfc_ga", SIGNAL_F32, "1", "the DFC signal Gamma_a / v_dc held by the source (2.101)", sig_ga},
    {"dfc_gb", SIGNAL_F32, "1", "the DFC signal Gamma_b / v_dc", sig_gb},
    {"dfc_gc", SIGNAL_F32, "1", "the DFC signal Gamma_c / v_dc", sig_gc},
    {"dfc_k0", SIGNAL_F32, "rad",
     "2 theta_e of the standard DFC (3.8), or of the inverse DFC (IVD step 0)", sig_k0},
    K_ROW(1),
    K_ROW(2),
    K_ROW(3),
    K_ROW(4),
    K_ROW(5),
    K_ROW(6),
    K_ROW(7),
    K_ROW(8),
    {"rls_a", SIGNAL_F32, "1",
     "the a the IVD used this period, identified online (ivd+kf+rls, within its guards, "
     "docs/dfc.md); 0 for the other sources",
     sig_rls_a},
    {"rls_b", SIGNAL_F32, "1", "the b the IVD used this period, as rls_a", sig_rls_b},
    {"kf_r", SIGNAL_F32, "rad^2 (EKF: (Gamma/v_dc)^2)",
     "the Kalman filter's measurement variance R_k of its last update ((4.29)-(4.31) or (4.38), "
     "times kf_r_scale); 0 for the PLL sources",
     sig_kf_r},
};
