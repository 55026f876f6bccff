/*
 * pos_encoder.h - the encoder's position source: its row's functions
 * (pos_encoder.c; the row: pos_sources.c).
 */
#ifndef FLUXDRIVE_POS_ENCODER_H
#define FLUXDRIVE_POS_ENCODER_H

#include "pos_source.h"

void pos_encoder_init(pos_state_t *s, const drive_config_t *cfg);
void pos_encoder_reset(pos_state_t *s);
void pos_encoder_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                        pos_io_t *io);
void pos_encoder_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                       float theta);
const char *pos_encoder_check(const drive_config_t *cfg, const char **field);

#endif
