/*
 * scenario.c - JSON scenario loading (schema: docs/scenarios.md).
 *
 * Every object is checked for unknown keys, every number for type, finiteness
 * and range; the first error is reported as "<file>: <field path>: <reason>".
 * The parameter sets are then validated as a whole by plant_check() and
 * drive_config_check(), whose field names are reported the same way.
 */
#include "scenario.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "presets.h"

#define PI 3.14159265358979323846

typedef struct {
  char *err;
  size_t errlen;
  const char *origin;
  int failed;
} ctx_t;

static int fail(ctx_t *c, const char *path, const char *fmt, ...) {
  if (c->failed) {
    return -1;
  }
  c->failed = 1;
  char reason[256];
  va_list ap;
  va_start(ap, fmt);
  /* the analyzer misses va_start on this path (LLVM 14) */
  vsnprintf(reason, sizeof reason, fmt, ap); // NOLINT(clang-analyzer-valist.Uninitialized)
  va_end(ap);
  snprintf(c->err, c->errlen, "%s: %s: %s", c->origin, path, reason);
  return -1;
}

static void join(char *out, size_t n, const char *path, const char *key) {
  int r = path[0] == '\0' ? snprintf(out, n, "%s", key) : snprintf(out, n, "%s.%s", path, key);
  if (r < 0 || (size_t)r >= n) {
    out[n - 1] = '\0';
  }
}

/* Rejects keys of obj that are not in the NULL-terminated list. */
static int check_keys(ctx_t *c, const cJSON *obj, const char *path, const char *const *allowed) {
  if (!cJSON_IsObject(obj)) {
    return fail(c, path[0] ? path : "(top level)", "must be an object");
  }
  for (const cJSON *it = obj->child; it != NULL; it = it->next) {
    int ok = 0;
    for (const char *const *a = allowed; *a != NULL; ++a) {
      ok |= strcmp(*a, it->string) == 0;
    }
    if (!ok) {
      char p[160];
      join(p, sizeof p, path, it->string);
      return fail(c, p, "unknown field");
    }
  }
  return 0;
}

/* Optional number in [lo, hi]; leaves *out unchanged when absent. */
static int get_num(ctx_t *c, const cJSON *obj, const char *path, const char *key, double lo,
                   double hi, double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  join(p, sizeof p, path, key);
  if (!cJSON_IsNumber(it)) {
    return fail(c, p, "must be a number");
  }
  double v = it->valuedouble;
  if (!isfinite(v) || v < lo || v > hi) {
    return fail(c, p, "must be in [%g, %g] (got %g)", lo, hi, v);
  }
  *out = v;
  return 0;
}

static int get_float(ctx_t *c, const cJSON *obj, const char *path, const char *key, double lo,
                     double hi, float *out) {
  double v = (double)*out;
  int r = get_num(c, obj, path, key, lo, hi, &v);
  *out = (float)v;
  return r;
}

static int get_int(ctx_t *c, const cJSON *obj, const char *path, const char *key, int lo, int hi,
                   int *out) {
  double v = (double)*out;
  if (get_num(c, obj, path, key, lo, hi, &v) != 0) {
    return -1;
  }
  if (floor(v) != v) {
    char p[160];
    join(p, sizeof p, path, key);
    return fail(c, p, "must be an integer (got %g)", v);
  }
  *out = (int)v;
  return 0;
}

/* Optional string from a list; returns its index in *out. */
static int get_enum(ctx_t *c, const cJSON *obj, const char *path, const char *key,
                    const char *const *names, int *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  join(p, sizeof p, path, key);
  char list[200] = "";
  for (int i = 0; names[i] != NULL; ++i) {
    if (cJSON_IsString(it) && strcmp(it->valuestring, names[i]) == 0) {
      *out = i;
      return 0;
    }
    strncat(list, i ? ", " : "", sizeof list - strlen(list) - 1);
    strncat(list, names[i], sizeof list - strlen(list) - 1);
  }
  return fail(c, p, "must be one of: %s", list);
}

/* ---- profiles ---------------------------------------------------------- */

