/*
 * pil_main.c - processor-in-the-loop replay (docs/pil.md).
 *
 * Reads pil_in.bin (an isr_stream recorded by `fluxdrive-sil --record-isr`)
 * through semihosting, initialises the drive with the recorded
 * configuration and board, and replays the exact inputs of the SIL run: per
 * record, the main loop's command block and identification request as the
 * ISR found them, then
 * drive_isr() on the recorded HAL sample set. Writes one
 * isr_stream_out_t per ISR to pil_out.bin. With ISR_STREAM_FORCE_APPLIED in
 * the header, the law's applied-voltage memory is set to the host's before
 * each ISR (outside the counted ISR; docs/pil.md explains why).
 *
 * With ISR_STREAM_SNAP_LOAD the state comes from pil_snap.bin (a replay of
 * the records before these, SNAP_SAVE) in place of drive_init; with
 * SNAP_SAVE it is written there after the last record: the whole .data and
 * .bss (the drive, the replay HAL, the configuration and the map; the
 * image has no other state), so a traced replay starts anywhere in a run.
 *
 * Exit status: 0 done, 2 input file, 3 stream format, 4 drive_init
 * rejected the configuration, 5 output file, 6 snapshot file, 70 fault
 * exception.
 *
 * Instruction counting (`fluxdrive pil`): drive_isr() is called only from
 * pil_step(), so an ISR spans the trace lines from drive_isr's entry to the
 * first line back in pil_step.
 */
#include <stdbool.h>
#include <stdint.h>

#include "drive.h"
#include "hal_pil.h"
#include "isr_stream.h"
#include "semihost.h"

#define CHUNK 64 /* records per semihosting transfer */

typedef struct {
  isr_stream_in_t in;
  /* the host's outputs, compared on the host: read with the record */
  // cppcheck-suppress unusedStructMember
  isr_stream_out_t host_out;
} record_t;

static drive_t drv;
static record_t rec[CHUNK];
static isr_stream_out_t out[CHUNK];

/* the image's RAM state (mps2_an386.ld: .data, then .bss) */
extern uint32_t _sdata, _ebss;

static size_t snap_bytes(void) {
  return (size_t)((uintptr_t)&_ebss - (uintptr_t)&_sdata);
}

/* Reads (load) or writes the RAM state from or to pil_snap.bin: 0, or -1. */
static int snap(bool load) {
  const int32_t f = sh_open("pil_snap.bin", load ? "rb" : "wb");
  if (f < 0) {
    return -1;
  }
  const int r = load ? sh_read(f, &_sdata, snap_bytes()) : sh_write(f, &_sdata, snap_bytes());
  sh_close(f);
  return r;
}

static int fail(int code, const char *msg) {
  sh_puts("fluxdrive-pil: ");
  sh_puts(msg);
  sh_puts("\n");
  return code;
}

/* One period: the command block as the ISR found it, then the ISR. */
static bool force_applied;

__attribute__((noinline)) static void pil_step(const isr_stream_in_t *in, isr_stream_out_t *o) {
  uint32_t seq;
  isr_stream_cmd_get(in, &seq, &drv.req.cmd, &drv.req.ident);
  drv.req.seq = seq;
  hal_pil_set_input(in);
  if (force_applied) {
    drv.v_applied = (ab_t){in->v_applied[0], in->v_applied[1]};
  }
  drive_isr(&drv);
  bool on = false;
  hal_pil_get_output(o->duty, &on);
  o->flags = on ? ISR_OUT_GATES_ON : 0u;
  o->faults = drv.faults;
  o->state = (uint32_t)drv.state;
}

