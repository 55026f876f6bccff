/*
 * break_comp.c - the comparator over-current trip into the TIM1 break.
 *
 * Each comparator of the board table (BOARD_BREAK_COMPS) compares a shunt
 * signal (INP, RM0440 24.3.2) with DAC3 (INMSEL = 100: DAC3_CH1 for COMP1
 * and COMP3, DAC3_CH2 for COMP2 and COMP4); its output is high while the
 * signal is above the threshold (POLARITY = 0) and reaches TIM1's break
 * through TIM1_AF1.BKCMPxE (RM0440 28.3.19, 28.6.25), where BKP = 1 makes
 * the high level the break.
 *
 * DAC3 has no pins: MODE = 011 (normal, on-chip peripherals only, buffer
 * off), HFSEL = 10 (AHB above 160 MHz), no trigger (the value is taken one
 * clock after the write), reference VREF+ = VDDA (RM0440 22.4). Both
 * channels hold the same threshold. The comparators have no hysteresis
 * (it would move the trip level) and no blanking; the break filter (BKF)
 * skips the switching edges. Their CSRs are locked (LOCK = 1) until reset.
 */
#include "break_comp.h"

#include "board.h"
#include "clock.h"

#if BOARD_HAS_BREAK_COMP

typedef struct {
  uint8_t comp;   /* COMP number 1..4 */
  uint8_t inpsel; /* COMP_CSR.INPSEL: 0 = INP IO1 */
} break_comp_t;

static const break_comp_t k_comps[BOARD_BREAK_NCOMPS] = BOARD_BREAK_COMPS;

/* the drive's sampled i_trip acts first; the comparators are the backstop */
_Static_assert((int)BOARD_HW_TRIP_A > (int)BOARD_I_TRIP, "BOARD_HW_TRIP_A above BOARD_I_TRIP");

/* the signal at the comparator per ampere, and at zero current [V] */
#define CMP_V_PER_A (1.0f / (BOARD_OPAMP_PGA_GAIN * BOARD_I_A_PER_V))
#define CMP_V_MID   (BOARD_I_MID_V / BOARD_OPAMP_PGA_GAIN)

static float abs_f(float x) {
  return x < 0.0f ? -x : x;
}

uint32_t hal_break_comp_dac_code(float i_trip) {
  const float v = CMP_V_MID + abs_f(i_trip * CMP_V_PER_A);
  const float code = v * (4095.0f / BOARD_VDDA) + 0.5f;
  if (!(code > 0.0f)) {
    return 0u;
  }
  return code >= 4095.0f ? 4095u : (uint32_t)code;
}

float hal_break_comp_trip_current(uint32_t code) {
  const float v = (float)code * (BOARD_VDDA / 4095.0f);
  return (v - CMP_V_MID) / abs_f(CMP_V_PER_A);
}

uint32_t hal_break_comp_af1(void) {
  uint32_t af1 = 0u;
  for (uint32_t k = 0; k < (uint32_t)BOARD_BREAK_NCOMPS; k++) {
    af1 |= TIM1_AF1_BKCMPE(k_comps[k].comp);
  }
  return af1;
}

bool hal_break_comp_init(void) {
  RCC->APB2ENR |= RCC_APB2ENR_SYSCFGEN; /* the COMP registers sit on the SYSCFG clock */
  RCC->AHB2ENR |= RCC_AHB2ENR_DAC3EN;
  (void)RCC->AHB2ENR;

  /* DAC3: mode while disabled, enable, wait ready, then the value */
  DAC3->CR = 0u;
  DAC3->MCR = (DAC_MODE_INTERNAL << 0) | (DAC_MODE_INTERNAL << DAC_MCR_MODE2_Pos) |
              (DAC_HFSEL_160MHZ << DAC_MCR_HFSEL_Pos);
  DAC3->CR = DAC_CR_EN1 | DAC_CR_EN2;
  bool ready = false;
  for (uint32_t t = 0; t < 100000u && !ready; t++) {
    ready = (DAC3->SR & (DAC_SR_DAC1RDY | DAC_SR_DAC2RDY)) == (DAC_SR_DAC1RDY | DAC_SR_DAC2RDY);
  }
  const uint32_t code = hal_break_comp_dac_code(BOARD_HW_TRIP_A);
  DAC3->DHR12R1 = code;
  DAC3->DHR12R2 = code;
  hal_delay_cycles(170u * 8u); /* t_wakeup: 8 us for the output to settle */

  /* comparators: configure, enable, start-up time, lock */
  for (uint32_t k = 0; k < (uint32_t)BOARD_BREAK_NCOMPS; k++) {
    const uint32_t csr = (COMP_INMSEL_DAC3 << COMP_CSR_INMSEL_Pos) |
                         (k_comps[k].inpsel != 0u ? COMP_CSR_INPSEL : 0u);
    COMP->CSR[k_comps[k].comp - 1u] = csr;
    COMP->CSR[k_comps[k].comp - 1u] = csr | COMP_CSR_EN;
  }
  hal_delay_cycles(170u * 5u); /* t_START: 5 us */
  for (uint32_t k = 0; k < (uint32_t)BOARD_BREAK_NCOMPS; k++) {
    COMP->CSR[k_comps[k].comp - 1u] |= COMP_CSR_LOCK;
  }
  return ready;
}

#else

uint32_t hal_break_comp_dac_code(float i_trip) {
  (void)i_trip;
  return 0u;
}

float hal_break_comp_trip_current(uint32_t code) {
  (void)code;
  return 0.0f;
}

uint32_t hal_break_comp_af1(void) {
  return 0u;
}

bool hal_break_comp_init(void) {
  return true;
}

#endif
