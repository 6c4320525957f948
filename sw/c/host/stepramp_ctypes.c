/* SPDX-License-Identifier: MIT */
/* ctypes entry points: the C driver on the fake register bank (see stepramp_ctypes.h). */
#include "stepramp_ctypes.h"

#include "stepramp.h"
#include "stepramp_fakebus.h"

int stepramp_fakebus_move(int64_t steps, double accel, double decel, double speed, double spr, double fclk,
                          uint32_t prescale)
{
    stepramp_t dev;
    int rc;

    stepramp_fakebus_reset(STEPRAMP_FAKEBUS_BASE, STEPRAMP_ID_VALUE);
    rc = stepramp_init(&dev, STEPRAMP_FAKEBUS_BASE, fclk, spr, prescale);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    stepramp_fakebus_clear_log();
    return stepramp_move(&dev, steps, accel, decel, speed);
}

int stepramp_fakebus_program(const stepramp_plan_t *plan)
{
    stepramp_t dev;
    int rc;

    stepramp_fakebus_reset(STEPRAMP_FAKEBUS_BASE, STEPRAMP_ID_VALUE);
    rc = stepramp_init(&dev, STEPRAMP_FAKEBUS_BASE, 1e6, 200.0, 1u);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    stepramp_fakebus_clear_log();
    return stepramp_program(&dev, plan);
}

size_t stepramp_fakebus_sizeof_plan(void)
{
    return sizeof(stepramp_plan_t);
}
