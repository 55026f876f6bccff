/*
 * scenario_read.c - the JSON readers of the scenario parser (scenario.c):
 * the first error as "<file>: <path>: <reason>" in valid UTF-8, keys given
 * twice, numbers in a range, names of a list, profiles (docs/scenarios.md,
 * "Profiles").
 */
#include "scenario_read.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define PI 3.14159265358979323846

/* The first error, as "<origin>: <path>: <reason>", made valid UTF-8 (a key
 * or a string from the file may carry any bytes; the summary is JSON). */
int scn_fail(ctx_t *c, const char *path, const char *fmt, ...) {
  if (c->failed) {
    return -1;
  }
  c->failed = 1;
  char reason[400];
  va_list ap;
  va_start(ap, fmt);
  /* the analyzer misses va_start on this path (LLVM 14) */
  vsnprintf(reason, sizeof reason, fmt, ap); // NOLINT(clang-analyzer-valist.Uninitialized)
  va_end(ap);
  snprintf(c->err, c->errlen, "%s: %s: %s", c->origin, path, reason);
  scn_utf8_clean(c->err);
  return -1;
}

void scn_join(char *out, size_t n, const char *path, const char *key) {
  int r = path[0] == '\0' ? snprintf(out, n, "%s", key) : snprintf(out, n, "%s.%s", path, key);
  if (r < 0 || (size_t)r >= n) {
    out[n - 1] = '\0';
  }
}

/* A key given twice in one object (JSON leaves it open; cJSON keeps both and
 * the lookups see the first): refused, with its path, anywhere in the
 * tree. Depth is bounded by cJSON's nesting limit. */
int scn_check_duplicates(ctx_t *c, const cJSON *node, const char *path) {
  for (const cJSON *it = node->child; it != NULL; it = it->next) {
    char p[160];
    if (cJSON_IsObject(node)) {
      for (const cJSON *jt = it->next; jt != NULL; jt = jt->next) {
        if (strcmp(it->string, jt->string) == 0) {
          scn_join(p, sizeof p, path, it->string);
          return scn_fail(c, p, "given twice (a key may appear once)");
        }
      }
      scn_join(p, sizeof p, path, it->string);
    } else {
      int k = 0;
      for (const cJSON *jt = node->child; jt != it; jt = jt->next) {
        ++k;
      }
      /* a longer path is cut (it only names the place in an error); the
       * bound keeps the index in p */
      snprintf(p, sizeof p, "%.140s[%d]", path, k);
    }
    if ((cJSON_IsObject(it) || cJSON_IsArray(it)) && scn_check_duplicates(c, it, p) != 0) {
      return -1;
    }
  }
  return 0;
}

/* s made valid UTF-8 in place: a sequence cut by a truncation at the end is
 * dropped, any other invalid byte becomes '?' (the summary is JSON, and
 * JSON is UTF-8). */
void scn_utf8_clean(char *s) {
  size_t i = 0;
  const size_t n = strlen(s);
  while (i < n) {
    const unsigned char b = (unsigned char)s[i];
    size_t len = b < 0x80u                    ? 1u
                 : (b >= 0xC2u && b <= 0xDFu) ? 2u
                 : (b >= 0xE0u && b <= 0xEFu) ? 3u
                 : (b >= 0xF0u && b <= 0xF4u) ? 4u
                                              : 0u;
    /* the second byte's range: no overlong forms, no surrogates, nothing
     * beyond U+10FFFF (RFC 3629) */
    const unsigned char lo = b == 0xE0u ? 0xA0u : (b == 0xF0u ? 0x90u : 0x80u);
    const unsigned char hi = b == 0xEDu ? 0x9Fu : (b == 0xF4u ? 0x8Fu : 0xBFu);
    size_t k = 1u;
    while (len > 1u && k < len && i + k < n) {
      const unsigned char x = (unsigned char)s[i + k];
      if (k == 1u ? (x < lo || x > hi) : (x & 0xC0u) != 0x80u) {
        break;
      }
      ++k;
    }
    if (len > 1u && k < len && i + k == n) {
      s[i] = '\0'; /* cut at the end: drop the partial sequence */
      return;
    }
    if (len == 0u || k < len) {
      s[i] = '?';
      len = 1u;
    }
    i += len;
  }
}

/* Rejects keys of obj that are not in the NULL-terminated list (profiles). */
int scn_check_list(ctx_t *c, const cJSON *obj, const char *path, const char *const *allowed) {
  if (!cJSON_IsObject(obj)) {
    return scn_fail(c, path[0] ? path : "(top level)", "must be an object");
  }
  for (const cJSON *it = obj->child; it != NULL; it = it->next) {
    int ok = 0;
    for (const char *const *a = allowed; *a != NULL; ++a) {
      ok |= strcmp(*a, it->string) == 0;
    }
    if (!ok) {
      char p[160];
      scn_join(p, sizeof p, path, it->string);
      return scn_fail(c, p, "unknown field");
    }
  }
  return 0;
}

/* Optional number in [lo, hi]; leaves *out unchanged when absent. */
int scn_get_num(ctx_t *c, const cJSON *obj, const char *path, const char *key, double lo, double hi,
                double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  scn_join(p, sizeof p, path, key);
  if (!cJSON_IsNumber(it)) {
    return scn_fail(c, p, "must be a number");
  }
  double v = it->valuedouble;
  if (!isfinite(v) || v < lo || v > hi) {
    return scn_fail(c, p, "must be in [%g, %g] (got %g)", lo, hi, v);
  }
  *out = v;
  return 0;
}

