/*
 * truth.h - the plant's true values that a self-commissioning identifies
 * (issue 25), as JSON: `fluxdrive-sil SCENARIO --print-truth`.
 */
#ifndef FD_SIL_TRUTH_H
#define FD_SIL_TRUTH_H

#include "scenario.h"

/* A malloc'ed, formatted JSON string (caller frees), or NULL. */
char *truth_json(const scenario_t *sc);

#endif
