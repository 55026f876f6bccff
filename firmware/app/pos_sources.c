/*
 * pos_sources.c - the table of position sources, one row per entry of
 * POS_SOURCE_LIST (drive_enums.h), at its index. The encoder's row is its
 * own functions (pos_encoder.c); a star-point row is the star point's
 * functions (pos_dfc.c) and three columns (pos_star.h): the method, the
 * tracker and the identification. A new combination of existing columns
 * is one line here (and its entry in POS_SOURCE_LIST); docs/architecture.md,
 * "Adding a position source".
 */
#include <stddef.h>

#include "pos_dfc_signals.h"
#include "pos_encoder.h"
#include "pos_star.h"

#define POS_STAR_ROW(m, t, i)                                                                      \
  {                                                                                                \
    .caps = POS_CAP_ALIGN | POS_CAP_GATED, .init = pos_star_init, .reset = pos_star_reset,         \
    .update = pos_star_update, .align = pos_star_align, .check = pos_star_check,                   \
    .hold = pos_star_hold, .method = (m), .tracker = (t), .ident = (i),                            \
    .signals = pos_dfc_signals, .n_signals = POS_DFC_N_SIGNALS,                                    \
  }

/* The EKF is not combined with the RLS: its angle is itself a function of
 * a and b, the non-observable combination of Fabbri 2022, 5.1.3 (pos_rls.c). */
static const pos_source_row_t sources[POS_SOURCE_COUNT] = {
    /* no angle at standstill: no held start */
    [POS_SOURCE_ENCODER] = {.caps = POS_CAP_ALIGN,
                            .init = pos_encoder_init,
                            .reset = pos_encoder_reset,
                            .update = pos_encoder_update,
                            .align = pos_encoder_align,
                            .check = pos_encoder_check,
                            .hold = NULL,
                            .signals = NULL,
                            .n_signals = 0u},
    /*                              method               tracker           identification */
    [POS_SOURCE_DFC] = POS_STAR_ROW(&pos_method_dfc, &pos_tracker_pll, NULL),
    [POS_SOURCE_DFC_INV] = POS_STAR_ROW(&pos_method_dfc_inv, &pos_tracker_pll, NULL),
    [POS_SOURCE_IVD] = POS_STAR_ROW(&pos_method_ivd, &pos_tracker_pll, NULL),
    [POS_SOURCE_DFC_KF] = POS_STAR_ROW(&pos_method_dfc, &pos_tracker_kf, NULL),
    [POS_SOURCE_IVD_KF] = POS_STAR_ROW(&pos_method_ivd, &pos_tracker_kf, NULL),
    [POS_SOURCE_EKF] = POS_STAR_ROW(&pos_method_dfc, &pos_tracker_ekf, NULL),
    [POS_SOURCE_IVD_KF_RLS] = POS_STAR_ROW(&pos_method_ivd, &pos_tracker_kf, &pos_ident_rls),
};

const pos_source_row_t *pos_source(pos_source_t src) {
  return (unsigned)src < (unsigned)POS_SOURCE_COUNT ? &sources[src] : NULL;
}
