/*
 * fdcan.c - FDCAN1 as a classic CAN 2.0 controller, RM0440 section 44.
 *
 * Kernel clock: PCLK1 = 170 MHz (RCC_CCIPR.FDCANSEL = 10, FDCAN_CKDIV = /1).
 * Both boards run SYSCLK from a crystal through the PLL, so the CAN clock
 * tolerance is the crystal's. Bit timing: see fdcan.h (17 tq per bit).
 *
 * Message RAM (RM0440 44.3.3): fixed layout per instance at SRAMCAN_BASE:
 * 28 standard filters, 8 extended filters, Rx FIFO 0/1 with 3 elements of
 * 18 words, Tx event FIFO 3 x 2 words, Tx buffers 3 x 18 words. Used here:
 * 2 standard + 2 extended filters -> Rx FIFO 0; Tx buffers as a FIFO
 * (TXBC.TFQM = 0). All accesses are 32-bit words.
 * hal_can_send / hal_can_receive never block; both are meant for one
 * context (the slow loop).
 */
#include "fdcan.h"

#include "board.h"
#include "hal.h"
#include "hal_stm32g4.h"

#define F_KERNEL     170000000u
#define TQ_PER_BIT   17u
#define SRAM_WORD(o) (*(reg32_t *)(SRAMCAN_BASE + (o)))

bool hal_fdcan_timing(uint32_t bitrate, fdcan_timing_t *t) {
  if (bitrate == 0u || F_KERNEL % (bitrate * TQ_PER_BIT) != 0u) {
    return false;
  }
  t->brp = F_KERNEL / (bitrate * TQ_PER_BIT);
  t->tseg1 = 13u;
  t->tseg2 = 3u;
  t->sjw = 3u;
  return t->brp >= 1u && t->brp <= 512u;
}

static bool wait_init(bool set) {
  for (uint32_t t = 0; t < 1000000u; t++) {
    if (((FDCAN1->CCCR & FDCAN_CCCR_INIT) != 0u) == set) {
      return true;
    }
  }
  return false;
}

void hal_can_set_node_filter(uint32_t node_id, uint32_t mask) {
  /* Standard filter element (RM0440 44.3.4): SFT = 10 classic (id, mask),
   * SFEC = 001 store in Rx FIFO 0, SFID1 = id, SFID2 = mask. */
  const uint32_t std = (2u << 30) | (1u << 27);
  SRAM_WORD(SRAMCAN_FLSSA + 0u) = std | ((node_id & 0x7FFu) << 16) | (mask & 0x7FFu);
  SRAM_WORD(SRAMCAN_FLSSA + 4u) = std | (mask & 0x7FFu); /* SFID1 = 0 */
  /* Extended filter element: F0 = EFEC 001 | EFID1, F1 = EFT 10 | EFID2. */
  SRAM_WORD(SRAMCAN_FLESA + 0u) = (1u << 29) | (node_id & 0x1FFFFFFFu);
  SRAM_WORD(SRAMCAN_FLESA + 4u) = (2u << 30) | (mask & 0x1FFFFFFFu);
  SRAM_WORD(SRAMCAN_FLESA + 8u) = (1u << 29); /* EFID1 = 0 */
  SRAM_WORD(SRAMCAN_FLESA + 12u) = (2u << 30) | (mask & 0x1FFFFFFFu);
}