int main(void) {
  const int32_t fin = sh_open("pil_in.bin", "rb");
  if (fin < 0) {
    return fail(2, "cannot open pil_in.bin");
  }
  isr_stream_header_t h = {0};
  if (sh_read(fin, &h, sizeof h) != 0) {
    return fail(3, "pil_in.bin: short header");
  }
  if (h.magic != ISR_STREAM_MAGIC || h.version != ISR_STREAM_VERSION || h.header_size != sizeof h ||
      h.config_size < 4u * ISR_STREAM_CONFIG_WORDS + 4u ||
      h.config_size > 4u * ISR_STREAM_CONFIG_WORDS + 4u + (uint32_t)ISR_STREAM_MAP_MAX ||
      h.caps_size != 4u * ISR_STREAM_CAPS_WORDS || h.in_size != sizeof(isr_stream_in_t) ||
      h.out_size != sizeof(isr_stream_out_t)) {
    return fail(3, "pil_in.bin: not an isr_stream of this version/layout");
  }
  force_applied = (h.flags & ISR_STREAM_FORCE_APPLIED) != 0u;
  static uint32_t words[ISR_STREAM_CONFIG_WORDS];
  if (sh_read(fin, words, sizeof words) != 0) {
    return fail(3, "pil_in.bin: short configuration");
  }
  static drive_config_t cfg;
  isr_stream_config_get(&cfg, words);
  /* the flux map's blob: the same bytes the host's drive parsed */
  static uint32_t map[ISR_STREAM_MAP_MAX / 4];
  uint32_t map_bytes = 0u;
  if (sh_read(fin, &map_bytes, sizeof map_bytes) != 0 ||
      map_bytes != h.config_size - 4u * ISR_STREAM_CONFIG_WORDS - 4u ||
      (map_bytes > 0u && sh_read(fin, map, map_bytes) != 0)) {
    return fail(3, "pil_in.bin: bad flux-map section");
  }
  cfg.machine_map = map_bytes > 0u ? map : NULL;
  static uint32_t cwords[ISR_STREAM_CAPS_WORDS];
  if (sh_read(fin, cwords, sizeof cwords) != 0) {
    return fail(3, "pil_in.bin: short capabilities");
  }
  hal_caps_t caps;
  uint32_t counts;
  isr_stream_caps_get(&caps, &counts, cwords);
  if ((h.flags & ISR_STREAM_SNAP_LOAD) != 0u) {
    /* the state after the records before these (the same configuration:
     * the words and the map read above are restored as they were) */
    if (snap(true) != 0) {
      return fail(6, "cannot read pil_snap.bin");
    }
    force_applied = (h.flags & ISR_STREAM_FORCE_APPLIED) != 0u; /* this file's */
  } else {
    hal_pil_set_caps(&caps, counts);
    drive_config_err_t err;
    if (drive_init(&drv, &cfg, &err) != 0) {
      sh_puts(err.field);
      sh_puts(": ");
      sh_puts(err.reason);
      return fail(4, ": drive_init rejected the recorded configuration");
    }
  }
  const int32_t fout = sh_open("pil_out.bin", "wb");
  if (fout < 0) {
    return fail(5, "cannot open pil_out.bin");
  }
  for (uint32_t done = 0; done < h.count;) {
    const uint32_t n = (h.count - done) < CHUNK ? (h.count - done) : CHUNK;
    if (sh_read(fin, rec, n * sizeof rec[0]) != 0) {
      return fail(3, "pil_in.bin: short record");
    }
    /* n >= 1 inside the loop (cppcheck misreads the chunking) */
    // cppcheck-suppress knownConditionTrueFalse
    for (uint32_t i = 0; i < n; ++i) {
      pil_step(&rec[i].in, &out[i]);
    }
    if (sh_write(fout, out, n * sizeof out[0]) != 0) {
      return fail(5, "pil_out.bin: write failed");
    }
    done += n;
  }
  sh_close(fout);
  sh_close(fin);
  if ((h.flags & ISR_STREAM_SNAP_SAVE) != 0u && snap(false) != 0) {
    return fail(6, "cannot write pil_snap.bin");
  }
  return 0;
}
