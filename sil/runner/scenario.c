/*
 * scenario.c - JSON scenario loading (schema: docs/scenarios.md).
 *
 * The keys are a table (scenario_keys.h, scenario_key_table.h) the parser
 * walks: every object is checked for unknown keys, every value for its
 * row's type and range (numbers also for finiteness); the first error is
 * reported as "<file>: <field path>: <reason>". The rules between keys are
 * the object rows' hooks (the section "the hooks" below). The parameter sets are then validated as
 * a whole by plant_check() and drive_config_check(), whose field names are reported the same way.
 */
#include "scenario.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "board_presets.h"
#include "drive.h"
#include "map_load.h"
#include "presets.h"
#include "scenario_key_table.h"
#include "scenario_keys.h"
#include "scenario_read.h"

/* the load grid (0 .. i_trip) Theorem 1 is checked on (check_star) */
#define STAR_LOAD_STEPS 256
/* star_tau at most this share of the sample's settling time (dfc_t_meas -
 * dead time): measured on the fabbri2022 presets, docs/dfc.md */
#define STAR_TAU_SHARE 0.2

/* ---- machines ---------------------------------------------------------- */

/* A flux map into plant and drive: the pole pairs are the map's; pp > 0,
 * the scenario's machine.pole_pairs: a map file without them takes them,
 * one with others is refused naming both. */
static int use_map(ctx_t *c, const char *key, const char *file, int pp, scenario_t *sc) {
  char why[640];
  const map_load_t *e = map_load(file, c->origin, pp, why, sizeof why);
  if (e == NULL) {
    if (strstr(why, ": pole pairs: ") != NULL) { /* the map tool's check (fluxmap/io.py) */
      return pp > 0 ? scn_fail(c, "machine.pole_pairs", "%d: %s", pp, why)
                    : scn_fail(c, "machine.pole_pairs", "required: %s", why);
    }
    return scn_fail(c, key, "%s", why);
  }
  if (pp > 0 && e->map.pole_pairs != (float)pp) {
    return scn_fail(c, "machine.pole_pairs", "%d, but the map file %s has %g", pp, file,
                    (double)e->map.pole_pairs);
  }
  sc->plant.machine.map = e->plant;
  snprintf(sc->map_file, sizeof sc->map_file, "%s", e->path);
  sc->plant.machine.pole_pairs = (int)e->map.pole_pairs;
  sc->drive.machine_map = e->words;
  return 0;
}

/* The first star-point key the machine section gives ("machine.star_p",
 * ...), NULL for none. */
static const char *star_key_given(const cJSON *m) {
  static const char *const keys[] = {"machine.star_p",         "machine.star_m2",
                                     "machine.star_m0",        "machine.star_amp_iq",
                                     "machine.star_phi_iq",    "machine.star_phi_self",
                                     "machine.star_phi_mutual"};
  for (size_t k = 0; m != NULL && k < sizeof keys / sizeof keys[0]; ++k) {
    if (cJSON_GetObjectItemCaseSensitive(m, keys[k] + 8) != NULL) {
      return keys[k];
    }
  }
  return NULL;
}

/* One controller parameter, by its type: a number in the table's range,
 * or the name of a law, mode or position source. */
static int get_param(ctx_t *c, const cJSON *o, const drive_param_t *p, drive_config_t *d) {
  const char *key = p->scenario + 11;
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, key);
  if (it == NULL) {
    return 0;
  }
  int idx = -1;
  if (p->type == DRIVE_PARAM_LAW || p->type == DRIVE_PARAM_MODE || p->type == DRIVE_PARAM_POS) {
    enum { NAMES_MAX = 16 };
    _Static_assert((int)DRIVE_LAW_COUNT < (int)NAMES_MAX &&
                       (int)DRIVE_MODE_COUNT < (int)NAMES_MAX &&
                       (int)POS_SOURCE_COUNT < (int)NAMES_MAX,
                   "an enumeration outgrows the scenario's name list");
    const char *names[NAMES_MAX];
    unsigned n = 0;
    for (unsigned v = 0; v <= (unsigned)p->max && n + 1u < (unsigned)NAMES_MAX; ++v) {
      names[n++] = p->type == DRIVE_PARAM_LAW    ? drive_law_name(v)
                   : p->type == DRIVE_PARAM_MODE ? drive_mode_name(v)
                                                 : drive_pos_source_name(v);
    }
    names[n] = NULL;
    if (scn_get_enum(c, o, "controller", key, names, &idx) != 0) {
      return -1;
    }
    drive_param_set(d, p, (float)idx);
    return 0;
  }
  double v = (double)drive_param_get(d, p);
  if (scn_get_num(c, o, "controller", key, (double)p->min, (double)p->max, &v) != 0) {
    return -1;
  }
  if (p->type != DRIVE_PARAM_F32 && floor(v) != v) {
    return scn_fail(c, p->scenario, "must be an integer (got %g)", v);
  }
  drive_param_set(d, p, (float)v);
  return 0;
}

/* ---- the key table -------------------------------------------------------- */

#define DEFAULT_BOARD       "g474_nucleo"
#define FAULT_NAME(E, n, d) #n,
static const char *const inverter_models[] = {"average", "switching", NULL};
static const char *const dc_kinds[] = {"ideal", "rc", "rectifier", NULL};
static const char *const mech_modes[] = {"free", "imposed", NULL};
static const char *const fault_names[] = {DRIVE_FAULT_LIST(FAULT_NAME) NULL};
static const char *const switch_names[] = {"a_low", "a_high", "b_low", "b_high",
                                           "c_low", "c_high", NULL};
static const char *const phase_names[] = {"a", "b", "c", NULL};
static const char *const pair_names[] = {"ab", "bc", "ca", NULL};

/* the enumerations stored as int (SK_AT_INT) */
_Static_assert(sizeof(plant_inverter_model_t) == sizeof(int) &&
                   sizeof(plant_dc_kind_t) == sizeof(int) &&
                   sizeof(plant_mech_mode_t) == sizeof(int) &&
                   sizeof(sil_adc_kind_t) == sizeof(int),
               "an enumeration the key table stores as int is not int-sized");

