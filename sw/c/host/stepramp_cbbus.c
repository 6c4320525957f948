/* SPDX-License-Identifier: MIT */
/* The callback host bus: stepramp_hostbus.h implemented by functions the loading program attaches. */
#include "stepramp_cbbus.h"

#include <stddef.h>

#include "stepramp_hostbus.h"

static stepramp_cbbus_read32_fn cb_read32;
static stepramp_cbbus_write32_fn cb_write32;
static stepramp_cbbus_write8_fn cb_write8;
static stepramp_cbbus_idle_fn cb_idle;

void stepramp_cbbus_attach(stepramp_cbbus_read32_fn read32, stepramp_cbbus_write32_fn write32,
                           stepramp_cbbus_write8_fn write8, stepramp_cbbus_idle_fn idle)
{
    cb_read32 = read32;
    cb_write32 = write32;
    cb_write8 = write8;
    cb_idle = idle;
}

uint32_t stepramp_hostbus_read32(uintptr_t addr)
{
    return cb_read32 != NULL ? cb_read32(addr) : UINT32_C(0xFFFFFFFF);
}

void stepramp_hostbus_write32(uintptr_t addr, uint32_t value)
{
    if (cb_write32 != NULL) {
        cb_write32(addr, value);
    }
}

void stepramp_hostbus_write8(uintptr_t addr, uint8_t value)
{
    if (cb_write8 != NULL) {
        cb_write8(addr, value);
    }
}

void stepramp_hostbus_idle(void)
{
    if (cb_idle != NULL) {
        cb_idle();
    }
}
