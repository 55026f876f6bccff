/*
 * signals_json.h - `fluxdrive-sil --print-signals`: the signal tables
 * (signal_row.h) as the log's columns, the CAN signals they fill and the PIL
 * stream's output fields, as JSON, from which `fluxdrive signals`
 * generates docs/log-format.md, the DBC's telemetry comments and the
 * tools' table (tools/src/fluxdrive/signals.py).
 */
#ifndef FD_SIL_SIGNALS_JSON_H
#define FD_SIL_SIGNALS_JSON_H

/* A malloc'ed JSON string (caller frees), or NULL. */
char *signals_json(void);

#endif
