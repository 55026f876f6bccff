/*
 * pos_dfc_signals.h - the star-point sources' signals (pos_dfc_signals.c),
 * the signal column of their rows (pos_sources.c).
 */
#ifndef FLUXDRIVE_POS_DFC_SIGNALS_H
#define FLUXDRIVE_POS_DFC_SIGNALS_H

#include "pos_source.h"

/* dfc_t, the three signals, 2 theta after each IVD step, rls_a, rls_b, kf_r */
#define POS_DFC_N_SIGNALS (4u + (DFC_ITER_MAX + 1u) + 3u)

extern const signal_row_t pos_dfc_signals[POS_DFC_N_SIGNALS];

#endif
