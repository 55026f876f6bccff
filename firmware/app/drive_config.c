/*
 * drive_config.c - defaults, descriptors and validation of the parameter
 * set, all generated from DRIVE_PARAM_TABLE (drive_param_table.h).
 */
#include "drive_config.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

/* Enum ranges: 0 .. count - 1. */
#define PARAM_MAX_F32(m)  (m)
#define PARAM_MAX_U16(m)  (m)
#define PARAM_MAX_U32(m)  (m)
#define PARAM_MAX_LAW(m)  ((float)(DRIVE_LAW_COUNT - 1))
#define PARAM_MAX_MODE(m) ((float)(DRIVE_MODE_COUNT - 1))
#define PARAM_MAX_POS(m)  ((float)(POS_SOURCE_COUNT - 1))
#define PARAM_MAX_MAP(m)  (m)

/* The arguments are literals and names from the table: the parentheses
 * clang-tidy asks for would not change a thing (and a name can't take them). */
/* NOLINTBEGIN(bugprone-macro-parentheses) */
#define PARAM_ROW(id_, name_, type_, unit_, def_, min_, max_, access_, scen_, doc_)                \
  {.name = #name_,                                                                                 \
   .unit = unit_,                                                                                  \
   .scenario = scen_,                                                                              \
   .doc = doc_,                                                                                    \
   .def = def_,                                                                                    \
   .min = min_,                                                                                    \
   .max = PARAM_MAX_##type_(max_),                                                                 \
   .offset = (uint16_t)offsetof(drive_config_t, name_),                                            \
   .id = id_,                                                                                      \
   .type = (uint8_t)DRIVE_PARAM_##type_,                                                           \
   .access = (uint8_t)DRIVE_PARAM_##access_},

static const drive_param_t table[DRIVE_PARAM_COUNT] = {DRIVE_PARAM_TABLE(PARAM_ROW)};
/* NOLINTEND(bugprone-macro-parentheses) */

const drive_param_t *drive_params_table(unsigned *count) {
  *count = (unsigned)DRIVE_PARAM_COUNT;
  return table;
}

const drive_param_t *drive_params_find(uint8_t id) {
  for (unsigned i = 0; i < (unsigned)DRIVE_PARAM_COUNT; ++i) {
    if (table[i].id == id) {
      return &table[i];
    }
  }
  return NULL;
}

const drive_param_t *drive_params_by_name(const char *name) {
  for (unsigned i = 0; name != NULL && i < (unsigned)DRIVE_PARAM_COUNT; ++i) {
    if (strcmp(table[i].name, name) == 0) {
      return &table[i];
    }
  }
  return NULL;
}

/* Enums are stored as their C type, whose size the compiler chooses
 * (arm-none-eabi: short enums): read and write through the right width. */
static unsigned field_size(const drive_param_t *p) {
  switch ((drive_param_type_t)p->type) {
  case DRIVE_PARAM_U16:
    return sizeof(uint16_t);
  case DRIVE_PARAM_LAW:
    return sizeof(drive_law_t);
  case DRIVE_PARAM_MODE:
    return sizeof(drive_mode_t);
  case DRIVE_PARAM_POS:
    return sizeof(pos_source_t);
  case DRIVE_PARAM_F32:
  case DRIVE_PARAM_U32:
  default:
    return 4u;
  }
}

static uint32_t read_uint(const unsigned char *base, unsigned size) {
  if (size == 1u) {
    uint8_t u;
    memcpy(&u, base, 1u);
    return u;
  }
  if (size == 2u) {
    uint16_t u;
    memcpy(&u, base, 2u);
    return u;
  }
  uint32_t u;
  memcpy(&u, base, 4u);
  return u;
}

static void write_uint(unsigned char *base, unsigned size, uint32_t v) {
  if (size == 1u) {
    const uint8_t u = (uint8_t)v;
    memcpy(base, &u, 1u);
  } else if (size == 2u) {
    const uint16_t u = (uint16_t)v;
    memcpy(base, &u, 2u);
  } else {
    memcpy(base, &v, 4u);
  }
}

/* The blob's CRC word, low 24 bits; 0 without a blob or when its header is
 * not a map's (the size word bounds the read: a blob's storage holds at
 * least the size it declares, the contract of whoever set the pointer). */
static float map_crc24(const uint32_t *w) {
  enum {
    MAX_WORDS = 12 + 2 * FLUX_MAP_GRID_MAX * FLUX_MAP_GRID_MAX + 2 + 4 * FLUX_MAP_LUT_MAX + 1
  };
  if (w == NULL || w[0] != FLUX_MAP_MAGIC || w[2] < 4u * 13u || w[2] > 4u * MAX_WORDS ||
      (w[2] & 3u) != 0u) {
    return 0.0f;
  }
  return (float)(w[w[2] / 4u - 1u] & 0xFFFFFFu);
}

float drive_param_get(const drive_config_t *cfg, const drive_param_t *p) {
  const unsigned char *base = (const unsigned char *)cfg + p->offset;
  if (p->type == DRIVE_PARAM_MAP) {
    const uint32_t *w;
    memcpy(&w, base, sizeof w);
    return map_crc24(w);
  }
  if (p->type == DRIVE_PARAM_F32) {
    float f;
    memcpy(&f, base, sizeof f);
    return f;
  }
  return (float)read_uint(base, field_size(p));
}

void drive_param_set(drive_config_t *cfg, const drive_param_t *p, float v) {
  unsigned char *base = (unsigned char *)cfg + p->offset;
  if (p->type == DRIVE_PARAM_MAP) {
    if (!(v > 0.0f || v < 0.0f)) {
      const uint32_t *none = NULL;
      memcpy(base, &none, sizeof none);
    }
  } else if (p->type == DRIVE_PARAM_F32) {
    memcpy(base, &v, sizeof v);
  } else {
    write_uint(base, field_size(p), (uint32_t)v);
  }
}

int drive_param_in_range(const drive_param_t *p, float v) {
  if (!(isfinite(v) && v >= p->min && v <= p->max)) {
    return 0;
  }
  return p->type == DRIVE_PARAM_F32 || !(v - floorf(v) > 0.0f);
}

void drive_config_default(drive_config_t *cfg) {
  memset(cfg, 0, sizeof *cfg);
  for (unsigned i = 0; i < (unsigned)DRIVE_PARAM_COUNT; ++i) {
    drive_param_set(cfg, &table[i], table[i].def);
  }
}

/* rad: largest phase shift of the 2theta term at the current limit */
#define DRIVE_DFC_PHI_I_MAX 0.1f

#define RULE(cond, name, why)                                                                      \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      e->field = (name);                                                                           \
      e->reason = (why);                                                                           \
      return -1;                                                                                   \
    }                                                                                              \
  } while (0)

