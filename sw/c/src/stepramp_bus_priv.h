/* SPDX-License-Identifier: MIT */
/*
 * Internal to the driver files that reach the registers (stepramp.c, stepramp_multi.c): their register access.
 * Include it first. It includes the user's STEPRAMP_CONFIG_HEADER when one is named (it may define
 * STEPRAMP_READ32 / _WRITE32 / _WRITE8 / _IDLE / _CMD_BYTE_LANE), then gives each access macro the user has not
 * defined the Xilinx standalone BSP's function (xil_io.h), and STEPRAMP_IDLE() (run between two polls of
 * stepramp_wait_done / stepramp_multi_wait_done) nothing to do. Not part of the API.
 */
#ifndef STEPRAMP_BUS_PRIV_H
#define STEPRAMP_BUS_PRIV_H

#ifdef STEPRAMP_CONFIG_HEADER
#include STEPRAMP_CONFIG_HEADER
#endif

#if !defined(STEPRAMP_READ32) || !defined(STEPRAMP_WRITE32) || !defined(STEPRAMP_WRITE8)
#include "xil_io.h"
#endif
#ifndef STEPRAMP_READ32
#define STEPRAMP_READ32(addr) Xil_In32(addr)
#endif
#ifndef STEPRAMP_WRITE32
#define STEPRAMP_WRITE32(addr, value) Xil_Out32((addr), (value))
#endif
#ifndef STEPRAMP_WRITE8
#define STEPRAMP_WRITE8(addr, value) Xil_Out8((addr), (value))
#endif

#ifndef STEPRAMP_IDLE
#define STEPRAMP_IDLE() ((void)0)
#endif

#endif /* STEPRAMP_BUS_PRIV_H */
