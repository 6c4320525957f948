/* SPDX-License-Identifier: MIT */
/*
 * ctypes entry points for the Python tests (sw/tests/test_c_driver.py, tb/test_plb_c.py): the C driver
 * (stepramp.c) run on the fake register bank (stepramp_fakebus.c) of the host library libstepramp.so.
 */
#ifndef STEPRAMP_CTYPES_H
#define STEPRAMP_CTYPES_H

#include <stddef.h>
#include <stdint.h>

#include "stepramp_plan.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Base address the entry points below put the fake core at. */
#define STEPRAMP_FAKEBUS_BASE ((uintptr_t)0x44A00000u)

/**
 * Reset the fake core, stepramp_init a device at STEPRAMP_FAKEBUS_BASE with fclk, spr, prescale, clear the log,
 * then stepramp_move. Returns stepramp_move's result (or stepramp_init's if it fails). The first program of a fresh
 * device: the log holds the segment registers written 0 after the motion registers, then START.
 */
int stepramp_fakebus_move(int64_t steps, double accel, double decel, double speed, double spr, double fclk,
                          uint32_t prescale);

/** Reset the fake core, init a device, clear the log, stepramp_program(plan) (with the segment registers 0, as the
 * first program after init). Returns its result. */
int stepramp_fakebus_program(const stepramp_plan_t *plan);

/** sizeof(stepramp_plan_t): lets ctypes check its structure layout. */
size_t stepramp_fakebus_sizeof_plan(void);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_CTYPES_H */
