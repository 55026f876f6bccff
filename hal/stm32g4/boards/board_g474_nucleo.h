/*
 * board_g474_nucleo.h - NUCLEO-G474RE (STM32G474RE: 512 KiB flash, SRAM1
 * 80 KiB + SRAM2 16 KiB, CCM SRAM 32 KiB) with a GENERIC three-phase power
 * stage on the Morpho connectors. Only board facts live here.
 *
 * ASSUMPTIONS (no specific power board is fixed yet; edit for real hardware):
 *  - HSE: the 24 MHz crystal X3 of the Nucleo-64 MB1367 board.
 *  - Gate driver inputs active high for both high (CHx) and low (CHxN) side.
 *  - Three low-side shunts, 10 mOhm, amplifiers with gain 8 biased at
 *    VDDA/2; the amplifier output rises with current INTO the machine.
 *  - DC-link and star-point dividers 1:20 (e.g. 190 k / 10 k), star point
 *    measured against ground through a 1:20 divider.
 *  - An external over-current comparator output, active low, on PA6 =
 *    TIM1_BKIN (AF6), open drain with a pull-up.
 */
#ifndef FLUXDRIVE_BOARD_G474_NUCLEO_H
#define FLUXDRIVE_BOARD_G474_NUCLEO_H

#define BOARD_NAME   "g474-nucleo"
#define BOARD_HSE_HZ 24000000u /* 0 = run from HSI16 */

/* PWM */
#define BOARD_PWM_HZ       16000u
#define BOARD_DEAD_TIME_NS 500u  /* generic MOSFET stage */
#define BOARD_DUTY_MAX     0.95f /* keeps the low side on >= 3 us around the valley */
/* TIM1 CH1, CH2, CH3, CH1N, CH2N, CH3N (STM32G474 datasheet, alternate functions) */
#define BOARD_PWM_PINS                                                                             \
  {                                                                                                \
    {PORT_A, 8, 6}, {PORT_A, 9, 6}, {PORT_A, 10, 6}, {PORT_B, 13, 6}, {PORT_B, 14, 6}, {           \
      PORT_B, 15, 4                                                                                \
    }                                                                                              \
  }
#define BOARD_PWM_HIGH_ACTIVE_LOW 0
#define BOARD_PWM_LOW_ACTIVE_LOW  0

/* Hardware over-current: BKIN pin, active low, digital filter fCK/32 N=8. */
#define BOARD_HAS_BKIN       1
#define BOARD_HAS_BREAK_COMP 0 /* no comparator trip: the external one on BKIN */
#define BOARD_BKIN_PIN                                                                             \
  { PORT_A, 6, 6 }
#define BOARD_BKIN_ACTIVE_HIGH 0
#define BOARD_BKIN_FILTER      0x3u /* BKF: fCK_INT, N = 8 (47 ns at 170 MHz) */

/* Gate driver fault output nFAULT (desaturation / shoot-through, driver
 * supply undervoltage; open drain, active low) on TIM1_BKIN2. ASSUMPTION:
 * PC3 = TIM1_BKIN2 on AF6 (check against the datasheet's alternate-function
 * table and the power board). Filter as BKIN. */
#define BOARD_HAS_BKIN2 1
#define BOARD_BKIN2_PIN                                                                            \
  { PORT_C, 3, 6 }
#define BOARD_BKIN2_ACTIVE_HIGH 0
#define BOARD_BKIN2_FILTER      0x3u /* BK2F */

/* FDCAN1: PA11 RX / PA12 TX (AF9) */
#define BOARD_CAN_RX_PIN                                                                           \
  { PORT_A, 11, 9 }
#define BOARD_CAN_TX_PIN                                                                           \
  { PORT_A, 12, 9 }
#define BOARD_CAN_BITRATE 500000u
#define BOARD_CAN_NODE_ID 1u

/* Analog front end: {ADC (1, 2; 0 = absent), channel, sample time} */
#define BOARD_ADC_IA                                                                               \
  { 1u, 1u, ADC_SMP_12_5 } /* PA0  ADC1_IN1 */
#define BOARD_ADC_IB                                                                               \
  { 2u, 2u, ADC_SMP_12_5 } /* PA1  ADC2_IN2 */
#define BOARD_ADC_IC                                                                               \
  { 1u, 7u, ADC_SMP_12_5 } /* PC1  ADC1_IN7 */
#define BOARD_ADC_VDC                                                                              \
  { 1u, 15u, ADC_SMP_47_5 } /* PB0  ADC1_IN15 */
#define BOARD_ADC_VSTAR                                                                            \
  { 2u, 17u, ADC_SMP_24_5 } /* PA4  ADC2_IN17: sampled 0.6..1.2 us after the valley */
/* The Direct Flux Control window (docs/dfc.md, star_window.c): the star
 * channel again, its regular conversion at the after-sample */
#ifndef BOARD_HAS_STAR_WINDOW
#define BOARD_HAS_STAR_WINDOW 0 /* CMake FD_STAR_WINDOW=ON sets it to 1 */
#endif
#define BOARD_ADC_VSTAR_ADC     2u
#define BOARD_ADC_VSTAR_CHANNEL 17u
#define BOARD_ADC_PINS                                                                             \
  {                                                                                                \
    {PORT_A, 0, 0}, {PORT_A, 1, 0}, {PORT_C, 1, 0}, {PORT_B, 0, 0}, {                              \
      PORT_A, 4, 0                                                                                 \
    }                                                                                              \
  }
#define BOARD_ADC_NPINS 5

#define BOARD_VDDA        3.3f
#define BOARD_I_MID_V     1.65f                    /* amplifier output at zero current [V] */
#define BOARD_I_A_PER_V   (1.0f / (0.010f * 8.0f)) /* 1 / (R_shunt * gain) [A/V] */
#define BOARD_VDC_RATIO   20.0f                    /* V_dc / V_adc */
#define BOARD_VSTAR_RATIO 20.0f                    /* V_star(to ground) / V_adc */

/* Internal OPAMPs in PGA mode: not used on this board. */
#define BOARD_USE_OPAMP_PGA 0

/* Protections handed to drive_config (the power stage's ratings). */
#define BOARD_I_TRIP   20.0f
#define BOARD_V_DC_MAX 60.0f
#define BOARD_V_DC_MIN 8.0f

#define BOARD_IWDG_TIMEOUT_MS 50u

#endif