static int root_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int set_name(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int machine_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int machine_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int inverter_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int set_pwm_frequency(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int mechanics_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int sensors_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int controller_params(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int controller_map(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int estimates_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int inject_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int current_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int current_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int encoder_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int can_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int can_dir_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int passive_load_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int board_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int commission_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int commission_proc(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static int commission_post(ctx_t *c, scenario_t *sc, const sk_val_t *v);
static const char *sil_proc_name(int index);

#define SK_ID(id, ...) id,
enum { SCENARIO_KEYS(SK_ID) K_COUNT };
#define SK_ROW(id, ...) [id] = {__VA_ARGS__},
static const scenario_key_t rows[K_COUNT] = {SCENARIO_KEYS(SK_ROW)};

const scenario_key_t *scenario_keys(unsigned *count) {
  *count = K_COUNT;
  return rows;
}

void scenario_key_path(unsigned id, char *out, size_t n) {
  char up[160] = "";
  const scenario_key_t *k = &rows[id];
  if (k->parent > K_ROOT) {
    scenario_key_path((unsigned)k->parent, up, sizeof up);
    if (rows[k->parent].type == SK_OBJECTS) {
      strncat(up, "[]", sizeof up - strlen(up) - 1);
    }
  }
  scn_join(out, n, up, k->key);
}

void scenario_key_range(const scenario_key_t *k, double *lo, double *hi) {
  const drive_param_t *p = k->param != NULL ? drive_params_by_name(k->param) : NULL;
  *lo = k->lo;
  *hi = k->hi;
  if (p != NULL && k->range == SK_RANGE_PARAM) {
    *lo = (double)p->min;
    *hi = (double)p->max;
  } else if (p != NULL && k->range == SK_RANGE_PARAM_INV) {
    *lo = 1.0 / (double)p->max;
    *hi = 1.0 / (double)p->min;
  } else if (p != NULL && k->range == SK_RANGE_PARAM_HI) {
    *hi = (double)p->max;
  }
}

/* The names of an SK_ENUM row, NULL-terminated, in names[max]. */
static const char *const *enum_names(const scenario_key_t *k, const char **names, int max) {
  if (k->names != NULL) {
    return k->names;
  }
  int n = 0;
  for (; n + 1 < max && k->name_of(n) != NULL; ++n) {
    names[n] = k->name_of(n);
  }
  names[n] = NULL;
  return names;
}

/* Stores a number (or an enumeration's index) where the row says. */
static int store(ctx_t *c, scenario_t *sc, const scenario_key_t *k, const sk_val_t *v) {
  if (k->set != NULL) {
    return k->set(c, sc, v);
  }
  char *at = (k->at >= SK_AT_CTX_F64 ? (char *)c : (char *)sc) + k->offset + v->shift;
  switch (k->at) {
  case SK_AT_F64:
  case SK_AT_CTX_F64:
    *(double *)(void *)at = v->num;
    break;
  case SK_AT_F32:
    *(float *)(void *)at = (float)v->num;
    break;
  case SK_AT_INT:
  case SK_AT_CTX_INT:
    *(int *)(void *)at = (int)v->num;
    break;
  case SK_AT_U32:
    *(uint32_t *)(void *)at = (uint32_t)(int)v->num;
    break;
  case SK_AT_BOOL:
    *(bool *)(void *)at = v->num != 0.0;
    break;
  default:
    break;
  }
  return 0;
}

/* A row's number: its type (SK_NUM, SK_INT) and range checked. */
static int read_num(ctx_t *c, const cJSON *obj, const char *path, unsigned id, double *out) {
  const scenario_key_t *k = &rows[id];
  double lo, hi;
  scenario_key_range(k, &lo, &hi);
  if (scn_get_num(c, obj, path, k->key, lo, hi, out) != 0) {
    return -1;
  }
  if (k->type == SK_INT && floor(*out) != *out) {
    char p[160];
    scn_join(p, sizeof p, path, k->key);
    return scn_fail(c, p, "must be an integer (got %g)", *out);
  }
  return 0;
}

/* An array of 3 numbers (phases a, b, c) in the row's range. */
static int read_array3(ctx_t *c, const cJSON *arr, const char *p, const scenario_key_t *k,
                       double *dst) {
  if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) != 3) {
    return scn_fail(c, p, "must be an array of 3 numbers (phases a, b, c)");
  }
  for (int i = 0; i < 3; ++i) {
    const cJSON *v = cJSON_GetArrayItem(arr, i);
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble < k->lo ||
        v->valuedouble > k->hi) {
      return scn_fail(c, p, "element %d must be a finite number", i);
    }
    dst[i] = v->valuedouble;
  }
  return 0;
}

/* Rejects the keys of obj that are not rows of object `id` (nor, for
 * the controller, drive parameters "<path>.<name>"). */
static int check_keys(ctx_t *c, const cJSON *obj, const char *path, unsigned id) {
  if (!cJSON_IsObject(obj)) {
    char list[300] = "";
    for (unsigned k = 0; k < K_COUNT && !rows[id].params; ++k) {
      if (rows[k].parent == (int)id) {
        strncat(list, list[0] ? ", " : " (", sizeof list - strlen(list) - 1);
        strncat(list, rows[k].key, sizeof list - strlen(list) - 1);
      }
    }
    strncat(list, list[0] ? ")" : "", sizeof list - strlen(list) - 1);
    return scn_fail(c, path[0] ? path : "(top level)", "must be an object%s", list);
  }
  for (const cJSON *it = obj->child; it != NULL; it = it->next) {
    int ok = 0;
    for (unsigned k = 0; k < K_COUNT && !ok; ++k) {
      ok = rows[k].parent == (int)id && strcmp(rows[k].key, it->string) == 0;
    }
    if (!ok && rows[id].params) {
      char p[160];
      scn_join(p, sizeof p, path, it->string);
      unsigned n;
      const drive_param_t *t = drive_params_table(&n);
      for (unsigned i = 0; i < n && !ok; ++i) {
        ok = strcmp(t[i].scenario, p) == 0;
      }
    }
    if (!ok) {
      char p[160];
      scn_join(p, sizeof p, path, it->string);
      return scn_fail(c, p, "unknown field");
    }
  }
  return 0;
}

static int walk(ctx_t *c, scenario_t *sc, const cJSON *o, const char *path, unsigned id,
                size_t shift, int index);

/* One key of object `id`'s row k: read by its type, stored or set. */
static int read_key(ctx_t *c, scenario_t *sc, const cJSON *o, const char *path, unsigned kid,
                    size_t shift, int index) {
  const scenario_key_t *k = &rows[kid];
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, k->key);
  char p[160];
  scn_join(p, sizeof p, path, k->key);
  if (it == NULL) {
    return k->req != NULL ? scn_fail(c, p, "required (%s)", k->req) : 0;
  }
  if (k->by_hook) {
    return 0;
  }
  sk_val_t v = {it, p, 0.0, index, shift, k};
  char *base = (char *)sc + k->offset + shift;
  switch (k->type) {
  case SK_NUM:
  case SK_INT:
    return read_num(c, o, path, kid, &v.num) ? -1 : store(c, sc, k, &v);
  case SK_ENUM: {
    const char *buf[20];
    int idx = -1;
    if (scn_get_enum(c, o, path, k->key, enum_names(k, buf, 20), &idx) != 0) {
      return -1;
    }
    v.num = idx;
    return store(c, sc, k, &v);
  }
  case SK_PROFILE:
    return scn_get_profile(c, o, path, k->key, (profile_t *)(void *)base);
  case SK_BOUNDED:
    return scn_get_bounded_profile(c, o, path, k->key, k->lo, k->lo_open, k->hi,
                                   (profile_t *)(void *)base);
  case SK_STRING:
    if (!cJSON_IsString(it)) {
      return scn_fail(c, p, "must be a string");
    }
    return k->set != NULL ? k->set(c, sc, &v) : 0;
  case SK_ARRAY3:
    return read_array3(c, it, p, k, (double *)(void *)base);
  case SK_OBJECT:
    return walk(c, sc, it, p, kid, shift, index);
  case SK_OBJECTS: {
    if (!cJSON_IsArray(it)) {
      return scn_fail(c, p, "must be an array of %s", k->doc);
    }
    int i = 0;
    for (const cJSON *e = it->child; e != NULL; e = e->next, ++i) {
      char ep[176];
      if (snprintf(ep, sizeof ep, "%s[%d]", p, i) >= (int)sizeof ep) {
        ep[sizeof ep - 1] = '\0';
      }
      /* the element's shift: at most k->max of them (its pre hook refuses more) */
      const size_t s = shift + (size_t)(i < k->max ? i : 0) * k->stride;
      if (walk(c, sc, e, ep, kid, s, i) != 0) {
        return -1;
      }
    }
    return 0;
  }
  }
  return 0;
}

/* Object `id` at path: its keys checked, its nested defaults stored, its
 * hooks around its keys read in the table's order. */
static int walk(ctx_t *c, scenario_t *sc, const cJSON *o, const char *path, unsigned id,
                size_t shift, int index) {
  if (check_keys(c, o, path, id) != 0) {
    return -1;
  }
  const scenario_key_t *obj = &rows[id];
  const sk_val_t v = {o, path, 0.0, index, shift, obj};
  /* the defaults of a nested object (the top level's: scenario_defaults) */
  for (unsigned k = 0; k < K_COUNT && id != K_ROOT && obj->parent != K_ROOT; ++k) {
    if (rows[k].parent == (int)id && rows[k].has_def) {
      const sk_val_t d = {NULL, path, rows[k].def, index, shift, &rows[k]};
      store(c, sc, &rows[k], &d);
    }
  }
  if (obj->set != NULL && obj->set(c, sc, &v) != 0) {
    return -1;
  }
  for (unsigned k = 0; k < K_COUNT; ++k) {
    if (rows[k].parent == (int)id && read_key(c, sc, o, path, k, shift, index) != 0) {
      return -1;
    }
  }
  return obj->post != NULL ? obj->post(c, sc, &v) : 0;
}

/* ---- the hooks: rules between keys --------------------------------------- */

static int root_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)sc;
  return scn_check_duplicates(c, v->it, "");
}