static int parse_term(ctx_t *c, const cJSON *t, const char *path, double scale, profile_t *pr) {
  static const char *const kinds[] = {"const", "step", "ramp", "sine", NULL};
  static const char *const keys[] = {"type", "value", "t",         "t0", "t1",
                                     "freq", "phase", "amplitude", NULL};
  if (check_keys(c, t, path, keys) != 0) {
    return -1;
  }
  int kind = -1;
  if (get_enum(c, t, path, "type", kinds, &kind) != 0) {
    return -1;
  }
  if (kind < 0) {
    char p[160];
    join(p, sizeof p, path, "type");
    return fail(c, p, "missing (const, step, ramp or sine)");
  }
  profile_term_t term = {.kind = (profile_kind_t)kind};
  const double big = 1e9;
  if (get_num(c, t, path, kind == PROFILE_SINE ? "amplitude" : "value", -big, big, &term.value) ||
      get_num(c, t, path, kind == PROFILE_STEP ? "t" : "t0", 0.0, big, &term.t0) ||
      get_num(c, t, path, "t1", 0.0, big, &term.t1) ||
      get_num(c, t, path, "freq", 0.0, 1e6, &term.freq) ||
      get_num(c, t, path, "phase", -1e3, 1e3, &term.phase)) {
    return -1;
  }
  if (kind == PROFILE_RAMP && !(term.t1 > term.t0)) {
    char p[160];
    join(p, sizeof p, path, "t1");
    return fail(c, p, "a ramp needs t1 > t0");
  }
  if (kind == PROFILE_SINE && !(term.freq > 0.0)) {
    char p[160];
    join(p, sizeof p, path, "freq");
    return fail(c, p, "a sine needs freq > 0");
  }
  term.value *= scale;
  if (profile_add(pr, term) != 0) {
    return fail(c, path, "too many terms (at most %d)", PROFILE_MAX_TERMS);
  }
  return 0;
}

/* A profile: a number (constant), an array of terms, or
 * {"unit": "...", "terms": [...]} with unit conversion to SI. */
static int get_profile(ctx_t *c, const cJSON *obj, const char *path, const char *key,
                       profile_t *pr) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (it == NULL) {
    return 0;
  }
  char p[160];
  join(p, sizeof p, path, key);
  *pr = (profile_t){0};
  double scale = 1.0;
  if (cJSON_IsNumber(it)) {
    if (!isfinite(it->valuedouble)) {
      return fail(c, p, "must be finite");
    }
    return profile_add(pr, (profile_term_t){.kind = PROFILE_CONST, .value = it->valuedouble});
  }
  const cJSON *terms = it;
  if (cJSON_IsObject(it)) {
    static const char *const keys[] = {"unit", "terms", NULL};
    static const char *const units[] = {"si", "rpm", "deg", NULL};
    if (check_keys(c, it, p, keys) != 0) {
      return -1;
    }
    int u = 0;
    if (get_enum(c, it, p, "unit", units, &u) != 0) {
      return -1;
    }
    scale = u == 1 ? PI / 30.0 : (u == 2 ? PI / 180.0 : 1.0);
    terms = cJSON_GetObjectItemCaseSensitive(it, "terms");
    char tp[160];
    join(tp, sizeof tp, p, "terms");
    if (!cJSON_IsArray(terms)) {
      return fail(c, tp, "must be an array of profile terms");
    }
    memcpy(p, tp, sizeof p);
  }
  if (!cJSON_IsArray(terms)) {
    return fail(c, p, "must be a number, an array of terms or {\"unit\", \"terms\"}");
  }
  int i = 0;
  for (const cJSON *t = terms->child; t != NULL; t = t->next, ++i) {
    char tp[176];
    if (snprintf(tp, sizeof tp, "%s[%d]", p, i) >= (int)sizeof tp) {
      tp[sizeof tp - 1] = '\0';
    }
    if (parse_term(c, t, tp, scale, pr) != 0) {
      return -1;
    }
  }
  return 0;
}

/* ---- sections ---------------------------------------------------------- */

