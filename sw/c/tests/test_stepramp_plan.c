/* SPDX-License-Identifier: MIT */
/*
 * Host unit tests of stepramp_plan, stepramp_change and stepramp_coord: expected values from the physics of the move
 * (not from the code under test), every error code, the empty moves; the exact mode (STEPRAMP_RAMP_EXACT) too. The
 * bit-for-bit comparison with the Python driver is done by sw/tests/test_c_plan.py, sw/tests/test_c_change.py and
 * sw/tests/test_c_coord.py. Exit status 0 when every check passes.
 */
#include "stepramp_plan.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "stepramp_change.h"
#include "stepramp_coord.h"
#include "test_check.h"

#define PI 3.141592653589793
#define Q16 65536.0
#define Q32 4294967296.0

/* |got - want| <= tol, reported with both values */
static int near(double got, double want, double tol)
{
    if (fabs(got - want) <= tol) {
        return 1;
    }
    printf("    got %.17g, want %.17g (tol %.3g)\n", got, want, tol);
    return 0;
}

/* a register value (an integer, rounded once) against the exact value: half an LSB plus a relative error */
static int rel_near(double got, double want, double rel)
{
    return near(got, want, 0.5 + rel * fabs(want));
}

/* a double against a double: relative error only */
static int rel_near_d(double got, double want, double rel)
{
    return near(got, want, rel * fabs(want));
}

/* The move in steps units, computed independently of the library (the physics of docs/algorithm.md). */
typedef struct {
    double f_tick, a, d, v, c0, cd0;
    double length;
} phys_t;

static phys_t physics(int64_t steps, double accel, double decel, double speed, double spr, double fclk,
                      uint32_t prescale)
{
    phys_t p;
    double alpha = 2.0 * PI / spr;
    p.f_tick = fclk / prescale;
    p.a = accel / alpha;
    p.d = decel / alpha;
    p.v = speed / alpha;
    p.c0 = p.f_tick * sqrt(2.0 / p.a);
    p.cd0 = p.f_tick * sqrt(2.0 / p.d);
    p.length = (double)((steps < 0 ? -steps : steps) - 1);
    return p;
}

/* prod_{k=1..m} (4k-1)/(4k+1), by the definition */
static double naive_product(int m)
{
    double p = 1.0;
    int k;
    for (k = 1; k <= m; k++) {
        p *= (4.0 * k - 1.0) / (4.0 * k + 1.0);
    }
    return p;
}

/* Gamma(m+3/4) Gamma(5/4) / (Gamma(m+5/4) Gamma(3/4)) for large m: Gamma(5/4)/Gamma(3/4) m^-1/2 (1 - 1/(4m)),
 * next term O(1/m^2) */
static double asymptotic_product(double m)
{
    return tgamma(1.25) / tgamma(0.75) / sqrt(m) * (1.0 - 0.25 / m);
}

/* The recurrence deficit by direct summation (not the closed form of stepramp_plan.c): the ideal time of a ramp's
 * intervals 2 .. n+1 from rest, c0 (sqrt(n+1) - 1), less the continuous recurrence values seed prod(4k-1)/(4k+1)
 * summed one by one. *unit gets the sum for seed 1. */
static double deficit_by_sum(double c0, double seed, int64_t n, double *unit)
{
    double p = 1.0;
    double sum = 0.0;
    int64_t k;
    for (k = 1; k <= n; k++) {
        p *= (4.0 * (double)k - 1.0) / (4.0 * (double)k + 1.0);
        sum += p;
    }
    *unit = sum;
    return c0 * (sqrt((double)n + 1.0) - 1.0) - seed * sum;
}

static void test_long_symmetric_trapezoid(void)
{
    /* 200 steps/rev, 1 MHz: a = d = 3183 steps/s^2, v = 1592 steps/s, n_a = n_d = 397.9 steps, L = 99999 */
    const int64_t steps = 100000;
    const double accel = 100.0, speed = 50.0, spr = 200.0, fclk = 1e6;
    phys_t p = physics(steps, accel, accel, speed, spr, fclk, 1);
    double n_a = p.v * p.v / (2.0 * p.a);
    double x_d = p.length - n_a;
    stepramp_plan_t plan;
    int64_t m0;

    double unit;
    double deficit;
    double seed;

    CHECK(stepramp_plan_move(&plan, steps, accel, accel, speed, spr, fclk, 1) == STEPRAMP_OK);
    CHECK(plan.steps == 100000 && plan.direction == 0 && plan.prescale == 1);
    CHECK(plan.sa == (uint32_t)floor(n_a) + 1 && plan.sa == 398);
    CHECK(plan.sd == (uint32_t)floor(x_d) + 1);
    /* the accel recurrence (intervals 2 .. sa-1) runs 0.01397 c0 short of the ideal ramp; half of that goes into
     * interval 1, whose ideal value is c0 = f_tick sqrt(2 / a) (AVR446's c0, without its 0.676 factor), and half
     * into the seed 0.676 c0, spread over the recurrence values */
    seed = 0.6759782400672847 * p.c0;
    deficit = deficit_by_sum(p.c0, seed, (int64_t)plan.sa - 2, &unit);
    CHECK(rel_near_d(deficit / p.c0, 0.01397, 2e-3));
    CHECK(near((double)plan.c_first, (p.c0 + deficit / 2.0) * Q16, 1.0));
    CHECK(near((double)plan.c_last, p.c0 * Q16, 1.0)); /* interval L stays the ideal one, cd0 = c0 */
    CHECK(near((double)plan.cruise, p.f_tick / p.v * Q32, 1.0));
    /* less the integer recurrence's mean truncation, n - (P(1) + .. + P(n)) LSB over values summing to unit seeds */
    CHECK(near((double)plan.accel_seed, (seed + deficit / 2.0 / unit) * Q16 - ((double)plan.sa - 2.0 - unit) / unit,
               1.0));
    /* interval sa: the end of the ramp from sa-1 to n_a, then cruise from n_a to sa */
    CHECK(rel_near((double)plan.c_sa,
                   (p.c0 * (sqrt(n_a) - sqrt((double)plan.sa - 1.0)) + ((double)plan.sa - n_a) * p.f_tick / p.v) * Q16,
                   1e-9));
    /* interval sd: cruise from sd-1 to x_d, then the first part of the decel ramp (L - x_d = n_a to go) */
    CHECK(rel_near((double)plan.c_sd,
                   ((x_d - ((double)plan.sd - 1.0)) * p.f_tick / p.v +
                    p.cd0 * (sqrt(n_a) - sqrt(p.length - (double)plan.sd))) *
                       Q16,
                   1e-9));
    /* decel recurrence value at m0 = L - sd - 1, from the Gamma-function form of the product */
    /* plus half the decel recurrence's deficit (the same one by symmetry), spread over D_m0 .. D_1 */
    m0 = (int64_t)p.length - plan.sd - 1;
    CHECK(m0 == 396);
    {
        double prod_m0 = exp(lgamma(m0 + 0.75) - lgamma(m0 + 1.25) + lgamma(1.25) - lgamma(0.75));
        double d_m0 = 0.6759782400672847 * p.cd0 * prod_m0;
        double deficit_d = deficit_by_sum(p.cd0, 0.6759782400672847 * p.cd0, m0, &unit);
        CHECK(rel_near_d(deficit_d, deficit, 1e-12));
        CHECK(rel_near((double)plan.decel_seed, (d_m0 + deficit_d / 2.0 / (unit / prod_m0)) * Q16, 1e-11));
        /* the seeds decay like cd0 / sqrt(m): 0.676 Gamma(5/4)/Gamma(3/4) = 1/2 */
        CHECK(rel_near((double)plan.decel_seed, 0.5 * p.cd0 / sqrt((double)m0) * Q16, 1e-3));
    }
}

static void test_asymmetric_trapezoids(void)
{
    /* accel/decel = 10 and 1/10; steps negative: direction 1 */
    static const double ratios[2] = {10.0, 0.1};
    int j;
    for (j = 0; j < 2; j++) {
        const double accel = 200.0, decel = 200.0 / ratios[j], speed = 30.0, spr = 400.0, fclk = 5e7;
        const uint32_t prescale = 50;
        const int64_t steps = -20000;
        phys_t p = physics(steps, accel, decel, speed, spr, fclk, prescale);
        double n_a = p.v * p.v / (2.0 * p.a);
        double n_d = p.v * p.v / (2.0 * p.d);
        stepramp_plan_t plan;

        CHECK(n_a + n_d < p.length); /* a trapezoid */
        CHECK(stepramp_plan_move(&plan, steps, accel, decel, speed, spr, fclk, prescale) == STEPRAMP_OK);
        CHECK(plan.steps == 20000 && plan.direction == 1 && plan.prescale == prescale);
        CHECK(plan.sa == (uint32_t)floor(n_a) + 1);
        CHECK(plan.sd == (uint32_t)floor(p.length - n_d) + 1);
        CHECK(plan.sa < plan.sd);
        double unit;
        double deficit = deficit_by_sum(p.c0, 0.6759782400672847 * p.c0, (int64_t)plan.sa - 2, &unit);
        CHECK(near((double)plan.c_first, (p.c0 + deficit / 2.0) * Q16, 1.0));
        CHECK(near((double)plan.c_last, p.cd0 * Q16, 1.0));
        CHECK(near((double)plan.cruise, p.f_tick / p.v * Q32, 1.0));
        CHECK(near((double)plan.accel_seed,
                   (0.6759782400672847 * p.c0 + deficit / 2.0 / unit) * Q16 - ((double)plan.sa - 2.0 - unit) / unit,
                   1.0));
        /* ratio of the first and last ideal intervals: sqrt(decel / accel) */
        CHECK(rel_near_d((double)plan.c_last / ((double)plan.c_first - deficit / 2.0 * Q16), sqrt(accel / decel),
                         1e-6));
    }
}