static int set_name(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)c;
  snprintf(sc->name, sizeof sc->name, "%s", ((const cJSON *)v->it)->valuestring);
  scn_utf8_clean(sc->name);
  return 0;
}

/* The scenario's pole pairs first (a map file may need them), then the
 * preset and the map; what a flux-map machine cannot take. */
static int machine_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const cJSON *m = v->it;
  double pp_given = 0.0;
  if (read_num(c, m, "machine", K_M_POLE_PAIRS, &pp_given) != 0) {
    return -1;
  }
  const cJSON *pre = cJSON_GetObjectItemCaseSensitive(m, "preset");
  if (pre != NULL) {
    const machine_preset_t *p = cJSON_IsString(pre) ? preset_find(pre->valuestring) : NULL;
    if (p == NULL) {
      return scn_fail(c, "machine.preset", "unknown preset (known: %s)", preset_names());
    }
    preset_apply(p, &sc->plant, &sc->drive);
    if (p->map != NULL && use_map(c, "machine.preset", p->map, (int)pp_given, sc) != 0) {
      return -1;
    }
  }
  const cJSON *map = cJSON_GetObjectItemCaseSensitive(m, "map");
  if (map != NULL) {
    if (!cJSON_IsString(map) || map->valuestring[0] == '\0') {
      return scn_fail(c, "machine.map", "must be a file name (.fdmap, .npz, .csv)");
    }
    if (use_map(c, "machine.map", map->valuestring, (int)pp_given, sc) != 0) {
      return -1;
    }
  }
  if (sc->plant.machine.map != NULL) {
    static const char *const linear_only[] = {"ld",     "lq",    "ls", "lambda_m",
                                              "ld_sat", "i_sat", NULL};
    for (int k = 0; linear_only[k] != NULL; ++k) {
      if (cJSON_GetObjectItemCaseSensitive(m, linear_only[k]) != NULL) {
        char key[32];
        snprintf(key, sizeof key, "machine.%s", linear_only[k]);
        return scn_fail(c, key,
                        "a flux-map machine takes its inductances and PM flux from the map");
      }
    }
  }
  /* the star point's inductance matrix (3.3), plant.h */
  const char *star = star_key_given(m);
  if (star != NULL && sc->plant.machine.map != NULL) {
    return scn_fail(c, star, "the star-point model needs a linear machine (no map)");
  }
  c->ls = -1.0;
  return 0;
}

/* ls for ld and lq; the magnet's saturation; the star point's aliases
 * (star_phi_iq, star_p); the drive's machine from the plant's. */
static int machine_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const cJSON *m = v->it;
  plant_machine_t *pm = &sc->plant.machine;
  if (c->ls > 0.0) {
    if (cJSON_GetObjectItemCaseSensitive(m, "ld") || cJSON_GetObjectItemCaseSensitive(m, "lq")) {
      return scn_fail(c, "machine.ls", "give either ls (SPM) or ld and lq, not both");
    }
    pm->ld = pm->lq = c->ls;
    c->ls_given = 1;
  }
  /* the magnet's d-axis saturation (plant.h, plant_magnetics.h) */
  if (pm->ld_sat > 0.0 && !(pm->i_sat > 0.0)) {
    return scn_fail(c, "machine.i_sat", "must be given (> 0 A) with machine.ld_sat > 0");
  }
  /* the cogging torque (plant_mech.c): its order with its amplitude */
  if (sc->plant.mech.cog_amp != 0.0 && sc->plant.mech.cog_order < 1) {
    return scn_fail(c, "machine.cogging_order",
                    "must be given (periods per mechanical turn, >= 1) with machine.cogging_amp");
  }
  /* star_phi_iq: both terms' shift (a turned saliency axis: phi_a = phi_iq,
   * phi_b = 2 phi_iq of (3.97)), an alias of the pair */
  if (cJSON_GetObjectItemCaseSensitive(m, "star_phi_iq") != NULL) {
    if (cJSON_GetObjectItemCaseSensitive(m, "star_phi_self") ||
        cJSON_GetObjectItemCaseSensitive(m, "star_phi_mutual")) {
      return scn_fail(c, "machine.star_phi_iq",
                      "sets star_phi_self and star_phi_mutual both: give either it or them");
    }
    pm->aniso.phi_self = c->star_phi_iq;
    pm->aniso.phi_mut = pm->aniso.phi_self;
  }
  /* star_p: the anisotropy p of (3.7) with L0, M0, L2 kept (Fig. 3.3):
   * gamma0 = L0 - M0, gamma2 = p gamma0 = L2/2 + M2, ld, lq = gamma0 +- gamma2 */
  if (cJSON_GetObjectItemCaseSensitive(m, "star_p") != NULL) {
    const double p = c->star_p;
    if (cJSON_GetObjectItemCaseSensitive(m, "ld") || cJSON_GetObjectItemCaseSensitive(m, "lq") ||
        cJSON_GetObjectItemCaseSensitive(m, "star_m2")) {
      return scn_fail(c, "machine.star_p", "sets ld, lq and star_m2: give none of them with it");
    }
    const double l0 = 0.5 * (pm->ld + pm->lq) + pm->aniso.m0;
    const double l2 = (pm->ld - pm->lq) - 2.0 * pm->aniso.m2;
    const double g0 = l0 - pm->aniso.m0, g2 = p * g0;
    pm->ld = g0 + g2;
    pm->lq = g0 - g2;
    pm->aniso.m2 = g2 - 0.5 * l2;
  }
  if (star_key_given(m) != NULL) {
    pm->aniso.enabled = 1; /* checked with the whole scenario known (check_star) */
  }
  if (pm->aniso.enabled) { /* the controller's DFC model (3.7), unless set */
    double a, b;
    plant_aniso_ab(pm, &a, &b);
    sc->drive.dfc_a = (float)a;
    sc->drive.dfc_b = (float)b;
  }
  sc->drive.pole_pairs = (float)pm->pole_pairs;
  sc->drive.rs = (float)pm->rs;
  sc->drive.ld = (float)pm->ld;
  sc->drive.lq = (float)pm->lq;
  sc->drive.lambda_m = (float)pm->lambda_m;
  return 0;
}