static int parse_machine(ctx_t *c, const cJSON *m, scenario_t *sc) {
  static const char *const keys[] = {"preset", "pole_pairs", "rs",       "ld",
                                     "lq",     "ls",         "lambda_m", NULL};
  if (check_keys(c, m, "machine", keys) != 0) {
    return -1;
  }
  const cJSON *pre = cJSON_GetObjectItemCaseSensitive(m, "preset");
  if (pre != NULL) {
    const machine_preset_t *p = cJSON_IsString(pre) ? preset_find(pre->valuestring) : NULL;
    if (p == NULL) {
      return fail(c, "machine.preset", "unknown preset (known: %s)", preset_names());
    }
    preset_apply(p, &sc->plant, &sc->drive);
  }
  plant_machine_t *pm = &sc->plant.machine;
  double ls = -1.0;
  if (get_int(c, m, "machine", "pole_pairs", 1, 100, &pm->pole_pairs) ||
      get_num(c, m, "machine", "rs", 1e-6, 1e4, &pm->rs) ||
      get_num(c, m, "machine", "ls", 1e-9, 100.0, &ls) ||
      get_num(c, m, "machine", "ld", 1e-9, 100.0, &pm->ld) ||
      get_num(c, m, "machine", "lq", 1e-9, 100.0, &pm->lq) ||
      get_num(c, m, "machine", "lambda_m", 0.0, 100.0, &pm->lambda_m)) {
    return -1;
  }
  if (ls > 0.0) {
    if (cJSON_GetObjectItemCaseSensitive(m, "ld") || cJSON_GetObjectItemCaseSensitive(m, "lq")) {
      return fail(c, "machine.ls", "give either ls (SPM) or ld and lq, not both");
    }
    pm->ld = pm->lq = ls;
  }
  sc->drive.pole_pairs = (float)pm->pole_pairs;
  sc->drive.rs = (float)pm->rs;
  sc->drive.ld = (float)pm->ld;
  sc->drive.lq = (float)pm->lq;
  sc->drive.lambda_m = (float)pm->lambda_m;
  return 0;
}

static int parse_inverter(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"model",         "dead_time", "substeps",
                                     "pwm_frequency", "hw_trip",   NULL};
  static const char *const models[] = {"average", "switching", NULL};
  if (check_keys(c, o, "inverter", keys) != 0) {
    return -1;
  }
  int model = (int)sc->plant.inverter.model;
  double f = 1.0 / sc->plant.ts;
  if (get_enum(c, o, "inverter", "model", models, &model) ||
      get_num(c, o, "inverter", "dead_time", 0.0, 1e-4, &sc->plant.inverter.dead_time) ||
      get_int(c, o, "inverter", "substeps", 1, 64, &sc->plant.inverter.substeps) ||
      get_num(c, o, "inverter", "pwm_frequency", 1e3, 1e5, &f) ||
      get_num(c, o, "inverter", "hw_trip", 0.0, 1e5, &sc->hw_trip)) {
    return -1;
  }
  sc->plant.inverter.model = (plant_inverter_model_t)model;
  sc->plant.ts = 1.0 / f;
  sc->drive.ts = (float)sc->plant.ts;
  sc->drive.dead_time = (float)sc->plant.inverter.dead_time;
  return 0;
}

static int parse_dclink(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"kind", "voltage", "r", "c", NULL};
  static const char *const kinds[] = {"ideal", "rc", NULL};
  if (check_keys(c, o, "dc_link", keys) != 0) {
    return -1;
  }
  int kind = (int)sc->plant.dclink.kind;
  if (get_enum(c, o, "dc_link", "kind", kinds, &kind) ||
      get_profile(c, o, "dc_link", "voltage", &sc->v_source) ||
      get_num(c, o, "dc_link", "r", 0.0, 1e6, &sc->plant.dclink.r) ||
      get_num(c, o, "dc_link", "c", 0.0, 10.0, &sc->plant.dclink.c)) {
    return -1;
  }
  sc->plant.dclink.kind = (plant_dc_kind_t)kind;
  return 0;
}