static void test_triangle(void)
{
    /* L = 102, decel = 3 accel: peak at x_p = 76.5, interval 77 holds the peak (76 -> 76.5 -> 77) */
    const double accel = 100.0, decel = 300.0, speed = 1000.0, spr = 200.0, fclk = 1e6;
    const int64_t steps = 103;
    phys_t p = physics(steps, accel, decel, speed, spr, fclk, 1);
    double x_p = p.length * p.d / (p.a + p.d);
    double peak_interval;
    stepramp_plan_t plan;

    CHECK(near(x_p, 76.5, 1e-12));
    CHECK(p.v * p.v / (2.0 * p.a) + p.v * p.v / (2.0 * p.d) > p.length); /* too short to reach v */
    CHECK(stepramp_plan_move(&plan, steps, accel, decel, speed, spr, fclk, 1) == STEPRAMP_OK);
    CHECK(plan.sa == 77 && plan.sd == 77);
    CHECK(plan.c_sa == plan.c_sd);
    peak_interval = p.c0 * (sqrt(76.5) - sqrt(76.0)) + p.cd0 * (sqrt(102.0 - 76.5) - sqrt(102.0 - 77.0));
    CHECK(rel_near((double)plan.c_sa, peak_interval * Q16, 1e-9));
    /* the peak interval is at least 1 / v_peak */
    CHECK((double)plan.c_sa >= p.f_tick / sqrt(2.0 * p.a * x_p) * Q16);
    /* interval 1: c0 plus half the deficit of the accel recurrence (intervals 2 .. 76); c_last: cd0 */
    {
        double unit;
        double deficit = deficit_by_sum(p.c0, 0.6759782400672847 * p.c0, 75, &unit);
        CHECK(near((double)plan.c_first, (p.c0 + deficit / 2.0) * Q16, 1.0));
    }
    CHECK(near((double)plan.c_last, p.cd0 * Q16, 1.0));
    /* m0 = L - sd - 1 = 24: D_24 = 0.676 cd0 prod_{k=1..24} (4k-1)/(4k+1), plus half the decel deficit spread over
     * D_24 .. D_1 */
    {
        double unit;
        double deficit = deficit_by_sum(p.cd0, 0.6759782400672847 * p.cd0, 24, &unit);
        CHECK(near((double)plan.decel_seed,
                   (0.6759782400672847 * p.cd0 * naive_product(24) + deficit / 2.0 / (unit / naive_product(24))) * Q16,
                   1.0));
    }
    /* cruise is unused in a triangle but still f_tick / v (here below the MIN_INTERVAL limit: not checked) */
    CHECK(near((double)plan.cruise, p.f_tick / p.v * Q32, 1.0));
}

static void test_triangle_symmetric_even(void)
{
    /* a = d, L = 10: x_p = 5 exactly, on the boundary between intervals 5 and 6: sa = sd = 6 */
    stepramp_plan_t plan;
    phys_t p = physics(11, 500.0, 500.0, 1e3, 200.0, 1e6, 1);
    CHECK(stepramp_plan_move(&plan, 11, 500.0, 500.0, 1e3, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(plan.sa == 6 && plan.sd == 6);
    /* interval 6 (position 5 -> 6) is all decel: cd0 (sqrt(5) - sqrt(4)) */
    CHECK(rel_near((double)plan.c_sa, p.cd0 * (sqrt(5.0) - 2.0) * Q16, 1e-12));
    /* mirror image but for the deficits: interval 1 takes half the accel one (intervals 2 .. 5), the decel seed
     * half the decel one (intervals 7 .. 9, m0 = 3) */
    {
        double unit;
        double deficit_a = deficit_by_sum(p.c0, 0.6759782400672847 * p.c0, 4, &unit);
        double deficit_d = deficit_by_sum(p.cd0, 0.6759782400672847 * p.cd0, 3, &unit);
        CHECK(near((double)plan.c_first, (p.cd0 + deficit_a / 2.0) * Q16, 1.0));
        CHECK(near((double)plan.c_last, p.cd0 * Q16, 1.0));
        CHECK(near((double)plan.decel_seed,
                   (0.6759782400672847 * p.cd0 * naive_product(3) + deficit_d / 2.0 / (unit / naive_product(3))) * Q16,
                   1.0));
    }
}

static void test_empty_and_tiny_moves(void)
{
    stepramp_plan_t plan;
    /* N = 0 and N = 1: every ramp field and cruise 0, the speed limits not checked (speed far too high) */
    static const int64_t tiny[3] = {0, 1, -1};
    int j;
    for (j = 0; j < 3; j++) {
        memset(&plan, 0xA5, sizeof plan);
        CHECK(stepramp_plan_move(&plan, tiny[j], 1.0, 1.0, 1e12, 200.0, 1e6, 7) == STEPRAMP_OK);
        CHECK(plan.steps == (uint32_t)(tiny[j] < 0 ? -tiny[j] : tiny[j]));
        CHECK(plan.direction == (tiny[j] < 0 ? 1u : 0u));
        CHECK(plan.prescale == 7);
        CHECK(plan.c_first == 0 && plan.c_last == 0 && plan.sa == 0 && plan.c_sa == 0 && plan.sd == 0 &&
              plan.c_sd == 0 && plan.accel_seed == 0 && plan.decel_seed == 0 && plan.cruise == 0);
    }
    /* ... but the arguments are still checked */
    CHECK(stepramp_plan_move(&plan, 0, 0.0, 1.0, 1.0, 200.0, 1e6, 1) == STEPRAMP_EACCEL);
    CHECK(stepramp_plan_move(&plan, 1, 1.0, 1.0, 1.0, 200.0, 1e6, 0) == STEPRAMP_EPRESCALE);

    /* N = 2: one interval, it is interval 1 and interval L: c_first = c_last = c_sa = c_sd, sa = sd = 1 */
    {
        phys_t p = physics(2, 1000.0, 1000.0, 50.0, 200.0, 1e6, 1);
        CHECK(stepramp_plan_move(&plan, 2, 1000.0, 1000.0, 50.0, 200.0, 1e6, 1) == STEPRAMP_OK);
        CHECK(plan.steps == 2 && plan.sa == 1 && plan.sd == 1);
        CHECK(plan.c_first == plan.c_last && plan.c_sa == plan.c_first && plan.c_sd == plan.c_first);
        CHECK(plan.decel_seed == 0); /* m0 = -1 */
        /* a triangle peaking at 1/2: accel over 1/2 step from rest, decel over the last 1/2 step to rest */
        CHECK(rel_near((double)plan.c_first, (p.c0 * sqrt(0.5) + p.cd0 * sqrt(0.5)) * Q16, 1e-12));
    }
    /* N = 3: two intervals, peak at 1: sa = sd = 2, m0 = -1 */
    CHECK(stepramp_plan_move(&plan, -3, 1000.0, 1000.0, 50.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(plan.steps == 3 && plan.direction == 1 && plan.sa == 2 && plan.sd == 2);
    CHECK(plan.c_first == plan.c_last && plan.c_sa == plan.c_last && plan.decel_seed == 0);
}

static void test_longest_move(void)
{
    stepramp_plan_t plan;
    /* +-(2^31 - 1) steps at 25600 steps/rev: a trapezoid with ramps of ~1.6e6 steps */
    const double spr = 25600.0, accel = 5.0, speed = 100.0, fclk = 1e8;
    const uint32_t prescale = 100;
    phys_t p = physics(2147483647, accel, accel, speed, spr, fclk, prescale);
    double n_a = p.v * p.v / (2.0 * p.a);
    double m0;
    CHECK(stepramp_plan_move(&plan, -STEPRAMP_MAX_STEPS, accel, accel, speed, spr, fclk, prescale) == STEPRAMP_OK);
    CHECK(plan.steps == 2147483647u && plan.direction == 1);
    CHECK(plan.sa == (uint32_t)floor(n_a) + 1);
    CHECK(plan.sd == (uint32_t)floor(p.length - n_a) + 1);
    CHECK(near((double)plan.cruise, p.f_tick / p.v * Q32, 1.0));
    m0 = p.length - plan.sd - 1;
    CHECK(m0 > 4e6);
    CHECK(rel_near((double)plan.decel_seed, 0.6759782400672847 * p.cd0 * asymptotic_product(m0) * Q16, 1e-11));
    CHECK(stepramp_plan_move(&plan, STEPRAMP_MAX_STEPS, accel, accel, speed, spr, fclk, prescale) == STEPRAMP_OK);
    CHECK(plan.steps == 2147483647u && plan.direction == 0);
}

static void test_speed_limit_boundary(void)
{
    stepramp_plan_t plan;
    const double alpha = 2.0 * PI / 200.0;
    /* f_tick / v = 64.5 ticks: floor 64 * prescale 1 = 64 clocks is allowed, 63.5 is not */
    CHECK(stepramp_plan_move(&plan, 1000, 1e6, 1e6, alpha * 1e6 / 64.5, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(stepramp_plan_move(&plan, 1000, 1e6, 1e6, alpha * 1e6 / 63.5, 200.0, 1e6, 1) == STEPRAMP_ETOOFAST);
    /* 32.5 ticks at prescale 2: 64 clocks allowed; 31.5 ticks: 62 clocks too few */
    CHECK(stepramp_plan_move(&plan, 1000, 1e6, 1e6, alpha * 5e5 / 32.5, 200.0, 1e6, 2) == STEPRAMP_OK);
    CHECK(stepramp_plan_move(&plan, 1000, 1e6, 1e6, alpha * 5e5 / 31.5, 200.0, 1e6, 2) == STEPRAMP_ETOOFAST);
    /* prescale 65535: a one-tick interval is plenty of clocks */
    CHECK(stepramp_plan_move(&plan, 1000, 1e3, 1e3, alpha * 1e8 / 65535.0 / 1.5, 200.0, 1e8, 65535) == STEPRAMP_OK);
    CHECK(plan.cruise >> 32 == 1);
}

static void test_every_error(void)
{
    static const double bad[4] = {0.0, -1.0, NAN, INFINITY};
    const double ok_a = 1000.0, ok_v = 50.0, ok_spr = 200.0, ok_f = 1e6;
    stepramp_plan_t plan;
    stepramp_plan_t before;
    int j;

    memset(&plan, 0x5A, sizeof plan);
    before = plan;
    for (j = 0; j < 4; j++) {
        CHECK(stepramp_plan_move(&plan, 100, bad[j], ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_EACCEL);
        CHECK(stepramp_plan_move(&plan, 100, ok_a, bad[j], ok_v, ok_spr, ok_f, 1) == STEPRAMP_EDECEL);
        CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, bad[j], ok_spr, ok_f, 1) == STEPRAMP_ESPEED);
        CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, bad[j], ok_f, 1) == STEPRAMP_ESPR);
        CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, ok_spr, bad[j], 1) == STEPRAMP_EFCLK);
    }
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, ok_spr, ok_f, 0) == STEPRAMP_EPRESCALE);
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, ok_spr, ok_f, 65536) == STEPRAMP_EPRESCALE);
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, ok_spr, ok_f, UINT32_MAX) == STEPRAMP_EPRESCALE);
    CHECK(stepramp_plan_move(&plan, INT64_C(2147483648), ok_a, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_ESTEPS);
    CHECK(stepramp_plan_move(&plan, -INT64_C(2147483648), ok_a, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_ESTEPS);
    CHECK(stepramp_plan_move(&plan, INT64_MIN, ok_a, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_ESTEPS);
    CHECK(stepramp_plan_move(&plan, INT64_MAX, ok_a, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_ESTEPS);
    /* order: the first bad argument in plan.py's order wins */
    CHECK(stepramp_plan_move(&plan, INT64_MAX, ok_a, 0.0, -1.0, ok_spr, ok_f, 0) == STEPRAMP_EDECEL);
    CHECK(stepramp_plan_move(&plan, INT64_MAX, ok_a, ok_a, ok_v, ok_spr, ok_f, 0) == STEPRAMP_EPRESCALE);
    /* c0 = 1e6 * sqrt(2 * 0.0314 / 1e-12) ~ 2.5e11 ticks > 2^32 */
    CHECK(stepramp_plan_move(&plan, 100, 1e-12, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_EOVERFLOW);
    /* cruise period ~ 6.4e9 ticks > 2^32 on a 3-step move (the ramps' intervals still fit) */
    CHECK(stepramp_plan_move(&plan, 3, 1e-6, 1e-6, 5e-6, ok_spr, ok_f, 1) == STEPRAMP_EOVERFLOW);
    /* a delay of 1e305 ticks: Q32.16 of it overflows the double itself (Python raises OverflowError) */
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, 1e-297, ok_spr, 1e8, 1) == STEPRAMP_EOVERFLOW);
    /* peak 1e5 rad/s = 3.2e6 steps/s at 1e6 ticks/s */
    CHECK(stepramp_plan_move(&plan, 100, 1e9, 1e9, 1e5, ok_spr, ok_f, 1) == STEPRAMP_ETICK);
    CHECK(stepramp_plan_move(&plan, 100, 1e6, 1e6, 2.0 * PI / 200.0 * 1e6 / 63.5, ok_spr, ok_f, 1) ==
          STEPRAMP_ETOOFAST);
    /* spr = 1: alpha = 2 pi, the smallest subnormal accel becomes 0 steps/s^2; spr = 1e10 makes 1e308 infinite */
    CHECK(stepramp_plan_move(&plan, 100, 5e-324, ok_a, ok_v, 1.0, ok_f, 1) == STEPRAMP_EACCEL_UNITS);
    CHECK(stepramp_plan_move(&plan, 100, 1e308, ok_a, ok_v, 1e10, ok_f, 1) == STEPRAMP_EACCEL_UNITS);
    CHECK(stepramp_plan_move(&plan, 100, ok_a, 5e-324, ok_v, 1.0, ok_f, 1) == STEPRAMP_EDECEL_UNITS);
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, 1e308, 1e10, ok_f, 1) == STEPRAMP_ESPEED_UNITS);
    CHECK(stepramp_plan_move(&plan, 100, ok_a, ok_a, ok_v, ok_spr, 5e-324, 3) == STEPRAMP_EFTICK);
    /* spr = 2 pi (alpha = 1): d = 5e-324 against a = 1e300 puts the peak at x_p = 0: v_peak = 0 */
    CHECK(stepramp_plan_move(&plan, 10, 1e300, 5e-324, 1.0, 2.0 * PI, ok_f, 1) == STEPRAMP_EPEAK);
    CHECK(memcmp(&plan, &before, sizeof plan) == 0); /* never written on error */
    CHECK(stepramp_plan_move(NULL, 100, ok_a, ok_a, ok_v, ok_spr, ok_f, 1) == STEPRAMP_ENULL);
}

