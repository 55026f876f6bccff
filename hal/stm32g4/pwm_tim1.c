/*
 * pwm_tim1.c - TIM1 as the three-phase modulator, RM0440 section 28
 * (advanced-control timer TIM1).
 *
 * Carrier: centre-aligned mode 1 (CMS = 01), ARR = 170 MHz / (2 f_pwm),
 * so the counter runs 0 -> ARR -> 0 once per PWM period.
 * Pattern: PWM mode 2 (OCxREF active while CNT > CCRx), CCRx = (1 - d) ARR:
 * the high side conducts around the peak and ALL LOW SIDES conduct around
 * the valley (zero vector 000), where the low-side shunts carry the phase
 * currents.
 * Sampling instant: the repetition counter (RCR = 1) makes one update event
 * per period, aligned to the underflow (valley); TRGO = update starts the
 * ADC injected sequence there (hal.h timing model).
 * Preload: OCxPE = 1 and ARPE = 1, so duties written by the ISR after the
 * valley of period k are transferred at the valley k+1 and act over
 * [k+1, k+2).
 * Protection: the break (BKE = 1) from the BKIN pin (an external
 * comparator, G474) or the MCU's comparators (TIM1_AF1.BKCMPxE, ESC1:
 * break_comp.c): MOE is cleared in hardware, the outputs go inactive at
 * once and to the idle level after the dead time (OSSI = 1, OISx = OISxN =
 * off level), BIF latches until software clears it and MOE cannot be set
 * while the input is active. AOE = 0: no automatic restart. BKBID = 0: the
 * break is an input only. LOCK level 1 freezes the dead time, the break
 * (BKE, BKP, BKF, AF1 sources and polarities) and the idle levels OISx
 * until reset; OSSI/OSSR (level 2) and OCxM (level 3) stay writable, so
 * hal_pwm_short() works.
 * BKIN2 (the gate driver's nFAULT, boards with BOARD_HAS_BKIN2) with BK2E = 1
 * acts the same way; BIF / B2IF latch separately (hal_fault_hw_source()
 * tells them apart).
 */
#include "pwm_tim1.h"

#include "board.h"
#include "break_comp.h"
#include "hal.h"
#include "star_window.h"

#define HOT __attribute__((section(".ccmram.text.hal")))

uint32_t hal_tim1_dtg(uint32_t dead_ns, uint32_t f_tim) {
  const uint64_t ticks = ((uint64_t)dead_ns * f_tim + 999999999u) / 1000000000u;
  if (ticks <= 127u) {
    return (uint32_t)ticks; /* DTG[7] = 0: DT = DTG x t_DTS */
  }
  if (ticks <= 254u) {
    return 0x80u | (uint32_t)((ticks + 1u) / 2u - 64u); /* (64 + DTG[5:0]) x 2 t_DTS */
  }
  if (ticks <= 504u) {
    return 0xC0u | (uint32_t)((ticks + 7u) / 8u - 32u); /* (32 + DTG[4:0]) x 8 t_DTS */
  }
  if (ticks <= 1008u) {
    return 0xE0u | (uint32_t)((ticks + 15u) / 16u - 32u); /* (32 + DTG[4:0]) x 16 t_DTS */
  }
  return 0xFFu;
}

static const hal_pin_t k_pwm_pins[6] = BOARD_PWM_PINS;

