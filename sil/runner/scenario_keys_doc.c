/*
 * scenario_keys_doc.c - the key reference of docs/scenarios.md, printed
 * from the key table (scenario_keys.h): one Markdown row per key, with its
 * type, range, default and doc; checked against the file (CTest
 * sil/scenario_keys_doc) or written into it between its markers.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenario_keys.h"

#define BEGIN_MARK "<!-- scenario-keys begin"
#define END_MARK   "<!-- scenario-keys end -->"
enum { DOC_MAX = 1 << 16 };

typedef struct {
  char *s;
  size_t n, cap;
} buf_t;

static void put(buf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(buf_t *b, const char *fmt, ...) {
  if (b->n + 1u >= b->cap) {
    return;
  }
  va_list ap;
  va_start(ap, fmt);
  /* the analyzer misses va_start on this path (as in scenario.c) */
  const int r =
      vsnprintf(b->s + b->n, b->cap - b->n, fmt, ap); // NOLINT(clang-analyzer-valist.Uninitialized)
  va_end(ap);
  if (r > 0) {
    b->n = b->n + (size_t)r < b->cap ? b->n + (size_t)r : b->cap - 1u;
  }
}

/* An enumeration's names, "`a`, `b`" (the row's list or its name_of). */
static void put_names(buf_t *b, const scenario_key_t *k) {
  for (int i = 0; i < 32; ++i) {
    const char *n = k->names != NULL ? k->names[i] : k->name_of(i);
    if (n == NULL) {
      return;
    }
    put(b, "%s`%s`", i ? ", " : "", n);
  }
}

static void put_range(buf_t *b, const scenario_key_t *k) {
  double lo, hi;
  scenario_key_range(k, &lo, &hi);
  put(b, "%s%.10g, %.10g]", k->lo_open ? "(" : "[", lo, hi);
}

static void put_row(buf_t *b, unsigned id, const scenario_key_t *k) {
  char path[160];
  scenario_key_path(id, path, sizeof path);
  put(b, "| `%s` | ", path);
  switch (k->type) {
  case SK_NUM:
    put(b, "number | ");
    put_range(b, k);
    break;
  case SK_INT:
    put(b, "integer | ");
    put_range(b, k);
    break;
  case SK_ENUM:
    put(b, "name | ");
    put_names(b, k);
    break;
  case SK_PROFILE:
    put(b, "profile | ");
    break;
  case SK_BOUNDED:
    put(b, "profile | ");
    if (!k->by_hook) {
      put_range(b, k);
    }
    break;
  case SK_STRING:
    put(b, "string | ");
    break;
  case SK_ARRAY3:
    put(b, "3 numbers | ");
    put_range(b, k);
    break;
  case SK_OBJECT:
    put(b, "object | ");
    break;
  case SK_OBJECTS:
    put(b, "array of objects | at most %d", k->max);
    break;
  }
  put(b, " | ");
  if (k->req != NULL) {
    put(b, "required");
  } else if (k->dflt != NULL) {
    put(b, "%s", k->dflt);
  } else if (k->has_def && k->type == SK_ENUM) {
    put(b, "`%s`", k->names != NULL ? k->names[(int)k->def] : k->name_of((int)k->def));
  } else if (k->has_def) {
    put(b, "%g", k->def);
  }
  put(b, " | %s |\n", k->doc != NULL ? k->doc : "");
  if (k->params) {
    put(b,
        "| `%s.<parameter>` | by the parameter | its range | its default | every parameter "
        "whose scenario key is `%s.<name>` (`docs/parameters.md`) |\n",
        path, path);
  }
}

char *scenario_keys_markdown(void) {
  buf_t b = {malloc(DOC_MAX), 0, DOC_MAX};
  if (b.s == NULL) {
    return NULL;
  }
  b.s[0] = '\0';
  unsigned n;
  const scenario_key_t *k = scenario_keys(&n);
  put(&b, "| key | type | range | default | meaning |\n|---|---|---|---|---|\n");
  for (unsigned i = 1; i < n; ++i) { /* row 0: the root */
    put_row(&b, i, &k[i]);
  }
  return b.s;
}

/* The file's text (malloc'ed), NULL when it cannot be read. */
static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    return NULL;
  }
  char *s = malloc((size_t)4 * DOC_MAX + 1);
  const size_t n = s != NULL ? fread(s, 1, (size_t)4 * DOC_MAX, f) : 0;
  fclose(f);
  if (s != NULL) {
    s[n] = '\0';
  }
  return s;
}

int scenario_keys_doc(const char *doc, int write, char *err, size_t errlen) {
  char *text = read_text(doc);
  char *gen = scenario_keys_markdown();
  int r = -1;
  char *b = text != NULL ? strstr(text, BEGIN_MARK) : NULL;
  char *e = b != NULL ? strstr(b, END_MARK) : NULL;
  char *body = b != NULL ? strchr(b, '\n') : NULL;
  if (text == NULL || gen == NULL) {
    snprintf(err, errlen, "%s: cannot read", doc);
  } else if (b == NULL || e == NULL || body == NULL || body > e) {
    snprintf(err, errlen, "%s: no \"%s ...\" and \"%s\" markers", doc, BEGIN_MARK, END_MARK);
  } else if ((size_t)(e - (body + 1)) == strlen(gen) && strncmp(body + 1, gen, strlen(gen)) == 0) {
    r = 0;
  } else if (!write) {
    snprintf(err, errlen,
             "%s: the scenario key reference differs from sil/runner/scenario_key_table.h: "
             "fluxdrive-sil --keys-doc-write %s",
             doc, doc);
    r = 1;
  } else {
    FILE *f = fopen(doc, "wb");
    const int ok = f != NULL && fwrite(text, 1, (size_t)(body + 1 - text), f) > 0 &&
                   fputs(gen, f) >= 0 && fputs(e, f) >= 0;
    r = f != NULL && fclose(f) == 0 && ok ? 0 : -1;
    if (r != 0) {
      snprintf(err, errlen, "%s: cannot write", doc);
    }
  }
  free(text);
  free(gen);
  return r;
}