static int parse_mechanics(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"mode",  "j",      "b",      "load_torque",
                                     "speed", "theta0", "speed0", NULL};
  static const char *const modes[] = {"free", "imposed", NULL};
  if (check_keys(c, o, "mechanics", keys) != 0) {
    return -1;
  }
  plant_mech_t *m = &sc->plant.mech;
  int mode = (int)m->mode;
  if (get_enum(c, o, "mechanics", "mode", modes, &mode) ||
      get_num(c, o, "mechanics", "j", 1e-9, 1e4, &m->j) ||
      get_num(c, o, "mechanics", "b", 0.0, 1e4, &m->b) ||
      get_profile(c, o, "mechanics", "load_torque", &m->load_torque) ||
      get_profile(c, o, "mechanics", "speed", &m->speed) ||
      get_num(c, o, "mechanics", "theta0", -1e3, 1e3, &m->theta0) ||
      get_num(c, o, "mechanics", "speed0", -1e5, 1e5, &m->omega0)) {
    return -1;
  }
  m->mode = (plant_mech_mode_t)mode;
  if (m->mode == PLANT_MECH_IMPOSED && !cJSON_GetObjectItemCaseSensitive(o, "speed")) {
    return fail(c, "mechanics.speed", "required when mode is \"imposed\"");
  }
  sc->drive.inertia = (float)m->j;
  return 0;
}

static int parse_sensors(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {
      "adc_bits", "i_full_scale", "v_full_scale", "gain_error", "offset_error",
      "i_noise",  "v_noise",      "encoder_cpr",  "seed",       NULL};
  if (check_keys(c, o, "sensors", keys) != 0) {
    return -1;
  }
  plant_sensors_t *s = &sc->plant.sensors;
  int seed = (int)s->seed;
  if (get_int(c, o, "sensors", "adc_bits", 8, 24, &s->adc_bits) ||
      get_num(c, o, "sensors", "i_full_scale", 1e-3, 1e5, &s->i_full_scale) ||
      get_num(c, o, "sensors", "v_full_scale", 1e-3, 1e5, &s->v_full_scale) ||
      get_num(c, o, "sensors", "i_noise", 0.0, 1e3, &s->i_noise) ||
      get_num(c, o, "sensors", "v_noise", 0.0, 1e3, &s->v_noise) ||
      get_int(c, o, "sensors", "encoder_cpr", 0, 1 << 24, &s->encoder_cpr) ||
      get_int(c, o, "sensors", "seed", 0, 0x7fffffff, &seed)) {
    return -1;
  }
  s->seed = (uint32_t)seed;
  const char *arrays[2] = {"gain_error", "offset_error"};
  double *dst[2] = {s->gain_error, s->offset_error};
  for (int a = 0; a < 2; ++a) {
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(o, arrays[a]);
    if (arr == NULL) {
      continue;
    }
    char p[64];
    join(p, sizeof p, "sensors", arrays[a]);
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) != 3) {
      return fail(c, p, "must be an array of 3 numbers (phases a, b, c)");
    }
    for (int i = 0; i < 3; ++i) {
      const cJSON *v = cJSON_GetArrayItem(arr, i);
      if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || fabs(v->valuedouble) > 1e3) {
        return fail(c, p, "element %d must be a finite number", i);
      }
      dst[a][i] = v->valuedouble;
    }
  }
  return 0;
}

