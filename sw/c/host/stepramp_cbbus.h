/* SPDX-License-Identifier: MIT */
/*
 * A host bus for the driver whose four functions (stepramp_hostbus.h) call back into the program that loaded it:
 * the cocotb tests (tb/test_c_driver_rtl.py) attach Python functions that run each access as a bus transaction
 * on the simulated core, so the driver's own code talks to the RTL. Built into build/libstepramp_cb.so with the
 * driver and the plan (not with the fake bank, which implements the same four functions).
 */
#ifndef STEPRAMP_CBBUS_H
#define STEPRAMP_CBBUS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef uint32_t (*stepramp_cbbus_read32_fn)(uintptr_t addr);
typedef void (*stepramp_cbbus_write32_fn)(uintptr_t addr, uint32_t value);
typedef void (*stepramp_cbbus_write8_fn)(uintptr_t addr, uint8_t value);
typedef void (*stepramp_cbbus_idle_fn)(void);

/**
 * Route the driver's register access to these functions (any may be NULL: a read then returns 0xFFFFFFFF, a write
 * or an idle call does nothing). Replaces the previous set.
 */
void stepramp_cbbus_attach(stepramp_cbbus_read32_fn read32, stepramp_cbbus_write32_fn write32,
                           stepramp_cbbus_write8_fn write8, stepramp_cbbus_idle_fn idle);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_CBBUS_H */
