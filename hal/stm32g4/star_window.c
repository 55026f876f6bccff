/*
 * star_window.c - the Direct Flux Control window on TIM1 (see
 * star_window.h).
 *
 * TIM1 in centre-aligned mode compares each channel once per half period:
 * in PWM mode 2 a channel goes active when the counter rises above CCRx
 * (first half) and inactive when it falls below CCRx (second half). With
 * one CCRx the two edges are symmetric about the peak. The window
 * (firmware/core/control/dfc_window.h) has every rising edge in the first
 * half and every falling edge in the second, at independent instants: so
 * CCR1..CCR3 are reloaded at every update, under- and overflow (RCR = 0),
 * by a DMA burst from a table of two rows {rising, falling}; with preload
 * on, the row written at the peak of period k acts over the first half of
 * k+1, the row written at its valley over the second half of k+1:
 *   rising edge at fraction on (< 1/2):  CCR = on 2 ARR      (up-count)
 *   falling edge at fraction off (> 1/2): CCR = (1 - off) 2 ARR (down-count)
 * Deadline: hal_pwm_write of the ISR after the valley of period k must
 * write the rising row before the peak of k (Ts/2 after the valley). If
 * it comes later the write applies the pattern centred (both rows the same
 * symmetric compare values, no test vector) and reports so in `applied`:
 * the drive's applied voltage stays right and the position source misses
 * one component.
 * Triggers: the current samples start at OC4REF's rising edge (CCR4 = 1:
 * just after the valley, TRGO) as the update did with RCR = 1; the star
 * point's after-sample at OC5REF's rising edge (CCR5 at t0 + t_meas,
 * TRGO2), on the star channel's regular conversion; its before-sample is
 * the injected conversion with the currents (its sampling window must end
 * before t0: docs/flashing.md).
 */
#include "star_window.h"

#include "board.h"
#include "hal_stm32g4.h"

#if BOARD_HAS_STAR_WINDOW

#define HOT __attribute__((section(".ccmram.text.hal")))

/* DMA table: row 0 rising edges (written by the DMA at the peak), row 1
 * falling edges (at the valley); CCR1..CCR3 each */
static volatile uint32_t s_ccr[2][3];
/* the star samples' pipeline: the pattern acting over the present period
 * (its test vector, after-sample instant) and the one before */
static struct {
  uint8_t tv_now, tv_prev;
  float t_after_now, t_after_prev;
  float before_prev, t_before_prev;
} s_win;

void star_window_tim1_init(void) {
  /* OC4REF: PWM mode 2, CCR4 = 1 -> rises just after the valley (TRGO) */
  TIM1->CCR4 = 1u;
  TIM1->CCMR2 |= (TIM_OCM_PWM2 << TIM_CCMR_OC4M_Pos) | TIM_CCMR_OC4PE;
  /* OC5REF: PWM mode 2, rises at the after-sample (TRGO2) */
  TIM1->CCR5 = BOARD_PWM_ARR / 8u;
  TIM1->CCMR3 = (TIM_OCM_PWM2 << TIM_CCMR3_OC5M_Pos) | TIM_CCMR3_OC5PE;
  TIM1->CR2 = (TIM1->CR2 & ~(7u << TIM_CR2_MMS_Pos) & ~(15u << TIM_CR2_MMS2_Pos)) |
              (TIM_CR2_MMS_OC4REF << TIM_CR2_MMS_Pos) | (TIM_CR2_MMS2_OC5REF << TIM_CR2_MMS2_Pos);
  /* the DMA burst: 3 words from CCR1 (register index 13) through DMAR */
  TIM1->DCR = (13u << TIM_DCR_DBA_Pos) | (2u << TIM_DCR_DBL_Pos);
  for (uint32_t x = 0; x < 3u; ++x) {
    s_ccr[0][x] = BOARD_PWM_ARR; /* duty 0 */
    s_ccr[1][x] = BOARD_PWM_ARR;
  }
  RCC->AHB1ENR |= RCC_AHB1ENR_DMA1EN | RCC_AHB1ENR_DMAMUX1EN;
  (void)RCC->AHB1ENR;
  DMAMUX1_C0CR = DMAMUX_REQ_TIM1_UP;
  dma_channel_regs_t *ch = &DMA1->CH[0];
  ch->CCR = 0u;
  ch->CPAR = (uint32_t)(uintptr_t)&TIM1->DMAR;
  ch->CMAR = (uint32_t)(uintptr_t)&s_ccr[0][0];
  ch->CNDTR = 6u;
  ch->CCR = DMA_CCR_DIR | DMA_CCR_CIRC | DMA_CCR_MINC | DMA_CCR_PSIZE_32 | DMA_CCR_MSIZE_32 |
            DMA_CCR_PL_VHIGH; /* EN by star_window_tim1_start */
  TIM1->DIER |= TIM_DIER_UDE;
}

bool star_window_tim1_start(void) {
  TIM1->RCR = 0u; /* an update at the valley and at the peak */
  /* enable the DMA while the counter rises, early in the first half: its
   * first burst (row 0, the rising edges) comes at the coming peak */
  for (uint32_t t = 0; t < 100000u; t++) {
    const uint32_t cnt = TIM1->CNT;
    if ((TIM1->CR1 & TIM_CR1_DIR) == 0u && cnt > 8u && cnt < BOARD_PWM_ARR / 4u) {
      DMA1->CH[0].CCR |= DMA_CCR_EN;
      return true;
    }
  }
  return false;
}