static int parse_controller(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {
      "law",         "mode",       "current_bw", "speed_bw",   "accel_max",      "i_max",
      "i_trip",      "torque_max", "speed_max",  "speed_trip", "v_dc_max",       "v_dc_min",
      "v_margin",    "pll_bw",     "enc_offset", "slow_div",   "offset_samples", "offset_max",
      "flux_obs_wc", "delta_max",  "vsd_max",    "flux_min",   "dfvc_flux_bw",   "dfvc_iqs_bw",
      "estimates",   NULL};
  static const char *const laws[] = {"foc", "pi_dfvc", "db_dfvc", NULL};
  static const char *const modes[] = {"torque", "speed", "current", NULL};
  if (check_keys(c, o, "controller", keys) != 0) {
    return -1;
  }
  drive_config_t *d = &sc->drive;
  int law = (int)d->law, mode = (int)d->mode;
  int slow_div = d->slow_div, offset_samples = d->offset_samples;
  const char *P = "controller";
  if (get_enum(c, o, P, "law", laws, &law) || get_enum(c, o, P, "mode", modes, &mode) ||
      get_float(c, o, P, "current_bw", 0.0, 1e6, &d->current_bw) ||
      get_float(c, o, P, "speed_bw", 0.0, 1e5, &d->speed_bw) ||
      get_float(c, o, P, "accel_max", 0.0, 1e8, &d->accel_max) ||
      get_float(c, o, P, "i_max", 0.0, 1e5, &d->i_max) ||
      get_float(c, o, P, "i_trip", 0.0, 1e5, &d->i_trip) ||
      get_float(c, o, P, "torque_max", 0.0, 1e6, &d->torque_max) ||
      get_float(c, o, P, "speed_max", 0.0, 1e5, &d->speed_max) ||
      get_float(c, o, P, "speed_trip", 0.0, 1e5, &d->speed_trip) ||
      get_float(c, o, P, "v_dc_max", 0.0, 1e5, &d->v_dc_max) ||
      get_float(c, o, P, "v_dc_min", 0.0, 1e5, &d->v_dc_min) ||
      get_float(c, o, P, "v_margin", 0.0, 1.0, &d->v_margin) ||
      get_float(c, o, P, "pll_bw", 0.0, 1e6, &d->pll_bw) ||
      get_float(c, o, P, "enc_offset", -7.0, 7.0, &d->enc_offset) ||
      get_int(c, o, P, "slow_div", 1, 1000, &slow_div) ||
      get_int(c, o, P, "offset_samples", 1, 60000, &offset_samples) ||
      get_float(c, o, P, "offset_max", 0.0, 1e3, &d->offset_max) ||
      get_float(c, o, P, "flux_obs_wc", 0.0, 1e5, &d->flux_obs_wc) ||
      get_float(c, o, P, "delta_max", 0.0, 2.0, &d->delta_max) ||
      get_float(c, o, P, "vsd_max", 0.0, 1e5, &d->vsd_max) ||
      get_float(c, o, P, "flux_min", 0.0, 100.0, &d->flux_min) ||
      get_float(c, o, P, "dfvc_flux_bw", 0.0, 1e6, &d->dfvc_flux_bw) ||
      get_float(c, o, P, "dfvc_iqs_bw", 0.0, 1e6, &d->dfvc_iqs_bw)) {
    return -1;
  }
  d->law = (drive_law_t)law;
  d->mode = (drive_mode_t)mode;
  d->slow_div = (uint16_t)slow_div;
  d->offset_samples = (uint16_t)offset_samples;

  /* Detuning: the controller's machine estimates as factors of the plant's. */
  const cJSON *e = cJSON_GetObjectItemCaseSensitive(o, "estimates");
  if (e != NULL) {
    static const char *const ekeys[] = {"rs_scale", "ls_scale",       "ld_scale",
                                        "lq_scale", "lambda_m_scale", NULL};
    const char *E = "controller.estimates";
    double rs = 1.0, ls = 1.0, ld = 1.0, lq = 1.0, lm = 1.0;
    if (check_keys(c, e, E, ekeys) || get_num(c, e, E, "rs_scale", 0.1, 10.0, &rs) ||
        get_num(c, e, E, "ls_scale", 0.1, 10.0, &ls) ||
        get_num(c, e, E, "ld_scale", 0.1, 10.0, &ld) ||
        get_num(c, e, E, "lq_scale", 0.1, 10.0, &lq) ||
        get_num(c, e, E, "lambda_m_scale", 0.1, 10.0, &lm)) {
      return -1;
    }
    d->rs = (float)(sc->plant.machine.rs * rs);
    d->ld = (float)(sc->plant.machine.ld * ld * ls);
    d->lq = (float)(sc->plant.machine.lq * lq * ls);
    d->lambda_m = (float)(sc->plant.machine.lambda_m * lm);
  }
  return 0;
}

static int parse_references(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"enable_at", "disable_at", "torque", "speed",
                                     "id",        "iq",         "flux",   NULL};
  const char *P = "references";
  if (check_keys(c, o, P, keys) || get_num(c, o, P, "enable_at", 0.0, 1e6, &sc->enable_at) ||
      get_num(c, o, P, "disable_at", 0.0, 1e6, &sc->disable_at) ||
      get_profile(c, o, P, "torque", &sc->ref.torque) ||
      get_profile(c, o, P, "speed", &sc->ref.speed) || get_profile(c, o, P, "id", &sc->ref.id) ||
      get_profile(c, o, P, "iq", &sc->ref.iq) || get_profile(c, o, P, "flux", &sc->ref.flux)) {
    return -1;
  }
  return 0;
}