/* Optional string from a list; returns its index in *out. */
int scn_get_enum(ctx_t *c, const cJSON *obj, const char *path, const char *key,
                 const char *const *names, int *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  scn_join(p, sizeof p, path, key);
  char list[200] = "";
  for (int i = 0; names[i] != NULL; ++i) {
    if (cJSON_IsString(it) && strcmp(it->valuestring, names[i]) == 0) {
      *out = i;
      return 0;
    }
    strncat(list, i ? ", " : "", sizeof list - strlen(list) - 1);
    strncat(list, names[i], sizeof list - strlen(list) - 1);
  }
  return scn_fail(c, p, "must be one of: %s", list);
}

/* ---- profiles ---------------------------------------------------------- */

static int scn_parse_term(ctx_t *c, const cJSON *t, const char *path, double scale, profile_t *pr) {
  static const char *const kinds[] = {"const", "step", "ramp", "sine", NULL};
  static const char *const keys[] = {"type", "value", "t",         "t0", "t1",
                                     "freq", "phase", "amplitude", NULL};
  if (scn_check_list(c, t, path, keys) != 0) {
    return -1;
  }
  int kind = -1;
  if (scn_get_enum(c, t, path, "type", kinds, &kind) != 0) {
    return -1;
  }
  if (kind < 0) {
    char p[160];
    scn_join(p, sizeof p, path, "type");
    return scn_fail(c, p, "missing (const, step, ramp or sine)");
  }
  profile_term_t term = {.kind = (profile_kind_t)kind};
  const double big = 1e9;
  if (scn_get_num(c, t, path, kind == PROFILE_SINE ? "amplitude" : "value", -big, big,
                  &term.value) ||
      scn_get_num(c, t, path, kind == PROFILE_STEP ? "t" : "t0", 0.0, big, &term.t0) ||
      scn_get_num(c, t, path, "t1", 0.0, big, &term.t1) ||
      scn_get_num(c, t, path, "freq", 0.0, 1e6, &term.freq) ||
      scn_get_num(c, t, path, "phase", -1e3, 1e3, &term.phase)) {
    return -1;
  }
  if (kind == PROFILE_RAMP && !(term.t1 > term.t0)) {
    char p[160];
    scn_join(p, sizeof p, path, "t1");
    return scn_fail(c, p, "a ramp needs t1 > t0");
  }
  if (kind == PROFILE_SINE && !(term.freq > 0.0)) {
    char p[160];
    scn_join(p, sizeof p, path, "freq");
    return scn_fail(c, p, "a sine needs freq > 0");
  }
  term.value *= scale;
  if (profile_add(pr, term) != 0) {
    return scn_fail(c, path, "too many terms (at most %d)", PROFILE_MAX_TERMS);
  }
  return 0;
}

/* A profile: a number (constant), an array of terms, or
 * {"unit": "...", "terms": [...]} with unit conversion to SI. */
int scn_get_profile(ctx_t *c, const cJSON *obj, const char *path, const char *key, profile_t *pr) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  scn_join(p, sizeof p, path, key);
  *pr = (profile_t){0};
  double scale = 1.0;
  if (cJSON_IsNumber(it)) {
    if (!isfinite(it->valuedouble)) {
      return scn_fail(c, p, "must be finite");
    }
    return profile_add(pr, (profile_term_t){.kind = PROFILE_CONST, .value = it->valuedouble});
  }
  const cJSON *terms = it;
  if (cJSON_IsObject(it)) {
    static const char *const keys[] = {"unit", "terms", NULL};
    static const char *const units[] = {"si", "rpm", "deg", NULL};
    if (scn_check_list(c, it, p, keys) != 0) {
      return -1;
    }
    int u = 0;
    if (scn_get_enum(c, it, p, "unit", units, &u) != 0) {
      return -1;
    }
    scale = u == 1 ? PI / 30.0 : (u == 2 ? PI / 180.0 : 1.0);
    terms = cJSON_GetObjectItemCaseSensitive(it, "terms");
    char tp[160];
    scn_join(tp, sizeof tp, p, "terms");
    if (!cJSON_IsArray(terms)) {
      return scn_fail(c, tp, "must be an array of profile terms");
    }
    memcpy(p, tp, sizeof p);
  }
  if (!cJSON_IsArray(terms)) {
    return scn_fail(c, p, "must be a number, an array of terms or {\"unit\", \"terms\"}");
  }
  int i = 0;
  for (const cJSON *t = terms->child; t != NULL; t = t->next, ++i) {
    char tp[176];
    if (snprintf(tp, sizeof tp, "%s[%d]", p, i) >= (int)sizeof tp) {
      tp[sizeof tp - 1] = '\0';
    }
    if (scn_parse_term(c, t, tp, scale, pr) != 0) {
      return -1;
    }
  }
  return 0;
}

/* A profile whose every value (its terms' bounds, profile_bounds) lies in
 * [lo, hi] ((lo, hi] with lo_open). */
int scn_get_bounded_profile(ctx_t *c, const cJSON *o, const char *path, const char *key, double lo,
                            int lo_open, double hi, profile_t *pr) {
  if (scn_get_profile(c, o, path, key, pr) != 0) {
    return -1;
  }
  if (cJSON_GetObjectItemCaseSensitive(o, key) == NULL) {
    return 0;
  }
  double l, h;
  profile_bounds(pr, &l, &h);
  if ((lo_open ? !(l > lo) : !(l >= lo)) || !(h <= hi)) {
    char p[160];
    scn_join(p, sizeof p, path, key);
    return scn_fail(c, p, "must stay in %s%g, %g] at all times (its terms reach [%g, %g])",
                    lo_open ? "(" : "[", lo, hi, l, h);
  }
  return 0;
}