void star_window_adc_init(void) {
  const uint32_t ch = (uint32_t)BOARD_ADC_VSTAR_CHANNEL;
  adc_regs_t *adc = BOARD_ADC_VSTAR_ADC == 1u ? ADC1 : ADC2;
  adc->SQR1 = ch << ADC_SQR1_SQ1_Pos; /* L = 0: one conversion */
  adc->CFGR |= (10u << ADC_CFGR_EXTSEL_Pos) | (1u << ADC_CFGR_EXTEN_Pos) | ADC_CFGR_OVRMOD;
}

void star_window_adc_start(void) {
  adc_regs_t *adc = BOARD_ADC_VSTAR_ADC == 1u ? ADC1 : ADC2;
  adc->CR |= ADC_CR_ADSTART; /* waits for TRGO2 */
}

HOT static uint32_t rise_ccr(float on) {
  const float c = on * (float)(2u * BOARD_PWM_ARR) + 0.5f;
  return c > 1.0f ? (uint32_t)c : 1u;
}

HOT static uint32_t fall_ccr(float off) {
  const float c = (1.0f - off) * (float)(2u * BOARD_PWM_ARR) + 0.5f;
  return c > 0.0f ? (uint32_t)c : 0u;
}

HOT void star_window_write(const hal_pwm_t *p, hal_pwm_t *applied) {
  /* before the peak, with a margin for these writes (1/32 of the half):
   * else the DMA has loaded the rising row of the next period already */
  const bool early =
      (TIM1->CR1 & TIM_CR1_DIR) == 0u && TIM1->CNT < BOARD_PWM_ARR - BOARD_PWM_ARR / 32u;
  const float k = 1.0f / (float)(2u * BOARD_PWM_ARR);
  bool window = early && p->test_vector != 0u;
  for (uint32_t x = 0; x < 3u; ++x) {
    float d = p->off[x] - p->on[x];
    d = d > 0.0f ? (d < BOARD_DUTY_MAX ? d : BOARD_DUTY_MAX) : 0.0f; /* NaN: 0 */
    float on = p->on[x];
    if (!early) { /* the rising edge in force: keep the width from it */
      on = (float)s_ccr[0][x] * k;
    } else if (!(on >= 0.0f && on < 0.5f && on + d > 0.5f && on + d <= 1.0f)) {
      on = 0.5f * (1.0f - d); /* not a window edge: centred */
      window = false;
    }
    float off = on + d;
    off = off > 0.5f ? (off < 1.0f ? off : 1.0f) : 0.5f;
    const uint32_t cr = rise_ccr(on), cf = fall_ccr(off);
    if (early) {
      s_ccr[0][x] = cr;
    }
    s_ccr[1][x] = cf;
    applied->on[x] = (float)cr * k;
    applied->off[x] = 1.0f - (float)cf * k;
  }
  /* late: the previous pattern's rising edges repeat, and with them its
   * test vector */
  const uint8_t tv = early ? (window ? p->test_vector : 0u) : s_win.tv_now;
  applied->test_vector = tv;
  applied->n_star = (tv != 0u && p->n_star >= 2u) ? 2u : 0u;
  applied->t_star_req[0] = p->t_star_req[0];
  applied->t_star_req[1] = p->t_star_req[1];
  if (applied->n_star == 2u && early) {
    const float ts = (float)(2u * BOARD_PWM_ARR) / (float)BOARD_SYSCLK_HZ;
    TIM1->CCR5 = rise_ccr(p->t_star_req[1] / ts); /* preloaded: from the peak */
  }
  /* the pipeline: this pattern acts over the next period */
  s_win.tv_prev = s_win.tv_now;
  s_win.t_after_prev = s_win.t_after_now;
  s_win.tv_now = applied->n_star == 2u ? tv : 0u;
  s_win.t_after_now = early ? p->t_star_req[1] : s_win.t_after_now;
}

HOT void star_window_read(hal_sample_t *s, float before_now, float t_before) {
  const float ts = (float)(2u * BOARD_PWM_ARR) / (float)BOARD_SYSCLK_HZ;
  const adc_regs_t *adc = BOARD_ADC_VSTAR_ADC == 1u ? ADC1 : ADC2;
  /* the after-sample of the last period, converted since its ISR */
  const float after =
      (float)(adc->DR & 0xFFFFu) * (BOARD_VDDA / 4095.0f) * BOARD_VSTAR_RATIO - 0.5f * s->v_dc;
  s->n_star = s_win.tv_prev != 0u ? 2u : 0u;
  s->test_vector = s_win.tv_prev;
  s->v_star[0] = s_win.before_prev;
  s->t_star[0] = s_win.t_before_prev - ts;
  s->v_star[1] = after;
  s->t_star[1] = s_win.t_after_prev - ts;
  s_win.before_prev = before_now;
  s_win.t_before_prev = t_before;
}

#endif /* BOARD_HAS_STAR_WINDOW */