static int parse_inject(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"encoder_error", NULL};
  if (check_keys(c, o, "inject", keys) != 0) {
    return -1;
  }
  return get_profile(c, o, "inject", "encoder_error", &sc->encoder_error);
}

static int parse_log(ctx_t *c, const cJSON *o, scenario_t *sc) {
  static const char *const keys[] = {"decimation", NULL};
  if (check_keys(c, o, "log", keys) != 0) {
    return -1;
  }
  return get_int(c, o, "log", "decimation", 1, 1000000, &sc->log_decimation);
}

static void scenario_defaults(scenario_t *sc) {
  memset(sc, 0, sizeof *sc);
  snprintf(sc->name, sizeof sc->name, "unnamed");
  drive_config_default(&sc->drive);
  preset_apply(preset_find("rubino2020_spm"), &sc->plant, &sc->drive);
  sc->plant.ts = 1.0 / 16000.0;
  sc->plant.inverter = (plant_inverter_t){PLANT_INV_AVERAGE, 1e-6, 1};
  sc->plant.dclink.kind = PLANT_DC_IDEAL;
  sc->plant.dclink.r = 0.1;
  sc->plant.dclink.c = 470e-6;
  sc->plant.mech.mode = PLANT_MECH_FREE;
  sc->plant.sensors.adc_bits = 12;
  sc->plant.sensors.i_noise = 0.0;
  sc->plant.sensors.v_noise = 0.0;
  sc->plant.sensors.encoder_cpr = 4096;
  sc->plant.sensors.seed = 1;
  sc->drive.ts = (float)sc->plant.ts;
  sc->log_decimation = 16;
}

int scenario_parse(const char *json, const char *origin, scenario_t *sc, char *err, size_t errlen) {
  ctx_t c = {err, errlen, origin, 0};
  scenario_defaults(sc);
  cJSON *root = cJSON_Parse(json);
  if (root == NULL) {
    const char *at = cJSON_GetErrorPtr();
    int line = 1;
    for (const char *p = json; at != NULL && p < at && *p; ++p) {
      line += *p == '\n';
    }
    snprintf(err, errlen, "%s: line %d: not valid JSON", origin, line);
    return -1;
  }
  static const char *const keys[] = {
      "name",    "description", "duration",   "machine", "inverter", "dc_link", "mechanics",
      "sensors", "controller",  "references", "inject",  "log",      NULL};
  int r = check_keys(&c, root, "", keys);
  const cJSON *name = cJSON_GetObjectItemCaseSensitive(root, "name");
  if (r == 0 && name != NULL) {
    if (!cJSON_IsString(name)) {
      r = fail(&c, "name", "must be a string");
    } else {
      snprintf(sc->name, sizeof sc->name, "%s", name->valuestring);
    }
  }
  if (r == 0 && !cJSON_GetObjectItemCaseSensitive(root, "duration")) {
    r = fail(&c, "duration", "required (simulated time in seconds)");
  }
  r = r ? r : get_num(&c, root, "", "duration", 1e-4, 3600.0, &sc->duration);
  /* Sections in dependency order: the machine preset sets defaults that the
   * others may override. */
  struct {
    const char *key;
    int (*fn)(ctx_t *, const cJSON *, scenario_t *);
  } sections[] = {{"machine", parse_machine},
                  {"inverter", parse_inverter},
                  {"dc_link", parse_dclink},
                  {"mechanics", parse_mechanics},
                  {"sensors", parse_sensors},
                  {"controller", parse_controller},
                  {"references", parse_references},
                  {"inject", parse_inject},
                  {"log", parse_log}};
  for (size_t i = 0; r == 0 && i < sizeof sections / sizeof sections[0]; ++i) {
    const cJSON *o = cJSON_GetObjectItemCaseSensitive(root, sections[i].key);
    if (o != NULL) {
      r = sections[i].fn(&c, o, sc);
    }
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
  const char *field = "";
  if (plant_check(&sc->plant, &field) != 0) {
    return fail(&c, field, "invalid plant parameter (see docs/scenarios.md)");
  }
  if (drive_config_check(&sc->drive, &field) != 0) {
    char p[96];
    snprintf(p, sizeof p, "controller.%s", field);
    return fail(&c, p,
                "invalid controller parameter (out of range or inconsistent, see "
                "docs/scenarios.md)");
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