void hal_tim1_init(void) {
  RCC->APB2ENR |= RCC_APB2ENR_TIM1EN;
  (void)RCC->APB2ENR;
  DBGMCU->APB2FZR |= DBGMCU_APB2FZR_TIM1_STOP; /* core halted: outputs disabled */

  TIM1->CR1 = 0u;
  TIM1->PSC = 0u;
  TIM1->ARR = BOARD_PWM_ARR;
  TIM1->RCR = 0u;
  TIM1->CCR1 = BOARD_PWM_ARR; /* d = 0 */
  TIM1->CCR2 = BOARD_PWM_ARR;
  TIM1->CCR3 = BOARD_PWM_ARR;

  TIM1->CCMR1 = (TIM_OCM_PWM2 << TIM_CCMR_OC1M_Pos) | TIM_CCMR_OC1PE |
                (TIM_OCM_PWM2 << TIM_CCMR_OC2M_Pos) | TIM_CCMR_OC2PE;
  TIM1->CCMR2 = (TIM_OCM_PWM2 << TIM_CCMR_OC1M_Pos) | TIM_CCMR_OC1PE; /* channel 3 */

  uint32_t chan = TIM_CCER_CC1E | TIM_CCER_CC1NE;
#if BOARD_PWM_HIGH_ACTIVE_LOW
  chan |= TIM_CCER_CC1P;
#endif
#if BOARD_PWM_LOW_ACTIVE_LOW
  chan |= TIM_CCER_CC1NP;
#endif
  const uint32_t ccer = chan | (chan << 4) | (chan << 8);
  TIM1->CCER = ccer;

  /* TRGO = update; idle levels (MOE = 0) = switch off. */
  uint32_t cr2 = TIM_CR2_MMS_UPDATE << TIM_CR2_MMS_Pos;
  for (uint32_t ch = 0; ch < 3u; ch++) {
    cr2 |= (BOARD_PWM_HIGH_ACTIVE_LOW ? 1u : 0u) << (8u + 2u * ch); /* OISx */
    cr2 |= (BOARD_PWM_LOW_ACTIVE_LOW ? 1u : 0u) << (9u + 2u * ch);  /* OISxN */
  }
  TIM1->CR2 = cr2;
#if BOARD_HAS_STAR_WINDOW
  star_window_tim1_init(); /* TRGO = OC4REF, TRGO2 = OC5REF, DMA burst of CCR1..3 */
#endif

  /* One BDTR write: dead time, break, off-state selection, LOCK level 1. */
  uint32_t bdtr = (hal_tim1_dtg(BOARD_DEAD_TIME_NS, BOARD_SYSCLK_HZ) & TIM_BDTR_DTG_Msk) |
                  TIM_BDTR_OSSI | TIM_BDTR_OSSR | (1u << TIM_BDTR_LOCK_Pos);
#if BOARD_HAS_BKIN
  TIM1->AF1 = TIM1_AF1_BKINE; /* BKIN pin only, BKINP = 0 */
  bdtr |= TIM_BDTR_BKE | (BOARD_BKIN_FILTER << TIM_BDTR_BKF_Pos);
#if BOARD_BKIN_ACTIVE_HIGH
  bdtr |= TIM_BDTR_BKP;
#endif
#elif BOARD_HAS_BREAK_COMP
  /* the comparators only (BKINE = 0), BKCMPxP = 0 with BKP = 1: active high */
  TIM1->AF1 = hal_break_comp_af1();
  bdtr |= TIM_BDTR_BKE | TIM_BDTR_BKP | (BOARD_BREAK_FILTER << TIM_BDTR_BKF_Pos);
#else
  TIM1->AF1 = 0u; /* no break source: BKE stays 0 */
#endif
#if BOARD_HAS_BKIN2
  TIM1->AF2 = TIM1_AF2_BK2INE; /* BKIN2 pin only, BK2INP = 0 */
  bdtr |= TIM_BDTR_BK2E | (BOARD_BKIN2_FILTER << TIM_BDTR_BK2F_Pos);
#if BOARD_BKIN2_ACTIVE_HIGH
  bdtr |= TIM_BDTR_BK2P;
#endif
#else
  TIM1->AF2 = 0u; /* no gate-driver fault input: BK2E stays 0 */
#endif
  TIM1->BDTR = bdtr;

  TIM1->CR1 = (1u << TIM_CR1_CMS_Pos) | TIM_CR1_ARPE;
  TIM1->EGR = TIM_EGR_UG; /* load ARR, CCRx, RCR */
  TIM1->SR = 0u;

  /* Pins last: the channels already drive the idle (off) level. */
  for (uint32_t i = 0; i < 6u; i++) {
    hal_gpio_af(k_pwm_pins[i], BOARD_PWM_HIGH_ACTIVE_LOW ? 1u : 2u);
  }
#if BOARD_HAS_BKIN
  const hal_pin_t bkin = BOARD_BKIN_PIN;
  hal_gpio_af(bkin, BOARD_BKIN_ACTIVE_HIGH ? 2u : 1u); /* pull to the inactive level */
#endif
#if BOARD_HAS_BKIN2
  const hal_pin_t bkin2 = BOARD_BKIN2_PIN;
  hal_gpio_af(bkin2, BOARD_BKIN2_ACTIVE_HIGH ? 2u : 1u); /* nFAULT is open drain */
#endif
}

