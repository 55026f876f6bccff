/*
 * board_b_g431b_esc1.h - ST B-G431B-ESC1 discovery kit (STM32G431CB: 128 KiB
 * flash, SRAM1 16 KiB + SRAM2 6 KiB, CCM SRAM 10 KiB), user manual UM2516.
 * Power stage: L6387 gate drivers, STL180N6F7 MOSFETs, three low-side
 * shunts read through the MCU's internal OPAMP1..3 (UM2516, "Hardware
 * layout and configuration": current sensing and bus voltage sensing; the
 * pin assignment is the one of the MCSDK board description for this kit).
 * Only board facts live here.
 */
#ifndef FLUXDRIVE_BOARD_B_G431B_ESC1_H
#define FLUXDRIVE_BOARD_B_G431B_ESC1_H

#define BOARD_NAME   "b-g431b-esc1"
#define BOARD_HSE_HZ 8000000u /* 8 MHz crystal on the ESC board */

/* PWM: U/V/W high = TIM1_CH1/2/3 on PA8/PA9/PA10 (AF6), low = TIM1_CH1N on
 * PC13 (AF4), TIM1_CH2N on PA12 (AF6), TIM1_CH3N on PB15 (AF4). The L6387
 * inputs HIN and LIN are active high. */
#define BOARD_PWM_HZ       16000u
#define BOARD_DEAD_TIME_NS 500u /* starting value; check the gate timing on a scope */
#define BOARD_DUTY_MAX     0.95f
#define BOARD_PWM_PINS                                                                             \
  {                                                                                                \
    {PORT_A, 8, 6}, {PORT_A, 9, 6}, {PORT_A, 10, 6}, {PORT_C, 13, 4}, {PORT_A, 12, 6}, {           \
      PORT_B, 15, 4                                                                                \
    }                                                                                              \
  }
#define BOARD_PWM_HIGH_ACTIVE_LOW 0
#define BOARD_PWM_LOW_ACTIVE_LOW  0

/* Hardware over-current: no BKIN pin; the MCU's comparators watch the
 * shunt signals at the op-amps' non-inverting inputs (the kit's wiring, as
 * ST's motor-control SDK configures it) against DAC3 and break TIM1
 * (hal/stm32g4/break_comp.c, docs/flashing.md "Hardware over-current"):
 *   U: COMP1 INP IO1 = PA1 (OPAMP1 VINP0), INM = DAC3_CH1
 *   V: COMP2 INP IO1 = PA7 (OPAMP2 VINP0), INM = DAC3_CH2
 *   W: COMP4 INP IO1 = PB0 (OPAMP3 VINP0), INM = DAC3_CH2
 * Entries {COMP number 1..4, INPSEL}. The comparator sees the PGA input:
 * the ADC pin voltage over BOARD_OPAMP_PGA_GAIN. */
#define BOARD_HAS_BKIN       0
#define BOARD_HAS_BREAK_COMP 1
#define BOARD_BREAK_COMPS                                                                          \
  {                                                                                                \
    {1u, 0u}, {2u, 0u}, {                                                                          \
      4u, 0u                                                                                       \
    }                                                                                              \
  }
#define BOARD_BREAK_NCOMPS 3
/* The phase current at which the stage trips, taken OUT of the machine
 * through a low-side shunt (where its signal rises; a leg shoot-through
 * flows that way too). Above BOARD_I_TRIP (the drive trips first), at the
 * kit's 40 A peak rating. */
#define BOARD_HW_TRIP_A 40.0f
/* BKF = 0111: f_DTS / 4, N = 8: 8 x 4 / 170 MHz = 188 ns of the switching
 * edges' ringing ignored */
#define BOARD_BREAK_FILTER 0x7u
/* The kit's L6387E gate drivers have no fault output: no break 2. */
#define BOARD_HAS_BKIN2 0

/* FDCAN1: PA11 RX / PB9 TX (AF9), transceiver on the ESC board. */
#define BOARD_CAN_RX_PIN                                                                           \
  { PORT_A, 11, 9 }
#define BOARD_CAN_TX_PIN                                                                           \
  { PORT_B, 9, 9 }
#define BOARD_CAN_BITRATE 500000u
#define BOARD_CAN_NODE_ID 1u

/* Analog front end. OPAMP1/2/3 in PGA mode (non-inverting gain 16 with the
 * bias network on VINM0), outputs on their pins:
 *   U: OPAMP1 VINP0 PA1, VINM0 PA3, VOUT PA2 = ADC1_IN3
 *   V: OPAMP2 VINP0 PA7, VINM0 PA5, VOUT PA6 = ADC2_IN3
 *   W: OPAMP3 VINP0 PB0, VINM0 PB2, VOUT PB1 = ADC1_IN12
 *   V_bus: divider to PA0 = ADC1_IN1
 * The kit has no star-point sensing: v_star is reported as 0. */
#define BOARD_ADC_IA                                                                               \
  { 1u, 3u, ADC_SMP_12_5 }
#define BOARD_ADC_IB                                                                               \
  { 2u, 3u, ADC_SMP_12_5 }
#define BOARD_ADC_IC                                                                               \
  { 1u, 12u, ADC_SMP_12_5 }
#define BOARD_ADC_VDC                                                                              \
  { 1u, 1u, ADC_SMP_47_5 }
#define BOARD_ADC_VSTAR                                                                            \
  { 0u, 0u, 0u }
#define BOARD_ADC_PINS                                                                             \
  {                                                                                                \
    {PORT_A, 1, 0}, {PORT_A, 2, 0}, {PORT_A, 3, 0}, {PORT_A, 5, 0}, {PORT_A, 6, 0},                \
        {PORT_A, 7, 0}, {PORT_B, 0, 0}, {PORT_B, 1, 0}, {PORT_B, 2, 0}, {                          \
      PORT_A, 0, 0                                                                                 \
    }                                                                                              \
  }
#define BOARD_ADC_NPINS 10

#define BOARD_USE_OPAMP_PGA       1
#define BOARD_OPAMP_PGA_GAIN_CODE 0x0Bu /* PGA_GAIN = 01011: x16, bias/input on VINM0 */
#define BOARD_OPAMP_PGA_GAIN      16.0f /* the PGA output over its VINP input */

/* Shunt 3 mOhm; total gain shunt -> ADC pin 9.14 V/V (external resistor
 * network + PGA x16); the signal FALLS with current into the machine. */
#define BOARD_VDDA            3.3f
#define BOARD_I_MID_V         1.65f /* nominal; the drive calibrates the real offset */
#define BOARD_I_A_PER_V       (-1.0f / (0.003f * 9.14f))
#define BOARD_VDC_RATIO       (1.0f / 0.0962f) /* bus divider gain 0.0962 */
#define BOARD_VSTAR_RATIO     0.0f
#define BOARD_HAS_STAR_WINDOW 0 /* no star-point sensing on the kit */

/* Protections: 6S LiPo (25.2 V) max, kit rated 40 A peak. */
#define BOARD_I_TRIP   30.0f
#define BOARD_V_DC_MAX 28.0f
#define BOARD_V_DC_MIN 7.0f

#define BOARD_IWDG_TIMEOUT_MS 50u

#endif