static void test_strerror(void)
{
    int e;
    int k;
    for (e = STEPRAMP_OK; e <= STEPRAMP_ERAMP; e++) {
        const char *s = stepramp_strerror((stepramp_err_t)e);
        CHECK(s != NULL && s[0] != '\0' && strcmp(s, "unknown error") != 0);
        for (k = STEPRAMP_OK; k < e; k++) {
            CHECK(strcmp(s, stepramp_strerror((stepramp_err_t)k)) != 0);
        }
    }
    CHECK(strcmp(stepramp_strerror((stepramp_err_t)999), "unknown error") == 0);
    CHECK(strstr(stepramp_strerror(STEPRAMP_EOVERFLOW), "overflows its register") != NULL);
    CHECK(strstr(stepramp_strerror(STEPRAMP_ETOOFAST), "speed too high for the hardware") != NULL);
}

static void test_decel_product_and_constants(void)
{
    int64_t m;
    double prev = 1.0;
    CHECK(stepramp_decel_product(0) == 1.0);
    CHECK(stepramp_decel_product(-5) == 1.0);
    CHECK(stepramp_decel_product(1) == 3.0 / 5.0);
    CHECK(stepramp_decel_product(256) == naive_product(256));
    /* the series takes over seamlessly at 257 */
    CHECK(rel_near_d(stepramp_decel_product(257), naive_product(257), 1e-14));
    CHECK(rel_near_d(stepramp_decel_product(2000), naive_product(2000), 1e-13));
    /* against the Gamma form (lgamma differences lose digits as m grows: looser tolerance) */
    CHECK(rel_near_d(stepramp_decel_product(1000000),
                   exp(lgamma(1000000.75) - lgamma(1000001.25) + lgamma(1.25) - lgamma(0.75)), 1e-8));
    m = 2147483647;
    CHECK(rel_near_d(stepramp_decel_product(m), asymptotic_product((double)m), 1e-13));
    CHECK(rel_near_d(stepramp_decel_product(100000), asymptotic_product(100000.0), 1e-11));
    for (m = 250; m < 270; m++) { /* decreasing across the switch */
        double p = stepramp_decel_product(m);
        CHECK(p < prev);
        prev = p;
    }
    CHECK(rel_near_d(stepramp_seed_factor, tgamma(0.75) / (2.0 * tgamma(1.25)), 1e-15));
    CHECK(rel_near_d(stepramp_lgamma_ratio_0, lgamma(1.25) - lgamma(0.75), 1e-14));
}