int drive_config_check(const drive_config_t *cfg, drive_config_err_t *err) {
  drive_config_err_t dummy = {"", ""};
  drive_config_err_t *e = err != NULL ? err : &dummy;
  e->field = "";
  e->reason = "";
  for (unsigned i = 0; i < (unsigned)DRIVE_PARAM_COUNT; ++i) {
    RULE(drive_param_in_range(&table[i], drive_param_get(cfg, &table[i])), table[i].name,
         "outside its range");
  }
  const float c = cfg->ts;
  RULE(!(cfg->pole_pairs - floorf(cfg->pole_pairs) > 0.0f), "pole_pairs", "must be an integer");
  RULE(cfg->i_trip >= cfg->i_max, "i_trip", "must be at least i_max");
  RULE(cfg->v_dc_min <= cfg->v_dc_max, "v_dc_min", "must not exceed v_dc_max");
  RULE(cfg->speed_trip >= cfg->speed_max, "speed_trip", "must be at least speed_max");
  RULE(cfg->dead_time <= 0.25f * c, "dead_time", "must be at most a quarter of the period ts");
  /* discrete loops: a bandwidth beyond ~0.5/Ts is not a sane design */
  RULE(cfg->current_bw <= 0.5f / c, "current_bw", "must be at most 0.5/ts");
  RULE(cfg->speed_bw <= 0.25f * cfg->current_bw, "speed_bw", "must be at most current_bw/4");
  RULE(cfg->pll_bw <= 0.5f / c, "pll_bw", "must be at most 0.5/ts");
  RULE(cfg->flux_obs_wc <= 0.25f / c, "flux_obs_wc", "must be at most 0.25/ts");
  RULE(cfg->dfvc_flux_bw <= 0.5f / c, "dfvc_flux_bw", "must be at most 0.5/ts");
  RULE(cfg->dfvc_iqs_bw <= 0.5f / c, "dfvc_iqs_bw", "must be at most 0.5/ts");
  RULE(cfg->align_time <= 0.0f || cfg->align_current > 0.0f, "align_current",
       "must be positive when align_time > 0");
  RULE(cfg->align_current <= cfg->i_max, "align_current", "must be at most i_max");
  RULE(cfg->dfc_t_meas < cfg->dfc_tw, "dfc_t_meas", "must be shorter than dfc_tw");
  /* the star point settles only after the switches have: a sample within the
   * dead time reads the old vector */
  RULE(cfg->dfc_t_meas > cfg->dead_time, "dfc_t_meas",
       "must be longer than dead_time (the star-point sample after the edge must come after the "
       "dead time)");
  /* an alignment shorter than one period is none (a denormal never ends it) */
  RULE(!(cfg->align_time > 0.0f) || cfg->align_time >= c, "align_time",
       "must be 0 (no alignment) or at least one PWM period ts");
  /* the Full IVD's phase shifts at the current limit: a turn of the 2theta term
   * by more than 0.1 rad at i_max (an angle error of 0.05 rad if the machine
   * has none) trips the star-point presets' Kalman filter (ebike 0.15 rad:
   * overspeed at 0.28 s; fig33 0.2 rad: the speed 23 % off); phi_b = 2 phi_a
   * for a turned saliency axis (docs/faults.md) */
  RULE(fabsf(cfg->dfc_phi_a) * cfg->i_max <= DRIVE_DFC_PHI_I_MAX, "dfc_phi_a",
       "|dfc_phi_a| i_max must be at most 0.1 rad (the 2theta term's phase shift at the current "
       "limit)");
  RULE(fabsf(cfg->dfc_phi_b) * cfg->i_max <= 2.0f * DRIVE_DFC_PHI_I_MAX, "dfc_phi_b",
       "|dfc_phi_b| i_max must be at most 0.2 rad (the 4theta term's phase shift at the current "
       "limit)");
  RULE(cfg->overrun_k <= cfg->overrun_n, "overrun_k", "must be at most overrun_n");
  RULE(cfg->dfc_t0 + cfg->dfc_tw <= 0.25f * c, "dfc_tw",
       "the DFC window dfc_t0 + dfc_tw must end within the first quarter of the period ts");
  flux_map_t map;
  const int has_map = drive_config_map(cfg, &map, e);
  if (has_map < 0) {
    return -1;
  }
  RULE(has_map != 0 || !(map.pole_pairs < cfg->pole_pairs || map.pole_pairs > cfg->pole_pairs),
       "pole_pairs", "must equal the flux map's pole pairs");
  return 0;
}

int drive_config_map(const drive_config_t *cfg, flux_map_t *map, drive_config_err_t *err) {
  const uint32_t *w = cfg->machine_map;
  if (w == NULL) {
    return 1;
  }
  flux_map_status_t st;
  if (flux_map_parse(map, w, w[2], &st) != 0) {
    err->field = "machine_map";
    err->reason = flux_map_err_str(st.code);
    return -1;
  }
  return 0;
}
