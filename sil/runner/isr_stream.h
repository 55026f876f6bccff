/*
 * isr_stream.h - the ISR input/output stream shared by the SIL recorder
 * (sil/runner/isr_record.c, `fluxdrive-sil --record-isr PATH`) and the PIL
 * image (pil/, Cortex-M4F on QEMU mps2-an386). Format in docs/pil.md.
 *
 * File: header; the parameter set in force as ISR_STREAM_CONFIG_WORDS words
 * (one per row of the parameter table, in table order: drive_param_table.h)
 * followed by the flux map's blob (a word with its size in bytes, 0 for a
 * linear machine, then the blob: docs/flux-maps.md), header.config_size
 * covering both;
 * the board's HAL capabilities (ISR_STREAM_CAPS_WORDS words); then `count`
 * records of isr_stream_in_t followed by isr_stream_out_t (the host's
 * outputs). Every field is 32-bit little-endian (uint32_t or IEEE-754
 * binary32), so the layout is the same on x86-64 and on ARMv7E-M; no C
 * struct of the firmware is copied as bytes (arm-none-eabi uses short
 * enums). The PIL writes `count` isr_stream_out_t records (no header).
 */
#ifndef FD_ISR_STREAM_H
#define FD_ISR_STREAM_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "drive.h"

#define ISR_STREAM_MAGIC   0x52534946u /* "FISR" */
#define ISR_STREAM_VERSION 6u

/* isr_stream_header_t.flags: the replay sets the drive's applied-voltage
 * memory (drive_t.v_applied) to the host's before each ISR, see
 * docs/pil.md ("Why the applied voltage is forced"). */
#define ISR_STREAM_FORCE_APPLIED (1u << 0)
/* The replay's RAM state (its .data and .bss: the drive, the replay HAL,
 * the configuration) in a file pil_snap.bin, so that a traced replay can
 * start at a record other than the first (`fluxdrive pil --sample`): LOAD
 * takes the state from it in place of drive_init (the file's records are
 * the ones that follow that state), SAVE writes it after the last record.
 * Set by `fluxdrive pil` in the copy it gives the image (docs/pil.md). */
#define ISR_STREAM_SNAP_LOAD (1u << 1)
#define ISR_STREAM_SNAP_SAVE (1u << 2)

/* isr_stream_in_t.flags */
#define ISR_IN_ENC_VALID   (1u << 0) /* hal_sample_t.enc_valid */
#define ISR_IN_VALID       (1u << 1) /* hal_sample_t.valid */
#define ISR_IN_HW_TRIPPED  (1u << 2) /* hal_fault_hw_tripped() at the start of this ISR */
#define ISR_IN_GATE_DRIVER (1u << 3) /* and hal_fault_hw_source() has the gate driver */

/* isr_stream_out_t.flags */
#define ISR_OUT_GATES_ON (1u << 0)

#define ISR_STREAM_FAULT_WORDS 16 /* >= DRIVE_FAULT_COUNT */

typedef struct {
  uint32_t magic;       /* ISR_STREAM_MAGIC */
  uint32_t version;     /* ISR_STREAM_VERSION */
  uint32_t header_size; /* sizeof(isr_stream_header_t) */
  uint32_t config_size; /* 4 * ISR_STREAM_CONFIG_WORDS + 4 + map blob bytes */
  uint32_t caps_size;   /* 4 * ISR_STREAM_CAPS_WORDS */
  uint32_t in_size;     /* sizeof(isr_stream_in_t) */
  uint32_t out_size;    /* sizeof(isr_stream_out_t) */
  uint32_t count;       /* records */
  uint32_t flags;       /* ISR_STREAM_FORCE_APPLIED, _SNAP_* (set by the PIL runner) */
} isr_stream_header_t;

/* Everything the drive sees before and during one ISR: the HAL sample set,
 * the break input, and the main loop's command block (drive_t.req) as the
 * ISR finds it, its identification request (drive_t.req.ident) included.
 * host_proc and host_phase are the words the image does not read: the
 * procedure the host's drive had in force after this ISR (drive_t.proc's
 * id, PROC_NONE: none) and its phase (the procedure telemetry's), by which
 * `fluxdrive pil` groups the ISRs per procedure and places its sample. */
