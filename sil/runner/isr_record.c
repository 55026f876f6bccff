/*
 * isr_record.c - ISR input/output recorder (see isr_record.h).
 *
 * Everything the ISR reads is recorded as it found it: the HAL sample set
 * (the runner filled it before the ISR), the break input (sil_step_t
 * .hw_tripped), the command block drive_t.req (only the main loop writes it,
 * between ISRs: after ISR k it still holds what ISR k read; its
 * identification request req.ident too) and the drive's applied-voltage
 * memory before the ISR (drive_t.v_applied after ISR k-1). Besides, the
 * procedure the drive has in force after the ISR and its phase
 * (host_proc, host_phase: the tool's grouping per procedure and its
 * sample, not inputs).
 */
#include "isr_record.h"

#include <stddef.h>
#include <string.h>

static void write_block(isr_record_t *r, const void *p, size_t n) {
  if (r->failed == 0 && fwrite(p, 1, n, r->f) != n) {
    r->failed = 1;
  }
}

static void write_header(isr_record_t *r, uint32_t count) {
  isr_stream_header_t h = {ISR_STREAM_MAGIC,
                           ISR_STREAM_VERSION,
                           sizeof(isr_stream_header_t),
                           4u * ISR_STREAM_CONFIG_WORDS + 4u + r->map_bytes,
                           4u * ISR_STREAM_CAPS_WORDS,
                           sizeof(isr_stream_in_t),
                           sizeof(isr_stream_out_t),
                           count,
                           0u};
  write_block(r, &h, sizeof h);
}

int isr_record_open(isr_record_t *r, const char *path) {
  memset(r, 0, sizeof *r);
  r->f = fopen(path, "wb");
  return r->f != NULL ? 0 : -1;
}

void isr_record_observer(void *user, const sil_step_t *st) {
  isr_record_t *r = user;
  const drive_t *drv = st->drive;
  if (!r->started) {
    r->started = true;
    r->map_bytes = isr_stream_map_bytes(&drv->cfg);
    write_header(r, 0u);
    uint32_t w[ISR_STREAM_CONFIG_WORDS];
    isr_stream_config_put(&drv->cfg, w);
    write_block(r, w, sizeof w);
    write_block(r, &r->map_bytes, sizeof r->map_bytes);
    if (r->map_bytes > 0u) {
      write_block(r, drv->cfg.machine_map, r->map_bytes);
    }
    uint32_t cw[ISR_STREAM_CAPS_WORDS];
    isr_stream_caps_put(drv->caps, st->timer_counts, cw);
    write_block(r, cw, sizeof cw);
  }
  /* not replayable: a parameter request, a watchdog reset (drive_init
   * again) or a stalled ISR */
  if (drv->creq.seq != 0u || drv->isr_count != r->isr_count + 1u) {
    if (r->failed == 0) {
      fprintf(stderr, "isr_record: the run has parameter requests, a watchdog reset or a "
                      "stalled ISR: not recordable for the PIL replay\n");
    }
    r->failed = 1;
  }
  r->isr_count = drv->isr_count;
  if (r->pending) {
    memcpy(r->out.duty, st->duty_active, sizeof r->out.duty);
    write_block(r, &r->in, sizeof r->in);
    write_block(r, &r->out, sizeof r->out);
    r->count++;
  }

  isr_stream_in_t *in = &r->in;
  memset(in, 0, sizeof *in);
  const hal_sample_t *s = st->adc;
  in->flags = (s->enc_valid ? ISR_IN_ENC_VALID : 0u) | (s->valid ? ISR_IN_VALID : 0u) |
              (st->hw_tripped ? ISR_IN_HW_TRIPPED : 0u) |
              ((st->hw_source & HAL_BREAK_GATE_DRIVER) != 0u ? ISR_IN_GATE_DRIVER : 0u);
  in->time_us = (uint32_t)(uint64_t)(st->t * 1e6);
  memcpy(in->i_abc, s->i_abc, sizeof in->i_abc);
  in->v_dc = s->v_dc;
  in->t_i = s->t_i;
  memcpy(in->v_star, s->v_star, sizeof in->v_star);
  memcpy(in->t_star, s->t_star, sizeof in->t_star);
  in->n_star = s->n_star;
  in->test_vector = s->test_vector;
  in->enc_angle = s->enc_angle;
  in->t_enc = s->t_enc;
  isr_stream_cmd_put(drv->req.seq, &drv->req.cmd, &drv->req.ident, in);
  in->host_proc = drv->proc != NULL ? (uint32_t)drv->proc->id : (uint32_t)PROC_NONE;
  in->host_phase = drv->tm.proc.phase;
  in->v_applied[0] = r->prev_v_applied[0];
  in->v_applied[1] = r->prev_v_applied[1];
  r->prev_v_applied[0] = drv->v_applied.alpha;
  r->prev_v_applied[1] = drv->v_applied.beta;

  r->out.flags = st->gates_on ? ISR_OUT_GATES_ON : 0u;
  r->out.faults = drv->faults;
  r->out.state = (uint32_t)drv->state;
  r->pending = true;

  if (r->next != NULL) {
    r->next(r->next_user, st);
  }
}

int isr_record_close(isr_record_t *r) {
  if (r->f == NULL) {
    return -1;
  }
  if (r->started && fseek(r->f, 0L, SEEK_SET) == 0) {
    write_header(r, r->count);
  } else {
    r->failed = 1;
  }
  if (fclose(r->f) != 0) {
    r->failed = 1;
  }
  r->f = NULL;
  return r->failed != 0 ? -1 : 0;
}
