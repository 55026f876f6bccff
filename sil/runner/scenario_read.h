/*
 * scenario_read.h - the scenario parser's context and JSON readers
 * (scenario_read.c), private to sil/runner/scenario*.c. Every reader
 * reports the first error through scn_fail() and returns -1; an absent
 * optional key leaves its destination unchanged.
 */
#ifndef FD_SIL_SCENARIO_READ_H
#define FD_SIL_SCENARIO_READ_H

#include <cjson/cJSON.h>
#include <stddef.h>

#include "profile.h"

typedef struct sk_ctx {
  char *err;
  size_t errlen;
  const char *origin;
  int failed;
  int ls_given; /* machine.ls set both inductances (for the error's key) */
  /* the machine key that set the star point's p = b/a (3.7) the drive's
   * dfc_b follows, when controller.dfc_b is not given ("" otherwise) */
  char p_key[32];
  /* values the hooks combine (the table's AT_CTX rows) */
  double ls, star_phi_iq, star_p;
  double est[5]; /* controller.estimates: rs, ls, ld, lq, lambda_m scales */
  int cause;     /* inject.trip_cause's index, -1 none */
} ctx_t;

/* The first error, as "<origin>: <path>: <reason>", made valid UTF-8 (a key
 * or a string from the file may carry any bytes; the summary is JSON);
 * later ones are dropped. Returns -1. */
int scn_fail(ctx_t *c, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* "path.key" (or "key" at the top level) into out[n], cut to fit. */
void scn_join(char *out, size_t n, const char *path, const char *key);
/* s made valid UTF-8 in place. */
void scn_utf8_clean(char *s);
/* A key given twice in one object, anywhere in the tree: refused. */
int scn_check_duplicates(ctx_t *c, const cJSON *node, const char *path);
/* Keys of obj not in the NULL-terminated list: refused. */
int scn_check_list(ctx_t *c, const cJSON *obj, const char *path, const char *const *allowed);
/* An optional number in [lo, hi]. */
int scn_get_num(ctx_t *c, const cJSON *obj, const char *path, const char *key, double lo, double hi,
                double *out);
/* An optional name of the NULL-terminated list: its index. */
int scn_get_enum(ctx_t *c, const cJSON *obj, const char *path, const char *key,
                 const char *const *names, int *out);
/* An optional profile: a number, an array of terms or {"unit", "terms"}. */
int scn_get_profile(ctx_t *c, const cJSON *obj, const char *path, const char *key, profile_t *pr);
/* A profile whose terms' bounds stay in [lo, hi] ((lo, hi] with lo_open). */
int scn_get_bounded_profile(ctx_t *c, const cJSON *o, const char *path, const char *key, double lo,
                            int lo_open, double hi, profile_t *pr);

#endif