static int set_pwm_frequency(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)c;
  sc->plant.ts = 1.0 / v->num;
  return 0;
}

static int inverter_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)c;
  sc->drive.ts = (float)sc->plant.ts;
  sc->drive.dead_time = (float)sc->plant.inverter.dead_time;
  /* the board's datasheet figure: the devices' mean resistance in a
   * phase's path at standstill (half the period each, proc_rs.c), unless
   * the scenario states another (a datasheet's tolerance) */
  if (!cJSON_GetObjectItemCaseSensitive(v->it, "r_dev")) {
    sc->drive.r_dev = (float)(0.5 * (sc->plant.inverter.r_on_sw + sc->plant.inverter.r_diode));
  }
  return 0;
}

static int mechanics_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  plant_mech_t *m = &sc->plant.mech;
  if (m->mode == PLANT_MECH_IMPOSED && !cJSON_GetObjectItemCaseSensitive(v->it, "speed")) {
    return scn_fail(c, "mechanics.speed", "required when mode is \"imposed\"");
  }
  sc->drive.inertia = (float)m->j;
  sc->drive.friction = (float)m->b;
  return 0;
}

static int sensors_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)c;
  (void)v;
  sc->drive.enc_cpr = (uint32_t)sc->plant.sensors.encoder_cpr;
  return 0;
}

/* The drive's parameters "controller.<name>" (drive_param_table.h). */
static int controller_params(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  for (unsigned i = 0; i < n; ++i) {
    if (strncmp(t[i].scenario, "controller.", 11) == 0 &&
        get_param(c, v->it, &t[i], &sc->drive) != 0) {
      return -1;
    }
  }
  return 0;
}

/* The drive's own flux map (controller.map: an identified one, the
 * commissioning's), the plant keeping its own: both maps of one machine
 * (the same pole pairs). */
static int controller_map(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const cJSON *it = v->it;
  if (sc->plant.machine.map == NULL) {
    return scn_fail(c, v->path, "needs a flux-map machine (machine.map or a map preset)");
  }
  char why[640];
  const int pp = sc->plant.machine.pole_pairs;
  const map_load_t *e = map_load(it->valuestring, c->origin, pp, why, sizeof why);
  if (e == NULL) {
    return scn_fail(c, v->path, "%s", why);
  }
  if (e->map.pole_pairs != (float)pp) {
    return scn_fail(c, v->path, "%s has %g pole pairs, the machine %d", it->valuestring,
                    (double)e->map.pole_pairs, pp);
  }
  sc->drive.machine_map = e->words;
  return 0;
}

/* Detuning: the controller's machine estimates as factors of the plant's. */
static int estimates_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  drive_config_t *d = &sc->drive;
  if (sc->plant.machine.map != NULL) {
    /* a map machine's model is its map: these factors would act on
     * nothing (scaling the controller's map comes with the decoupled DFVC) */
    for (unsigned k = K_C_E_LS; k <= K_C_E_LAMBDA_M; ++k) {
      if (cJSON_GetObjectItemCaseSensitive(v->it, rows[k].key) != NULL) {
        char key[64];
        scn_join(key, sizeof key, v->path, rows[k].key);
        return scn_fail(c, key, "a flux-map machine's model is its map (only rs_scale applies)");
      }
    }
  }
  d->rs = (float)(sc->plant.machine.rs * c->est[0]);
  d->ld = (float)(sc->plant.machine.ld * c->est[2] * c->est[1]);
  d->lq = (float)(sc->plant.machine.lq * c->est[3] * c->est[1]);
  d->lambda_m = (float)(sc->plant.machine.lambda_m * c->est[4]);
  return 0;
}

/* trip_at with trip_cause; the power-stage faults' rules; what each
 * plant fault needs of the machine and the link. */
static int inject_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const cJSON *o = v->it;
  const plant_faults_t *pf = &sc->plant.faults;
  const int cause = c->cause;
  if ((cause >= 0) != (sc->trip_at > 0.0)) {
    return scn_fail(c, cause >= 0 ? "inject.trip_at" : "inject.trip_cause",
                    "trip_at (> 0) and trip_cause go together");
  }
  sc->trip_cause = cause >= 0 ? 1u << (unsigned)cause : 0u;
  if (cJSON_GetObjectItemCaseSensitive(o, "phase_short") != NULL &&
      cJSON_GetObjectItemCaseSensitive(o, "phase_open") != NULL &&
      (sc->phase_open.target == sc->phase_short.target ||
       sc->phase_open.target == (sc->phase_short.target + 1) % 3)) {
    return scn_fail(c, "inject.phase_short",
                    "shares a lead with inject.phase_open (an open lead cannot be shorted)");
  }
  static const unsigned power[] = {K_I_SWITCH_OPEN, K_I_SWITCH_CLOSED, K_I_PHASE_LOST,
                                   K_I_PHASE_OPEN,  K_I_PHASE_SHORT,   K_I_GROUND_SHORT};
  for (size_t k = 0; k < sizeof power / sizeof power[0]; ++k) {
    if (cJSON_GetObjectItemCaseSensitive(o, rows[power[k]].key) == NULL) {
      continue;
    }
    sc->power_faults = 1;
    if (sc->plant.inverter.model != PLANT_INV_SWITCHING) {
      char p[160];
      scn_join(p, sizeof p, v->path, rows[power[k]].key);
      return scn_fail(c, p,
                      "needs inverter.model: switching (a fault of the switch-level circuit)");
    }
  }
  if (pf->lambda_m_scale.n > 0 && sc->plant.machine.map != NULL) {
    return scn_fail(c, "inject.lambda_m_scale",
                    "a flux-map machine's PM flux is inside its map (saturated with the currents): "
                    "give the demagnetised machine as its own map (machine.map)");
  }
  if (pf->star_shift.n > 0 && !sc->plant.machine.aniso.enabled) {
    return scn_fail(c, "inject.star_shift",
                    "needs a star-point machine (machine.star_m0, star_m2 or a star-point preset)");
  }
  if (pf->c_scale.n > 0 && sc->plant.dclink.kind == PLANT_DC_IDEAL) {
    return scn_fail(c, "inject.c_scale",
                    "needs dc_link.kind \"rc\" or \"rectifier\" (an ideal link has no capacitor)");
  }
  return 0;
}

/* inject.current[i]: at most SIL_ADC_FAULTS_MAX, each from a clean slate. */
static int current_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  if (v->index >= SIL_ADC_FAULTS_MAX) {
    return scn_fail(c, v->path, "too many channel faults (at most %d)", SIL_ADC_FAULTS_MAX);
  }
  sc->current_faults.f[v->index] = (sil_adc_fault_t){.channel = -1, .kind = SIL_ADC_KIND_COUNT};
  return 0;
}

/* Its value, by its kind: a stuck or drifting channel reads within its
 * ADC's range; a gain from 0 (dead) to 10 times. */