typedef struct {
  uint32_t flags;
  uint32_t time_us; /* hal_time_us() */
  float i_abc[3];   /* hal_sample_t */
  float v_dc;
  float t_i;
  float v_star[2];
  float t_star[2];
  uint32_t n_star;
  uint32_t test_vector;
  float enc_angle;
  float t_enc;
  uint32_t req_seq; /* drive_t.req.seq */
  uint32_t cmd_seq; /* drive_t.req.cmd, field by field */
  uint32_t enable;
  uint32_t law;
  uint32_t mode;
  float torque;
  float speed;
  float id;
  float iq;
  float flux;
  uint32_t clear_count;
  uint32_t fault_count[ISR_STREAM_FAULT_WORDS];
  uint32_t enable_count;
  uint32_t clear_enable_mark;
  uint32_t fault_total; /* drive_request_fault() calls, all bits */
  uint32_t ident_proc;  /* drive_t.req.ident: the identification asked for (proc_id_t) */
  uint32_t ident_count; /* and drive_cmd_identify() calls */
  uint32_t host_proc;   /* not read by the image: the host's procedure after this ISR */
  uint32_t host_phase;  /* nor this: its phase (drive_t.tm.proc.phase) */
  uint32_t reserved[ISR_STREAM_FAULT_WORDS - 7]; /* zero */
  float v_applied[2]; /* host drive_t.v_applied before this ISR (alpha, beta) */
} isr_stream_in_t;

/* What one ISR produced. */
typedef struct {
  float duty[3];   /* duties of the pattern the HAL holds (off - on) */
  uint32_t flags;  /* ISR_OUT_GATES_ON */
  uint32_t faults; /* drive_t.faults after the ISR */
  uint32_t state;  /* drive_state_t after the ISR */
} isr_stream_out_t;

/* Its fields, in order, each named after the signal it carries (the log's
 * column: docs/log-format.md; gates: ISR_OUT_GATES_ON only, the active
 * short circuit is not told apart): X(signal, type, member). The PIL tool
 * reads this list (`fluxdrive-sil --print-signals`, pil.py) and
 * signals/agreement checks every name is a signal of the tables. */
#define ISR_STREAM_OUT_FIELDS(X)                                                                   \
  X(duty_a, F32, duty[0])                                                                          \
  X(duty_b, F32, duty[1])                                                                          \
  X(duty_c, F32, duty[2])                                                                          \
  X(gates, U32, flags)                                                                             \
  X(faults, U32, faults)                                                                           \
  X(state, U32, state)