static void test_move_info(void)
{
    stepramp_plan_t plan;
    stepramp_plan_t plan2;
    stepramp_info_t info;
    stepramp_info_t before;
    phys_t p = physics(103, 100.0, 300.0, 1000.0, 200.0, 1e6, 1);

    /* the triangle of test_triangle: the same plan as stepramp_plan_move, and the informative values */
    CHECK(stepramp_plan_move_info(&plan, &info, 103, 100.0, 300.0, 1000.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(stepramp_plan_move(&plan2, 103, 100.0, 300.0, 1000.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(memcmp(&plan, &plan2, sizeof plan) == 0);
    CHECK(info.length == 102 && info.triangle == 1 && info.m0 == 24);
    CHECK(info.f_tick == 1e6);
    CHECK(rel_near_d(info.a, p.a, 1e-15) && rel_near_d(info.d, p.d, 1e-15) && rel_near_d(info.v, p.v, 1e-15));
    CHECK(near(info.x_a, 76.5, 1e-12) && info.x_d == info.x_a);
    CHECK(rel_near_d(info.v_peak, sqrt(2.0 * p.a * 76.5), 1e-14));
    CHECK(rel_near_d(info.min_interval, p.f_tick / info.v_peak, 1e-15));
    CHECK(info.c0 == p.c0 && info.cd0 == p.cd0);
    /* each register is its unrounded value, rounded once */
    CHECK((double)plan.c_first == rint(info.t_first * Q16) && (double)plan.c_last == rint(info.t_last * Q16));
    CHECK((double)plan.c_sa == rint(info.t_sa * Q16) && (double)plan.c_sd == rint(info.t_sd * Q16));
    CHECK((double)plan.accel_seed == rint(info.t_accel_seed * Q16));
    CHECK((double)plan.decel_seed == rint(info.t_decel_seed * Q16));
    CHECK((double)plan.cruise == rint(info.t_cruise * Q32));

    /* a trapezoid: x_a = n_a, x_d = L - n_d, v_peak = v */
    CHECK(stepramp_plan_move_info(&plan, &info, 100000, 100.0, 100.0, 50.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(info.triangle == 0 && info.v_peak == info.v && info.length == 99999);
    CHECK(rel_near_d(info.x_a, info.v * info.v / (2.0 * info.a), 1e-15));
    CHECK(rel_near_d(info.x_d, 99999.0 - info.v * info.v / (2.0 * info.d), 1e-15));

    /* N = 1: no interval; info like Python's MoveInfo (length 0, triangle, min_interval inf) */
    CHECK(stepramp_plan_move_info(&plan, &info, -1, 100.0, 100.0, 50.0, 200.0, 1e6, 4) == STEPRAMP_OK);
    CHECK(info.length == 0 && info.triangle == 1 && info.m0 == 0 && isinf(info.min_interval));
    CHECK(info.f_tick == 250000.0 && info.x_a == 0.0 && info.c0 == 0.0 && info.t_cruise == 0.0);

    /* NULL info is allowed; on error info is not written */
    CHECK(stepramp_plan_move_info(&plan, NULL, 100, 100.0, 100.0, 50.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    memset(&info, 0x3C, sizeof info);
    before = info;
    CHECK(stepramp_plan_move_info(&plan, &info, 100, 1e9, 1e9, 1e5, 200.0, 1e6, 1) == STEPRAMP_ETICK);
    CHECK(memcmp(&info, &before, sizeof info) == 0);
    CHECK(stepramp_plan_move_info(NULL, &info, 100, 100.0, 100.0, 50.0, 200.0, 1e6, 1) == STEPRAMP_ENULL);
}

/* changes while moving, 400 steps/rev at 1 MHz: a = 6366 steps/s^2, d = 5093 steps/s^2, v = 1273 steps/s */
#define CH_ACCEL 100.0
#define CH_DECEL 80.0
#define CH_SPEED 20.0
#define CH_SPR 400.0
#define CH_FCLK 1e6

static int change(stepramp_change_t *ch, double u, int64_t remaining)
{
    return stepramp_plan_change(ch, u, remaining, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1);
}

static void test_change_kinds(void)
{
    phys_t p = physics(100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1);
    double stop = p.v * p.v / (2.0 * p.d); /* 159.2 steps */
    stepramp_plan_t move;
    stepramp_change_t ch;

    /* a jog from rest starts like a move from rest: its accel ramp, then the cruise; a soft stop takes v^2 / 2d */
    CHECK(stepramp_plan_move(&move, 100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1) == STEPRAMP_OK);
    CHECK(change(&ch, 0.0, STEPRAMP_ENDLESS) == STEPRAMP_OK);
    CHECK(ch.segment.endless == 1 && ch.segment.length == 0 && ch.segment.sd == 0 && ch.has_back == 0);
    CHECK(ch.segment.head == STEPRAMP_HEAD_UP && ch.segment.head_index == 0 && ch.start_speed == 0.0);
    CHECK(ch.segment.sa == move.sa && ch.segment.sa == (uint32_t)floor(p.v * p.v / (2.0 * p.a)) + 1u);
    CHECK(near((double)ch.segment.c_first, (double)move.c_first, 1.0));
    CHECK(near((double)ch.segment.accel_seed, (double)move.accel_seed, 1.0));
    CHECK(near((double)ch.segment.c_sa, (double)move.c_sa, 1.0) && ch.segment.cruise == move.cruise);
    CHECK(ch.segment.run_stop == (uint32_t)ceil(stop) && rel_near((double)ch.segment.c_last, p.cd0 * Q16, 1e-15));
    CHECK(ch.segment.stop_ratio == (uint32_t)rint(CH_ACCEL / CH_DECEL * Q16) && ch.segment.prescale == 1);

    /* slower from twice the speed: a down head from the rest K = floor(u^2 / 2d) steps ahead, snapped to it */
    CHECK(change(&ch, 2.0 * p.v, 100000) == STEPRAMP_OK);
    CHECK(ch.segment.head == STEPRAMP_HEAD_DOWN && ch.segment.head_index == (uint32_t)floor(4.0 * stop));
    CHECK(ch.segment.length == 100000 && ch.segment.endless == 0 && ch.has_back == 0);
    CHECK(ch.start_speed <= 2.0 * p.v && 2.0 * p.v - ch.start_speed < 2.0 * p.d / (2.0 * p.v));
    CHECK(ch.segment.sd > ch.segment.sa && ch.segment.decel_seed > 0 && ch.segment.run_stop == 0);

    /* faster from v: an up head from n0 = round(v^2 / 2a) */
    CHECK(stepramp_plan_change(&ch, p.v, 100000, CH_ACCEL, CH_DECEL, 2.0 * CH_SPEED, CH_SPR, CH_FCLK, 1) ==
          STEPRAMP_OK);
    CHECK(ch.segment.head == STEPRAMP_HEAD_UP && ch.segment.head_index == (uint32_t)rint(p.v * p.v / (2.0 * p.a)));

    /* the target 10 steps ahead, inside the stop distance: to rest 159 steps ahead, then 149 steps back */
    CHECK(change(&ch, p.v, 10) == STEPRAMP_OK);
    CHECK(ch.has_back == 1 && ch.back.steps == (uint32_t)floor(stop) - 10u && ch.back.direction == 1);
    CHECK(ch.segment.length == (uint32_t)floor(stop) && ch.segment.sa == 1 && ch.segment.sd == 1);
    CHECK(ch.segment.accel_seed == 0 && ch.segment.cruise == 0 && ch.segment.head_index == 0);
    CHECK(rel_near_d(ch.start_speed, sqrt(2.0 * p.d * floor(stop)), 1e-15));
    CHECK(rel_near((double)ch.segment.c_last, p.cd0 * Q16, 1e-12)); /* the last step of a decel to rest */

    /* at the target at rest: the empty segment */
    CHECK(change(&ch, 0.0, 0) == STEPRAMP_OK);
    CHECK(ch.segment.length == 0 && ch.segment.sa == 0 && ch.segment.c_first == 0 && ch.segment.c_last == 0);
    CHECK(ch.has_back == 0 && ch.start_speed == 0.0 && ch.segment.stop_ratio != 0);
}

static void test_change_errors(void)
{
    stepramp_change_t ch;
    stepramp_change_t before;
    /* a stop distance of 2^31 + 9 steps; and of 2^31 - 1/2 steps: rest 2^31 - 1 steps ahead, then 2^31 - 11 back */
    const double far = sqrt(2.0 * 80.0 / (2.0 * PI / 400.0) * 2147483657.0);
    const double near_far = sqrt(2.0 * 80.0 / (2.0 * PI / 400.0) * 2147483647.5);
    int e;

    memset(&ch, 0x5A, sizeof ch);
    before = ch;
    CHECK(change(&ch, -1.0, 100) == STEPRAMP_ECHANGE_SPEED);
    CHECK(change(&ch, NAN, 100) == STEPRAMP_ECHANGE_SPEED);
    CHECK(change(&ch, INFINITY, STEPRAMP_ENDLESS) == STEPRAMP_ECHANGE_SPEED);
    CHECK(change(&ch, 10.0, -2) == STEPRAMP_EREMAINING);
    CHECK(change(&ch, 10.0, INT64_C(2147483648)) == STEPRAMP_EREMAINING);
    CHECK(change(&ch, far, 10) == STEPRAMP_ESEGMENT);               /* the stop distance */
    CHECK(change(&ch, far * 2.0, STEPRAMP_ENDLESS) == STEPRAMP_ESEGMENT); /* also for a jog */
    /* the accel ramp's index u^2 / 2a = 3.1e9 steps, its stop distance 3.1e6 (d = 1000 a) */
    CHECK(stepramp_plan_change(&ch, 2e4, STEPRAMP_ENDLESS, 1e-3, 1.0, 1000.0, 400.0, 1e6, 1) == STEPRAMP_ESEGMENT);
    /* a jog's soft stop v^2 / 2d = 2.5e10 steps */
    CHECK(stepramp_plan_change(&ch, 0.0, STEPRAMP_ENDLESS, 50.0, 1e-2, 1600.0, 400.0, 1e9, 1) == STEPRAMP_ESEGMENT);
    CHECK(stepramp_plan_change(&ch, 10.0, 100, 0.0, 1.0, 1.0, 400.0, 1e6, 1) == STEPRAMP_EACCEL);
    CHECK(stepramp_plan_change(&ch, -1.0, -2, 1.0, 1.0, 1.0, 400.0, 1e6, 0) == STEPRAMP_EPRESCALE);
    CHECK(stepramp_plan_change(&ch, 0.0, STEPRAMP_ENDLESS, 1.0, 1.0, 1e9, 400.0, 1e6, 1) == STEPRAMP_ETOOFAST);
    /* in steps units: 0 (spr = 1: the smallest subnormal accel), a square that overflows, f_tick's square */
    CHECK(stepramp_plan_change(&ch, 0.0, 100, 5e-324, 1.0, 1.0, 1.0, 1e6, 1) == STEPRAMP_EACCEL_UNITS);
    CHECK(stepramp_plan_change(&ch, 0.0, 100, 1.0, 1e160, 1.0, 400.0, 1e6, 1) == STEPRAMP_EDECEL_UNITS);
    CHECK(stepramp_plan_change(&ch, 0.0, 100, 1.0, 1.0, 1e160, 400.0, 1e6, 1) == STEPRAMP_ESPEED_UNITS);
    CHECK(stepramp_plan_change(&ch, 0.0, 100, 1.0, 1.0, 1.0, 400.0, 2e154, 1) == STEPRAMP_EFTICK);
    /* the target inside the stop distance (2513 steps, 100 to the target): the move back's own error */
    CHECK(stepramp_plan_change(&ch, 4000.0, 100, 50.0, 50.0, 10.0, 400.0, 2e4, 1) == STEPRAMP_ETOOFAST);
    CHECK(memcmp(&ch, &before, sizeof ch) == 0); /* never written on error */
    CHECK(change(NULL, 0.0, 100) == STEPRAMP_ENULL);
    CHECK(change(&ch, near_far, 10) == STEPRAMP_OK);
    CHECK(ch.segment.length == 2147483647u && ch.has_back && ch.back.steps == 2147483637u && ch.back.direction == 1);
    for (e = STEPRAMP_ECHANGE_SPEED; e <= STEPRAMP_ECOORD_LONG; e++) { /* the change's results, then coord's */
        const char *s = stepramp_strerror((stepramp_err_t)e);
        CHECK(strcmp(s, "unknown error") != 0 && strcmp(s, stepramp_strerror((stepramp_err_t)(e - 1))) != 0);
    }
    CHECK(strcmp(stepramp_strerror((stepramp_err_t)(STEPRAMP_ECOORD_LONG + 1)), "unknown error") == 0);
}

/* Segment.head_prod and Segment.registers */
static void test_segment_registers(void)
{
    stepramp_change_t ch;
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;
    stepramp_segment_t seg = {0};

    /* a jog from rest: STEPS 1 (the sign only), ENDLESS, an up head from 0, RUN_STOP */
    CHECK(change(&ch, 0.0, STEPRAMP_ENDLESS) == STEPRAMP_OK);
    CHECK(stepramp_segment_registers(&ch.segment, 1u, &plan, &regs) == STEPRAMP_OK);
    CHECK(plan.steps == 1u && plan.direction == 1u && plan.prescale == 1u && plan.sa == ch.segment.sa);
    CHECK(plan.c_first == ch.segment.c_first && plan.c_last == ch.segment.c_last && plan.c_sa == ch.segment.c_sa);
    CHECK(plan.sd == 0u && plan.c_sd == 0u && plan.decel_seed == 0u && plan.cruise == ch.segment.cruise);
    CHECK(plan.accel_seed == ch.segment.accel_seed && plan.stop_ratio == ch.segment.stop_ratio);
    CHECK(regs.head_down == 0u && regs.endless == 1u && regs.head_index == 0u && regs.head_prod == 0u);
    CHECK(regs.run_stop == ch.segment.run_stop && regs.run_stop > 0u);
    /* faster from v: an up head from n0, HEAD_PROD = n0 * STOP_RATIO; STEPS = L + 1 */
    CHECK(stepramp_plan_change(&ch, 1000.0, 100000, CH_ACCEL, CH_DECEL, 2.0 * CH_SPEED, CH_SPR, CH_FCLK, 1) ==
          STEPRAMP_OK);
    CHECK(stepramp_segment_registers(&ch.segment, 0u, &plan, &regs) == STEPRAMP_OK);
    CHECK(plan.steps == 100001u && plan.direction == 0u && plan.sd == ch.segment.sd && regs.endless == 0u);
    CHECK(regs.head_down == 0u && regs.head_index > 0u && regs.run_stop == 0u);
    CHECK(regs.head_prod == (uint64_t)regs.head_index * ch.segment.stop_ratio);
    /* slower: a down head, HEAD_PROD 0 */
    CHECK(change(&ch, 2000.0, 100000) == STEPRAMP_OK);
    CHECK(stepramp_segment_registers(&ch.segment, 7u, &plan, &regs) == STEPRAMP_OK);
    CHECK(regs.head_down == 1u && regs.head_index == ch.segment.head_index && regs.head_prod == 0u);
    CHECK(plan.direction == 1u);
    /* HEAD_PROD saturates at 2^47 */
    seg.head_index = 2147483647u;
    seg.stop_ratio = 0xFFFFFFFFu;
    CHECK(stepramp_segment_head_prod(&seg) == UINT64_C(1) << 47);
    seg.head_index = 65536u;
    seg.stop_ratio = 0x7FFFFFFFu; /* 2^47 - 2^16 */
    CHECK(stepramp_segment_head_prod(&seg) == (UINT64_C(1) << 47) - 65536u);
    seg.head = STEPRAMP_HEAD_DOWN;
    CHECK(stepramp_segment_head_prod(&seg) == 0u && stepramp_segment_head_prod(NULL) == 0u);
    /* STEPS = L + 1 must fit 31 bits; NULL pointers */
    seg.length = 2147483647u;
    CHECK(stepramp_segment_registers(&seg, 0u, &plan, &regs) == STEPRAMP_ESTEPS);
    seg.length = 2147483646u;
    CHECK(stepramp_segment_registers(&seg, 0u, &plan, &regs) == STEPRAMP_OK && plan.steps == 2147483647u);
    CHECK(stepramp_segment_registers(NULL, 0u, &plan, &regs) == STEPRAMP_ENULL);
    CHECK(stepramp_segment_registers(&seg, 0u, NULL, &regs) == STEPRAMP_ENULL);
    CHECK(stepramp_segment_registers(&seg, 0u, &plan, NULL) == STEPRAMP_ENULL);
}

static void test_speed_at_pulse(void)
{
    stepramp_plan_t plan;
    stepramp_info_t info;
    phys_t p = physics(100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1);

    CHECK(stepramp_plan_move_info(&plan, &info, 100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1) ==
          STEPRAMP_OK);
    CHECK(rel_near_d(stepramp_speed_at_pulse(&info, 50), sqrt(2.0 * p.a * 50.0), 1e-15)); /* accelerating */
    CHECK(stepramp_speed_at_pulse(&info, 50000) == info.v_peak && info.v_peak == info.v); /* cruising */
    CHECK(rel_near_d(stepramp_speed_at_pulse(&info, 99999 - 50), sqrt(2.0 * p.d * 50.0), 1e-15)); /* decelerating */
    CHECK(stepramp_speed_at_pulse(&info, 0) == 0.0 && stepramp_speed_at_pulse(&info, -5) == 0.0);
    CHECK(stepramp_speed_at_pulse(&info, 99999) == 0.0 && stepramp_speed_at_pulse(&info, 100003) == 0.0);
    CHECK(stepramp_speed_at_pulse(NULL, 50) == 0.0);
}

/* ---- exact mode (G_RAMP = 1): expected values from the physics and from C = c0^2 * 2^8 written out ---- */

#define EXACT STEPRAMP_RAMP_EXACT

/* round(c0^2 * 256), half to even: the ramp constant written out with exact integer arithmetic where it can be */
static void test_ramp_constant(void)
{
    uint64_t c = 0;
    uint64_t before;
    double c0;
    int ties = 0;

    CHECK(stepramp_ramp_constant(1.0, &c) == STEPRAMP_OK && c == 256u);
    CHECK(stepramp_ramp_constant(0.5, &c) == STEPRAMP_OK && c == 64u);
    CHECK(stepramp_ramp_constant(3.0 / 32.0, &c) == STEPRAMP_OK && c == 2u); /* 2.25 */
    CHECK(stepramp_ramp_constant(0.0625, &c) == STEPRAMP_OK && c == 1u);     /* the smallest: 1 */
    /* (2^20 - 1)^2 * 2^8 is the largest square below 2^48, 2^48 itself still scale 0; 2^60 needs scale 1 */
    CHECK(stepramp_ramp_constant(1048575.0, &c) == STEPRAMP_OK);
    CHECK(c == (UINT64_C(1048575) * UINT64_C(1048575)) << 8);
    CHECK(stepramp_ramp_constant(1048576.0, &c) == STEPRAMP_OK && c == UINT64_C(1) << 48);
    CHECK(stepramp_ramp_constant(67108864.0, &c) == STEPRAMP_OK && c == ((UINT64_C(1) << 60) | (UINT64_C(1) << 58)));
    /* 2^32 - 1 ticks: C = (2^32 - 1)^2 * 2^8 at scale 6, mantissa (2^32 - 1)^2 >> 4 (the double's 53 bits) */
    CHECK(stepramp_ramp_constant(4294967295.0, &c) == STEPRAMP_OK && c >> 60 == 6u);
    CHECK((c & ((UINT64_C(1) << 60) - 1u)) == (uint64_t)ldexp(rint(4294967295.0 * 4294967295.0 * 256.0), -12));
    before = c;
    /* 2^32 ticks: C = 2^72, above 2^72 - 2^36 */
    CHECK(stepramp_ramp_constant(4294967296.0, &c) == STEPRAMP_EOVERFLOW && c == before);
    /* below sqrt(1/512) ticks it rounds to 0: out of range too; so are inf, NaN and a square that overflows */
    CHECK(stepramp_ramp_constant(0.044, &c) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_ramp_constant(0.0, &c) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_ramp_constant(1e160, &c) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_ramp_constant((double)INFINITY, &c) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_ramp_constant((double)NAN, &c) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_ramp_constant(1.0, NULL) == STEPRAMP_ENULL);
    CHECK(c == before);
    /* ties (c0 * c0 rounds to a double whose product with 256 ends in .5) go to the even integer, like Python's */
    for (c0 = 1048000.0; c0 < 1048575.0 && ties < 20; c0 += 0.3) {
        double x = c0 * c0 * 256.0;
        if (x - floor(x) == 0.5) {
            double even = (fmod(floor(x), 2.0) == 0.0) ? floor(x) : floor(x) + 1.0;
            CHECK(stepramp_ramp_constant(c0, &c) == STEPRAMP_OK && (double)c == even);
            ties++;
        }
    }
    CHECK(ties == 20);
}

static void test_exact_moves(void)
{
    /* the asymmetric trapezoid of test_asymmetric_trapezoids at prescale 50 (f_tick 1e6), and a triangle */
    const double accel = 200.0, decel = 20.0, speed = 30.0, spr = 400.0, fclk = 5e7;
    const uint32_t prescale = 50;
    phys_t p = physics(-20000, accel, decel, speed, spr, fclk, prescale);
    stepramp_plan_t plan;
    stepramp_plan_t avr;
    stepramp_plan_t before;
    stepramp_info_t info;
    stepramp_info_t avr_info;

    CHECK(stepramp_plan_move_info_ramp(&plan, &info, -20000, accel, decel, speed, spr, fclk, prescale, EXACT) ==
          STEPRAMP_OK);
    CHECK(stepramp_plan_move_info(&avr, &avr_info, -20000, accel, decel, speed, spr, fclk, prescale) == STEPRAMP_OK);
    CHECK(plan.ramp == STEPRAMP_RAMP_EXACT && avr.ramp == STEPRAMP_RAMP_AVR446);
    /* the same boundaries, exact intervals c_last, c_sa, c_sd, cruise and stop ratio as the AVR446 plan */
    CHECK(plan.steps == 20000 && plan.direction == 1 && plan.sa == avr.sa && plan.sd == avr.sd);
    CHECK(plan.c_last == avr.c_last && plan.c_sa == avr.c_sa && plan.c_sd == avr.c_sd);
    CHECK(plan.cruise == avr.cruise && plan.stop_ratio == avr.stop_ratio);
    /* c_first without the deficit: interval 1 of the accel ramp is c0 (sqrt(1) - sqrt(0)) */
    CHECK(rel_near((double)plan.c_first, p.c0 * Q16, 1e-15) && plan.c_first < avr.c_first);
    /* the seeds are the ramp constants c0^2 * 2^8 and cd0^2 * 2^8 */
    CHECK(rel_near((double)plan.accel_seed, p.c0 * p.c0 * 256.0, 1e-15));
    CHECK(rel_near((double)plan.decel_seed, p.cd0 * p.cd0 * 256.0, 1e-15));
    /* info: the same move, its t_ values unrounded (the seeds' are c0 and cd0) */
    CHECK(info.x_a == avr_info.x_a && info.m0 == avr_info.m0 && info.min_interval == avr_info.min_interval);
    CHECK(info.t_accel_seed == info.c0 && info.t_decel_seed == info.cd0 && info.t_sa == avr_info.t_sa);
    CHECK((double)plan.c_first == rint(info.t_first * Q16) && info.t_first < avr_info.t_first);
    /* stepramp_plan_move_ramp gives the same plan; AVR446 through it is stepramp_plan_move */
    CHECK(stepramp_plan_move_ramp(&before, -20000, accel, decel, speed, spr, fclk, prescale, EXACT) == STEPRAMP_OK);
    CHECK(memcmp(&before, &plan, sizeof plan) == 0);
    CHECK(stepramp_plan_move_ramp(&before, -20000, accel, decel, speed, spr, fclk, prescale,
                                  STEPRAMP_RAMP_AVR446) == STEPRAMP_OK);
    CHECK(memcmp(&before, &avr, sizeof avr) == 0);

    /* a 3-step move: m0 = -1, the AVR446 decel seed is 0, the exact one the constant of cd0 (a soft stop needs it) */
    CHECK(stepramp_plan_move_ramp(&plan, 3, 1000.0, 250.0, 50.0, 200.0, 1e6, 1, EXACT) == STEPRAMP_OK);
    p = physics(3, 1000.0, 250.0, 50.0, 200.0, 1e6, 1);
    CHECK(plan.sa == plan.sd && rel_near((double)plan.decel_seed, p.cd0 * p.cd0 * 256.0, 1e-15));
    CHECK(rel_near((double)plan.accel_seed, p.c0 * p.c0 * 256.0, 1e-15));
    /* N = 0, 1: no interval, every ramp field 0, but the plan is for the exact mode */
    memset(&plan, 0xA5, sizeof plan);
    CHECK(stepramp_plan_move_ramp(&plan, -1, 1.0, 1.0, 1e12, 200.0, 1e6, 7, EXACT) == STEPRAMP_OK);
    CHECK(plan.steps == 1 && plan.direction == 1 && plan.accel_seed == 0 && plan.decel_seed == 0 && plan.cruise == 0);
    CHECK(plan.ramp == STEPRAMP_RAMP_EXACT);
}

static void test_exact_move_errors(void)
{
    stepramp_plan_t plan;
    stepramp_plan_t before;
    const double alpha = 2.0 * PI / 200.0;

    memset(&plan, 0x5A, sizeof plan);
    before = plan;
    /* the ramp first (check_ramp), after the NULL plan */
    CHECK(stepramp_plan_move_ramp(&plan, 100, 1.0, 1.0, 1.0, 200.0, 1e6, 1, 2u) == STEPRAMP_ERAMP);
    CHECK(stepramp_plan_move_ramp(&plan, 100, 0.0, 1.0, 1.0, 200.0, 1e6, 0, UINT32_MAX) == STEPRAMP_ERAMP);
    CHECK(stepramp_plan_move_ramp(NULL, 100, 1.0, 1.0, 1.0, 200.0, 1e6, 1, 2u) == STEPRAMP_ENULL);
    CHECK(stepramp_plan_move_ramp(&plan, 100, 0.0, 1.0, 1.0, 200.0, 1e6, 1, EXACT) == STEPRAMP_EACCEL);
    /* the speed limit: STEPRAMP_MIN_INTERVAL_CLKS_EXACT clocks (f_tick / v = 256.5 ticks passes, 255.5 does not,
     * which AVR446 mode takes) */
    CHECK(STEPRAMP_MIN_INTERVAL_CLKS_EXACT == 256);
    CHECK(STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE == 304);
    CHECK(stepramp_plan_move_ramp(&plan, 1000, 1e6, 1e6, alpha * 1e6 / 256.5, 200.0, 1e6, 1, EXACT) == STEPRAMP_OK);
    CHECK(stepramp_plan_move_ramp(&plan, 1000, 1e6, 1e6, alpha * 1e6 / 255.5, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_ETOOFAST);
    CHECK(stepramp_plan_move(&plan, 1000, 1e6, 1e6, alpha * 1e6 / 255.5, 200.0, 1e6, 1) == STEPRAMP_OK);
    /* 128.5 ticks at prescale 2: 256 clocks allowed; 127.5: 254 too few */
    CHECK(stepramp_plan_move_ramp(&plan, 1000, 1e6, 1e6, alpha * 5e5 / 128.5, 200.0, 1e6, 2, EXACT) == STEPRAMP_OK);
    CHECK(stepramp_plan_move_ramp(&plan, 1000, 1e6, 1e6, alpha * 5e5 / 127.5, 200.0, 1e6, 2, EXACT) ==
          STEPRAMP_ETOOFAST);
    memcpy(&before, &plan, sizeof plan);
    /* c0 = 1e6 sqrt(2 / (0.01 * 200 / 2 pi)) = 2.5e6 ticks: its ramp constant passes 2^48 (c0 >= 2^20 ticks): the
     * speed limit becomes STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE (f_tick / v = 304.5 ticks passes, 303.5 does not) */
    CHECK(stepramp_plan_move_ramp(&plan, 50000000, 0.01, 0.01, alpha * 1e6 / 304.5, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_OK);
    CHECK(plan.accel_seed >= UINT64_C(1) << 48);
    CHECK(stepramp_plan_move_ramp(&plan, 50000000, 0.01, 0.01, alpha * 1e6 / 303.5, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_ETOOFAST);
    CHECK(stepramp_plan_move(&plan, 50000000, 0.01, 0.01, alpha * 1e6 / 303.5, 200.0, 1e6, 1) == STEPRAMP_OK);
    /* the decel's alone: cd0 = 2.5e6 ticks */
    CHECK(stepramp_plan_move_ramp(&plan, 50000000, 1.0, 0.01, alpha * 1e6 / 303.5, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_ETOOFAST);
    CHECK(stepramp_plan_move_ramp(&plan, 50000000, 1.0, 1.0, alpha * 1e6 / 303.5, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_OK);
    /* c0 = 1e6 sqrt(2 / (1e-8 * 200 / 2 pi)) = 2.5e9 ticks: the AVR446 plan and the exact one fit; c0 = 5e9 ticks
     * (c_first of 2^32 ticks or more in both modes) fits neither */
    CHECK(stepramp_plan_move_ramp(&plan, 3, 1e-8, 1e-8, 0.3, 200.0, 1e6, 1, EXACT) == STEPRAMP_OK);
    CHECK(plan.accel_seed >> 60 == 6u);
    CHECK(stepramp_plan_move(&plan, 3, 1e-8, 1e-8, 0.3, 200.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(stepramp_plan_move_ramp(&plan, 3, 2.5e-9, 2.5e-9, 0.3, 200.0, 1e6, 1, EXACT) == STEPRAMP_EOVERFLOW);
    /* c0 = 0.025 ticks (a = 3.2e15 steps/s^2): the constant rounds to 0 */
    CHECK(stepramp_plan_move_ramp(&plan, 1000, 1e14, 1e14, 100.0, 200.0, 1e6, 1, EXACT) == STEPRAMP_EOVERFLOW);
    CHECK(stepramp_plan_move(&plan, 1000, 1e14, 1e14, 100.0, 200.0, 1e6, 1) == STEPRAMP_OK);
    memcpy(&plan, &before, sizeof plan);
    CHECK(stepramp_plan_move_ramp(&plan, 3, 2.5e-9, 2.5e-9, 0.3, 200.0, 1e6, 1, EXACT) == STEPRAMP_EOVERFLOW);
    CHECK(memcmp(&plan, &before, sizeof plan) == 0); /* never written on error */
    CHECK(strstr(stepramp_strerror(STEPRAMP_EOVERFLOW), "ramp constant") != NULL);
    CHECK(strstr(stepramp_strerror(STEPRAMP_ERAMP), "ramp must be 0 (avr446) or 1 (exact)") != NULL);
}

static void test_exact_changes(void)
{
    phys_t p = physics(100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1);
    double n_d = p.v * p.v / (2.0 * p.d); /* 159.2 steps */
    double m = ceil(n_d);
    stepramp_plan_t move;
    stepramp_change_t ch;
    stepramp_change_t avr;
    stepramp_change_t before;
    stepramp_change_info_t info;
    stepramp_segment_t seg;
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;

    /* a jog from rest: the move's accel ramp (its ramp constant), the decel's constant for a soft stop; c_sd is the
     * first interval of a stop in the cruise: (m - n_d) of a step at v, then the decel from n_d to m - 1 steps before
     * the rest, f_tick (sqrt(2 n_d / d) - sqrt(2 (m - 1) / d)) */
    CHECK(stepramp_plan_move_ramp(&move, 100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1, EXACT) ==
          STEPRAMP_OK);
    CHECK(stepramp_plan_change_info_ramp(&ch, &info, 0.0, STEPRAMP_ENDLESS, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR,
                                         CH_FCLK, 1, EXACT) == STEPRAMP_OK);
    CHECK(change(&avr, 0.0, STEPRAMP_ENDLESS) == STEPRAMP_OK);
    CHECK(ch.segment.ramp == STEPRAMP_RAMP_EXACT && avr.segment.ramp == STEPRAMP_RAMP_AVR446);
    CHECK(ch.segment.endless == 1 && ch.segment.head == STEPRAMP_HEAD_UP && ch.segment.sa == move.sa);
    CHECK(ch.segment.accel_seed == move.accel_seed && ch.segment.decel_seed == move.decel_seed);
    CHECK(ch.segment.c_first == move.c_first && ch.segment.c_sa == move.c_sa && ch.segment.cruise == move.cruise);
    CHECK(ch.segment.run_stop == avr.segment.run_stop && ch.segment.run_stop == (uint32_t)m);
    CHECK(ch.segment.c_last == avr.segment.c_last && avr.segment.c_sd == 0 && avr.segment.decel_seed == 0);
    CHECK(rel_near((double)ch.segment.c_sd,
                   p.f_tick * ((m - n_d) / p.v + sqrt(2.0 * n_d / p.d) - sqrt(2.0 * (m - 1.0) / p.d)) * Q16, 1e-9));
    CHECK(info.t_accel_seed == p.c0 && info.t_decel_seed == p.cd0 && (double)ch.segment.c_sd == rint(info.t_sd * Q16));

    /* slower from twice the speed: a down head, its constant the decel's (cd0) */
    CHECK(stepramp_plan_change_ramp(&ch, 2.0 * p.v, 100000, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1,
                                    EXACT) == STEPRAMP_OK);
    CHECK(change(&avr, 2.0 * p.v, 100000) == STEPRAMP_OK);
    CHECK(ch.segment.head == STEPRAMP_HEAD_DOWN && ch.segment.head_index == avr.segment.head_index);
    CHECK(ch.segment.sa == avr.segment.sa && ch.segment.sd == avr.segment.sd && ch.segment.c_sa == avr.segment.c_sa);
    CHECK(ch.segment.accel_seed == move.decel_seed && ch.segment.decel_seed == move.decel_seed);
    CHECK(ch.segment.c_first != avr.segment.c_first); /* no deficit in the exact mode */
    /* faster from v: an up head from n0, its constant the accel's (c0) */
    CHECK(stepramp_plan_change_ramp(&ch, p.v, 100000, CH_ACCEL, CH_DECEL, 2.0 * CH_SPEED, CH_SPR, CH_FCLK, 1,
                                    EXACT) == STEPRAMP_OK);
    CHECK(ch.segment.head == STEPRAMP_HEAD_UP && ch.segment.head_index == (uint32_t)rint(p.v * p.v / (2.0 * p.a)));
    CHECK(ch.segment.accel_seed == move.accel_seed && ch.segment.decel_seed == move.decel_seed);

    /* the target inside the stop distance: the stop segment and the move back, both for the exact mode */
    CHECK(stepramp_plan_change_ramp(&ch, p.v, 10, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1, EXACT) ==
          STEPRAMP_OK);
    CHECK(ch.has_back == 1 && ch.back.ramp == STEPRAMP_RAMP_EXACT && ch.segment.ramp == STEPRAMP_RAMP_EXACT);
    CHECK(ch.back.steps == (uint32_t)floor(n_d) - 10u && ch.back.decel_seed == move.decel_seed);
    CHECK(ch.segment.accel_seed == 0 && ch.segment.decel_seed == move.decel_seed && ch.segment.sa == 1);
    /* at the target at rest: the empty segment (no interval: decel_seed 0 too) */
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, 0, CH_ACCEL, CH_DECEL, CH_SPEED, CH_SPR, CH_FCLK, 1, EXACT) ==
          STEPRAMP_OK);
    CHECK(ch.segment.length == 0 && ch.segment.decel_seed == 0 && ch.segment.ramp == STEPRAMP_RAMP_EXACT);

    /* the ramp travels with a segment: of_move, and the registers' plan */
    CHECK(stepramp_segment_of_move(&seg, &move) == STEPRAMP_OK && seg.ramp == STEPRAMP_RAMP_EXACT);
    CHECK(stepramp_segment_registers(&seg, 0u, &plan, &regs) == STEPRAMP_OK && plan.ramp == STEPRAMP_RAMP_EXACT);
    CHECK(plan.steps == move.steps && plan.c_first == move.c_first && plan.accel_seed == move.accel_seed);
    CHECK(plan.c_sd == move.c_sd && plan.decel_seed == move.decel_seed && plan.cruise == move.cruise);

    /* errors: the ramp first; the exact speed limit (256 clocks); a head constant out of range (c0 = 5e9 ticks; 2.5e6
     * ticks is in range since the scaled constant) */
    memset(&ch, 0x5A, sizeof ch);
    before = ch;
    CHECK(stepramp_plan_change_ramp(&ch, -1.0, -2, 0.0, 1.0, 1.0, 400.0, 1e6, 0, 5u) == STEPRAMP_ERAMP);
    CHECK(stepramp_plan_change_ramp(NULL, 0.0, 100, 1.0, 1.0, 1.0, 400.0, 1e6, 1, 5u) == STEPRAMP_ENULL);
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 40.0, 30.0, 20.0, 400.0, 3e5, 1, EXACT) ==
          STEPRAMP_ETOOFAST);
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 2.5e-9, 2.5e-9, 0.3, 200.0, 1e6, 1, EXACT) ==
          STEPRAMP_EOVERFLOW);
    CHECK(memcmp(&ch, &before, sizeof ch) == 0); /* never written on error */
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 0.01, 0.01, 0.3, 200.0, 1e6, 1, EXACT) == STEPRAMP_OK);
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 40.0, 30.0, 20.0, 400.0, 3e5, 1,
                                    STEPRAMP_RAMP_AVR446) == STEPRAMP_OK);
    CHECK(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 0.01, 0.01, 0.3, 200.0, 1e6, 1,
                                    STEPRAMP_RAMP_AVR446) == STEPRAMP_OK);
}

/* The engine's tick of a plan's last pulse, by the spec's rules (docs/algorithm.md, "Which value each interval gets",
 * the recurrences and the accumulator) run interval by interval: an independent model for short moves. */
static uint64_t engine_last_tick(const stepramp_plan_t *p)
{
    int64_t length = (int64_t)p->steps - 1;
    int64_t sa = p->sa;
    int64_t sd = p->sd;
    int64_t i;
    int64_t an = 0;
    int64_t dm = -1;
    uint64_t a = p->accel_seed;
    uint64_t ar = 0;
    uint64_t d = p->decel_seed;
    uint64_t dr = 0;
    uint64_t t = 0;
    uint64_t acc = 0;

    for (i = 1; i <= length; i++) {
        uint64_t value;
        uint64_t s;
        int cruise = 0;
        if (i == 1) {
            value = p->c_first;
        } else if (i == length) {
            value = p->c_last;
        } else if (i == sa) {
            value = p->c_sa;
        } else if (i == sd) {
            value = p->c_sd;
        } else if (i < sa) {
            while (an < i - 1) { /* A_n from A_(n-1): den 4n + 1 */
                uint64_t num = 2u * a + ar;
                uint64_t den = 4u * (uint64_t)(++an) + 1u;
                a -= num / den;
                ar = num % den;
            }
            value = a;
        } else if (i > sd) {
            if (dm < 0) {
                dm = length - sd - 1; /* D_m0 = decel_seed, r = 0 */
            }
            while (dm > length - i) { /* D_(m-1) from D_m: den 4m - 1 */
                uint64_t num = 2u * d + dr;
                uint64_t den = 4u * (uint64_t)dm - 1u;
                d += num / den;
                dr = num % den;
                dm--;
            }
            value = d;
        } else {
            value = p->cruise;
            cruise = 1;
        }
        s = acc + (cruise ? value : value << 16);
        t += s >> 32;
        acc = s & 0xFFFFFFFFu;
    }
    return t;
}

/* the ideal end of a move (ticks), from the physics: accel to the peak, cruise, decel */
static double ideal_end_ticks(int64_t steps, double accel, double decel, double speed, double spr, double fclk,
                              uint32_t prescale)
{
    phys_t p = physics(steps, accel, decel, speed, spr, fclk, prescale);
    double n_a = p.v * p.v / (2.0 * p.a);
    double n_d = p.v * p.v / (2.0 * p.d);
    double peak = p.v;
    double cruise = 0.0;
    if (n_a + n_d <= p.length) {
        cruise = (p.length - n_a - n_d) / p.v;
    } else {
        peak = sqrt(2.0 * p.a * p.length * p.d / (p.a + p.d));
    }
    return (peak / p.a + cruise + peak / p.d) * p.f_tick;
}

/* a coordinated move: every axis of 2 steps or more ends on the tick nearest the ideal end, by the engine's rules */
static void check_coordinated(const int64_t *steps, uint32_t count, double accel, double decel, double speed,
                              double spr, double fclk, uint32_t prescale)
{
    stepramp_plan_t plans[STEPRAMP_COORD_MAX_AXES];
    stepramp_plan_t plain[STEPRAMP_COORD_MAX_AXES];
    stepramp_coord_info_t info;
    uint32_t i;
    int64_t lead = 0;
    double t_end;

    for (i = 0; i < count; i++) {
        int64_t n = steps[i] < 0 ? -steps[i] : steps[i];
        lead = n > lead ? n : lead;
    }
    t_end = ideal_end_ticks(lead, accel, decel, speed, spr, fclk, prescale);
    CHECK(stepramp_plan_coordinated_info(plans, &info, steps, count, accel, decel, speed, spr, fclk, prescale) ==
          STEPRAMP_OK);
    CHECK(stepramp_plan_coordinated(plain, steps, count, accel, decel, speed, spr, fclk, prescale) == STEPRAMP_OK);
    CHECK(memcmp(plans, plain, count * sizeof plans[0]) == 0);
    CHECK(info.failed_axis == STEPRAMP_COORD_NO_AXIS && info.count == count);
    CHECK(rel_near_d(info.t_end, t_end, 1e-12));
    CHECK(info.end_tick == floor(t_end + 0.5));
    for (i = 0; i < count; i++) {
        int64_t n = steps[i] < 0 ? -steps[i] : steps[i];
        double r = n >= 2 ? (double)(n - 1) / (double)(lead - 1) : 0.0;
        stepramp_plan_t base;
        CHECK(info.ratio[i] == r);
        if (n < 2) { /* 0 and 1 step: plan_move's plan with the path's values */
            CHECK(stepramp_plan_move(&base, steps[i], accel, decel, speed, spr, fclk, prescale) == STEPRAMP_OK);
            CHECK(memcmp(&plans[i], &base, sizeof base) == 0);
            continue;
        }
        CHECK(stepramp_plan_move(&base, steps[i], accel * r, decel * r, speed * r, spr, fclk, prescale) ==
              STEPRAMP_OK);
        CHECK(plans[i].steps == base.steps && plans[i].direction == base.direction && plans[i].sa == base.sa &&
              plans[i].sd == base.sd && plans[i].cruise == base.cruise && plans[i].decel_seed == base.decel_seed &&
              plans[i].accel_seed == base.accel_seed); /* plan_move's seed, its truncation already out */
        CHECK(near((double)plans[i].c_last, (double)base.c_last, 0.01 * (double)base.c_last + 2.0 * Q16));
        CHECK(engine_last_tick(&plans[i]) == (uint64_t)info.end_tick);
    }
}

static void test_coordinated(void)
{
    const int64_t demo[3] = {400, 200, -100};
    const int64_t small[4] = {50, 17, -3, 2};
    const int64_t with_empty[5] = {400, 1, -1, 0, 250};
    const int64_t eight[8] = {1000, -999, 500, 250, 7, 3, 2, -1};
    const int64_t zeros[2] = {0, 0};
    const int64_t too_big[3] = {3, 2147483648LL, 2};
    const int64_t slow_two[3] = {100000, 50000, -2};
    const int64_t one[1] = {329689501};
    stepramp_plan_t plans[STEPRAMP_COORD_MAX_AXES];
    stepramp_plan_t before[STEPRAMP_COORD_MAX_AXES];
    stepramp_coord_info_t info;
    double a;
    double v;

    check_coordinated(demo, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 1); /* the AVR446 demo move on three axes */
    check_coordinated(demo, 3, 83.7, 2.94, 62.25, 200.0, 129297.4, 1); /* decel 28 times slower than accel */
    check_coordinated(demo, 3, 2.94, 83.7, 62.25, 200.0, 129297.4, 1); /* and the other way */
    check_coordinated(small, 4, 40.0, 30.0, 200.0, 400.0, 1e6, 3);     /* triangles */
    check_coordinated(with_empty, 5, 40.0, 40.0, 20.0, 400.0, 1e6, 1);
    check_coordinated(eight, 8, 40.0, 40.0, 20.0, 400.0, 1e6, 1);
    check_coordinated(demo, 1, 40.0, 40.0, 20.0, 400.0, 1e6, 1); /* one axis */
    CHECK(stepramp_plan_coordinated_info(plans, &info, demo, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_OK);
    CHECK(info.lead == 0 && info.ratio[0] == 1.0 && info.ratio[1] == 199.0 / 399.0 && info.ratio[2] == 99.0 / 399.0);

    /* errors: the result, the failed axis, nothing written */
    memset(plans, 0x5A, sizeof plans);
    memcpy(before, plans, sizeof plans);
    CHECK(stepramp_plan_coordinated_info(plans, &info, demo, 0, 40.0, 40.0, 20.0, 400.0, 1e6, 1) ==
          STEPRAMP_ECOORD_AXES);
    CHECK(info.failed_axis == STEPRAMP_COORD_NO_AXIS);
    CHECK(stepramp_plan_coordinated(plans, eight, 9, 40.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_ECOORD_AXES);
    CHECK(stepramp_plan_coordinated(plans, zeros, 2, 40.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_ECOORD_ZERO);
    CHECK(stepramp_plan_coordinated(plans, demo, 3, 0.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_EACCEL);
    CHECK(stepramp_plan_coordinated(plans, demo, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 0) == STEPRAMP_EPRESCALE);
    CHECK(stepramp_plan_coordinated_info(plans, &info, too_big, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 1) ==
          STEPRAMP_ESTEPS);
    CHECK(info.failed_axis == 1u);
    /* a 2-step axis beside a long, slow lead (cruise 60,000 ticks, 10-step ramps): its one interval lasts the whole
     * move, more than 2^32 ticks */
    v = 2.0 * PI / 200.0 * (1e6 / 60000.0);
    a = v * (1e6 / 60000.0) / 20.0;
    CHECK(stepramp_plan_coordinated_info(plans, &info, slow_two, 3, a, a, v, 200.0, 1e6, 1) == STEPRAMP_EOVERFLOW);
    CHECK(info.failed_axis == 2u);
    /* a path of 2^48 ticks or more */
    CHECK(stepramp_plan_coordinated_info(plans, &info, one, 1, 3.8e7, 1.55e5, 8.77e-7, 10756.75, 84743112.2, 64) ==
          STEPRAMP_ECOORD_LONG);
    CHECK(info.failed_axis == STEPRAMP_COORD_NO_AXIS);
    CHECK(stepramp_plan_coordinated(NULL, demo, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_ENULL);
    CHECK(stepramp_plan_coordinated(plans, NULL, 3, 40.0, 40.0, 20.0, 400.0, 1e6, 1) == STEPRAMP_ENULL);
    CHECK(memcmp(plans, before, sizeof plans) == 0);
    CHECK(stepramp_time_before_last(NULL) == 0.0 && stepramp_ideal_end(NULL) == 0.0);
}

int main(void)
{
    test_long_symmetric_trapezoid();
    test_asymmetric_trapezoids();
    test_triangle();
    test_triangle_symmetric_even();
    test_empty_and_tiny_moves();
    test_longest_move();
    test_speed_limit_boundary();
    test_every_error();
    test_strerror();
    test_decel_product_and_constants();
    test_move_info();
    test_change_kinds();
    test_change_errors();
    test_segment_registers();
    test_speed_at_pulse();
    test_coordinated();
    test_ramp_constant();
    test_exact_moves();
    test_exact_move_errors();
    test_exact_changes();
    return test_report("test_stepramp_plan");
}
