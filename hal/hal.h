/*
 * hal.h - the one boundary between fluxdrive and hardware.
 *
 * Three implementations link against this interface: hal/stm32g4/
 * (registers), hal/sil/ (the plant model on a Linux host) and pil/ (a
 * recorded SIL run replayed on QEMU). firmware/app uses it; firmware/core
 * never includes it.
 *
 * Timing model (docs/architecture.md). Period k starts at the carrier
 * valley t_k. Every instant below is relative to the start of the period
 * the sample set belongs to. The HAL samples the phase currents and the DC
 * link at t_i (the valley plus the ADC's sampling delay: the centre of the
 * zero vector 000, where the sampled current equals the period average),
 * the encoder at t_enc and up to HAL_STAR_MAX star-point voltages at their
 * own instants; drive_isr() runs after the last of them (a star-point
 * sample taken in the period before, as the DFC window's after-sample is
 * on the SIL and the STM32G4, has a negative instant). The pattern
 * written by hal_pwm_write() is preloaded and acts over the next period
 * [t_{k+1}, t_{k+2}), so a command computed from the samples of period k
 * acts one period later; the drive extrapolates the rotor angle from the
 * sample timestamps to the centre of that interval.
 */
#ifndef FLUXDRIVE_HAL_H
#define FLUXDRIVE_HAL_H

#include <stdbool.h>
#include <stdint.h>

#define HAL_STAR_MAX 2 /* star-point samples per period */

/* What the board can do, published once (constant after start-up). The
 * modulation keeps every duty inside [duty_min, duty_max], so that the
 * HAL never clamps a request and the voltage the observers integrate is
 * the voltage applied. */
typedef struct {
  float ts;           /* PWM period [s] */
  float t_count;      /* timer resolution: one compare step [s] of pulse width */
  float dead_time;    /* inserted by the timer [s] */
  float duty_min;     /* smallest duty that is not 0 (gate driver, bootstrap) */
  float duty_max;     /* largest duty: the low side must stay on t_i_clear around the valley */
  float t_i;          /* current / DC-link sampling instant after the period start [s] */
  float t_i_clear;    /* zero-vector time the current sample needs around t_i [s] */
  float t_enc;        /* encoder sampling instant after the period start [s] */
  float cpu_hz;       /* CPU clock for hal_isr_stats() [Hz] (0: no cycle counter) */
  float i_full_scale; /* largest phase current the ADC reads, either sign [A] (0: not known) */
  float v_full_scale; /* largest DC-link voltage the ADC reads [V] (0: not known) */
  float i_lsb;        /* the current ADC's step [A] (0: not known) */
  uint32_t features;  /* HAL_CAP_* */
} hal_caps_t;

enum {
  HAL_CAP_ENCODER = 1u << 0,    /* an encoder input is fitted */
  HAL_CAP_ASYM_EDGES = 1u << 1, /* hal_pwm_t.on/off placed independently (else
                                   centred pulses only: on = 1 - off) */
  HAL_CAP_STAR_POINT = 1u << 2, /* star-point samples at requested instants */
  HAL_CAP_DWT_CYCLES = 1u << 3, /* hal_isr_stats() measures cycles */
  HAL_CAP_I_ABC = 1u << 4       /* all three phase currents measured (not one
                                   reconstructed from the others): their sum
                                   is a check (drive: current_sensor fault) */
};

const hal_caps_t *hal_caps(void);

/* One period's sample set, in SI units with the board's nominal gains.
 * The current offsets are NOT removed: the drive calibrates them with the
 * gates off (state offset_cal). */
typedef struct {
  float i_abc[3]; /* phase currents, positive into the machine [A] */
  float v_dc;     /* DC-link voltage [V] */
  float t_i;      /* instant of i_abc and v_dc [s] */
  /* star-point voltage w.r.t. the DC-link midpoint, at t_star[n] */
  float v_star[HAL_STAR_MAX];
  float t_star[HAL_STAR_MAX];
  uint8_t n_star;      /* samples taken (0..HAL_STAR_MAX) */
  uint8_t test_vector; /* active vector v1..v6 applied around them, 0 none */
  bool enc_valid;      /* false: no encoder or it reports an error */
  float enc_angle;     /* mechanical angle, [0, 2 pi) [rad] */
  float t_enc;         /* instant of enc_angle [s] */
  bool valid;          /* false: the sample set is incomplete (ADC timeout) */
} hal_sample_t;

