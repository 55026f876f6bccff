/*
 * hal.h - the one boundary between fluxdrive and hardware.
 *
 * Two implementations link against this interface: hal/stm32g4/ (registers)
 * and hal/sil/ (the plant model on a Linux host). firmware/app uses it;
 * firmware/core never includes it.
 *
 * Timing model (docs/architecture.md): the PWM carrier is centre-aligned with
 * period Ts. The ADC sample set is taken at the carrier valley, the centre of
 * the zero vector where the symmetric pattern makes the sampled current equal
 * to its period average. drive_isr() runs right after; duties written by
 * hal_pwm_set_duty() are preloaded and take effect at the next valley, so a
 * command computed from the samples of period k acts over [k+1, k+2).
 */
#ifndef FLUXDRIVE_HAL_H
#define FLUXDRIVE_HAL_H

#include <stdbool.h>
#include <stdint.h>

/* One sample set, converted to SI units with the board's nominal gains. The
 * current offsets are NOT removed here: the drive calibrates them with the
 * gates off (state DRIVE_OFFSET_CAL). */
typedef struct {
  float i_abc[3];  /* phase currents, positive into the machine [A] */
  float v_dc;      /* DC-link voltage [V] */
  float v_star;    /* star-point voltage w.r.t. the DC-link midpoint [V] */
  float enc_angle; /* mechanical rotor angle from the encoder [rad], [0, 2pi) */
  bool enc_valid;  /* false when the board has no encoder or it failed */
} hal_adc_sample_t;

/* Reads the sample set of the current PWM period. */
void hal_adc_read(hal_adc_sample_t *s);

/* Duty cycles of the three high-side switches in [0, 1]; values outside are
 * clamped by the HAL. Preloaded: they act from the next period start. */
void hal_pwm_set_duty(float da, float db, float dc);
/* Gates on (complementary outputs with dead time) / all gates off. */
void hal_pwm_enable(void);
void hal_pwm_disable(void);
bool hal_pwm_is_enabled(void);

/* Classic CAN frame. */
typedef struct {
  uint32_t id;   /* 11-bit or 29-bit identifier */
  bool extended; /* 29-bit identifier */
  uint8_t dlc;   /* 0..8 */
  uint8_t data[8];
} hal_can_frame_t;

/* Queue a frame for transmission; false when the TX queue is full. */
bool hal_can_send(const hal_can_frame_t *f);
/* Pop one received frame; false when none is pending. Never blocks. */
bool hal_can_receive(hal_can_frame_t *f);

/* Free-running microsecond time (wraps after 2^32 us). */
uint32_t hal_time_us(void);

/* Hardware protection: the break input (comparator overcurrent) turns the
 * gates off in hardware and latches; the drive reads and clears it. */
bool hal_fault_hw_tripped(void);
void hal_fault_hw_clear(void);

/* Watchdog refresh, called by the control loop. */
void hal_watchdog_kick(void);

#endif /* FLUXDRIVE_HAL_H */
