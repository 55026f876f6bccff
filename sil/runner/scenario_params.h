/*
 * scenario_params.h - a parameter file over a scenario's drive: the
 * drive's parameters by their table names (docs/parameters.md), as a
 * commissioning writes them (`fluxdrive commission`, docs/commissioning.md)
 * and as PARAM_REQ writes them over CAN. Only the drive's set changes: the
 * plant keeps the scenario's machine, so a run compares the identified
 * drive against the true motor.
 *
 * The file is one JSON object {"name": value, ...}; enumerations (law,
 * mode, pos_source) by name; "map": a flux-map file, the drive's own
 * (like controller.map); "identified" (the commissioning's record of what
 * each procedure found) is skipped. Every error names the file and the
 * parameter.
 */
#ifndef FD_SIL_SCENARIO_PARAMS_H
#define FD_SIL_SCENARIO_PARAMS_H

#include <stddef.h>

#include "scenario.h"

/* 0, or -1 with the message in err (nothing applied then). */
int scenario_apply_params(scenario_t *sc, const char *path, char *err, size_t errlen);

#endif