static int current_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  sil_adc_fault_t *f = &sc->current_faults.f[v->index];
  const bool has = cJSON_GetObjectItemCaseSensitive(v->it, "value") != NULL;
  char q[190];
  scn_join(q, sizeof q, v->path, "value");
  if (sil_adc_kind_has_value(f->kind) != has) {
    return scn_fail(c, q, has ? "not taken by kind \"%s\"" : "required for kind \"%s\"",
                    sil_adc_kind_name((int)f->kind));
  }
  if (has) {
    const bool gain = f->kind == SIL_ADC_GAIN;
    const double fsc = sc->plant.sensors.i_full_scale;
    if (scn_get_bounded_profile(c, v->it, v->path, "value", gain ? -1.0 : -fsc, 0, gain ? 9.0 : fsc,
                                &f->value) != 0) {
      return -1;
    }
  }
  sc->current_faults.n = v->index + 1;
  return 0;
}

static int encoder_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)v;
  if (sc->encoder_faults.missing > 0.0 && sc->plant.sensors.encoder_cpr <= 0) {
    return scn_fail(c, "inject.encoder.missing",
                    "needs counts to lose: sensors.encoder_cpr > 0 (0 is an ideal encoder)");
  }
  return 0;
}

static int can_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  (void)c;
  (void)v;
  sc->can_faults.on = true;
  return 0;
}

static int can_dir_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const sil_can_dir_t *d = (const sil_can_dir_t *)(const void *)((char *)sc + v->row->offset);
  if (d->every == 1u) {
    char p[160];
    scn_join(p, sizeof p, v->path, "every");
    return scn_fail(c, p, "must be 0 (none) or at least 2 (1 would lose every frame: use loss 1)");
  }
  return 0;
}

static int passive_load_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  if (sc->plant.mech.mode != PLANT_MECH_FREE) {
    return scn_fail(c, v->path, "needs mechanics.mode \"free\" (a dynamometer imposes the speed)");
  }
  return 0;
}

/* The board the SIL HAL models: a preset (its board header's numbers),
 * which the keys then override. Read after the inverter (period and dead
 * time). */
static int board_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const cJSON *pre = cJSON_GetObjectItemCaseSensitive(v->it, "preset");
  const sil_board_preset_t *bp =
      pre == NULL ? sil_board_find(DEFAULT_BOARD)
                  : (cJSON_IsString(pre) ? sil_board_find(pre->valuestring) : NULL);
  if (bp == NULL) {
    return scn_fail(c, "board.preset", "unknown board (known: %s)", sil_board_names());
  }
  sil_board_apply(bp, sc->plant.ts, sc->plant.inverter.dead_time, &sc->board);
  return 0;
}

/* The defaults: the preset rubino2020_spm's, then the table's for the
 * top-level sections' keys. */
static void scenario_defaults(ctx_t *c, scenario_t *sc) {
  memset(sc, 0, sizeof *sc);
  snprintf(sc->name, sizeof sc->name, "unnamed");
  drive_config_default(&sc->drive);
  preset_apply(preset_find("rubino2020_spm"), &sc->plant, &sc->drive);
  for (unsigned k = 0; k < K_COUNT; ++k) {
    if (rows[k].has_def && rows[k].parent > K_ROOT && rows[rows[k].parent].parent == K_ROOT) {
      const sk_val_t d = {NULL, "", rows[k].def, 0, 0, &rows[k]};
      store(c, sc, &rows[k], &d);
    }
  }
  sc->drive.ts = (float)sc->plant.ts;
}

/* The scenario key of a plant parameter plant_check names (its fields are
 * the plant's struct members; errors name what the user wrote): the row's
 * plant_field, else the same name (machine.*, inverter.*, sensors.*). */
static const char *scenario_key_of(const char *plant_field) {
  static char out[160];
  for (unsigned k = 0; k < K_COUNT; ++k) {
    if (rows[k].plant_field != NULL && strcmp(rows[k].plant_field, plant_field) == 0) {
      scenario_key_path(k, out, sizeof out);
      return out;
    }
  }
  return plant_field;
}

/* The plant's integration steps per period: the fewest that keep it stable
 * on this machine (plant_substeps_needed: h R / L_min <= 0.5) unless the
 * scenario gives them; too few given, or more needed than the plant
 * allows, is an error naming the key to change. */
static int resolve_substeps(ctx_t *c, scenario_t *sc) {
  plant_params_t *p = &sc->plant;
  const int need = plant_substeps_needed(p);
  const double lmin = p->machine.map != NULL
                          ? plant_fluxmap_l_min(p->machine.map)
                          : (p->machine.ld < p->machine.lq ? p->machine.ld : p->machine.lq);
  if (p->inverter.substeps == 0) {
    if (need > PLANT_SUBSTEPS_MAX && plant_substeps_link(p) >= need) {
      return scn_fail(
          c, p->faults.c_scale.n > 0 ? "inject.c_scale" : "dc_link.c",
          "the plant cannot integrate this DC link at this PWM period: its time constant "
          "R C (at the smallest capacitance) needs %d integration steps per period, at "
          "most %d",
          need, PLANT_SUBSTEPS_MAX);
    }
    if (need > PLANT_SUBSTEPS_MAX && plant_substeps_mech(p) >= need) {
      /* the inertia the mechanical share allows with PLANT_SUBSTEPS_MAX
       * steps: both its rules scale as 1 / sqrt(J) and 1 / J */
      plant_params_t q = *p;
      double j_min = p->mech.j;
      for (int i = 0; i < 200 && plant_substeps_mech(&q) > PLANT_SUBSTEPS_MAX; ++i) {
        j_min *= 1.1;
        q.mech.j = j_min;
      }
      return scn_fail(
          c, "mechanics.j",
          "the plant cannot integrate this inertia at this PWM period: the rotor against "
          "the PM flux (and the friction) needs %d integration steps per period, at most "
          "%d: at least %.3g kg m^2 (got %.3g)",
          need, PLANT_SUBSTEPS_MAX, j_min, p->mech.j);
    }
    if (need > PLANT_SUBSTEPS_MAX) {
      const char *key = p->machine.map != NULL           ? "machine.map"
                        : c->ls_given                    ? "machine.ls"
                        : p->machine.ld <= p->machine.lq ? "machine.ld"
                                                         : "machine.lq";
      return scn_fail(c, key,
                      "the plant cannot integrate this machine at this PWM period: its electrical "
                      "time constant L/R (%.3g s with L = %.3g H, R = R_s and the inverter's "
                      "device resistance) needs %d integration steps per period, at most %d",
                      lmin / (p->machine.rs + fmax(p->inverter.r_on_sw, p->inverter.r_diode)), lmin,
                      need, PLANT_SUBSTEPS_MAX);
    }
    p->inverter.substeps = need;
  } else if (p->inverter.substeps < need) {
    return scn_fail(
        c, "inverter.substeps",
        "%d steps per period are unstable for this machine (h R_s / L_min = %.2f > %g): "
        "at least %d, or leave it out (chosen automatically)",
        p->inverter.substeps, p->ts / p->inverter.substeps * p->machine.rs / lmin, PLANT_HR_MAX,
        need);
  }
  return 0;
}

/* ---- the star point, with the whole scenario known --------------------- */

/* The key that set the machine's star-point split (Fabbri 2022 (3.3)): the
 * first of `keys` the machine section gives, else its preset. */
static const char *machine_key(const cJSON *m, const char *const *keys) {
  static char out[32];
  for (int k = 0; keys[k] != NULL; ++k) {
    if (m != NULL && cJSON_GetObjectItemCaseSensitive(m, keys[k]) != NULL) {
      snprintf(out, sizeof out, "machine.%s", keys[k]);
      return out;
    }
  }
  return "machine.preset";
}