/* Reads the sample set of the present PWM period. */
void hal_adc_read(hal_sample_t *s);

/* A PWM pattern for one period: leg x's high side is commanded on over
 * [on[x], off[x]) in fractions of the period from its start (0 <= on <=
 * off <= 1); on = off: always low. A centred pulse of duty d has
 * on = (1 - d)/2, off = (1 + d)/2 (hal_pwm_centred()). A short test vector
 * at the period start (Direct Flux Control) is an earlier `on` of one leg
 * (HAL_CAP_ASYM_EDGES), with star-point samples requested at t_star_req. */
typedef struct {
  float on[3], off[3];
  uint8_t test_vector;            /* 0 none; 1..6: the vector the pattern starts with */
  uint8_t n_star;                 /* star-point samples requested */
  float t_star_req[HAL_STAR_MAX]; /* their instants [s] */
} hal_pwm_t;

static inline hal_pwm_t hal_pwm_centred(float da, float db, float dc) {
  hal_pwm_t p = {{0.5f * (1.0f - da), 0.5f * (1.0f - db), 0.5f * (1.0f - dc)},
                 {0.5f * (1.0f + da), 0.5f * (1.0f + db), 0.5f * (1.0f + dc)},
                 0u,
                 0u,
                 {0.0f, 0.0f}};
  return p;
}

/* Preloads the pattern of the next period. *applied (may be NULL)
 * receives what the timer will really do: edges rounded to its resolution,
 * limited to its range; the drive rebuilds the applied voltage from it. */
void hal_pwm_write(const hal_pwm_t *p, hal_pwm_t *applied);
/* Gates on (complementary outputs with dead time) / all gates off (at
 * once, not at the next period). */
void hal_pwm_enable(void);
void hal_pwm_disable(void);
bool hal_pwm_is_enabled(void);
/* Active short circuit (ASC): the three low-side switches on, the high
 * sides off, at once. A PM machine's back-EMF then drives its short-circuit
 * current in the windings and none into the DC link (the safe state above
 * the rectifier speed: docs/faults.md). Ended by hal_pwm_disable() or
 * hal_pwm_enable(); refused by the hardware while the break input is
 * active. hal_pwm_is_enabled() is false while shorted. */
void hal_pwm_short(void);
bool hal_pwm_is_shorted(void);

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

/* Hardware protection: a break input turns the gates off in hardware and
 * latches; the drive reads and clears it. Two sources: the board's
 * overcurrent comparator (break 1) and the gate driver's fault output
 * nFAULT (break 2: desaturation / shoot-through, driver supply
 * undervoltage, overtemperature). hal_fault_hw_tripped() is either (the one
 * call the ISR makes every period); hal_fault_hw_source() says which
 * (HAL_BREAK_* bits), read only once one has tripped. */
enum { HAL_BREAK_OVERCURRENT = 1u << 0, HAL_BREAK_GATE_DRIVER = 1u << 1 };
bool hal_fault_hw_tripped(void);
uint32_t hal_fault_hw_source(void);
void hal_fault_hw_clear(void);

/* Watchdog refresh. Called only by drive_background() (main loop), and
 * only when the ISR has advanced since the previous refresh: a hung main
 * loop or a stopped ISR both let the watchdog reset the MCU. */
void hal_watchdog_kick(void);
/* True when the last reset was caused by the watchdog. */
bool hal_reset_by_watchdog(void);

/* Execution statistics of the PWM-period interrupt as the board measures
 * them (HAL_CAP_DWT_CYCLES; zeros otherwise). */
typedef struct {
  uint32_t cycles_last, cycles_max; /* whole interrupt, entry to exit [CPU cycles] */
  uint32_t cycles_mean;             /* exponential mean over ~256 periods */
  uint32_t overruns;                /* periods whose interrupt did not finish in time */
} hal_isr_stats_t;
void hal_isr_stats(hal_isr_stats_t *st);
/* hal_isr_stats_t.overruns alone (one word, read in the ISR's slow path:
 * the drive's overrun check, drive_overrun.h). */
uint32_t hal_isr_overruns(void);

#endif /* FLUXDRIVE_HAL_H */
