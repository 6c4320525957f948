/* SPDX-License-Identifier: MIT */
/*
 * Internal to the plan library (stepramp_plan.c, stepramp_change.c): the helpers of plan.py that change.py imports
 * (_check_positive, _to_fixed, _cruise, _stop_ratio, decel_product, min_interval_clks), shared by the two C files. Not
 * part of the API: an application includes stepramp_plan.h and stepramp_change.h only.
 */
#ifndef STEPRAMP_PLAN_PRIV_H
#define STEPRAMP_PLAN_PRIV_H

#include <stdint.h>

#include "stepramp_plan.h"

/* math.pi (the double nearest pi). M_PI is not C99. */
#define STEPRAMP_PI 3.141592653589793

#define TWO_POW_16 65536.0
#define TWO_POW_32 4294967296.0
#define TWO_POW_48 281474976710656.0
#define TWO_POW_60 1152921504606846976.0
#define TWO_POW_64 18446744073709551616.0

/* Python's max(a, b): a unless b > a (keeps a NaN or a -0.0 in a, unlike fmax). */
static inline double py_max(double a, double b)
{
    return (b > a) ? b : a;
}

/* Python's min(a, b): a unless b < a. */
static inline double py_min(double a, double b)
{
    return (b < a) ? b : a;
}

/*
 * The argument checks that plan_move_info and plan_change start with, in their order: accel, decel, speed, spr and
 * fclk finite and > 0 (plan._check_positive without the type checks), then prescale in 1 .. 65535.
 */
stepramp_err_t stepramp_priv_check_args(double accel, double decel, double speed, double spr, double fclk,
                                        uint32_t prescale);

/*
 * The check of a, d, v (the accel, decel and speed in steps units) and f_tick, in that order: each finite and > 0
 * (plan_move_info), with squares also its square finite (plan_change): STEPRAMP_EACCEL_UNITS .. STEPRAMP_EFTICK.
 */
stepramp_err_t stepramp_priv_check_units(double a, double d, double v, double f_tick, int squares);

/*
 * plan._to_fixed: round(ticks * scale) below limit into *out, else STEPRAMP_EOVERFLOW (also for a ticks that is not
 * finite, or whose product is not). The value must not be negative (the caller checks where it can be).
 */
stepramp_err_t stepramp_priv_to_fixed(double ticks, double scale, double limit, uint64_t *out);

/* plan._cruise: round(f_tick / v * 2^32) below 2^64 into *out, else STEPRAMP_EOVERFLOW. */
stepramp_err_t stepramp_priv_cruise(double f_tick, double v, uint64_t *out);

/* plan.min_interval_clks: for STEPRAMP_RAMP_EXACT STEPRAMP_MIN_INTERVAL_CLKS_EXACT when the ramp constants of both
 * first intervals c0_a and c0_d are below 2^48, else STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE; else
 * STEPRAMP_MIN_INTERVAL_CLKS. */
uint32_t stepramp_priv_min_interval_clks(uint32_t ramp, double c0_a, double c0_d);

/* plan._stop_ratio: round(accel / decel * 2^16), saturated at 2^32 - 1. */
uint32_t stepramp_priv_stop_ratio(double accel, double decel);

/*
 * plan.decel_product of an integer held in a double (any size: change.py's ramp indices are Python ints that may
 * exceed int64_t), the same value as stepramp_decel_product for every m that fits it. 1.0 for m <= 0.
 */
double stepramp_priv_decel_product(double m);

/*
 * plan.accel_truncation: the accel recurrence's mean truncation over A_1 .. A_n, n - (2 (n + 3/4) P(n) - 3/2) Q32.16
 * LSB (shared with stepramp_coord.c's time_before_last).
 */
double stepramp_priv_accel_truncation(int64_t n);

/*
 * The final decel ramp's seed D_m0 = SEED_FACTOR cd0 decel_product(m0), with half its recurrence deficit put back
 * (plan.register_doubles, change._fields), for m0 >= 1.
 */
double stepramp_priv_decel_seed(double cd0, int64_t m0);

#endif /* STEPRAMP_PLAN_PRIV_H */