static bool wait_update(void) {
  for (uint32_t t = 0; t < 100000u; t++) { /* > 2 periods at 170 MHz */
    if ((TIM1->SR & TIM_SR_UIF) != 0u) {
      return true;
    }
  }
  return false;
}

bool hal_tim1_start(void) {
#if BOARD_HAS_STAR_WINDOW
  /* updates at both ends (RCR = 0): the ADC trigger is OC4REF, not the
   * update, so there is no repetition phase to align */
  TIM1->CR1 |= TIM_CR1_CEN;
  return star_window_tim1_start();
#endif
  /* RM0440 28.3.4: with an odd RCR in centre-aligned mode the update falls
   * on the underflow if RCR is written after the counter started. Write it
   * so, then verify with DIR (counting up right after an underflow) and
   * shift by one half period if needed. */
  TIM1->CR1 |= TIM_CR1_CEN;
  TIM1->RCR = 1u;
  for (uint32_t attempt = 0; attempt < 3u; attempt++) {
    TIM1->SR = ~TIM_SR_UIF;
    if (!wait_update()) {
      return false;
    }
    if ((TIM1->CR1 & TIM_CR1_DIR) == 0u) {
      TIM1->SR = ~TIM_SR_UIF;
      return true;
    }
    /* Update came at the overflow: one update with RCR = 0 moves the
     * repetition phase by half a period. */
    TIM1->RCR = 0u;
    TIM1->SR = ~TIM_SR_UIF;
    if (!wait_update()) {
      return false;
    }
    TIM1->RCR = 1u;
  }
  return false;
}

/* The flag set once per period near the valley: the update (RCR = 1), or
 * with the DFC window (updates at both ends) the OC4 match after it. */
#if BOARD_HAS_STAR_WINDOW
#define TIM1_PERIOD_FLAG TIM_SR_CC4IF
#else
#define TIM1_PERIOD_FLAG TIM_SR_UIF
#endif

HOT void hal_tim1_clear_update(void) {
  TIM1->SR = ~TIM1_PERIOD_FLAG; /* rc_w0 */
}

HOT bool hal_tim1_update_pending(void) {
  return (TIM1->SR & TIM1_PERIOD_FLAG) != 0u;
}

/* ---- hal.h: PWM and hardware fault ---- */

/* Without the DFC window: centred pulses only (no HAL_CAP_ASYM_EDGES):
 * the duty off - on, limited to [0, BOARD_DUTY_MAX] (NaN: 0), rounded to a
 * compare step. */
HOT static uint32_t duty_to_ccr(float d) {
  if (!(d > 0.0f)) { /* also NaN */
    d = 0.0f;
  }
  if (d > BOARD_DUTY_MAX) {
    d = BOARD_DUTY_MAX;
  }
  return (uint32_t)((1.0f - d) * (float)BOARD_PWM_ARR + 0.5f);
}

