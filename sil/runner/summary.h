/*
 * summary.h - the run's metrics as a JSON object (docs/log-format.md).
 */
#ifndef FD_SIL_SUMMARY_H
#define FD_SIL_SUMMARY_H

#include "scenario.h"
#include "sil_preempt.h"
#include "sil_run.h"

/* Returns a malloc'ed, formatted JSON string (caller frees), or NULL. */
char *summary_json(const scenario_t *sc, const sil_result_t *res);

/* The resolved parameters of a scenario (plant and controller), as JSON:
 * what offline tools (tools/: capability curves) compute from. Caller frees. */
char *config_json(const scenario_t *sc);

/* The parameter table (every row), the CAN protocol's parameters and the
 * drive's named values (laws, modes, states, position sources, faults, CAN
 * results), as JSON: `fluxdrive-sil --print-params`, from which `fluxdrive
 * params` generates the DBC value tables, the tools' table and the docs.
 * Caller frees. */
char *params_json(void);

/* The result of a preempting run (sil_preempt.h), as JSON. Caller frees. */
char *preempt_json(const sil_preempt_result_t *r);

#endif
