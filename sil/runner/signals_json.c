/*
 * signals_json.c - the signal tables as JSON (see signals_json.h).
 */
#include "signals_json.h"

#include <cjson/cJSON.h>

#include "ctrl_laws.h"
#include "drive_enums.h"
#include "isr_stream.h"
#include "log_columns.h"

static const char *const type_names[] = {"f32", "u32", "bool"};

static cJSON *row_json(const signal_row_t *r, const char *source) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "name", r->name);
  cJSON_AddStringToObject(o, "type", type_names[r->type]);
  cJSON_AddStringToObject(o, "unit", r->unit);
  cJSON_AddStringToObject(o, "source", source);
  cJSON_AddStringToObject(o, "doc", r->doc);
  return o;
}

/* The laws or sources whose hook fills column k. */
static cJSON *owners(const log_columns_t *c, unsigned k, log_col_kind_t kind) {
  cJSON *a = cJSON_CreateArray();
  if (kind == LOG_COL_LAW) {
    for (unsigned l = 0u; l < (unsigned)DRIVE_LAW_COUNT; ++l) {
      const ctrl_law_t *law = ctrl_law((drive_law_t)l);
      for (unsigned i = 0u; i < law->n_signals; ++i) {
        if (c->law_col[l][i] == k) {
          cJSON_AddItemToArray(a, cJSON_CreateString(drive_law_name(l)));
        }
      }
    }
  } else if (kind == LOG_COL_POS) {
    for (unsigned p = 0u; p < (unsigned)POS_SOURCE_COUNT; ++p) {
      const pos_source_row_t *src = pos_source((pos_source_t)p);
      for (unsigned i = 0u; i < src->n_signals; ++i) {
        if (c->pos_col[p][i] == k) {
          cJSON_AddItemToArray(a, cJSON_CreateString(drive_pos_source_name(p)));
        }
      }
    }
  }
  return a;
}

static const char *message_of(can_sig_t s) {
  for (unsigned m = 0u; m < (unsigned)CAN_MSG_COUNT; ++m) {
    const can_msg_desc_t *d = can_codec_msg((can_msg_t)m);
    if ((unsigned)s >= (unsigned)d->first && (unsigned)s < (unsigned)d->first + d->n_signals) {
      return d->name;
    }
  }
  return "?";
}

char *signals_json(void) {
  static log_columns_t c;
  char err[128];
  if (log_columns_init(&c, err, sizeof err) != 0) {
    return NULL;
  }
  static const char *const kinds[] = {"", "drive", "law", "source"};
  cJSON *o = cJSON_CreateObject();
  cJSON *log = cJSON_AddArrayToObject(o, "log");
  unsigned n_sil;
  (void)sil_signals(&n_sil);
  for (unsigned k = 0u; k < c.n; ++k) {
    const log_column_t *col = &c.col[k];
    const char *source = col->kind == LOG_COL_SIL ? sil_signal_source(k) : kinds[col->kind];
    cJSON *r = row_json(col->row, source);
    cJSON_AddItemToObject(r, "owners", owners(&c, k, col->kind));
    cJSON_AddItemToArray(log, r);
  }
  cJSON *can = cJSON_AddArrayToObject(o, "can");
  unsigned n;
  const drive_signal_t *d = drive_signals(&n);
  for (unsigned i = 0u; i < n; ++i) {
    if (d[i].can == CAN_SIG_NONE) {
      continue;
    }
    cJSON *r = cJSON_CreateObject();
    cJSON_AddStringToObject(r, "signal", d[i].row.name);
    cJSON_AddStringToObject(r, "message", message_of(d[i].can));
    cJSON_AddStringToObject(r, "can", can_codec_sig(d[i].can)->name);
    cJSON_AddNumberToObject(r, "scale", (double)d[i].can_scale);
    cJSON_AddStringToObject(r, "unit", d[i].can_unit);
    cJSON_AddItemToArray(can, r);
  }
  cJSON *pil = cJSON_AddArrayToObject(o, "pil_out");
#define PIL_FIELD(name, type, member)                                                              \
  {                                                                                                \
    cJSON *r = cJSON_CreateObject();                                                               \
    cJSON_AddStringToObject(r, "name", #name);                                                     \
    cJSON_AddStringToObject(r, "type", type_names[SIGNAL_##type]);                                 \
    cJSON_AddItemToArray(pil, r);                                                                  \
  }
  ISR_STREAM_OUT_FIELDS(PIL_FIELD)
#undef PIL_FIELD
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}