HOT static void ccr_to_pattern(uint32_t ccr, int x, hal_pwm_t *a) {
  const float d = 1.0f - (float)ccr * (1.0f / (float)BOARD_PWM_ARR);
  a->on[x] = 0.5f * (1.0f - d);
  a->off[x] = 0.5f * (1.0f + d);
}

HOT void hal_pwm_write(const hal_pwm_t *p, hal_pwm_t *applied) {
#if BOARD_HAS_STAR_WINDOW
  hal_pwm_t a;
  star_window_write(p, applied != 0 ? applied : &a);
  return;
#endif
  const uint32_t c1 = duty_to_ccr(p->off[0] - p->on[0]);
  const uint32_t c2 = duty_to_ccr(p->off[1] - p->on[1]);
  const uint32_t c3 = duty_to_ccr(p->off[2] - p->on[2]);
  TIM1->CCR1 = c1;
  TIM1->CCR2 = c2;
  TIM1->CCR3 = c3;
  if (applied != 0) {
    ccr_to_pattern(c1, 0, applied);
    ccr_to_pattern(c2, 1, applied);
    ccr_to_pattern(c3, 2, applied);
    applied->test_vector = 0u;
    applied->n_star = 0u;
  }
}

/* Output compare mode m on channels 1-3 (OCxM[2:0]; OCxM[3] stays 0; the
 * mode is not preloaded: it acts at once), preload kept. */
static void set_oc_modes(uint32_t m) {
  const uint32_t mask = (7u << TIM_CCMR_OC1M_Pos) | (7u << (TIM_CCMR_OC1M_Pos + 8u));
  TIM1->CCMR1 = (TIM1->CCMR1 & ~mask) | (m << TIM_CCMR_OC1M_Pos) | (m << (TIM_CCMR_OC1M_Pos + 8u));
  TIM1->CCMR2 = (TIM1->CCMR2 & ~(7u << TIM_CCMR_OC1M_Pos)) | (m << TIM_CCMR_OC1M_Pos);
}

static bool oc_forced(void) {
  return ((TIM1->CCMR1 >> TIM_CCMR_OC1M_Pos) & 7u) == TIM_OCM_FORCE_LOW;
}

void hal_pwm_enable(void) {
  set_oc_modes(TIM_OCM_PWM2);
  TIM1->BDTR |= TIM_BDTR_MOE; /* refused by hardware while the break is active */
}

HOT void hal_pwm_disable(void) {
  TIM1->BDTR &= ~TIM_BDTR_MOE;
}

bool hal_pwm_is_enabled(void) {
  return (TIM1->BDTR & TIM_BDTR_MOE) != 0u && !oc_forced();
}

/* ASC: OCxREF forced low (RM0440 28.6.7 OCxM = 0100), so OCx (high side)
 * is inactive and the complementary OCxN (low side) active, after the dead
 * time; MOE set (refused by hardware while the break is active). */
void hal_pwm_short(void) {
  set_oc_modes(TIM_OCM_FORCE_LOW);
  TIM1->BDTR |= TIM_BDTR_MOE;
}

bool hal_pwm_is_shorted(void) {
  return (TIM1->BDTR & TIM_BDTR_MOE) != 0u && oc_forced();
}

bool hal_fault_hw_tripped(void) {
  return (TIM1->SR & (TIM_SR_BIF | TIM_SR_B2IF | TIM_SR_SBIF)) != 0u;
}

uint32_t hal_fault_hw_source(void) {
  const uint32_t sr = TIM1->SR;
  return ((sr & (TIM_SR_BIF | TIM_SR_SBIF)) != 0u ? (uint32_t)HAL_BREAK_OVERCURRENT : 0u) |
         ((sr & TIM_SR_B2IF) != 0u ? (uint32_t)HAL_BREAK_GATE_DRIVER : 0u);
}

void hal_fault_hw_clear(void) {
  /* stays set while the input is active */
  TIM1->SR = ~(TIM_SR_BIF | TIM_SR_B2IF | TIM_SR_SBIF);
}