/* star_p's range with L0, M0, L2 kept: the matrix is linear in M2 = p
 * (L0 - M0) - L2/2, so positive definite on an interval of p (bisection
 * from p = 0 to either side); 0 when p = 0 itself is not. */
static int star_p_range(const plant_machine_t *pm, double l2, double *lo, double *hi) {
  plant_machine_t q = *pm;
  q.aniso.amp_iq = 0.0;
  const double g0 = 0.5 * (pm->ld + pm->lq);
  double ends[2];
  for (int side = 0; side < 2; ++side) {
    double ok = 0.0, bad = side == 0 ? -1.0 : 1.0;
    for (int i = 0; i < 40; ++i) {
      const double p = 0.5 * (ok + bad);
      q.ld = g0 * (1.0 + p);
      q.lq = g0 * (1.0 - p);
      q.aniso.m2 = p * g0 - 0.5 * l2;
      if (i == 0) { /* p = 0 first */
        q.ld = q.lq = g0;
        q.aniso.m2 = -0.5 * l2;
        if (!plant_aniso_ok(&q)) {
          return 0;
        }
        q.ld = g0 * (1.0 + p);
        q.lq = g0 * (1.0 - p);
        q.aniso.m2 = p * g0 - 0.5 * l2;
      }
      if (plant_aniso_ok(&q)) {
        ok = p;
      } else {
        bad = p;
      }
    }
    ends[side] = ok;
  }
  *lo = ends[0];
  *hi = ends[1];
  return 1;
}

/* The star point's matrix (3.3) and the drive's model of it: errors name
 * the key the scenario wrote and the condition (docs/dfc.md). The load
 * scale is checked up to controller.i_trip, the largest current the plant
 * carries before the drive trips, and held there (plant_aniso_t.k_max). */
static int check_star(ctx_t *c, const cJSON *root, scenario_t *sc) {
  const cJSON *m = cJSON_GetObjectItemCaseSensitive(root, "machine");
  const cJSON *ctl = cJSON_GetObjectItemCaseSensitive(root, "controller");
  plant_machine_t *pm = &sc->plant.machine;
  if (!pm->aniso.enabled) {
    return 0;
  }
  const double g0 = 0.5 * (pm->ld + pm->lq), m0 = pm->aniso.m0, m2 = pm->aniso.m2;
  const double l0 = g0 + m0, l2 = (pm->ld - pm->lq) - 2.0 * m2, lz = g0 + 3.0 * m0;
  const int star_p = m != NULL && cJSON_GetObjectItemCaseSensitive(m, "star_p") != NULL;
  /* the zero-sequence inductance L0 + 2 M0: a star winding's zero-sequence
   * currents make no fundamental field (leakage and triplen harmonics):
   * positive, and at most twice (L_d + L_q)/2 (M0 <= (L_d + L_q)/6; Fig.
   * 3.3's machine: 1.15) */
  if (!(lz > 0.0 && lz <= 2.0 * g0)) {
    static const char *const k0[] = {"star_m0", NULL};
    return scn_fail(
        c, machine_key(m, k0),
        "%g H gives the zero-sequence inductance L0 + 2 M0 = (ld + lq)/2 + 3 M0 = %.4g H, "
        "%.3g times (ld + lq)/2 (%.4g H): a star winding's is leakage and harmonics only, "
        "in (0, 2] times (M0 in (%.4g, %.4g] H; a unit error?)",
        m0, lz, lz / g0, g0, -g0 / 3.0, g0 / 3.0);
  }
  plant_machine_t q = *pm;
  q.aniso.amp_iq = 0.0;
  if (!(fabs(l2 - m2) > 1e-9 * l0)) {
    static const char *const k2[] = {"star_p", "star_m2", "ld", "lq", NULL};
    return scn_fail(
        c, machine_key(m, k2),
        "the (3.3) matrix carries no position: L2 = M2 (%.4g H) makes a = b = 0 in (3.7)", m2);
  }
  if (!plant_aniso_ok(&q)) {
    double lo, hi;
    if (star_p && star_p_range(pm, l2, &lo, &hi)) {
      return scn_fail(
          c, "machine.star_p",
          "%.3g: with L0 %.4g, M0 %.4g, L2 %.4g H kept (Fig. 3.3's split) the (3.3) matrix "
          "is not positive definite at every angle (no inductance matrix): star_p in "
          "(%.3f, %.3f) with these",
          (pm->ld - pm->lq) / (pm->ld + pm->lq), l0, m0, l2, lo, hi);
    }
    static const char *const km[] = {"star_p", "star_m2", "star_m0", "ld", "lq", "ls", NULL};
    return scn_fail(
        c, machine_key(m, km),
        "the (3.3) matrix of ld %.4g, lq %.4g, star_m0 %.4g, star_m2 %.4g H is not positive "
        "definite at every angle (no inductance matrix)",
        pm->ld, pm->lq, m0, m2);
  }
  /* the load scale 1 + amp_iq |i_q| up to i_trip */
  const double amp = pm->aniso.amp_iq, i_lim = (double)sc->drive.i_trip;
  double k_end = 1.0 + amp * i_lim;
  k_end = k_end < 0.5 ? 0.5 : (k_end > 2.0 ? 2.0 : k_end);
  pm->aniso.k_min = k_end < 1.0 ? k_end : 1.0;
  pm->aniso.k_max = k_end > 1.0 ? k_end : 1.0;
  if (!plant_aniso_ok(pm)) {
    double ok = 0.0, bad = i_lim; /* the current where it stops being one */
    for (int i = 0; i < 40; ++i) {
      const double i_q = 0.5 * (ok + bad), k = 1.0 + amp * i_q;
      q.aniso.amp_iq = amp;
      q.aniso.k_min = k < 1.0 ? k : 1.0;
      q.aniso.k_max = k > 1.0 ? k : 1.0;
      if (plant_aniso_ok(&q)) {
        ok = i_q;
      } else {
        bad = i_q;
      }
    }
    return scn_fail(
        c, "machine.star_amp_iq",
        "%g 1/A scales L2 and M2 by 1 + %g |i_q|: the (3.3) matrix stops being positive "
        "definite at |i_q| = %.3g A, below controller.i_trip (%g A), the current the plant "
        "may carry before the drive trips: lower star_amp_iq or i_trip",
        amp, amp, ok, i_lim);
  }
  /* the self and mutual terms turned apart by the load: an inductance
   * matrix at every load up to i_trip */
  if (pm->aniso.phi_self != pm->aniso.phi_mut) {
    for (int k = 0; k <= STAR_LOAD_STEPS; ++k) {
      const double i_q = i_lim * k / STAR_LOAD_STEPS;
      if (!plant_aniso_ok_at(pm, i_q)) {
        static const char *const ks[] = {"star_phi_self", "star_phi_mutual", NULL};
        return scn_fail(c, machine_key(m, ks),
                        "star_phi_self %g, star_phi_mutual %g rad/A turn the self and mutual terms "
                        "apart by %.3g rad at |i_q| = %.3g A, within controller.i_trip (%g A): the "
                        "(3.3) matrix is not positive definite there (no inductance matrix)",
                        pm->aniso.phi_self, pm->aniso.phi_mut,
                        (pm->aniso.phi_self - pm->aniso.phi_mut) * i_q, i_q, i_lim);
      }
    }
  }
  /* Theorem 1 at every load the plant may carry: the IVD's p = b/a with
   * the load scale and the self / mutual shifts (plant_aniso_load) up to
   * controller.i_trip, not only the unloaded p the drive's dfc_b holds */
  const pos_source_t src = sc->drive.pos_source;
  if (src == POS_SOURCE_IVD || src == POS_SOURCE_IVD_KF || src == POS_SOURCE_IVD_KF_RLS) {
    double p_max = 0.0, i_at = 0.0, pa_at = 0.0, pb_at = 0.0, i_half = -1.0;
    for (int k = 0; k <= STAR_LOAD_STEPS; ++k) {
      const double i_q = i_lim * k / STAR_LOAD_STEPS;
      double pa, pb, p;
      plant_aniso_load(pm, i_q, &pa, &pb, &p);
      if (!(fabs(p) < 0.5) && i_half < 0.0) {
        i_half = i_q;
      }
      if (fabs(p) > fabs(p_max)) {
        p_max = p;
        i_at = i_q;
        pa_at = pa;
        pb_at = pb;
      }
    }
    double pa0, pb0, p0, k_at = 1.0 + amp * i_at;
    plant_aniso_load(pm, 0.0, &pa0, &pb0, &p0);
    k_at = k_at < pm->aniso.k_min ? pm->aniso.k_min
                                  : (k_at > pm->aniso.k_max ? pm->aniso.k_max : k_at);
    /* the unloaded p at or above 1/2 is the drive's dfc_b (named by p_key) */
    /* mut: star_load_theorem1_off */
    if (fabs(p0) < 0.5 && !(fabs(p_max) < 0.5)) {
      static const char *const kl[] = {"star_amp_iq", "star_phi_self", "star_phi_mutual",
                                       "star_phi_iq", NULL};
      return scn_fail(c, machine_key(m, kl),
                      "the star point's p = b/a reaches %.3g (3.7) at |i_q| = %.3g A (load scale "
                      "%.3g, phase shifts phi_a %.3g, phi_b %.3g rad of (3.97)), |p| >= 1/2 from "
                      "%.3g A, within controller.i_trip (%g A): the IVD needs |p| < 1/2 at every "
                      "load (Theorem 1: no convergence otherwise; the drive's dfc_b holds the "
                      "unloaded p %.3g): lower the load's scale or i_trip",
                      p_max, i_at, k_at, pa_at, pb_at, i_half, i_lim, p0);
    }
  }
  /* the drive's a against the matrix's: a's sign is L2 - M2's (3.7); the
   * other sign turns the DFC angle 2 theta_e by pi, theta_e by 90 degrees,
   * and nothing detects it */
  double a, b;
  plant_aniso_ab(pm, &a, &b);
  const double da = (double)sc->drive.dfc_a;
  if (ctl != NULL && cJSON_GetObjectItemCaseSensitive(ctl, "dfc_a") != NULL && da * a <= 0.0) {
    return scn_fail(
        c, "controller.dfc_a",
        "%g has the opposite sign of the machine's star-point a = %.4g ((3.7): the sign of "
        "L2 - M2 = %.4g H): the angle would be 90 degrees (electrical) off with no fault",
        da, a, l2 - m2);
  }
  if (ctl == NULL || cJSON_GetObjectItemCaseSensitive(ctl, "dfc_b") == NULL) {
    static const char *const kp[] = {"star_p", "star_m2", "ld", "lq", "star_m0", NULL};
    snprintf(c->p_key, sizeof c->p_key, "%s", machine_key(m, kp));
  }
  return 0;
}

