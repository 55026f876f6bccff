/*
 * scenario_keys.h - every key of a scenario file, one row each: its type,
 * range, default, where its value goes and its documentation.
 *
 * The parser (scenario.c) walks this table: an object's known keys are its
 * rows, each value is read and checked by its row's type and range, and
 * stored at the row's offset in scenario_t or handed to its setter; an
 * object row's hooks (`set` before its keys, `post` after them) hold the
 * rules between keys (ls or ld and lq, trip_at with trip_cause, ...). The
 * key reference of docs/scenarios.md is printed from it
 * (`fluxdrive-sil --keys`, checked by CTest `sil/scenario_keys_doc`).
 *
 * Adding a key: one row in scenario_key_table.h (under its object's row,
 * in the order it is read), its field in scenario_t (or a setter in
 * scenario.c), then `fluxdrive-sil --keys-doc-write docs/scenarios.md`.
 */
#ifndef FD_SIL_SCENARIO_KEYS_H
#define FD_SIL_SCENARIO_KEYS_H

#include <stddef.h>

#include "scenario.h"

typedef enum {
  SK_NUM,     /* a number in [lo, hi] */
  SK_INT,     /* an integer in [lo, hi] */
  SK_ENUM,    /* a name of `names` (or of name_of), stored as its index */
  SK_PROFILE, /* a profile (docs/scenarios.md, "Profiles") */
  SK_BOUNDED, /* a profile whose terms stay in [lo, hi] ((lo, hi] with lo_open) */
  SK_STRING,  /* a string */
  SK_ARRAY3,  /* 3 numbers in [lo, hi] (phases a, b, c) */
  SK_OBJECT,  /* an object: the rows whose parent it is */
  SK_OBJECTS  /* an array of at most `max` such objects */
} sk_type_t;

/* Where a value goes: scenario_t (offset) or the parser's context
 * (SK_AT_CTX_*: values the hooks combine). */
typedef enum {
  SK_AT_NONE, /* the setter, the hooks, or nowhere (description) */
  SK_AT_F64,
  SK_AT_F32,
  SK_AT_INT, /* int, and the enumerations (int-sized: scenario.c asserts) */
  SK_AT_U32,
  SK_AT_BOOL,
  SK_AT_PROFILE,
  SK_AT_F64X3,
  SK_AT_CTX_F64,
  SK_AT_CTX_INT
} sk_at_t;

/* The range's source: the row's lo, hi or a drive parameter's
 * (drive_param_table.h: one range for plant and drive). */
typedef enum {
  SK_RANGE_FIXED,
  SK_RANGE_PARAM,     /* [min, max] of `param` */
  SK_RANGE_PARAM_INV, /* [1 / max, 1 / min] of `param` (a frequency of a period) */
  SK_RANGE_PARAM_HI   /* [lo, max of `param`] */
} sk_range_t;

struct scenario_key;
struct sk_ctx;

/* What a setter or hook is handed: the JSON item, its path, the value
 * read (number or index) and, inside an array of objects, the element's
 * index and byte shift. */
typedef struct {
  const void *it; /* const cJSON * */
  const char *path;
  double num;
  int index;
  size_t shift;
  const struct scenario_key *row;
} sk_val_t;

typedef struct scenario_key {
  const char *key;
  const char *param;                 /* SK_RANGE_PARAM*: the drive parameter */
  const char *const *names;          /* SK_ENUM: NULL-terminated */
  const char *(*name_of)(int index); /* SK_ENUM, instead of names */
  /* values: called instead of the store; objects: before their keys */
  int (*set)(struct sk_ctx *c, scenario_t *sc, const sk_val_t *v);
  int (*post)(struct sk_ctx *c, scenario_t *sc, const sk_val_t *v); /* objects: after */
  const char *req;                                                  /* required: what to give */
  const char *dflt;        /* the default, documented, when not a number */
  const char *plant_field; /* the name plant_check() reports, when not the key's */
  const char *doc;
  double lo, hi;
  double def;    /* stored when the enclosing object is read (top-level sections: always) */
  size_t offset; /* in scenario_t (or ctx_t: SK_AT_CTX_*) */
  size_t stride; /* SK_OBJECTS: bytes between elements */
  int parent;    /* row id of the enclosing object; -1 for the root */
  sk_type_t type;
  sk_range_t range;
  sk_at_t at;
  int lo_open; /* the range is (lo, hi] */
  int max;     /* SK_OBJECTS: elements */
  int has_def;
  int by_hook; /* read by its object's hook (rules between keys) */
  int params;  /* objects: the drive parameters "<path>.<name>" are keys too */
} scenario_key_t;

/* The table (scenario.c), indexed by row id; rows in reading order. */
const scenario_key_t *scenario_keys(unsigned *count);
/* The row's dotted path ("inject.can.rx.loss"; "inject.current[].kind"). */
void scenario_key_path(unsigned id, char *out, size_t n);
/* A row's range as read (the drive parameter's resolved). */
void scenario_key_range(const scenario_key_t *k, double *lo, double *hi);

/* The key reference (Markdown) of docs/scenarios.md. */
char *scenario_keys_markdown(void);
/* Checks (write = 0) or rewrites (write = 1) the reference between the
 * markers in the file at `doc`. Returns 0 when it agrees (or was
 * written), 1 when it differs, -1 on an I/O error or missing markers;
 * a message in err. */
int scenario_keys_doc(const char *doc, int write, char *err, size_t errlen);

#endif
