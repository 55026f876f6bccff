/*
 * The scenario key table (sil/runner/scenario_key_table.h) against the
 * parser that walks it: every key's path is unique and its object is an
 * object row; every key is accepted where the table puts it, and refused
 * with an error naming its path and the reason when it is of the wrong
 * type, out of its range (the message giving the range) or not a name of
 * its list; an unknown key in every object is refused naming it.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "scenario.h"
#include "scenario_keys.h"

/* {"duration": 1, "a": {"b": {"c": VALUE}}} for the row's path a.b.c
 * (an element of an array: [{...}]); duration itself: {"duration": VALUE}. */
static void json_with(unsigned id, const char *value, char *out, size_t n) {
  unsigned n_rows;
  const scenario_key_t *k = scenario_keys(&n_rows);
  unsigned chain[8];
  int depth = 0;
  for (int r = (int)id; r > 0 && depth < 8; r = k[r].parent) {
    chain[depth++] = (unsigned)r;
  }
  const int is_duration = depth == 1 && strcmp(k[id].key, "duration") == 0;
  int len = snprintf(out, n, "{%s", is_duration ? "" : "\"duration\": 1, ");
  for (int d = depth - 1; d >= 0; --d) {
    const scenario_key_t *r = &k[chain[d]];
    len += snprintf(out + len, n - (size_t)len, "\"%s\": ", r->key);
    if (d > 0) {
      len += snprintf(out + len, n - (size_t)len, "%s", r->type == SK_OBJECTS ? "[{" : "{");
    }
  }
  len += snprintf(out + len, n - (size_t)len, "%s", value);
  for (int d = 1; d < depth; ++d) {
    len += snprintf(out + len, n - (size_t)len, "%s", k[chain[d]].type == SK_OBJECTS ? "}]" : "}");
  }
  snprintf(out + len, n - (size_t)len, "}");
}

/* Whether a sibling of the row (or of an enclosing object) is required:
 * the parser then names that one first. */
static int has_required_sibling(unsigned id) {
  unsigned n;
  const scenario_key_t *k = scenario_keys(&n);
  for (int r = (int)id; r > 0; r = k[r].parent) {
    for (unsigned s = 0; s < n; ++s) {
      if (k[s].parent == k[r].parent && s != (unsigned)r && k[s].req != NULL && k[r].parent != 0) {
        return 1;
      }
    }
  }
  return 0;
}

static void expect_error(const char *js, const char *want) {
  static scenario_t sc;
  char err[600] = "";
  if (scenario_parse(js, "keys.json", &sc, err, sizeof err) == 0) {
    fail_msg("accepted %s (expected \"%s\")", js, want);
  }
  if (strstr(err, want) == NULL) {
    fail_msg("%s: got \"%s\", expected \"%s\"", js, err, want);
  }
}

static void paths_are_unique_and_objects_are_objects(void **state) {
  (void)state;
  unsigned n;
  const scenario_key_t *k = scenario_keys(&n);
  assert_true(n > 100);
  for (unsigned i = 1; i < n; ++i) {
    assert_true(k[i].parent >= 0 && (unsigned)k[i].parent < i);
    const sk_type_t pt = k[k[i].parent].type;
    assert_true(pt == SK_OBJECT || pt == SK_OBJECTS);
    assert_non_null(k[i].doc);
    char a[160], b[160];
    scenario_key_path(i, a, sizeof a);
    for (unsigned j = 1; j < i; ++j) {
      scenario_key_path(j, b, sizeof b);
      if (strcmp(a, b) == 0) {
        fail_msg("%s given twice in the table", a);
      }
    }
  }
}

static void wrong_type_and_range_name_the_key(void **state) {
  (void)state;
  unsigned n;
  const scenario_key_t *k = scenario_keys(&n);
  int checked = 0;
  for (unsigned i = 1; i < n; ++i) {
    if (k[i].by_hook || has_required_sibling(i)) {
      continue;
    }
    char path[160], js[600], want[300];
    scenario_key_path(i, path, sizeof path);
    /* the element index the parser writes: [0] */
    char *br = strstr(path, "[]");
    if (br != NULL) {
      memmove(br + 3, br + 2, strlen(br + 2) + 1);
      memcpy(br, "[0]", 3);
    }
    double lo, hi;
    scenario_key_range(&k[i], &lo, &hi);
    if (k[i].type == SK_NUM || k[i].type == SK_INT) {
      json_with(i, "\"x\"", js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must be a number", path);
      expect_error(js, want);
      char v[40];
      snprintf(v, sizeof v, "%.17g", hi + (hi > 1.0 ? hi : 1.0));
      json_with(i, v, js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must be in [%g, %g] (got", path, lo, hi);
      expect_error(js, want);
      ++checked;
    } else if (k[i].type == SK_ENUM) {
      json_with(i, "\"nope\"", js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must be one of: ", path);
      expect_error(js, want);
      ++checked;
    } else if (k[i].type == SK_BOUNDED) {
      char v[40];
      snprintf(v, sizeof v, "%.17g", hi + (hi > 1.0 ? hi : 1.0));
      json_with(i, v, js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must stay in %s%g, %g] at all times", path,
               k[i].lo_open ? "(" : "[", lo, hi);
      expect_error(js, want);
      ++checked;
    } else if (k[i].type == SK_OBJECT) {
      json_with(i, "{\"zz\": 1}", js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s.zz: unknown field", path);
      expect_error(js, want);
      json_with(i, "3", js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must be an object", path);
      expect_error(js, want);
      ++checked;
    } else if (k[i].type == SK_STRING && k[i].set == NULL) {
      json_with(i, "3", js, sizeof js);
      snprintf(want, sizeof want, "keys.json: %s: must be a string", path);
      expect_error(js, want);
      ++checked;
    }
  }
  assert_true(checked > 90);
}

static void required_keys_are_named(void **state) {
  (void)state;
  unsigned n;
  const scenario_key_t *k = scenario_keys(&n);
  for (unsigned i = 1; i < n; ++i) {
    if (k[i].req == NULL || k[i].parent == 0) {
      continue;
    }
    char path[160], js[600], want[300];
    scenario_key_path((unsigned)k[i].parent, path, sizeof path);
    /* the object with none of its keys: the first required one is named */
    json_with((unsigned)k[i].parent, "{}", js, sizeof js);
    unsigned first = 0;
    for (unsigned s = 1; s < n && first == 0; ++s) {
      first = k[s].parent == k[i].parent && k[s].req != NULL ? s : 0;
    }
    const int array = k[k[i].parent].type == SK_OBJECTS; /* inject.current: [{}] */
    snprintf(want, sizeof want, "keys.json: %s%s.%s: required (%s)", path, array ? "[0]" : "",
             k[first].key, k[first].req);
    if (array) {
      json_with((unsigned)k[i].parent, "[{}]", js, sizeof js);
      /* json_with wrote the array's own key: {"current": [{}]} */
    }
    expect_error(js, want);
  }
  expect_error("{\"name\": \"x\"}", "keys.json: duration: required (simulated time in seconds)");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(paths_are_unique_and_objects_are_objects),
                                     cmocka_unit_test(wrong_type_and_range_name_the_key),
                                     cmocka_unit_test(required_keys_are_named)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
