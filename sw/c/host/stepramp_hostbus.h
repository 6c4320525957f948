/* SPDX-License-Identifier: MIT */
/*
 * The host build's register access: the four functions the driver (stepramp.c) calls on a host instead of the
 * BSP's Xil_In32 / Xil_Out32 / Xil_Out8. The host build compiles stepramp.c with
 * -DSTEPRAMP_CONFIG_HEADER='"stepramp_hostbus.h"'; a bus implementation defines the functions (here the fake
 * register bank, stepramp_fakebus.c). The driver and the bank know only this header, not each other.
 */
#ifndef STEPRAMP_HOSTBUS_H
#define STEPRAMP_HOSTBUS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Read the 32-bit word at bus address addr. */
uint32_t stepramp_hostbus_read32(uintptr_t addr);
/** Write a 32-bit word (all four byte lanes). */
void stepramp_hostbus_write32(uintptr_t addr, uint32_t value);
/** Write one byte (one byte lane). */
void stepramp_hostbus_write8(uintptr_t addr, uint8_t value);
/** The driver's idle hook, called once per polling round. */
void stepramp_hostbus_idle(void);

#define STEPRAMP_READ32(addr) stepramp_hostbus_read32(addr)
#define STEPRAMP_WRITE32(addr, value) stepramp_hostbus_write32((addr), (value))
#define STEPRAMP_WRITE8(addr, value) stepramp_hostbus_write8((addr), (value))
#define STEPRAMP_IDLE() stepramp_hostbus_idle()

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_HOSTBUS_H */