/* The drive's current limit within the map's grid (issue 23): beyond it
 * the plant and the drive's tables extrapolate a saturation curve nobody
 * measured. The drive works at i_d <= 0 (MTPA, field weakening; either
 * sign of torque), so the grid must hold i_d from -i_max to 0 and i_q from
 * -i_max to i_max. */
static int check_map_range(ctx_t *c, const scenario_t *sc, const char *map_key) {
  if (sc->drive.machine_map == NULL) {
    return 0;
  }
  flux_map_t fm;
  flux_map_status_t st;
  if (flux_map_parse(&fm, sc->drive.machine_map, sc->drive.machine_map[2], &st) != 0) {
    return 0; /* parsed once by map_load: cannot fail */
  }
  const double i_max = (double)sc->drive.i_max, tol = 1e-5 * i_max;
  const double id_lo = (double)fm.id0, id_hi = (double)fm.id0 + (double)fm.did * (fm.nd - 1u);
  const double iq_lo = (double)fm.iq0, iq_hi = (double)fm.iq0 + (double)fm.diq * (fm.nq - 1u);
  if (id_lo > -i_max + tol || id_hi < -tol || iq_lo > -i_max + tol || iq_hi < i_max - tol) {
    return scn_fail(
        c, "controller.i_max",
        "%g A reaches beyond the flux map %s (i_d %g .. %g A, i_q %g .. %g A): the drive "
        "needs i_d from -i_max to 0 and i_q from -i_max to i_max inside it (the tables "
        "would be extrapolated): at most %g A with this map%s",
        i_max, map_key, id_lo, id_hi, iq_lo, iq_hi, fmin(fmin(-id_lo, -iq_lo), iq_hi),
        id_hi < -tol ? " (and the map must reach i_d = 0)" : "");
  }
  /* the unit check of `fluxdrive map check --i-max` (docs/flux-maps.md): a
   * grid a hundred times beyond the current limit is a unit error (mA) */
  const double i_grid = fmax(fmax(-id_lo, id_hi), fmax(-iq_lo, iq_hi));
  if (i_grid > 100.0 * i_max) {
    return scn_fail(
        c, map_key,
        "currents implausible (unit?): the grid reaches %g A, %g times controller.i_max "
        "(%g A): currents in mA? state current_unit \"mA\" in the file (or convert it "
        "with fluxdrive map convert --current-unit mA)",
        i_grid, i_grid / i_max, i_max);
  }
  return 0;
}