#define ISR_OUT_INDEX(n, t, m) ISR_OUT_FIELD_##n,
enum { ISR_STREAM_OUT_FIELDS(ISR_OUT_INDEX) ISR_OUT_FIELD_COUNT };
#undef ISR_OUT_INDEX
#define ISR_OUT_AT(n, t, m)                                                                        \
  _Static_assert(offsetof(isr_stream_out_t, m) == sizeof(uint32_t) * (size_t)ISR_OUT_FIELD_##n,    \
                 "isr_stream_out_t: the field of " #n);
ISR_STREAM_OUT_FIELDS(ISR_OUT_AT)
#undef ISR_OUT_AT

_Static_assert(sizeof(isr_stream_header_t) == 36, "isr_stream_header_t layout");
_Static_assert(sizeof(isr_stream_in_t) == 240, "isr_stream_in_t layout");
/* read by `fluxdrive pil` at these offsets (pil.py HOST_PROC_AT) */
_Static_assert(offsetof(isr_stream_in_t, host_proc) == 188, "isr_stream_in_t.host_proc");
_Static_assert(offsetof(isr_stream_in_t, host_phase) == 192, "isr_stream_in_t.host_phase");
_Static_assert(sizeof(isr_stream_out_t) == sizeof(uint32_t) * (size_t)ISR_OUT_FIELD_COUNT,
               "isr_stream_out_t layout: ISR_STREAM_OUT_FIELDS");
_Static_assert(DRIVE_FAULT_COUNT <= ISR_STREAM_FAULT_WORDS, "fault counters");

enum { ISR_STREAM_CONFIG_WORDS = DRIVE_PARAM_COUNT };
/* The largest flux-map blob (docs/flux-maps.md) in bytes. */
enum {
  ISR_STREAM_MAP_MAX =
      4 * (12 + 2 * FLUX_MAP_GRID_MAX * FLUX_MAP_GRID_MAX + 2 + 4 * FLUX_MAP_LUT_MAX + 1)
};

/* Bytes of the flux-map blob of c (0: linear machine). */
static inline uint32_t isr_stream_map_bytes(const drive_config_t *c) {
  return c->machine_map != NULL ? c->machine_map[2] : 0u;
}

/* The parameter set as words: floats as their bits, the rest as integers
 * (the map as its CRC word: the blob follows the words, and _get leaves
 * machine_map to the reader of the blob). */
static inline void isr_stream_config_put(const drive_config_t *c,
                                         uint32_t w[ISR_STREAM_CONFIG_WORDS]) {
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  for (unsigned i = 0; i < n; ++i) {
    const float v = drive_param_get(c, &t[i]);
    if (t[i].type == DRIVE_PARAM_F32) {
      memcpy(&w[i], &v, sizeof v);
    } else {
      w[i] = (uint32_t)v;
    }
  }
}

static inline void isr_stream_config_get(drive_config_t *c,
                                         const uint32_t w[ISR_STREAM_CONFIG_WORDS]) {
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  memset(c, 0, sizeof *c);
  for (unsigned i = 0; i < n; ++i) {
    float v;
    if (t[i].type == DRIVE_PARAM_F32) {
      memcpy(&v, &w[i], sizeof v);
    } else {
      v = (float)w[i];
    }
    drive_param_set(c, &t[i], v);
  }
}

/* The HAL capabilities as words (hal_caps_t field by field), plus the
 * timer's compare steps per period (the SIL board's rounding). */
enum { ISR_STREAM_CAPS_WORDS = 13 };

static inline void isr_stream_caps_put(const hal_caps_t *c, uint32_t counts,
                                       uint32_t w[ISR_STREAM_CAPS_WORDS]) {
  const float f[10] = {c->ts,  c->t_count,   c->dead_time, c->duty_min, c->duty_max,
                       c->t_i, c->t_i_clear, c->t_enc,     c->cpu_hz,   c->i_full_scale};
  memcpy(w, f, sizeof f);
  w[10] = c->features;
  w[11] = counts;
  memcpy(&w[12], &c->v_full_scale, sizeof(float));
}

static inline void isr_stream_caps_get(hal_caps_t *c, uint32_t *counts,
                                       const uint32_t w[ISR_STREAM_CAPS_WORDS]) {
  float f[10];
  memcpy(f, w, sizeof f);
  c->ts = f[0];
  c->t_count = f[1];
  c->dead_time = f[2];
  c->duty_min = f[3];
  c->duty_max = f[4];
  c->t_i = f[5];
  c->t_i_clear = f[6];
  c->t_enc = f[7];
  c->cpu_hz = f[8];
  c->i_full_scale = f[9];
  c->features = w[10];
  *counts = w[11];
  memcpy(&c->v_full_scale, &w[12], sizeof(float));
}

/* The command block and its identification request, and back. */
static inline void isr_stream_cmd_put(uint32_t req_seq, const drive_cmd_t *c,
                                      const drive_ident_req_t *ident, isr_stream_in_t *in) {
  in->req_seq = req_seq;
  in->cmd_seq = c->seq;
  in->enable = c->enable;
  in->law = (uint32_t)c->law;
  in->mode = (uint32_t)c->mode;
  in->torque = c->torque;
  in->speed = c->speed;
  in->id = c->id;
  in->iq = c->iq;
  in->flux = c->flux;
  in->clear_count = c->clear_count;
  in->enable_count = c->enable_count;
  in->clear_enable_mark = c->clear_enable_mark;
  in->fault_total = c->fault_total;
  in->ident_proc = ident->proc;
  in->ident_count = ident->count;
  memset(in->reserved, 0, sizeof in->reserved);
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    in->fault_count[b] = c->fault_count[b];
  }
}

static inline void isr_stream_cmd_get(const isr_stream_in_t *in, uint32_t *req_seq, drive_cmd_t *c,
                                      drive_ident_req_t *ident) {
  *req_seq = in->req_seq;
  c->seq = in->cmd_seq;
  c->enable = in->enable;
  c->law = (drive_law_t)in->law;
  c->mode = (drive_mode_t)in->mode;
  c->torque = in->torque;
  c->speed = in->speed;
  c->id = in->id;
  c->iq = in->iq;
  c->flux = in->flux;
  c->clear_count = in->clear_count;
  c->enable_count = in->enable_count;
  c->clear_enable_mark = in->clear_enable_mark;
  c->fault_total = in->fault_total;
  ident->proc = in->ident_proc;
  ident->count = in->ident_count;
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    c->fault_count[b] = in->fault_count[b];
  }
}

#endif
