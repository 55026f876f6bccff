/*
 * can_codec_tool.c - the C side of the DBC agreement test
 * (test_dbc_agreement.py): prints the codec's tables and packs / unpacks
 * frames given on stdin, so that pytest can compare them with cantools.
 *
 *   can_codec_tool describe         tables: MSG, SIG, RESULT, PARAM lines
 *   can_codec_tool unpack < lines   "MSG HEX"          -> "sig raw phys in_range" ...
 *   can_codec_tool pack < lines     "MSG sig=v ..."    -> "HEX"
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_codec.h"
#include "can_proto.h"
#include "drive_params.h"

static int find_msg(const char *name) {
  for (int m = 0; m < (int)CAN_MSG_COUNT; ++m) {
    if (strcmp(can_codec_msg((can_msg_t)m)->name, name) == 0) {
      return m;
    }
  }
  return -1;
}

static int64_t signed_raw(const can_sig_desc_t *d, uint32_t raw) {
  if (d->is_signed && !d->is_float && d->length < 32u && (raw & (1u << (d->length - 1u))) != 0u) {
    return (int64_t)raw - (int64_t)(1ll << d->length);
  }
  if (d->is_signed && !d->is_float && d->length == 32u) {
    return (int64_t)(int32_t)raw;
  }
  return (int64_t)raw;
}

static void describe(void) {
  for (int m = 0; m < (int)CAN_MSG_COUNT; ++m) {
    const can_msg_desc_t *md = can_codec_msg((can_msg_t)m);
    printf("MSG %s %u %u %d\n", md->name, (unsigned)md->base_id, (unsigned)md->dlc,
           md->to_drive ? 1 : 0);
    for (unsigned i = 0; i < md->n_signals; ++i) {
      can_sig_t s = (can_sig_t)((unsigned)md->first + i);
      const can_sig_desc_t *d = can_codec_sig(s);
      printf("SIG %s %s %u %u %d %d %.9g %.9g %.9g %.9g %lld %lld %d\n", md->name, d->name,
             (unsigned)d->start, (unsigned)d->length, d->is_signed ? 1 : 0, d->is_float ? 1 : 0,
             (double)d->scale, (double)d->offset, (double)d->min, (double)d->max,
             (long long)d->raw_min, (long long)d->raw_max, (int)s + 1);
    }
  }
  for (unsigned r = 0; r < CAN_RESULT_COUNT; ++r) {
    printf("RESULT %u %s\n", r, can_codec_result_name(r));
  }
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  for (unsigned i = 0; i < n; ++i) {
    printf("PARAM %u %s\n", (unsigned)t[i].id, t[i].name);
  }
  can_proto_t p;
  can_proto_cfg_t cfg;
  can_proto_cfg_default(&cfg);
  can_proto_init(&p, &cfg);
  for (unsigned id = 0; id < 256u; ++id) {
    float v;
    if (can_proto_param_get(&p, (uint8_t)id, &v)) {
      printf("PPARAM %u\n", id);
    }
  }
}

static int unpack(void) {
  char line[512], name[64], hex[64];
  while (fgets(line, sizeof line, stdin) != NULL) {
    if (sscanf(line, "%63s %63s", name, hex) != 2) {
      continue;
    }
    int m = find_msg(name);
    if (m < 0) {
      fprintf(stderr, "unknown message %s\n", name);
      return 1;
    }
    uint8_t data[8] = {0};
    for (size_t i = 0; i < 8 && 2 * i + 1 < strlen(hex); ++i) {
      unsigned b;
      sscanf(hex + 2 * i, "%2x", &b);
      data[i] = (uint8_t)b;
    }
    const can_msg_desc_t *md = can_codec_msg((can_msg_t)m);
    for (unsigned i = 0; i < md->n_signals; ++i) {
      can_sig_t s = (can_sig_t)((unsigned)md->first + i);
      const can_sig_desc_t *d = can_codec_sig(s);
      printf("%s %lld %.9g %d ", d->name, (long long)signed_raw(d, can_codec_get_raw(s, data)),
             (double)can_codec_get(s, data), can_codec_in_range(s, data) ? 1 : 0);
    }
    printf("\n");
  }
  return 0;
}

static int pack(void) {
  char line[1024];
  while (fgets(line, sizeof line, stdin) != NULL) {
    char *tok = strtok(line, " \n");
    if (tok == NULL) {
      continue;
    }
    int m = find_msg(tok);
    if (m < 0) {
      fprintf(stderr, "unknown message %s\n", tok);
      return 1;
    }
    const can_msg_desc_t *md = can_codec_msg((can_msg_t)m);
    uint8_t data[8] = {0};
    while ((tok = strtok(NULL, " \n")) != NULL) {
      char *eq = strchr(tok, '=');
      if (eq == NULL) {
        return 1;
      }
      *eq = '\0';
      int found = 0;
      for (unsigned i = 0; i < md->n_signals; ++i) {
        can_sig_t s = (can_sig_t)((unsigned)md->first + i);
        if (strcmp(can_codec_sig(s)->name, tok) == 0) {
          can_codec_set(s, data, strtof(eq + 1, NULL));
          found = 1;
        }
      }
      if (!found) {
        fprintf(stderr, "unknown signal %s\n", tok);
        return 1;
      }
    }
    for (unsigned i = 0; i < md->dlc; ++i) {
      printf("%02X", data[i]);
    }
    printf("\n");
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc == 2 && strcmp(argv[1], "describe") == 0) {
    describe();
    return 0;
  }
  if (argc == 2 && strcmp(argv[1], "unpack") == 0) {
    return unpack();
  }
  if (argc == 2 && strcmp(argv[1], "pack") == 0) {
    return pack();
  }
  fprintf(stderr, "usage: can_codec_tool describe|unpack|pack\n");
  return 2;
}
