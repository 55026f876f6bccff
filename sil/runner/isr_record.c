/*
 * isr_record.c - ISR input/output recorder (see isr_record.h).
 *
 * What the observer cannot see directly is derived exactly from the drive:
 *  - the staged commands: drive_t.cmd after the slow loop. The slow loop
 *    changes cmd only in ways that replaying the changed values reproduces
 *    (enable forced off in fault, the mode fixed up for DFVC laws), except
 *    clear_fault, which it consumes: a clear is recorded when the drive left
 *    the fault state or lost a fault bit (bits only ever accumulate
 *    otherwise);
 *  - the hardware trip input: the drive latches DRIVE_FAULT_HW_OVERCURRENT
 *    in the ISR that reads hal_fault_hw_tripped() true, and the HAL latch
 *    and that bit are cleared together (drive_slow_loop), so the input of
 *    ISR k equals that bit after ISR k;
 *  - faults raised from outside the ISR (drive_raise_fault: the command
 *    timeout, the one cause the ISR never detects) appear as new bits.
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
                           sizeof(drive_config_t),
                           sizeof(isr_stream_in_t),
                           sizeof(isr_stream_out_t),
                           count,
                           0u};
  write_block(r, &h, sizeof h);
}

/* True when ISR_STREAM_CONFIG_FIELDS covers drive_config_t: no gap of a
 * 32-bit field or more between the listed fields (padding is shorter). */
static bool config_fields_complete(void) {
  struct {
    size_t off, size;
  } f[ISR_STREAM_CONFIG_WORDS];
  unsigned n = 0;
#define REC_FLT(m)    f[n].off = offsetof(drive_config_t, m), f[n++].size = sizeof(float);
#define REC_INT(m, t) f[n].off = offsetof(drive_config_t, m), f[n++].size = sizeof(t);
  ISR_STREAM_CONFIG_FIELDS(REC_FLT, REC_INT)
#undef REC_FLT
#undef REC_INT
  for (unsigned i = 1; i < n; ++i) { /* sort by offset */
    for (unsigned j = i; j > 0 && f[j - 1].off > f[j].off; --j) {
      size_t o = f[j].off, z = f[j].size;
      f[j] = f[j - 1];
      f[j - 1].off = o;
      f[j - 1].size = z;
    }
  }
  size_t pos = 0;
  for (unsigned i = 0; i < n; ++i) {
    if (f[i].off < pos || f[i].off - pos >= 4u) {
      return false;
    }
    pos = f[i].off + f[i].size;
  }
  return sizeof(drive_config_t) - pos < 4u;
}

int isr_record_open(isr_record_t *r, const char *path) {
  memset(r, 0, sizeof *r);
  if (!config_fields_complete()) {
    fprintf(stderr, "isr_record: drive_config_t has fields that ISR_STREAM_CONFIG_FIELDS "
                    "(sil/runner/isr_stream.h) does not list\n");
    return -1;
  }
  r->f = fopen(path, "wb");
  return r->f != NULL ? 0 : -1;
}

void isr_record_observer(void *user, const sil_step_t *st) {
  isr_record_t *r = user;
  const drive_t *drv = st->drive;
  if (!r->started) {
    r->started = true;
    write_header(r, 0u);
    uint32_t w[ISR_STREAM_CONFIG_WORDS];
    isr_stream_config_put(&drv->cfg, w);
    write_block(r, w, sizeof w);
    r->prev_faults = 0u;
    r->prev_state = DRIVE_STATE_IDLE; /* after drive_init */
  }
  if (r->pending) {
    memcpy(r->out.duty, st->duty_active, sizeof r->out.duty);
    write_block(r, &r->in, sizeof r->in);
    write_block(r, &r->out, sizeof r->out);
    r->count++;
  }

  isr_stream_in_t *in = &r->in;
  memset(in, 0, sizeof *in);
  const uint32_t faults = drv->faults;
  if (st->k % drv->cfg.slow_div == 0u) {
    in->flags |= ISR_IN_SLOW;
    in->flags |= drv->cmd.enable ? ISR_IN_CMD_ENABLE : 0u;
    const bool cleared = r->prev_state == DRIVE_STATE_FAULT &&
                         (drv->state != DRIVE_STATE_FAULT || (r->prev_faults & ~faults) != 0u);
    in->flags |= cleared ? ISR_IN_CMD_CLEAR : 0u;
    in->cmd_law = (uint32_t)drv->cmd.law;
    in->cmd_mode = (uint32_t)drv->cmd.mode;
    in->cmd_torque = drv->cmd.torque;
    in->cmd_speed = drv->cmd.speed;
    in->cmd_id = drv->cmd.id;
    in->cmd_iq = drv->cmd.iq;
    in->cmd_flux = drv->cmd.flux;
  }
  in->flags |= st->adc->enc_valid ? ISR_IN_ENC_VALID : 0u;
  in->flags |= (faults & DRIVE_FAULT_HW_OVERCURRENT) != 0u ? ISR_IN_HW_TRIPPED : 0u;
  in->time_us = (uint32_t)(uint64_t)(st->t * 1e6);
  memcpy(in->i_abc, st->adc->i_abc, sizeof in->i_abc);
  in->v_dc = st->adc->v_dc;
  in->v_star = st->adc->v_star;
  in->enc_angle = st->adc->enc_angle;
  in->raise_fault = faults & ~r->prev_faults & DRIVE_FAULT_CMD_TIMEOUT;
  in->v_applied[0] = r->prev_v_applied[0];
  in->v_applied[1] = r->prev_v_applied[1];
  r->prev_v_applied[0] = drv->ctrl.v_applied.alpha;
  r->prev_v_applied[1] = drv->ctrl.v_applied.beta;

  r->out.flags = st->gates_on ? ISR_OUT_GATES_ON : 0u;
  r->out.faults = faults;
  r->out.state = (uint32_t)drv->state;
  r->pending = true;
  r->prev_faults = faults;
  r->prev_state = drv->state;

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