bool hal_fdcan_init(uint32_t bitrate, uint32_t node_id, uint32_t mask) {
  fdcan_timing_t bt;
  if (!hal_fdcan_timing(bitrate, &bt)) {
    return false;
  }
  RCC->CCIPR =
      (RCC->CCIPR & ~RCC_CCIPR_FDCANSEL_Msk) | (RCC_CCIPR_FDCANSEL_PCLK1 << RCC_CCIPR_FDCANSEL_Pos);
  RCC->APB1ENR1 |= RCC_APB1ENR1_FDCANEN;
  (void)RCC->APB1ENR1;
  const hal_pin_t rx = BOARD_CAN_RX_PIN;
  const hal_pin_t tx = BOARD_CAN_TX_PIN;
  hal_gpio_af(rx, 1u);
  hal_gpio_af(tx, 0u);

  /* Initialisation mode, configuration change enabled (RM0440 44.3.2). */
  FDCAN1->CCCR |= FDCAN_CCCR_INIT;
  if (!wait_init(true)) {
    return false;
  }
  FDCAN1->CCCR |= FDCAN_CCCR_CCE;
  FDCAN1->CCCR &= ~(FDCAN_CCCR_FDOE | FDCAN_CCCR_BRSE | FDCAN_CCCR_DAR); /* classic, retransmit */

  FDCAN1->NBTP =
      ((bt.sjw - 1u) << 25) | ((bt.brp - 1u) << 16) | ((bt.tseg1 - 1u) << 8) | (bt.tseg2 - 1u);

  for (uint32_t o = 0; o < SRAMCAN_SIZE; o += 4u) {
    SRAM_WORD(o) = 0u;
  }
  hal_can_set_node_filter(node_id, mask);
  /* 2 standard, 2 extended filters; non-matching frames and all remote
   * frames rejected. */
  FDCAN1->RXGFC = (2u << FDCAN_RXGFC_LSS_Pos) | (2u << FDCAN_RXGFC_LSE_Pos) |
                  (2u << FDCAN_RXGFC_ANFS_Pos) | (2u << FDCAN_RXGFC_ANFE_Pos) | FDCAN_RXGFC_RRFS |
                  FDCAN_RXGFC_RRFE;
  FDCAN1->XIDAM = 0x1FFFFFFFu;
  FDCAN1->TXBC = 0u; /* Tx FIFO mode */
  FDCAN1->IE = 0u;   /* polled */

  FDCAN1->CCCR &= ~FDCAN_CCCR_INIT;
  return wait_init(false);
}

bool hal_can_bus_off(void) {
  return (FDCAN1->PSR & FDCAN_PSR_BO) != 0u;
}

/* ---- hal.h ---- */

bool hal_can_send(const hal_can_frame_t *f) {
  const uint32_t fqs = FDCAN1->TXFQS;
  if ((fqs & FDCAN_TXFQS_TFQF) != 0u || f->dlc > 8u) {
    return false;
  }
  const uint32_t idx = (fqs >> FDCAN_TXFQS_TFQPI_Pos) & 3u;
  const uint32_t base = SRAMCAN_TFQSA + idx * SRAMCAN_ELEM_SIZE;
  /* Tx buffer element (RM0440 44.3.4): T0 = XTD | ID (standard in 28:18),
   * T1 = DLC in 19:16, FDF = BRS = EFC = 0. */
  const uint32_t t0 = f->extended ? ((1u << 30) | (f->id & 0x1FFFFFFFu)) : ((f->id & 0x7FFu) << 18);
  SRAM_WORD(base + 0u) = t0;
  SRAM_WORD(base + 4u) = (uint32_t)f->dlc << 16;
  SRAM_WORD(base + 8u) = (uint32_t)f->data[0] | ((uint32_t)f->data[1] << 8) |
                         ((uint32_t)f->data[2] << 16) | ((uint32_t)f->data[3] << 24);
  SRAM_WORD(base + 12u) = (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) |
                          ((uint32_t)f->data[6] << 16) | ((uint32_t)f->data[7] << 24);
  FDCAN1->TXBAR = 1u << idx;
  return true;
}

bool hal_can_receive(hal_can_frame_t *f) {
  const uint32_t s = FDCAN1->RXF0S;
  if ((s & FDCAN_RXF0S_F0FL_Msk) == 0u) {
    return false;
  }
  const uint32_t idx = (s >> FDCAN_RXF0S_F0GI_Pos) & 3u;
  const uint32_t base = SRAMCAN_RF0SA + idx * SRAMCAN_ELEM_SIZE;
  const uint32_t r0 = SRAM_WORD(base + 0u);
  const uint32_t r1 = SRAM_WORD(base + 4u);
  const uint32_t d0 = SRAM_WORD(base + 8u);
  const uint32_t d1 = SRAM_WORD(base + 12u);
  FDCAN1->RXF0A = idx; /* release the element */

  f->extended = (r0 & (1u << 30)) != 0u;
  f->id = f->extended ? (r0 & 0x1FFFFFFFu) : ((r0 >> 18) & 0x7FFu);
  uint32_t dlc = (r1 >> 16) & 0xFu;
  f->dlc = (uint8_t)(dlc > 8u ? 8u : dlc);
  for (uint32_t k = 0; k < 4u; k++) {
    f->data[k] = (uint8_t)(d0 >> (8u * k));
    f->data[4u + k] = (uint8_t)(d1 >> (8u * k));
  }
  return true;
}