int scenario_parse(const char *json, const char *origin, scenario_t *sc, char *err, size_t errlen) {
  ctx_t c = {err, errlen, origin, 0, 0, "", -1.0, 0.0, 0.0, {1.0, 1.0, 1.0, 1.0, 1.0}, -1};
  scenario_defaults(&c, sc);
  /* the whole text is the one object: nothing but white space after it */
  cJSON *root = cJSON_ParseWithOpts(json, NULL, 1);
  if (root == NULL) {
    const char *at = cJSON_GetErrorPtr();
    int line = 1;
    for (const char *p = json; at != NULL && p < at && *p; ++p) {
      line += *p == '\n';
    }
    snprintf(err, errlen, "%s: line %d: not valid JSON (or text after the top-level object)",
             origin, line);
    scn_utf8_clean(err);
    return -1;
  }
  /* the table's walk from its root: the top-level keys, then the sections
   * in dependency order (the machine preset sets defaults that the others
   * may override) */
  int r = walk(&c, sc, root, "", K_ROOT, 0, 0);
  r = r ? r : check_star(&c, root, sc);
  r = r ? r : check_map_range(&c, sc, sc->map_file);
  if (r == 0 && cJSON_GetObjectItemCaseSensitive(root, "board") == NULL) {
    sil_board_apply(sil_board_find(DEFAULT_BOARD), sc->plant.ts, sc->plant.inverter.dead_time,
                    &sc->board);
  }
  cJSON_Delete(root);
  if (r != 0) {
    return -1;
  }
  if (sc->v_source.n == 0) {
    profile_add(&sc->v_source,
                (profile_term_t){.kind = PROFILE_CONST, .value = sc->plant.dclink.v_source});
  }
  sc->plant.dclink.v_source = profile_eval(&sc->v_source, 0.0);
  /* the drive's protection range (v_dc_max at most 1e4 V) bounds the link */
  if (!(sc->plant.dclink.v_source > 0.0 && sc->plant.dclink.v_source <= 1e4)) {
    return scn_fail(&c, "dc_link.voltage", "must be in (0, 10000] V at t = 0 (got %g)",
                    sc->plant.dclink.v_source);
  }
  const pos_source_row_t *ps = pos_source(sc->drive.pos_source);
  if (ps != NULL && (ps->caps & POS_CAP_GATED) != 0u &&
      sc->plant.inverter.model != PLANT_INV_SWITCHING) {
    return scn_fail(
        &c, "inverter.model",
        "a star-point position source needs the switching model (the DFC window's edges)");
  }
  if (ps != NULL && (ps->caps & POS_CAP_GATED) != 0u && !sc->board.asym_edges) {
    return scn_fail(&c, "board",
                    "a star-point position source needs a board with asymmetric edges");
  }
  /* the star-point circuit settles within the sample's delay after the
   * edge (issue 23: the fabbri2022 presets trip `position` from a settling
   * time of 4 time constants on, docs/dfc.md) */
  const double settle = (double)sc->drive.dfc_t_meas - sc->plant.inverter.dead_time;
  /* a sample at or before the dead time's end is the drive's own refusal
   * (controller.dfc_t_meas: drive_config_check), named there */
  if (ps != NULL && (ps->caps & POS_CAP_GATED) != 0u && settle > 0.0 &&
      sc->plant.sensors.star_tau > STAR_TAU_SHARE * settle * (1.0 + 1e-6)) {
    return scn_fail(
        &c, "sensors.star_tau",
        "%g s: the star-point sample at controller.dfc_t_meas (%g s) after the edge, less "
        "the dead time (%g s), leaves the circuit %.2g time constants to settle: at "
        "least %g (star_tau <= %g s; the position trips from 4 on)",
        sc->plant.sensors.star_tau, (double)sc->drive.dfc_t_meas, sc->plant.inverter.dead_time,
        settle / sc->plant.sensors.star_tau, 1.0 / STAR_TAU_SHARE, STAR_TAU_SHARE * settle);
  }
  if (resolve_substeps(&c, sc) != 0) {
    return -1;
  }
  const char *field = "";
  if (plant_check(&sc->plant, &field) != 0) {
    return scn_fail(&c, scenario_key_of(field), "invalid plant parameter (see docs/scenarios.md)");
  }
  /* the ADC ranges the drive's HAL reports (hal_caps_t): the sensors' */
  sc->board.i_full_scale = (float)sc->plant.sensors.i_full_scale;
  sc->board.v_full_scale = (float)sc->plant.sensors.v_full_scale;
  sc->board.i_lsb =
      (float)(2.0 * sc->plant.sensors.i_full_scale / ldexp(1.0, sc->plant.sensors.adc_bits));
  if (!(sc->drive.i_trip < sc->board.i_full_scale)) {
    return scn_fail(
        &c, "controller.i_trip",
        "must be below the current ADC's full scale sensors.i_full_scale (%g A): a current "
        "beyond it reads as the full scale and would never trip (got %g A)",
        sc->plant.sensors.i_full_scale, (double)sc->drive.i_trip);
  }
  if (!(sc->drive.v_dc_max < sc->board.v_full_scale)) {
    return scn_fail(
        &c, "controller.v_dc_max",
        "must be below the DC-link ADC's full scale sensors.v_full_scale (%g V): a voltage "
        "beyond it reads as the full scale and would never trip (got %g V)",
        sc->plant.sensors.v_full_scale, (double)sc->drive.v_dc_max);
  }
  /* the set as a whole, reported under the scenario key that sets the
   * field (drive_param_table.h) */
  drive_config_err_t e;
  machine_t m;
  flux_map_t map;
  if (drive_config_usable(&sc->drive, sc->drive.law, &m, &map, &e) != 0) {
    const drive_param_t *p = drive_params_by_name(e.field);
    const char *key = p != NULL ? p->scenario : e.field;
    if (strcmp(e.field, "dfc_b") == 0 && c.p_key[0] != '\0') {
      /* the drive's b follows the machine's star point: name what set it */
      return scn_fail(&c, c.p_key, "the star point's p = b/a = %.3g (3.7), the drive's dfc_b: %s",
                      (double)(sc->drive.dfc_b / sc->drive.dfc_a), e.reason);
    }
    if (p != NULL && strcmp(e.reason, "outside its range") == 0) {
      return scn_fail(&c, key, "must be in [%g, %g] (got %g)", (double)p->min, (double)p->max,
                      (double)drive_param_get(&sc->drive, p));
    }
    return scn_fail(&c, key, "%s", e.reason);
  }
  return 0;
}

int scenario_load_file(const char *path, scenario_t *sc, char *err, size_t errlen) {
  FILE *f = fopen(path, "rb");
  if (f == NULL) {
    snprintf(err, errlen, "%s: cannot open", path);
    return -1;
  }
  enum { MAX_SIZE = 1 << 20 };
  char *buf = malloc(MAX_SIZE + 1);
  size_t n = buf ? fread(buf, 1, MAX_SIZE + 1, f) : 0;
  fclose(f);
  if (buf == NULL) {
    snprintf(err, errlen, "%s: out of memory", path);
    return -1;
  }
  if (n > MAX_SIZE) {
    free(buf);
    snprintf(err, errlen, "%s: larger than 1 MiB", path);
    return -1;
  }
  buf[n] = '\0';
  int r = scenario_parse(buf, path, sc, err, errlen);
  free(buf);
  return r;
}

int scenario_dump(const scenario_t *sc, const char *path) {
  static scenario_t d;
  memcpy(&d, sc, sizeof d);
  d.plant.machine.map = NULL;
  d.drive.machine_map = NULL;
  FILE *f = fopen(path, "wb");
  if (f == NULL) {
    return -1;
  }
  const int ok = fwrite(&d, sizeof d, 1, f) == 1;
  return (fclose(f) == 0 && ok) ? 0 : -1;
}

/* ---- commission: identification procedures (sil_commission.h) ---- */

static const char *sil_proc_name(int index) {
  const proc_row_t *r = proc_row((proc_id_t)index);
  return r != NULL ? r->name : NULL;
}

static int commission_pre(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  if (v->index >= SIL_COMMISSION_MAX) {
    return scn_fail(c, v->path, "too many procedures (at most %d)", SIL_COMMISSION_MAX);
  }
  sc->commission.n = v->index + 1;
  sc->commission.proc[v->index] = -1;
  return 0;
}

/* Only the rows the host may run alone. */
static int commission_proc(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  const proc_row_t *r = proc_row((proc_id_t)(int)v->num);
  if (r == NULL || (r->caps & PROC_CAP_IDENT) == 0u) {
    return scn_fail(c, v->path, "\"%s\" is not an identification procedure",
                    r != NULL ? r->name : "?");
  }
  *(int *)(void *)((char *)&sc->commission.proc[0] + v->shift) = (int)v->num;
  return 0;
}

static int commission_post(ctx_t *c, scenario_t *sc, const sk_val_t *v) {
  if (sc->commission.proc[v->index] < 0) {
    char q[190];
    scn_join(q, sizeof q, v->path, "proc");
    return scn_fail(c, q, "required: an identification procedure");
  }
  return 0;
}
