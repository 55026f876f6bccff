/*
 * summary.h - the run's metrics as a JSON object (docs/log-format.md).
 */
#ifndef FD_SIL_SUMMARY_H
#define FD_SIL_SUMMARY_H

#include "scenario.h"
#include "sil_run.h"

/* Returns a malloc'ed, formatted JSON string (caller frees), or NULL. */
char *summary_json(const scenario_t *sc, const sil_result_t *res);

/* The resolved parameters of a scenario (plant and controller), as JSON:
 * what offline tools (tools/: capability curves) compute from. Caller frees. */
char *config_json(const scenario_t *sc);

#endif
