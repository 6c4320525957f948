/* SPDX-License-Identifier: MIT */
/*
 * Host unit tests of the stepramp driver (stepramp.c) on the fake register bank of stepramp_fakebus.c, which the
 * host build routes STEPRAMP_READ32 / _WRITE32 / _WRITE8 to. Expected register words are computed here from the
 * plan struct with the offsets of docs/registers.md written out, not with the driver's code. The comparison with
 * the Python driver's plan_writes() is done by sw/tests/test_c_driver.py. Exit status 0 when every check passes.
 */
#include "stepramp.h"
#include "stepramp_fakebus.h"
#include "stepramp_hostbus.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "test_check.h"

#define BASE ((uintptr_t)0x40A00000u)
#define GOOD_ID 0x53520003u

/* Offsets from docs/registers.md, written out (not stepramp_regs.h) */
enum {
    O_ID = 0x00,
    O_CTRL = 0x04,
    O_STATUS = 0x08,
    O_STEPS = 0x0C,
    O_PRESCALE = 0x10,
    O_C_FIRST_LO = 0x14,
    O_C_FIRST_HI = 0x18,
    O_C_LAST_LO = 0x1C,
    O_C_LAST_HI = 0x20,
    O_SA = 0x24,
    O_C_SA_LO = 0x28,
    O_C_SA_HI = 0x2C,
    O_SD = 0x30,
    O_C_SD_LO = 0x34,
    O_C_SD_HI = 0x38,
    O_ACCEL_SEED_LO = 0x3C,
    O_ACCEL_SEED_HI = 0x40,
    O_DECEL_SEED_LO = 0x44,
    O_DECEL_SEED_HI = 0x48,
    O_CRUISE_LO = 0x4C,
    O_CRUISE_HI = 0x50,
    O_STOP_RATIO = 0x54,
    O_POSITION = 0x58,
    O_SEGMENT = 0x78,
    O_HEAD_INDEX = 0x7C,
    O_RUN_STOP = 0x80,
    O_HEAD_PROD_LO = 0x84,
    O_HEAD_PROD_HI = 0x88,
    O_CHANGE_AT = 0x8C,
    O_INPUT_FILTER = 0x90,
    O_INPUT_CFG = 0x94,
    O_LATCH_POS = 0x98,
    O_LATCH_TIME_LO = 0x9C,
    O_LATCH_TIME_HI = 0xA0,
    O_TIME_LO = 0xA4,
    O_TIME_HI = 0xA8
};

#define N_MOTION 19 /* STEPS .. STOP_RATIO: (0x54 - 0x0C) / 4 + 1 */
#define N_SEGMENT 5 /* SEGMENT .. HEAD_PROD_HI */
#define TWO32 4294967296.0

typedef struct {
    uint32_t offset, value;
} word_t;

/* The expected motion-register words of a plan, in address order: LO / HI by division, STEPS by negation in
 * 64-bit signed arithmetic. */
static void expected_words(const stepramp_plan_t *p, word_t out[N_MOTION])
{
    int64_t signed_steps = p->direction ? -(int64_t)p->steps : (int64_t)p->steps;
    const uint64_t wide[7] = {p->c_first, p->c_last, p->c_sa, p->c_sd, p->accel_seed, p->decel_seed, p->cruise};
    const uint32_t lo_off[7] = {O_C_FIRST_LO,    O_C_LAST_LO,     O_C_SA_LO,  O_C_SD_LO,
                                O_ACCEL_SEED_LO, O_DECEL_SEED_LO, O_CRUISE_LO};
    int i, n = 0;

    memset(out, 0, N_MOTION * sizeof *out);
    out[n].offset = O_STEPS;
    out[n++].value = (uint32_t)(signed_steps < 0 ? (uint64_t)(signed_steps + 4294967296LL) : (uint64_t)signed_steps);
    out[n].offset = O_PRESCALE;
    out[n++].value = p->prescale;
    for (i = 0; i < 7; i++) {
        out[n].offset = lo_off[i];
        out[n++].value = (uint32_t)(wide[i] % 4294967296ULL);
        out[n].offset = lo_off[i] + 4u;
        out[n++].value = (uint32_t)(wide[i] / 4294967296ULL);
    }
    out[n].offset = O_SA;
    out[n++].value = p->sa;
    out[n].offset = O_SD;
    out[n++].value = p->sd;
    out[n].offset = O_STOP_RATIO;
    out[n++].value = p->stop_ratio;
    CHECK_EQ(n, N_MOTION);
    /* address order (insertion sort: n is small) */
    for (i = 1; i < n; i++) {
        word_t w = out[i];
        int j = i - 1;
        while (j >= 0 && out[j].offset > w.offset) {
            out[j + 1] = out[j];
            j--;
        }
        out[j + 1] = w;
    }
}

static stepramp_fakebus_t *const bus = &stepramp_fakebus;

static uint32_t reg(uint32_t offset)
{
    CHECK(offset < 4u * STEPRAMP_FAKEBUS_WORDS);
    return offset < 4u * STEPRAMP_FAKEBUS_WORDS ? bus->regs[offset / 4u] : 0xDEADBEEFu;
}

/* a device on a freshly reset fake core, log cleared */
static stepramp_t fresh(double fclk, double spr, uint32_t prescale)
{
    stepramp_t dev;

    stepramp_fakebus_reset(BASE, GOOD_ID);
    CHECK_EQ(stepramp_init(&dev, BASE, fclk, spr, prescale), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    return dev;
}

/* the log holds exactly the n words of want as full-word writes from entry first on, and the registers hold them */
static void check_log_words(const word_t *want, int n, uint32_t first)
{
    int i;

    for (i = 0; i < n; i++) {
        const stepramp_fakebus_write_t *w = &bus->log[first + (uint32_t)i];
        CHECK_EQ(w->offset, want[i].offset);
        CHECK_EQ(w->value, want[i].value);
        CHECK_EQ(w->be, 0xFu);
        CHECK_EQ(reg(want[i].offset), want[i].value);
    }
}

/* the log holds exactly the motion words of plan (full-word writes, address order) from entry first on */
static void check_program_log(const stepramp_plan_t *plan, uint32_t first)
{
    word_t want[N_MOTION];

    expected_words(plan, want);
    check_log_words(want, N_MOTION, first);
}

/* the log holds exactly the segment words of regs (full-word writes, address order) from entry first on:
 * SEGMENT = HEAD_DOWN (bit 0) | ENDLESS (bit 1), HEAD_PROD split by division */
static void check_segment_log(const stepramp_segment_regs_t *regs, uint32_t first)
{
    const word_t want[N_SEGMENT] = {{O_SEGMENT, regs->head_down + 2u * regs->endless},
                                    {O_HEAD_INDEX, regs->head_index},
                                    {O_RUN_STOP, regs->run_stop},
                                    {O_HEAD_PROD_LO, (uint32_t)(regs->head_prod % 4294967296ULL)},
                                    {O_HEAD_PROD_HI, (uint32_t)(regs->head_prod / 4294967296ULL)}};

    check_log_words(want, N_SEGMENT, first);
}

/* the segment registers of a move from rest to rest (driver.NO_SEGMENT) */
static const stepramp_segment_regs_t no_segment = {0u, 0u, 0u, 0u, 0u};

/* log entry i is START: bit 0 in byte 0 of CTRL only */
static void check_start(uint32_t i)
{
    CHECK_EQ(bus->log[i].offset, O_CTRL);
    CHECK_EQ(bus->log[i].be, 0x1u);
    CHECK_EQ(bus->log[i].value, 0x1u);
}

static void test_init(void)
{
    stepramp_t dev;
    static const uint32_t bad_ids[] = {0x00000000u, 0xFFFFFFFFu, 0x53530002u, 0x52530002u, 0x00005352u, 0x5352FFFFu};
    size_t i;

    stepramp_fakebus_reset(BASE, GOOD_ID);
    CHECK_EQ(stepramp_init(&dev, BASE, 50e6, 6400.0, 50u), STEPRAMP_OK);
    CHECK(dev.base == BASE && dev.fclk == 50e6 && dev.spr == 6400.0 && dev.prescale == 50u);
    CHECK_EQ(dev.version, 0x0003u);
    /* the segment registers unknown (the first program writes them), the stepping outputs at their reset values */
    CHECK(dev.segment_dirty == 1u && dev.min_gap == STEPRAMP_MIN_GAP_RESET && STEPRAMP_MIN_GAP_RESET == 2u);
    CHECK_EQ(bus->writes, 0u); /* init only reads */
    CHECK_EQ(bus->reads, 1u);
    CHECK_EQ(dev.ramp, STEPRAMP_RAMP_AVR446);
    for (i = 0; i < sizeof bad_ids / sizeof bad_ids[0]; i++) {
        /* a stepramp core, and ID bit 15 (G_RAMP) the driver's ramp: AVR446 (clear) for stepramp_init */
        int want = ((bad_ids[i] >> 16) == 0x5352u && (bad_ids[i] & 0x8000u) == 0u) ? STEPRAMP_OK : STEPRAMP_EID;
        int want_exact = ((bad_ids[i] >> 16) == 0x5352u && (bad_ids[i] & 0x8000u) != 0u) ? STEPRAMP_OK : STEPRAMP_EID;
        stepramp_fakebus_reset(BASE, bad_ids[i]);
        CHECK_EQ(stepramp_init(&dev, BASE, 50e6, 6400.0, 50u), want);
        CHECK_EQ(stepramp_init_ramp(&dev, BASE, 50e6, 6400.0, 50u, STEPRAMP_RAMP_EXACT), want_exact);
        CHECK_EQ(bus->writes, 0u);
    }
    /* a core built with G_RAMP = 1: ID bit 15 set, the version in bits 14:0 */
    stepramp_fakebus_reset(BASE, GOOD_ID | 0x8000u);
    CHECK_EQ(stepramp_init(&dev, BASE, 50e6, 6400.0, 50u), STEPRAMP_EID);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 50e6, 6400.0, 50u, STEPRAMP_RAMP_EXACT), STEPRAMP_OK);
    CHECK(dev.ramp == STEPRAMP_RAMP_EXACT && dev.version == 0x0003u && dev.prescale == 50u);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 50e6, 6400.0, 50u, STEPRAMP_RAMP_AVR446), STEPRAMP_EID);
    /* a ramp that is neither: nothing read, dev untouched */
    memset(&dev, 0x5A, sizeof dev);
    stepramp_fakebus_reset(BASE, GOOD_ID);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 50e6, 6400.0, 50u, 2u), STEPRAMP_ERAMP);
    CHECK(bus->reads == 0u && dev.prescale == 0x5A5A5A5Au);
    CHECK_EQ(stepramp_init_ramp(NULL, BASE, 50e6, 6400.0, 50u, STEPRAMP_RAMP_EXACT), STEPRAMP_ENULL);
    /* a core at another address: the device's base is where it reads */
    stepramp_fakebus_reset(BASE + 0x1000u, GOOD_ID);
    CHECK_EQ(stepramp_init(&dev, BASE + 0x1000u, 1e6, 200.0, 1u), STEPRAMP_OK);
    CHECK_EQ(bus->bus_errors, 0u);
    CHECK_EQ(stepramp_init(NULL, BASE, 1e6, 200.0, 1u), STEPRAMP_ENULL);
}

/* move = plan + program + START, for a trapezoid, a triangle with negative steps, and the empty moves; the first
 * move after stepramp_init writes the segment registers 0 too */
static void test_move_writes(void)
{
    static const struct {
        int64_t steps;
        double accel, decel, speed, spr, fclk;
        uint32_t prescale;
    } moves[] = {
        {200, 10.35, 10.35, 31.4159, 200.0, 1e6, 1u},         /* trapezoid */
        {-75, 12.0, 16.0, 0.628, 200.0, 1e6, 1u},             /* triangle, negative */
        {400, 40.0, 40.0, 20.0, 400.0, 1e6, 1u},              /* AVR446 demo move */
        {-3200, 40.0, 25.0, 20.0, 6400.0, 50e6, 50u},         /* prescale */
        {2147483647, 40.0, 40.0, 20.0, 6400.0, 100e6, 1000u}, /* the largest |steps| */
        {-2147483647, 40.0, 40.0, 20.0, 6400.0, 100e6, 1000u},
        {0, 1.0, 1.0, 1.0, 200.0, 1e6, 1u},
        {-1, 1.0, 1.0, 1.0, 200.0, 1e6, 1u},
    };
    size_t i;

    for (i = 0; i < sizeof moves / sizeof moves[0]; i++) {
        stepramp_t dev = fresh(moves[i].fclk, moves[i].spr, moves[i].prescale);
        stepramp_plan_t plan;
        const stepramp_fakebus_write_t *last = &bus->log[N_MOTION + N_SEGMENT];

        CHECK_EQ(stepramp_plan_move(&plan, moves[i].steps, moves[i].accel, moves[i].decel, moves[i].speed, moves[i].spr,
                                    moves[i].fclk, moves[i].prescale),
                 STEPRAMP_OK);
        CHECK_EQ(stepramp_move(&dev, moves[i].steps, moves[i].accel, moves[i].decel, moves[i].speed), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
        check_program_log(&plan, 0u);
        check_segment_log(&no_segment, N_MOTION); /* the first program after init: SEGMENT .. HEAD_PROD_HI = 0 */
        CHECK_EQ(dev.segment_dirty, 0u);
        /* then START: byte 0 of CTRL only */
        CHECK_EQ(last->offset, O_CTRL);
        CHECK_EQ(last->be, 0x1u);
        CHECK_EQ(last->value, 0x1u);
        CHECK_EQ(bus->starts, 1u);
        CHECK_EQ(bus->soft_stops + bus->hard_stops, 0u);
        /* STEPS is the signed step count */
        CHECK((int64_t)(reg(O_STEPS) >= 0x80000000u ? (int64_t)reg(O_STEPS) - 4294967296LL : (int64_t)reg(O_STEPS)) ==
              moves[i].steps);
        CHECK_EQ(bus->bus_errors, 0u);
        /* the log accessors (for ctypes) give the same entries */
        CHECK_EQ(stepramp_fakebus_log_count(), N_MOTION + N_SEGMENT + 1u);
        {
            uint32_t off = 0u, value = 0u, be = 0u;
            CHECK_EQ(stepramp_fakebus_log_entry(N_MOTION + N_SEGMENT, &off, &value, &be), 0);
            CHECK(off == O_CTRL && value == 0x1u && be == 0x1u);
            CHECK_EQ(stepramp_fakebus_log_entry(0u, &off, NULL, NULL), 0);
            CHECK_EQ(off, O_STEPS);
            CHECK_EQ(stepramp_fakebus_log_entry(N_MOTION, &off, &value, &be), 0);
            CHECK(off == O_SEGMENT && value == 0u && be == 0xFu);
            CHECK_EQ(stepramp_fakebus_log_entry(N_MOTION + N_SEGMENT + 1u, &off, &value, &be), -1);
        }
    }
}

/* program() of hand-made plans whose wide fields use every word and byte */
static void test_program_splits_wide_values(void)
{
    stepramp_plan_t plan;
    stepramp_t dev = fresh(1e6, 200.0, 1u);

    memset(&plan, 0, sizeof plan);
    plan.steps = 0x7FFFFFFFu;
    plan.direction = 1u;
    plan.prescale = 0xFFFFu;
    plan.c_first = UINT64_C(0xABCD12345678);
    plan.c_last = UINT64_C(0xFFFFFFFFFFFF);
    plan.sa = 0x12345678u;
    plan.c_sa = UINT64_C(0x000100000000);
    plan.sd = 0x7FFFFFFEu;
    plan.c_sd = UINT64_C(0x0000FFFFFFFF);
    plan.accel_seed = UINT64_C(0x8000DEADBEEF);
    plan.decel_seed = UINT64_C(0x0001);
    plan.cruise = UINT64_C(0x0123456789ABCDEF);
    plan.stop_ratio = 0x00018000u; /* 1.5 */
    CHECK_EQ(stepramp_program(&dev, &plan), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT); /* the first program after init clears the segment registers */
    CHECK_EQ(bus->starts, 0u);                   /* program does not start */
    check_program_log(&plan, 0u);
    check_segment_log(&no_segment, N_MOTION);
    /* the same words, spelled out */
    CHECK_EQ(reg(O_STEPS), 0x80000001u);
    CHECK_EQ(reg(O_C_FIRST_LO), 0x12345678u);
    CHECK_EQ(reg(O_C_FIRST_HI), 0xABCDu);
    CHECK_EQ(reg(O_C_SA_LO), 0u);
    CHECK_EQ(reg(O_C_SA_HI), 1u);
    CHECK_EQ(reg(O_C_SD_LO), 0xFFFFFFFFu);
    CHECK_EQ(reg(O_C_SD_HI), 0u);
    CHECK_EQ(reg(O_CRUISE_LO), 0x89ABCDEFu);
    CHECK_EQ(reg(O_CRUISE_HI), 0x01234567u);
    CHECK_EQ(reg(O_STOP_RATIO), 0x00018000u);

    plan.direction = 0u;
    plan.steps = 5u;
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program(&dev, &plan), STEPRAMP_OK);
    CHECK_EQ(bus->writes, (uint32_t)N_MOTION); /* the segment registers are known to be 0 now */
    CHECK_EQ(reg(O_STEPS), 5u);
    plan.direction = 1u;
    plan.steps = 0u; /* -0 */
    CHECK_EQ(stepramp_program(&dev, &plan), STEPRAMP_OK);
    CHECK_EQ(reg(O_STEPS), 0u);
    plan.steps = 1u;
    CHECK_EQ(stepramp_program(&dev, &plan), STEPRAMP_OK);
    CHECK_EQ(reg(O_STEPS), 0xFFFFFFFFu);

    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program(&dev, NULL), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_program(NULL, &plan), STEPRAMP_ENULL);
    CHECK_EQ(bus->writes, 0u);
}

/* START, SOFT_STOP, HARD_STOP touch byte 0 of CTRL only; the enables in byte 1 survive them */
static void test_commands_keep_irq_enables(void)
{
    static const uint32_t enables[4] = {0x000u, 0x100u, 0x200u, 0x300u};
    size_t i;

    for (i = 0; i < 4; i++) {
        stepramp_t dev = fresh(1e6, 200.0, 1u);

        stepramp_enable_irq(&dev, (enables[i] & 0x100u) != 0u, (enables[i] & 0x200u) != 0u);
        CHECK_EQ(bus->writes, 1u);
        CHECK_EQ(bus->log[0].offset, O_CTRL);
        CHECK_EQ(bus->log[0].value, enables[i]);
        CHECK_EQ(bus->starts + bus->soft_stops + bus->hard_stops, 0u); /* enabling starts nothing */
        CHECK_EQ(reg(O_CTRL), enables[i]);

        stepramp_start(&dev);
        stepramp_soft_stop(&dev);
        stepramp_hard_stop(&dev);
        CHECK_EQ(bus->writes, 4u);
        CHECK_EQ(bus->log[1].value, 0x1u);
        CHECK_EQ(bus->log[2].value, 0x2u);
        CHECK_EQ(bus->log[3].value, 0x4u);
        CHECK(bus->log[1].be == 0x1u && bus->log[2].be == 0x1u && bus->log[3].be == 0x1u);
        CHECK(bus->log[1].offset == O_CTRL && bus->log[2].offset == O_CTRL && bus->log[3].offset == O_CTRL);
        CHECK(bus->starts == 1u && bus->soft_stops == 1u && bus->hard_stops == 1u);
        CHECK_EQ(reg(O_CTRL), enables[i]);
        CHECK_EQ(stepramp_hostbus_read32(BASE + O_CTRL), enables[i]); /* the command bits read 0 */

        /* a whole move keeps them too */
        CHECK_EQ(stepramp_move(&dev, 200, 10.35, 10.35, 31.4159), STEPRAMP_OK);
        CHECK_EQ(reg(O_CTRL), enables[i]);
        CHECK_EQ(bus->bus_errors, 0u);
    }
    {
        stepramp_t dev = fresh(1e6, 200.0, 1u);
        stepramp_enable_irq(&dev, 7, 0); /* any nonzero is true */
        CHECK_EQ(reg(O_CTRL), 0x100u);
        stepramp_enable_irq(&dev, 0, -1);
        CHECK_EQ(reg(O_CTRL), 0x200u);
        stepramp_enable_irq(&dev, 0, 0);
        CHECK_EQ(reg(O_CTRL), 0u);
    }
}

static void test_enable_and_outputs(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    stepramp_outputs_t out = {4u, 4u, 7u, 20u, 9u, 40u, 3u};

    stepramp_enable_irq(&dev, 1, 1);
    stepramp_set_enable(&dev, 1);
    CHECK_EQ(reg(O_CTRL), 0x10300u);
    CHECK_EQ(bus->log[1].be, 0x4u); /* byte 2 only */
    stepramp_enable_irq(&dev, 0, 1);
    CHECK_EQ(reg(O_CTRL), 0x10200u); /* ENABLE kept */
    stepramp_start(&dev);
    CHECK_EQ(reg(O_CTRL), 0x10200u);
    stepramp_set_enable(&dev, 0);
    CHECK_EQ(reg(O_CTRL), 0x00200u);
    CHECK_EQ(bus->starts, 1u);

    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
    CHECK_EQ(reg(0x64u), 4u | (4u << 4));
    CHECK_EQ(reg(0x68u), 7u);
    CHECK_EQ(reg(0x6Cu), 20u | (9u << 16));
    CHECK_EQ(reg(0x70u), 40u);
    CHECK_EQ(reg(0x74u), 3u);
    CHECK_EQ(dev.min_gap, 7u + 3u);
    out.mode = 5u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_EOUTPUTS);
    out.mode = 3u;
    out.ustep_log2 = 8u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_EOUTPUTS);
    CHECK_EQ(stepramp_configure_outputs(&dev, NULL), STEPRAMP_EOUTPUTS);
    CHECK_EQ(reg(0x64u), 4u | (4u << 4)); /* nothing written on error */
    CHECK_EQ(dev.min_gap, 7u + 3u);
    out.step_width = 0u; /* 0 acts as 1 */
    out.step_space = 0u;
    out.ustep_log2 = 0u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
    CHECK_EQ(dev.min_gap, 2u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EOUTPUTS), "mode") != NULL);
}

/* ID bit 14 (NO_WINDINGS: a core built with G_WINDINGS false): init clears dev->windings, the version is ID bits 13:0,
 * and stepramp_configure_outputs refuses every winding mode (1 .. 4) with STEPRAMP_EWINDINGS, writing nothing, but
 * takes STEP/DIR (DRIVE.MODE 0); with bit 14 clear every mode is taken as before */
static void test_no_windings(void)
{
    stepramp_t dev;
    stepramp_outputs_t out = {0u, 2u, 5u, 0u, 0u, 0u, 1u};
    uint32_t mode;

    CHECK_EQ(STEPRAMP_ID_WINDINGS_BIT, 14u);
    stepramp_fakebus_reset(BASE, 0x53520000u | 0x4000u | 0x3A5Cu);
    CHECK_EQ(stepramp_init(&dev, BASE, 1e6, 200.0, 1u), STEPRAMP_OK);
    CHECK_EQ(dev.version, 0x3A5Cu);
    CHECK_EQ(dev.windings, 0u);
    stepramp_fakebus_clear_log();
    for (mode = 1u; mode <= 4u; mode++) {
        out.mode = mode;
        CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_EWINDINGS);
    }
    CHECK_EQ(bus->writes, 0u); /* nothing written */
    CHECK_EQ(dev.min_gap, STEPRAMP_MIN_GAP_RESET);
    out.mode = 5u; /* still an invalid mode first */
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_EOUTPUTS);
    out.mode = 0u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
    CHECK_EQ(reg(0x64u), 2u << 4); /* DRIVE.MODE 0 */
    CHECK_EQ(reg(0x68u), 5u);
    CHECK_EQ(dev.min_gap, 6u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EWINDINGS), "G_WINDINGS") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EWINDINGS), "ID bit 14") != NULL);
    /* with G_RAMP = 1 too: both bits out of the version */
    stepramp_fakebus_reset(BASE, 0x53520000u | 0xC000u | 0x0003u);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 1e6, 200.0, 1u, STEPRAMP_RAMP_EXACT), STEPRAMP_OK);
    CHECK(dev.version == 0x0003u && dev.windings == 0u);
    /* bit 14 clear: windings, every mode */
    stepramp_fakebus_reset(BASE, 0x53520000u | 0x3FFFu);
    CHECK_EQ(stepramp_init(&dev, BASE, 1e6, 200.0, 1u), STEPRAMP_OK);
    CHECK(dev.version == 0x3FFFu && dev.windings == 1u);
    for (mode = 0u; mode <= 4u; mode++) {
        out.mode = mode;
        CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
        CHECK_EQ(reg(0x64u), mode | (2u << 4));
    }
}

/* the registers of two plans are the same words */
static int same_words(const stepramp_plan_t *a, const stepramp_plan_t *b)
{
    word_t wa[N_MOTION];
    word_t wb[N_MOTION];

    expected_words(a, wa);
    expected_words(b, wb);
    return memcmp(wa, wb, sizeof wa) == 0;
}

/* jog = plan_change from rest, endless + registers + program with the segment + START; the next move clears the
 * segment registers, the one after it writes what a move always did */
static void test_jog_writes(void)
{
    static const struct {
        double speed, accel, decel, spr, fclk;
        uint32_t prescale;
    } jogs[] = {
        {20.0, 40.0, 40.0, 400.0, 1e6, 1u},
        {-20.0, 40.0, 25.0, 6400.0, 50e6, 50u},
        {-0.5, 100.0, 3.0, 200.0, 1e6, 1u},
        {3.0, 1.0, 500.0, 3200.0, 10e6, 7u},
    };
    static const stepramp_segment_regs_t zero = {0u, 0u, 0u, 0u, 0u};
    size_t i;

    for (i = 0; i < sizeof jogs / sizeof jogs[0]; i++) {
        stepramp_t dev = fresh(jogs[i].fclk, jogs[i].spr, jogs[i].prescale);
        stepramp_change_t ch;
        stepramp_plan_t plan;
        stepramp_plan_t again;
        stepramp_plan_t move;
        stepramp_segment_regs_t regs;
        stepramp_segment_regs_t regs_again;

        CHECK_EQ(stepramp_plan_change(&ch, 0.0, STEPRAMP_ENDLESS, jogs[i].accel, jogs[i].decel, fabs(jogs[i].speed),
                                      jogs[i].spr, jogs[i].fclk, jogs[i].prescale),
                 STEPRAMP_OK);
        CHECK_EQ(stepramp_segment_registers(&ch.segment, jogs[i].speed < 0.0, &plan, &regs), STEPRAMP_OK);
        CHECK_EQ(stepramp_jog(&dev, jogs[i].speed, jogs[i].accel, jogs[i].decel), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
        check_program_log(&plan, 0u);
        check_segment_log(&regs, N_MOTION);
        check_start(N_MOTION + N_SEGMENT);
        CHECK(bus->starts == 1u && bus->bus_errors == 0u && dev.segment_dirty == 1u);
        /* STEPS is +-1 (the direction only), an endless up head from rest with its soft stop's length */
        CHECK_EQ(reg(O_STEPS), jogs[i].speed < 0.0 ? 0xFFFFFFFFu : 1u);
        CHECK_EQ(reg(O_SEGMENT), 2u);
        CHECK(reg(O_HEAD_INDEX) == 0u && reg(O_HEAD_PROD_LO) == 0u && reg(O_HEAD_PROD_HI) == 0u);
        CHECK(reg(O_RUN_STOP) == ch.segment.run_stop && ch.segment.run_stop > 0u);
        CHECK(reg(O_SD) == 0u && reg(O_SA) == ch.segment.sa);
        /* stepramp_plan_jog: the same registers, none written */
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_plan_jog(&dev, &again, &regs_again, jogs[i].speed, jogs[i].accel, jogs[i].decel),
                 STEPRAMP_OK);
        CHECK(same_words(&again, &plan) && regs_again.run_stop == regs.run_stop && regs_again.endless == 1u);
        CHECK_EQ(bus->writes, 0u);

        /* a move after the jog: its registers, the segment registers cleared, START */
        CHECK_EQ(stepramp_plan_move(&move, -400, 40.0, 40.0, 1.0, jogs[i].spr, jogs[i].fclk, jogs[i].prescale),
                 STEPRAMP_OK);
        CHECK_EQ(stepramp_move(&dev, -400, 40.0, 40.0, 1.0), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
        check_program_log(&move, 0u);
        check_segment_log(&zero, N_MOTION);
        check_start(N_MOTION + N_SEGMENT);
        CHECK_EQ(dev.segment_dirty, 0u);
        /* and the move after it: the motion registers and START only */
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_move(&dev, -400, 40.0, 40.0, 1.0), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + 1u);
        check_program_log(&move, 0u);
        check_start(N_MOTION);
        CHECK_EQ(bus->bus_errors, 0u);
    }
}

/* A driver set up for an exact-mode core (stepramp_init_ramp): its moves, jogs and changes are the exact-mode plans
 * (stepramp_plan_move_ramp, stepramp_plan_change_ramp), written like the AVR446 ones. */
static void test_exact_mode_driver(void)
{
    stepramp_t dev;
    stepramp_plan_t plan;
    stepramp_plan_t avr;
    stepramp_change_t ch;
    stepramp_plan_t jog_plan;
    stepramp_segment_regs_t regs;

    stepramp_fakebus_reset(BASE, GOOD_ID | 0x8000u);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 4e6, 400.0, 4u, STEPRAMP_RAMP_EXACT), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    /* a move: the exact plan (its seeds the ramp constants, not the AVR446 seeds) */
    CHECK_EQ(stepramp_plan_move_ramp(&plan, -4000, 40.0, 30.0, 20.0, 400.0, 4e6, 4u, STEPRAMP_RAMP_EXACT), STEPRAMP_OK);
    CHECK_EQ(stepramp_plan_move(&avr, -4000, 40.0, 30.0, 20.0, 400.0, 4e6, 4u), STEPRAMP_OK);
    CHECK(plan.ramp == STEPRAMP_RAMP_EXACT && avr.ramp == STEPRAMP_RAMP_AVR446 && plan.accel_seed != avr.accel_seed);
    CHECK_EQ(stepramp_move(&dev, -4000, 40.0, 30.0, 20.0), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
    check_program_log(&plan, 0u);
    check_segment_log(&no_segment, N_MOTION);
    check_start(N_MOTION + N_SEGMENT);
    /* stepramp_plan gives it too */
    CHECK_EQ(stepramp_plan(&dev, &avr, -4000, 40.0, 30.0, 20.0), STEPRAMP_OK);
    CHECK(same_words(&avr, &plan) && avr.ramp == STEPRAMP_RAMP_EXACT);
    /* a jog: the exact-mode segment */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, 40.0, 30.0, 20.0, 400.0, 4e6, 4u,
                                       STEPRAMP_RAMP_EXACT),
             STEPRAMP_OK);
    CHECK_EQ(stepramp_segment_registers(&ch.segment, 0u, &jog_plan, &regs), STEPRAMP_OK);
    CHECK(jog_plan.ramp == STEPRAMP_RAMP_EXACT && jog_plan.c_sd != 0u && jog_plan.decel_seed == plan.decel_seed);
    CHECK_EQ(stepramp_jog(&dev, 20.0, 40.0, 30.0), STEPRAMP_OK);
    check_program_log(&jog_plan, 0u);
    check_segment_log(&regs, N_MOTION);
    /* the speed limit is 256 clocks: 20 rad/s at 400 steps/rev is 1273 steps/s, 785 ticks; at prescale 1 and 3e5 Hz
     * 235 clocks, enough for AVR446 (64) but not for the exact mode */
    stepramp_fakebus_reset(BASE, GOOD_ID | 0x8000u);
    CHECK_EQ(stepramp_init_ramp(&dev, BASE, 3e5, 400.0, 1u, STEPRAMP_RAMP_EXACT), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_move(&dev, 4000, 40.0, 30.0, 20.0), STEPRAMP_ETOOFAST);
    CHECK_EQ(stepramp_jog(&dev, 20.0, 40.0, 30.0), STEPRAMP_ETOOFAST);
    CHECK_EQ(stepramp_queue_move(&dev, 4000, 40.0, 30.0, 20.0), STEPRAMP_ETOOFAST);
    CHECK_EQ(bus->writes, 0u);
    CHECK_EQ(stepramp_plan_move(&avr, 4000, 40.0, 30.0, 20.0, 400.0, 3e5, 1u), STEPRAMP_OK);
}

/* program with segment registers: all 0 leaves them clear, anything else set; NULL writes them only when set */
static void test_program_segment(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs = {1u, 1u, 0x7FFFFFFFu, 0x12345u, UINT64_C(0x800012345678)};
    static const stepramp_segment_regs_t zero = {0u, 0u, 0u, 0u, 0u};

    memset(&plan, 0, sizeof plan);
    plan.steps = 10u;
    plan.prescale = 1u;
    CHECK_EQ(stepramp_program_segment(&dev, &plan, &regs), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT);
    CHECK_EQ(bus->starts, 0u);
    check_program_log(&plan, 0u);
    check_segment_log(&regs, N_MOTION);
    CHECK(reg(O_SEGMENT) == 3u && reg(O_HEAD_INDEX) == 0x7FFFFFFFu && reg(O_RUN_STOP) == 0x12345u);
    CHECK(reg(O_HEAD_PROD_LO) == 0x12345678u && reg(O_HEAD_PROD_HI) == 0x8000u && dev.segment_dirty == 1u);
    /* one field alone keeps them set */
    regs = zero;
    regs.head_prod = UINT64_C(1) << 40;
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program_segment(&dev, &plan, &regs), STEPRAMP_OK);
    CHECK(bus->writes == N_MOTION + N_SEGMENT && reg(O_HEAD_PROD_HI) == 0x100u && dev.segment_dirty == 1u);
    /* all 0 given: written, clear */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program_segment(&dev, &plan, &zero), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT);
    check_segment_log(&zero, N_MOTION);
    CHECK_EQ(dev.segment_dirty, 0u);
    /* then NULL: the motion registers only */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program_segment(&dev, &plan, NULL), STEPRAMP_OK);
    CHECK_EQ(bus->writes, (uint32_t)N_MOTION);
    /* NULL pointers: nothing written, the flag kept */
    dev.segment_dirty = 1u;
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_program_segment(&dev, NULL, &regs), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_program_segment(NULL, &plan, &regs), STEPRAMP_ENULL);
    CHECK(bus->writes == 0u && dev.segment_dirty == 1u);
}

/* after stepramp_init the segment registers are unknown: the first plain move writes them 0, once; on a core
 * that an earlier program (a restart without a core reset) or another master left with a segment, that runs the
 * move from rest to rest rather than the stale segment */
static void test_first_program_clears_segment(void)
{
    static const word_t stale[N_SEGMENT] = {{O_SEGMENT, 2u},
                                            {O_HEAD_INDEX, 17u},
                                            {O_RUN_STOP, 0x1234u},
                                            {O_HEAD_PROD_LO, 0x89ABCDEFu},
                                            {O_HEAD_PROD_HI, 0x42u}};
    stepramp_t dev;
    stepramp_plan_t move;
    int pass;
    size_t i;

    CHECK_EQ(stepramp_plan_move(&move, 300, 40.0, 40.0, 20.0, 400.0, 1e6, 1u), STEPRAMP_OK);
    for (pass = 0; pass < 2; pass++) { /* a core from reset (all 0), then one left with an endless segment */
        stepramp_fakebus_reset(BASE, GOOD_ID);
        for (i = 0; pass == 1 && i < N_SEGMENT; i++) {
            bus->regs[stale[i].offset / 4u] = stale[i].value;
        }
        CHECK_EQ(stepramp_init(&dev, BASE, 1e6, 400.0, 1u), STEPRAMP_OK);
        CHECK_EQ(bus->writes, 0u); /* init writes nothing */
        CHECK_EQ(dev.segment_dirty, 1u);
        /* the first plain move: its registers, the five segment registers 0 in address order, START */
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_move(&dev, 300, 40.0, 40.0, 20.0), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
        check_program_log(&move, 0u);
        check_segment_log(&no_segment, N_MOTION);
        check_start(N_MOTION + N_SEGMENT);
        for (i = 0; i < N_SEGMENT; i++) {
            CHECK_EQ(reg(stale[i].offset), 0u);
        }
        CHECK_EQ(dev.segment_dirty, 0u);
        /* the second plain move: the motion registers and START only */
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_move(&dev, 300, 40.0, 40.0, 20.0), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + 1u);
        check_program_log(&move, 0u);
        check_start(N_MOTION);
        CHECK_EQ(dev.segment_dirty, 0u);
        CHECK_EQ(bus->starts, 1u);
        CHECK_EQ(bus->bus_errors, 0u);
    }
}

/* the jog's checks: its speed, the plan's errors, STEP width + space against its shortest interval; nothing written */
static void test_jog_errors(void)
{
    static const double bad_speeds[] = {0.0, -0.0, NAN, INFINITY, -INFINITY};
    stepramp_t dev = fresh(1e6, 400.0, 4u);
    stepramp_outputs_t out = {0u, 0u, 1u, 0u, 0u, 0u, 1u};
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;
    /* 20 rad/s at 400 steps/rev: 1273.2 steps/s, 196.3 ticks of 4 clocks: 784 clocks */
    const uint32_t shortest = (uint32_t)floor(1e6 / 4.0 / (20.0 * 400.0 / (2.0 * 3.141592653589793))) * 4u;
    size_t i;

    CHECK_EQ(shortest, 784u);
    for (i = 0; i < sizeof bad_speeds / sizeof bad_speeds[0]; i++) {
        CHECK_EQ(stepramp_jog(&dev, bad_speeds[i], 40.0, 40.0), STEPRAMP_EJOG_SPEED);
    }
    CHECK_EQ(stepramp_jog(&dev, 20.0, 0.0, 40.0), STEPRAMP_EACCEL);
    CHECK_EQ(stepramp_jog(&dev, 20.0, 40.0, NAN), STEPRAMP_EDECEL);
    CHECK_EQ(stepramp_jog(&dev, -1e4, 40.0, 40.0), STEPRAMP_ETOOFAST);
    CHECK_EQ(stepramp_jog(&dev, 20.0, 40.0, 1e-9), STEPRAMP_ESEGMENT); /* a soft stop of 2^31 steps or more */
    CHECK_EQ(bus->writes, 0u);

    /* STEP width + space: up to the shortest interval, not one clock more */
    out.step_width = (uint16_t)(shortest - 100u);
    out.step_space = 100u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_plan_jog(&dev, &plan, &regs, -20.0, 40.0, 40.0), STEPRAMP_OK);
    out.step_space = 101u;
    CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_jog(&dev, -20.0, 40.0, 40.0), STEPRAMP_EGAP);
    CHECK_EQ(stepramp_jog(&dev, 19.9, 40.0, 40.0), STEPRAMP_OK); /* a little slower fits */
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);

    /* a move that fast does not fit that STEP width + space either, and writes nothing; a slower one does */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_move(&dev, 4000, 40.0, 40.0, 20.0), STEPRAMP_EGAP); /* a trapezoid: it cruises at 20 rad/s */
    CHECK_EQ(bus->writes, 0u);
    CHECK_EQ(stepramp_move(&dev, 4000, 40.0, 40.0, 19.9), STEPRAMP_OK);

    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_plan_jog(NULL, &plan, &regs, 20.0, 40.0, 40.0), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_plan_jog(&dev, NULL, &regs, 20.0, 40.0, 40.0), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_plan_jog(&dev, &plan, NULL, 20.0, 40.0, 40.0), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_jog(NULL, 20.0, 40.0, 40.0), STEPRAMP_ENULL);
    CHECK_EQ(bus->writes, 0u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EJOG_SPEED), "jog speed") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EGAP), "STEP width + STEP space") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ESEGMENT), "2^31 - 1") != NULL);
}

/* log entry i is a CTRL command: bits in byte 0 of CTRL only */
static void check_command(uint32_t i, uint32_t bits)
{
    CHECK_EQ(bus->log[i].offset, O_CTRL);
    CHECK_EQ(bus->log[i].be, 0x1u);
    CHECK_EQ(bus->log[i].value, bits);
}

/* log entry i is CHANGE_AT = pulse, a full-word write. The fake bank maps the registers up to HEAD_PROD_HI only:
 * while it does not know CHANGE_AT the write counts as its one bus error, once it does the register holds pulse. */
static void check_change_at(uint32_t i, uint32_t pulse)
{
    CHECK_EQ(bus->log[i].offset, O_CHANGE_AT);
    CHECK_EQ(bus->log[i].value, pulse);
    CHECK_EQ(bus->log[i].be, 0xFu);
    CHECK_EQ(bus->bus_errors, reg(O_CHANGE_AT) == pulse ? 0u : 1u);
}

/* STEPS of a segment staged in direction dir: its length + 1 (1 when endless), negated for direction 1 */
static uint32_t segment_steps_word(const stepramp_segment_t *seg, uint32_t dir)
{
    int64_t steps = seg->endless ? 1 : (int64_t)seg->length + 1;

    return (uint32_t)(dir ? (uint64_t)(4294967296LL - steps) : (uint64_t)steps);
}

/* the whole log of a change: the segment's motion and segment words, CHANGE_AT, then CTRL.CHANGE (bit 3) */
static void check_change_log(const stepramp_segment_t *seg, uint32_t dir, uint32_t pulse)
{
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;

    CHECK_EQ(stepramp_segment_registers(seg, dir, &plan, &regs), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 2u);
    check_program_log(&plan, 0u);
    check_segment_log(&regs, N_MOTION);
    check_change_at(N_MOTION + N_SEGMENT, pulse);
    check_command(N_MOTION + N_SEGMENT + 1u, 0x8u);
    CHECK(bus->starts + bus->soft_stops + bus->hard_stops == 0u);
    /* spelled out: STEPS carries the direction, SEGMENT the head and endless bits */
    CHECK_EQ(reg(O_STEPS), segment_steps_word(seg, dir));
    CHECK_EQ(reg(O_SEGMENT), seg->head + 2u * seg->endless);
    CHECK(reg(O_HEAD_INDEX) == seg->head_index && reg(O_RUN_STOP) == seg->run_stop && reg(O_SA) == seg->sa &&
          reg(O_SD) == seg->sd && reg(O_PRESCALE) == seg->prescale);
}

/* the continuations stepramp_change and stepramp_change_to are tested with */
static const struct {
    double u;          /* steps/s at the pulse */
    int64_t remaining; /* steps from the pulse to the target, or STEPRAMP_ENDLESS */
    double accel, decel, speed, spr, fclk;
    uint32_t prescale;
    uint32_t pulse;
} changes[] = {
    {3000.0, 5000, 40.0, 40.0, 20.0, 400.0, 1e6, 1u, 77u},              /* down head, to a target */
    {500.0, 2000, 60.0, 30.0, 20.0, 400.0, 1e6, 1u, 0x7FFFFFFFu},       /* up head, the last pulse */
    {1000.0, STEPRAMP_ENDLESS, 40.0, 25.0, 5.0, 6400.0, 50e6, 50u, 1u}, /* endless (a jog), pulse 1 */
    {0.0, 300, 100.0, 100.0, 10.0, 200.0, 1e6, 4u, 4u},                 /* from rest */
    {3000.0, 1767, 40.0, 40.0, 20.0, 400.0, 1e6, 1u, 9u},               /* to rest at the stop distance */
};
#define N_CHANGES (sizeof changes / sizeof changes[0])

/* stepramp_change: the segment's registers in address order, CHANGE_AT, CTRL.CHANGE; argument errors write nothing */
static void test_change_writes(void)
{
    size_t i;

    for (i = 0; i < N_CHANGES; i++) {
        stepramp_t dev = fresh(changes[i].fclk, changes[i].spr, changes[i].prescale);
        stepramp_change_t ch;
        uint32_t dir;

        CHECK_EQ(stepramp_plan_change(&ch, changes[i].u, changes[i].remaining, changes[i].accel, changes[i].decel,
                                      changes[i].speed, changes[i].spr, changes[i].fclk, changes[i].prescale),
                 STEPRAMP_OK);
        CHECK_EQ(ch.has_back, 0);
        for (dir = 0; dir < 2u; dir++) {
            stepramp_fakebus_clear_log();
            CHECK_EQ(stepramp_change(&dev, &ch.segment, dir, changes[i].pulse), STEPRAMP_OK);
            check_change_log(&ch.segment, dir, changes[i].pulse);
        }
        /* any nonzero direction is 1 */
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_change(&dev, &ch.segment, 7u, changes[i].pulse), STEPRAMP_OK);
        check_change_log(&ch.segment, 1u, changes[i].pulse);
        /* the next program clears them unless they are all 0 (a positioning up head from index 0) */
        CHECK_EQ(dev.segment_dirty,
                 (ch.segment.head | ch.segment.endless | ch.segment.head_index | ch.segment.run_stop) != 0u);
    }
    {
        stepramp_t dev = fresh(1e6, 400.0, 1u);
        stepramp_change_t ch;
        stepramp_segment_t longest;

        CHECK_EQ(stepramp_plan_change(&ch, 1000.0, 100, 40.0, 40.0, 20.0, 400.0, 1e6, 1u), STEPRAMP_OK);
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_change(&dev, &ch.segment, 0u, 0u), STEPRAMP_EPULSE);
        CHECK_EQ(stepramp_change(&dev, &ch.segment, 0u, 0x80000000u), STEPRAMP_EPULSE);
        CHECK_EQ(stepramp_change(&dev, &ch.segment, 1u, 0xFFFFFFFFu), STEPRAMP_EPULSE);
        CHECK_EQ(stepramp_change(NULL, &ch.segment, 0u, 10u), STEPRAMP_ENULL);
        CHECK_EQ(stepramp_change(&dev, NULL, 0u, 10u), STEPRAMP_ENULL);
        longest = ch.segment; /* STEPS = 2^31 does not fit */
        longest.length = 0x7FFFFFFFu;
        CHECK_EQ(stepramp_change(&dev, &longest, 0u, 10u), STEPRAMP_ESTEPS);
        CHECK_EQ(bus->writes, 0u);
        CHECK_EQ(bus->reads, 0u);
        CHECK(dev.segment_dirty == 1u); /* untouched: nothing was written */
        CHECK(strstr(stepramp_strresult(STEPRAMP_EPULSE), "pulse") != NULL);
    }
}

/* stepramp_change_to: plans as stepramp_plan_change with the device's spr, fclk and prescale, reads STATUS once and
 * commits in STATUS.DIR; refusals write nothing */
static void test_change_to(void)
{
    size_t i;

    for (i = 0; i < N_CHANGES; i++) {
        uint32_t dir;

        for (dir = 0; dir < 2u; dir++) {
            stepramp_t dev = fresh(changes[i].fclk, changes[i].spr, changes[i].prescale);
            stepramp_change_t ch;

            CHECK_EQ(stepramp_plan_change(&ch, changes[i].u, changes[i].remaining, changes[i].accel, changes[i].decel,
                                          changes[i].speed, changes[i].spr, changes[i].fclk, changes[i].prescale),
                     STEPRAMP_OK);
            stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, dir, 0u, 0u);
            CHECK_EQ(stepramp_change_to(&dev, changes[i].pulse, changes[i].u, changes[i].remaining, changes[i].accel,
                                        changes[i].decel, changes[i].speed),
                     STEPRAMP_OK);
            CHECK(bus->reads == 1u && bus->status_reads == 1u);
            check_change_log(&ch.segment, dir, changes[i].pulse);
        }
    }
    {
        stepramp_t dev = fresh(1e6, 400.0, 1u);

        stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
        /* argument and plan errors: no access at all */
        CHECK_EQ(stepramp_change_to(&dev, 0u, 1000.0, 100, 40.0, 40.0, 20.0), STEPRAMP_EPULSE);
        CHECK_EQ(stepramp_change_to(&dev, 0x80000000u, 1000.0, 100, 40.0, 40.0, 20.0), STEPRAMP_EPULSE);
        CHECK_EQ(stepramp_change_to(NULL, 10u, 1000.0, 100, 40.0, 40.0, 20.0), STEPRAMP_ENULL);
        CHECK_EQ(stepramp_change_to(&dev, 10u, NAN, 100, 40.0, 40.0, 20.0), STEPRAMP_ECHANGE_SPEED);
        CHECK_EQ(stepramp_change_to(&dev, 10u, -1.0, 100, 40.0, 40.0, 20.0), STEPRAMP_ECHANGE_SPEED);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, -2, 40.0, 40.0, 20.0), STEPRAMP_EREMAINING);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, INT64_C(2147483648), 40.0, 40.0, 20.0), STEPRAMP_EREMAINING);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, 100, 0.0, 40.0, 20.0), STEPRAMP_EACCEL);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, 100, 40.0, 40.0, INFINITY), STEPRAMP_ESPEED);
        /* 3000 steps/s stops in 3000^2 / (2 * 40 * 400 / 2 pi) = 1767 steps: a target 10 ahead needs a move back */
        CHECK_EQ(stepramp_change_to(&dev, 10u, 3000.0, 10, 40.0, 40.0, 20.0), STEPRAMP_EREVERSE);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 3000.0, 1766, 40.0, 40.0, 20.0), STEPRAMP_EREVERSE);
        CHECK_EQ(bus->reads, 0u);
        CHECK_EQ(bus->writes, 0u);
        /* the core idle, or something pending: STATUS read, nothing written */
        stepramp_fakebus_set_status(STEPRAMP_STATE_STOP, 0u, 1u, 0u, STEPRAMP_STATUS_DONE_MASK);
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, 1000, 40.0, 40.0, 20.0), STEPRAMP_EIDLE);
        stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 1u, 0u, 0u);
        bus->regs[O_STATUS / 4u] |= 0x80u; /* STATUS.PENDING */
        CHECK_EQ(stepramp_change_to(&dev, 10u, 1000.0, 1000, 40.0, 40.0, 20.0), STEPRAMP_EPENDING);
        CHECK_EQ(bus->status_reads, 2u);
        CHECK_EQ(bus->writes, 0u);
        CHECK(strstr(stepramp_strresult(STEPRAMP_EREVERSE), "move back") != NULL);
        CHECK(strstr(stepramp_strresult(STEPRAMP_EIDLE), "idle") != NULL);
        CHECK(strstr(stepramp_strresult(STEPRAMP_EPENDING), "PENDING") != NULL);
        /* the target exactly at the stop distance is a take-over (the stop segment), not a reversal */
        bus->regs[O_STATUS / 4u] &= ~0x80u;
        CHECK_EQ(stepramp_change_to(&dev, 10u, 3000.0, 1767, 40.0, 40.0, 20.0), STEPRAMP_OK);
    }
    {
        /* STEP width + space: up to the segment's shortest interval, at its start speed (a down head from 3000
         * steps/s) or at its peak (an up head to 20 rad/s = 1273 steps/s), not one clock more */
        static const double starts[2] = {3000.0, 500.0};
        size_t k;

        for (k = 0; k < 2u; k++) {
            stepramp_t dev = fresh(1e6, 400.0, 4u);
            stepramp_outputs_t out = {0u, 0u, 1u, 0u, 0u, 0u, 1u};
            stepramp_change_t ch;
            stepramp_change_info_t info;
            double f_tick = 1e6 / 4.0;
            double peak;
            double fastest;
            uint32_t shortest;

            CHECK_EQ(stepramp_plan_change_info(&ch, &info, starts[k], 4000, 40.0, 40.0, 20.0, 400.0, 1e6, 4u),
                     STEPRAMP_OK);
            peak = f_tick / info.t_cruise; /* steps/s */
            fastest = ch.start_speed > peak ? ch.start_speed : peak;
            shortest = (uint32_t)floor(f_tick / fastest) * 4u; /* clocks */
            CHECK(k == 0u ? ch.start_speed > peak : ch.start_speed < peak);
            CHECK(shortest > 200u && shortest < 65535u);
            out.step_width = (uint16_t)(shortest - 100u);
            out.step_space = 100u;
            CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
            stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
            stepramp_fakebus_clear_log();
            CHECK_EQ(stepramp_change_to(&dev, 10u, starts[k], 4000, 40.0, 40.0, 20.0), STEPRAMP_OK);
            CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 2u);
            stepramp_fakebus_set_status(STEPRAMP_STATE_STOP, 0u, 0u, 0u, 0u);
            out.step_space = 101u;
            CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
            stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
            stepramp_fakebus_clear_log();
            CHECK_EQ(stepramp_change_to(&dev, 10u, starts[k], 4000, 40.0, 40.0, 20.0), STEPRAMP_EGAP);
            CHECK(bus->writes == 0u && bus->reads == 0u);
        }
    }
}

/* stepramp_queue: the plan's registers (with the segment registers cleared when a change or a jog may have set
 * them), then CTRL.QUEUE (bit 4); stepramp_queue_move plans first and writes nothing on error */
static void test_queue_writes(void)
{
    stepramp_t dev = fresh(1e6, 400.0, 1u);
    stepramp_plan_t plan;
    stepramp_change_t ch;

    CHECK_EQ(stepramp_plan_move(&plan, -3000, 40.0, 25.0, 20.0, 400.0, 1e6, 1u), STEPRAMP_OK);
    /* the first program after init clears the segment registers */
    CHECK_EQ(stepramp_queue(&dev, &plan), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
    check_program_log(&plan, 0u);
    check_segment_log(&no_segment, N_MOTION);
    check_command(N_MOTION + N_SEGMENT, 0x10u);
    CHECK(bus->starts + bus->soft_stops + bus->hard_stops == 0u && bus->bus_errors == 0u);
    CHECK_EQ(reg(O_STEPS), 0xFFFFF448u); /* -3000 */
    /* then they are known to be 0 */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_queue_move(&dev, -3000, 40.0, 25.0, 20.0), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + 1u);
    check_program_log(&plan, 0u);
    check_command(N_MOTION, 0x10u);
    /* after a change they hold its segment: the queued move clears them */
    CHECK_EQ(stepramp_plan_change(&ch, 800.0, STEPRAMP_ENDLESS, 40.0, 40.0, 20.0, 400.0, 1e6, 1u), STEPRAMP_OK);
    CHECK_EQ(stepramp_change(&dev, &ch.segment, 0u, 100u), STEPRAMP_OK);
    CHECK_EQ(reg(O_SEGMENT) & 2u, 2u);
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_queue_move(&dev, 1, 40.0, 25.0, 20.0), STEPRAMP_OK);
    CHECK_EQ(stepramp_plan_move(&plan, 1, 40.0, 25.0, 20.0, 400.0, 1e6, 1u), STEPRAMP_OK);
    CHECK_EQ(bus->writes, N_MOTION + N_SEGMENT + 1u);
    check_program_log(&plan, 0u);
    check_segment_log(&no_segment, N_MOTION);
    check_command(N_MOTION + N_SEGMENT, 0x10u);
    CHECK_EQ(dev.segment_dirty, 0u);
    /* errors: nothing written, nothing read */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_queue(NULL, &plan), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_queue(&dev, NULL), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_queue_move(NULL, 100, 40.0, 25.0, 20.0), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_queue_move(&dev, 100, 0.0, 25.0, 20.0), STEPRAMP_EACCEL);
    CHECK_EQ(stepramp_queue_move(&dev, INT64_C(2147483648), 40.0, 25.0, 20.0), STEPRAMP_ESTEPS);
    CHECK_EQ(stepramp_queue_move(&dev, 100, 1e6, 1e6, 1e4), STEPRAMP_ETOOFAST);
    CHECK(bus->writes == 0u && bus->reads == 0u);
    /* the STEP gap as for a move: 20 rad/s cruises at 785 clocks */
    {
        stepramp_outputs_t out = {0u, 0u, 700u, 0u, 0u, 0u, 86u};
        CHECK_EQ(stepramp_configure_outputs(&dev, &out), STEPRAMP_OK);
        stepramp_fakebus_clear_log();
        CHECK_EQ(stepramp_queue_move(&dev, 4000, 40.0, 25.0, 20.0), STEPRAMP_EGAP);
        CHECK_EQ(bus->writes, 0u);
        CHECK_EQ(stepramp_queue_move(&dev, 4000, 40.0, 25.0, 19.9), STEPRAMP_OK);
        CHECK_EQ(bus->writes, N_MOTION + 1u);
    }
}

static void test_status_decoding(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    uint32_t state, busy, dir, done, error, pending, code;

    for (state = 0; state < 4u; state++) {
        for (busy = 0; busy < 2u; busy++) {
            for (dir = 0; dir < 2u; dir++) {
                for (done = 0; done < 2u; done++) {
                    for (error = 0; error < 2u; error++) {
                        for (pending = 0; pending < 2u; pending++) {
                            for (code = 0; code < 32u; code++) {
                                stepramp_status_t st;
                                uint32_t raw =
                                    state | busy << 2 | dir << 3 | done << 4 | error << 5 | pending << 7 | code << 8;

                                bus->regs[O_STATUS / 4u] = raw;
                                memset(&st, 0xA5, sizeof st);
                                CHECK_EQ(stepramp_status(&dev, &st), raw);
                                CHECK(st.raw == raw && st.state == state && st.busy == (int)busy && st.dir == dir &&
                                      st.done == (int)done && st.error == (int)error && st.err_code == code &&
                                      st.pending == (int)pending);
                            }
                        }
                    }
                }
            }
        }
    }
    /* DIR_FAULT (bit 6) is in raw only */
    bus->regs[O_STATUS / 4u] = 0x40u;
    {
        stepramp_status_t st;
        CHECK_EQ(stepramp_status(&dev, &st), 0x40u);
        CHECK(st.state == 0u && !st.busy && st.dir == 0u && !st.done && !st.error && !st.pending && st.err_code == 0u);
    }
    CHECK_EQ(stepramp_status(&dev, NULL), bus->regs[O_STATUS / 4u]);
    CHECK_EQ(bus->writes, 0u); /* reading STATUS clears nothing */
    bus->regs[O_STATUS / 4u] = 0u;
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 1u, 0u, 0u);
    {
        stepramp_status_t st;
        (void)stepramp_status(&dev, &st);
        CHECK(st.state == STEPRAMP_STATE_RUN && st.busy && st.dir == 1u && !st.done && !st.error);
    }
}

static void test_clear_flags(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);

    stepramp_fakebus_set_status(0u, 0u, 1u, STEPRAMP_ERR_LATE, 0x30u);
    stepramp_clear_flags(&dev);
    CHECK_EQ(bus->writes, 1u);
    CHECK_EQ(bus->log[0].offset, O_STATUS);
    CHECK_EQ(bus->log[0].value, 0x30u);
    CHECK_EQ(reg(O_STATUS), (uint32_t)(STEPRAMP_ERR_LATE << 8 | 0x8u)); /* ERR_CODE and DIR stay */
}

static void test_wait_done(void)
{
    stepramp_t dev;
    stepramp_status_t st;
    uint32_t code;

    /* done at the 5th poll, no error */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(STEPRAMP_STATE_ACCEL, 1u, 0u, 0u, 0u);
    stepramp_fakebus_finish_after(5u, 0u);
    CHECK_EQ(stepramp_wait_done(&dev, 100u), STEPRAMP_OK);
    CHECK_EQ(bus->status_reads, 5u);
    CHECK_EQ(bus->idles, 4u); /* between polls */
    CHECK_EQ(bus->writes, 1u);
    CHECK(bus->log[0].offset == O_STATUS && bus->log[0].value == 0x30u);
    (void)stepramp_status(&dev, &st);
    CHECK(!st.done && !st.error && !st.busy && st.state == STEPRAMP_STATE_STOP);

    /* done already at the first poll */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(0u, 0u, 0u, 0u, STEPRAMP_STATUS_DONE_MASK);
    CHECK_EQ(stepramp_wait_done(&dev, 1u), STEPRAMP_OK);
    CHECK(bus->status_reads == 1u && bus->idles == 0u);

    /* every error code the core can report */
    for (code = 1; code < 16u; code++) {
        dev = fresh(1e6, 200.0, 1u);
        stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 1u, 0u, 0u);
        stepramp_fakebus_finish_after(3u, code);
        CHECK_EQ(stepramp_wait_done(&dev, 10u), STEPRAMP_ECORE(code));
        CHECK(STEPRAMP_IS_ECORE(STEPRAMP_ECORE(code)) && STEPRAMP_ECORE_CODE(STEPRAMP_ECORE(code)) == code);
        CHECK_EQ(bus->status_reads, 3u);
        (void)stepramp_status(&dev, &st);
        CHECK(!st.done && !st.error && st.err_code == code && st.dir == 1u); /* flags cleared, cause kept */
    }

    /* timeout: never done; nothing written */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
    stepramp_fakebus_finish_after(1001u, 0u);
    CHECK_EQ(stepramp_wait_done(&dev, 1000u), STEPRAMP_ETIMEOUT);
    CHECK_EQ(bus->status_reads, 1000u);
    CHECK_EQ(bus->idles, 999u);
    CHECK_EQ(bus->writes, 0u);
    CHECK_EQ(stepramp_wait_done(&dev, 1u), STEPRAMP_OK); /* the 1001st read: done */

    /* no polls at all */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(0u, 0u, 0u, 0u, STEPRAMP_STATUS_DONE_MASK);
    CHECK_EQ(stepramp_wait_done(&dev, 0u), STEPRAMP_ETIMEOUT);
    CHECK_EQ(bus->reads, 0u);

    /* ERROR is only acted on with DONE (a POSITION write during a move flags ERROR; the move goes on) */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, STEPRAMP_ERR_POS_BUSY, STEPRAMP_STATUS_ERROR_MASK);
    CHECK_EQ(stepramp_wait_done(&dev, 50u), STEPRAMP_ETIMEOUT);
    CHECK_EQ(bus->status_reads, 50u);
    CHECK_EQ(bus->bus_errors, 0u);
}

static void test_isr(void)
{
    stepramp_t dev;
    stepramp_status_t st;

    /* DONE without error: both flags as read are cleared (DONE only: the write is 0x10), result OK */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(0u, 0u, 1u, 0u, STEPRAMP_STATUS_DONE_MASK);
    CHECK_EQ(stepramp_isr(&dev, &st), STEPRAMP_OK);
    CHECK(st.done && !st.error && st.dir == 1u);
    CHECK_EQ(bus->status_reads, 1u);
    CHECK(bus->writes == 1u && bus->log[0].offset == O_STATUS && bus->log[0].value == STEPRAMP_STATUS_DONE_MASK);
    CHECK_EQ(reg(O_STATUS) & 0x30u, 0u);

    /* DONE with ERROR: the core error, both flags cleared, the cause kept */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(0u, 0u, 0u, STEPRAMP_ERR_LATE, 0x30u);
    CHECK_EQ(stepramp_isr(&dev, &st), STEPRAMP_ECORE(STEPRAMP_ERR_LATE));
    CHECK(st.done && st.error && st.err_code == STEPRAMP_ERR_LATE);
    CHECK(bus->writes == 1u && bus->log[0].value == 0x30u);
    CHECK_EQ(reg(O_STATUS) & 0x30u, 0u);

    /* ERROR alone (POS_BUSY during a move): ERROR cleared, DONE not written, the move goes on */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, STEPRAMP_ERR_POS_BUSY, STEPRAMP_STATUS_ERROR_MASK);
    CHECK_EQ(stepramp_isr(&dev, &st), STEPRAMP_ECORE(STEPRAMP_ERR_POS_BUSY));
    CHECK(!st.done && st.error && st.busy);
    CHECK(bus->writes == 1u && bus->log[0].value == STEPRAMP_STATUS_ERROR_MASK);

    /* neither flag: not this core's interrupt, nothing written; NULL status is allowed */
    dev = fresh(1e6, 200.0, 1u);
    stepramp_fakebus_set_status(STEPRAMP_STATE_ACCEL, 1u, 0u, 0u, 0u);
    CHECK_EQ(stepramp_isr(&dev, NULL), STEPRAMP_ENOIRQ);
    CHECK(bus->status_reads == 1u && bus->writes == 0u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ENOIRQ), "DONE") != NULL);
}

static void test_position(void)
{
    static const int32_t values[] = {0, 1, -1, 123456, -123456, INT32_MAX, INT32_MIN, INT32_MIN + 1, 0x12345678};
    static const uint32_t words[] = {0u,          1u,          0xFFFFFFFFu, 0x0001E240u, 0xFFFE1DC0u,
                                     0x7FFFFFFFu, 0x80000000u, 0x80000001u, 0x12345678u};
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    size_t i;

    for (i = 0; i < sizeof values / sizeof values[0]; i++) {
        stepramp_fakebus_clear_log();
        stepramp_set_position(&dev, values[i]);
        CHECK_EQ(bus->writes, 1u);
        CHECK(bus->log[0].offset == O_POSITION && bus->log[0].be == 0xFu);
        CHECK_EQ(reg(O_POSITION), words[i]);
        CHECK(stepramp_position(&dev) == values[i]);
        /* and from a raw word the core counted to */
        bus->regs[O_POSITION / 4u] = words[i];
        CHECK(stepramp_position(&dev) == values[i]);
    }
    /* during a move: ignored, ERROR with POS_BUSY, which wait_done reports at DONE */
    stepramp_set_position(&dev, 100);
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
    stepramp_set_position(&dev, -5);
    CHECK(stepramp_position(&dev) == 100);
    stepramp_fakebus_finish_after(2u, 0u);
    CHECK_EQ(stepramp_wait_done(&dev, 10u), STEPRAMP_ECORE(STEPRAMP_ERR_POS_BUSY));
}

/* INPUT_FILTER then INPUT_CFG, the words of docs/registers.md (POL_* bits 3:0, LIMIT_EN 4, LIMIT_HARD 5,
 * LATCH_SRC 9:8, LATCH_ON_ACTIVE 10, LATCH_ON_RELEASE 11); bad configurations write nothing */
static void test_configure_inputs(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    stepramp_inputs_t in = {150u, STEPRAMP_INPUT_HOME | STEPRAMP_INPUT_ESTOP, 1, 1, STEPRAMP_LATCH_LIMIT_POS, 0, 1};
    stepramp_inputs_t bad;

    CHECK_EQ(dev.input_filter, 0u);
    CHECK_EQ(dev.input_cfg, 0x10u); /* the reset value: LIMIT_EN */
    CHECK_EQ(reg(O_INPUT_CFG), 0x10u);
    CHECK_EQ(stepramp_configure_inputs(&dev, &in), STEPRAMP_OK);
    CHECK_EQ(bus->writes, 2u);
    CHECK(bus->log[0].offset == O_INPUT_FILTER && bus->log[0].value == 150u && bus->log[0].be == 0xFu);
    CHECK(bus->log[1].offset == O_INPUT_CFG && bus->log[1].value == (0xCu | 0x10u | 0x20u | 3u << 8 | 0x800u));
    CHECK(dev.input_filter == 150u && dev.input_cfg == bus->log[1].value);
    /* no latch source: the edge bits are not written */
    in.latch_source = STEPRAMP_LATCH_NONE;
    in.latch_on_active = 1;
    in.limit_enable = 0;
    in.limit_hard = 0;
    in.active_low = 0u;
    in.filter = STEPRAMP_FILTER_MAX;
    CHECK_EQ(stepramp_configure_inputs(&dev, &in), STEPRAMP_OK);
    CHECK(reg(O_INPUT_CFG) == 0u && reg(O_INPUT_FILTER) == 0xFFFFFu);
    stepramp_fakebus_clear_log();
    bad = in;
    bad.filter = STEPRAMP_FILTER_MAX + 1u;
    CHECK_EQ(stepramp_configure_inputs(&dev, &bad), STEPRAMP_EINPUTS);
    bad = in;
    bad.active_low = 0x10u;
    CHECK_EQ(stepramp_configure_inputs(&dev, &bad), STEPRAMP_EINPUTS);
    bad = in;
    bad.latch_source = 4u;
    CHECK_EQ(stepramp_configure_inputs(&dev, &bad), STEPRAMP_EINPUTS);
    bad = in;
    bad.latch_source = STEPRAMP_LATCH_HOME;
    bad.latch_on_active = 0;
    bad.latch_on_release = 0;
    CHECK_EQ(stepramp_configure_inputs(&dev, &bad), STEPRAMP_EINPUTS);
    CHECK_EQ(stepramp_configure_inputs(&dev, NULL), STEPRAMP_EINPUTS);
    CHECK_EQ(stepramp_configure_inputs(NULL, &in), STEPRAMP_EINPUTS);
    CHECK_EQ(bus->writes, 0u);
    CHECK_EQ(dev.input_filter, STEPRAMP_FILTER_MAX);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EINPUTS), "filter") != NULL);
    /* during a motion the core ignores the configuration (CFG_BUSY) */
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
    in.filter = 7u;
    CHECK_EQ(stepramp_configure_inputs(&dev, &in), STEPRAMP_OK);
    CHECK_EQ(reg(O_INPUT_FILTER), 0xFFFFFu);
    CHECK_EQ((reg(O_STATUS) & STEPRAMP_STATUS_ERR_CODE_MASK) >> 8, STEPRAMP_ERR_CFG_BUSY);
}

/* arm_latch keeps the polarity and limit bits, then clears LATCHED with a byte write; latch, read_latch, time */
static void test_latch_and_time(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    stepramp_inputs_t in = {50u, STEPRAMP_INPUT_LIMIT_NEG, 1, 0, STEPRAMP_LATCH_NONE, 0, 0};
    stepramp_latch_t latch = {7, 7u, 7};

    CHECK_EQ(stepramp_configure_inputs(&dev, &in), STEPRAMP_OK);
    stepramp_fakebus_clear_log();
    bus->regs[O_STATUS / 4u] = 0x01000000u | 0x10u; /* LATCHED, DONE */
    CHECK_EQ(stepramp_arm_latch(&dev, STEPRAMP_LATCH_HOME, 1, 1), STEPRAMP_OK);
    CHECK_EQ(bus->writes, 2u);
    CHECK(bus->log[0].offset == O_INPUT_CFG && bus->log[0].value == (0x1u | 0x10u | 1u << 8 | 0x400u | 0x800u));
    CHECK(bus->log[1].offset == O_STATUS && bus->log[1].be == 0x8u && bus->log[1].value == 0x01000000u);
    CHECK_EQ(reg(O_STATUS), 0x10u); /* LATCHED cleared, DONE kept */
    CHECK_EQ(dev.input_cfg, reg(O_INPUT_CFG));
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_arm_latch(&dev, STEPRAMP_LATCH_LIMIT_NEG, 0, 1), STEPRAMP_OK);
    CHECK_EQ(reg(O_INPUT_CFG), 0x1u | 0x10u | 2u << 8 | 0x800u);
    CHECK_EQ(stepramp_arm_latch(&dev, STEPRAMP_LATCH_NONE, 1, 1), STEPRAMP_OK); /* off: no edges */
    CHECK_EQ(reg(O_INPUT_CFG), 0x1u | 0x10u);
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_arm_latch(&dev, STEPRAMP_LATCH_HOME, 0, 0), STEPRAMP_EINPUTS);
    CHECK_EQ(stepramp_arm_latch(&dev, 5u, 1, 0), STEPRAMP_EINPUTS);
    CHECK_EQ(stepramp_arm_latch(NULL, STEPRAMP_LATCH_HOME, 1, 0), STEPRAMP_EINPUTS);
    CHECK_EQ(bus->writes, 0u);
    /* nothing latched: one STATUS read, latch untouched */
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_latch(&dev, &latch), STEPRAMP_ENOLATCH);
    CHECK(bus->reads == 1u && latch.position == 7 && latch.time == 7u);
    CHECK_EQ(stepramp_latch(&dev, NULL), STEPRAMP_ENULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ENOLATCH), "LATCHED") != NULL);
    /* latched: a negative position, a 64-bit time, pin_time = time - max(filter, 1) - 2 */
    bus->regs[O_STATUS / 4u] = 0x01000000u;
    bus->regs[O_LATCH_POS / 4u] = 0xFFFFFF85u; /* -123 */
    bus->regs[O_LATCH_TIME_LO / 4u] = 0x00000010u;
    bus->regs[O_LATCH_TIME_HI / 4u] = 0x00000002u;
    CHECK_EQ(stepramp_latch(&dev, &latch), STEPRAMP_OK);
    CHECK(latch.position == -123 && latch.time == UINT64_C(0x200000010));
    CHECK(latch.pin_time == (int64_t)UINT64_C(0x200000010) - 50 - 2);
    dev.input_filter = 0u; /* 0 acts as 1 */
    stepramp_read_latch(&dev, &latch);
    CHECK(latch.pin_time == (int64_t)UINT64_C(0x200000010) - 1 - 2);
    /* TIME: LO first, whose read brings bits 63:32 into TIME_HI (a stale TIME_HI shows a wrong order) */
    stepramp_fakebus_set_time(UINT64_C(0x123456789ABC));
    bus->regs[O_TIME_HI / 4u] = 0xDEADu;
    stepramp_fakebus_clear_log();
    CHECK(stepramp_time(&dev) == UINT64_C(0x123456789ABC));
    CHECK(bus->reads == 2u && bus->writes == 0u);
}

/* input events (byte 2 of STATUS), the E-stop fault (kept while ESTOP is active), the interrupt enables, decoding */
static void test_events_and_estop(void)
{
    stepramp_t dev = fresh(1e6, 200.0, 1u);
    stepramp_status_t st;

    bus->regs[O_STATUS / 4u] = 0x00F00030u; /* the four events, DONE, ERROR */
    stepramp_clear_events(&dev, STEPRAMP_INPUT_HOME | STEPRAMP_INPUT_ESTOP);
    CHECK_EQ(bus->writes, 1u);
    CHECK(bus->log[0].offset == O_STATUS && bus->log[0].be == 0x4u && bus->log[0].value == 0x00400000u);
    CHECK_EQ(reg(O_STATUS), 0x00B00030u); /* HOME_EV only: ESTOP_FAULT, DONE, ERROR kept */
    stepramp_clear_events(&dev, STEPRAMP_INPUT_LIMIT_NEG | STEPRAMP_INPUT_LIMIT_POS);
    CHECK_EQ(reg(O_STATUS), 0x00800030u);
    stepramp_fakebus_clear_log();
    stepramp_clear_events(&dev, STEPRAMP_INPUT_ESTOP); /* not an event: nothing written */
    CHECK_EQ(bus->writes, 0u);
    /* ESTOP active: the fault stays, ENABLE is not set */
    bus->regs[O_STATUS / 4u] = 0x00880000u;
    CHECK_EQ(stepramp_clear_estop(&dev, 1), STEPRAMP_EESTOP);
    CHECK(bus->writes == 1u && bus->log[0].be == 0x4u && bus->log[0].value == 0x00800000u);
    CHECK_EQ(reg(O_CTRL), 0u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EESTOP), "ESTOP") != NULL);
    /* inactive: cleared, ENABLE set again (byte 2 of CTRL) */
    bus->regs[O_STATUS / 4u] = 0x00800000u;
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_clear_estop(&dev, 1), STEPRAMP_OK);
    CHECK(reg(O_STATUS) == 0u && reg(O_CTRL) == 0x10000u);
    CHECK(bus->writes == 2u && bus->log[1].offset == O_CTRL && bus->log[1].be == 0x4u);
    bus->regs[O_STATUS / 4u] = 0x00800000u;
    stepramp_fakebus_clear_log();
    CHECK_EQ(stepramp_clear_estop(&dev, 0), STEPRAMP_OK);
    CHECK_EQ(bus->writes, 1u);
    /* every interrupt enable in byte 1 */
    stepramp_enable_input_irq(&dev, 1, 0, STEPRAMP_INPUT_HOME | STEPRAMP_INPUT_ESTOP, 1);
    CHECK_EQ(reg(O_CTRL), 0x10000u | 0x100u | 0x1000u | 0x2000u | 0x4000u);
    CHECK_EQ(bus->log[bus->writes - 1u].be, 0x2u);
    stepramp_enable_input_irq(&dev, 0, 1, STEPRAMP_INPUT_LIMIT_NEG | STEPRAMP_INPUT_LIMIT_POS, 0);
    CHECK_EQ(reg(O_CTRL), 0x10000u | 0x200u | 0x400u | 0x800u);
    /* enable_irq sets DONE / ERROR in byte 1 and keeps the input enables there (bits 10 .. 14), a byte-1 write */
    stepramp_fakebus_clear_log();
    stepramp_enable_irq(&dev, 1, 1);
    CHECK_EQ(reg(O_CTRL), 0x10000u | 0x300u | 0x400u | 0x800u);
    CHECK(bus->writes == 1u && bus->log[0].offset == O_CTRL && bus->log[0].be == 0x2u);
    stepramp_enable_irq(&dev, 0, 0);
    CHECK_EQ(reg(O_CTRL), 0x10000u | 0x400u | 0x800u);
    stepramp_enable_input_irq(&dev, 0, 0, 0u, 0);
    CHECK_EQ(reg(O_CTRL), 0x10000u);
    /* decoding: levels bits 19:16, events 23:20, LATCHED 24, DIR_FAULT 6 */
    bus->regs[O_STATUS / 4u] = 0x015A0040u;
    (void)stepramp_status(&dev, &st);
    CHECK(st.levels == 0xAu && st.events == 0x5u && st.latched && st.dir_fault && !st.done && !st.busy);
    bus->regs[O_STATUS / 4u] = 0x00A50000u;
    (void)stepramp_status(&dev, &st);
    CHECK(st.levels == 0x5u && st.events == 0xAu && !st.latched && !st.dir_fault);
    /* clear_flags writes DONE and ERROR only: the events and LATCHED stay */
    bus->regs[O_STATUS / 4u] = 0x01F00030u;
    stepramp_clear_flags(&dev);
    CHECK_EQ(reg(O_STATUS), 0x01F00000u);
}

/* an invalid move returns the plan's error and writes nothing */
static void test_invalid_move_writes_nothing(void)
{
    static const struct {
        int64_t steps;
        double accel, decel, speed, spr, fclk;
        uint32_t prescale;
        int want;
    } moves[] = {
        {200, 0.0, 10.0, 10.0, 200.0, 1e6, 1u, STEPRAMP_EACCEL},
        {200, 10.0, -1.0, 10.0, 200.0, 1e6, 1u, STEPRAMP_EDECEL},
        {200, 10.0, 10.0, 0.0, 200.0, 1e6, 1u, STEPRAMP_ESPEED},
        {200, 10.0, 10.0, 10.0, 0.0, 1e6, 1u, STEPRAMP_ESPR},
        {200, 10.0, 10.0, 10.0, 200.0, 0.0, 1u, STEPRAMP_EFCLK},
        {200, 10.0, 10.0, 10.0, 200.0, 1e6, 0u, STEPRAMP_EPRESCALE},
        {200, 10.0, 10.0, 10.0, 200.0, 1e6, 65536u, STEPRAMP_EPRESCALE},
        {INT64_C(2147483648), 10.0, 10.0, 10.0, 200.0, 1e6, 1u, STEPRAMP_ESTEPS},
        {-INT64_C(2147483648), 10.0, 10.0, 10.0, 200.0, 1e6, 1u, STEPRAMP_ESTEPS},
        {200, 1e6, 1e6, 1e4, 200.0, 1e6, 1u, STEPRAMP_ETOOFAST}, /* 318 kHz step rate at 1 MHz */
    };
    size_t i;

    for (i = 0; i < sizeof moves / sizeof moves[0]; i++) {
        stepramp_t dev = fresh(moves[i].fclk, moves[i].spr, moves[i].prescale);
        stepramp_plan_t plan;
        int plan_rc = stepramp_plan_move(&plan, moves[i].steps, moves[i].accel, moves[i].decel, moves[i].speed,
                                         moves[i].spr, moves[i].fclk, moves[i].prescale);

        CHECK_EQ(plan_rc, moves[i].want);
        CHECK_EQ(stepramp_move(&dev, moves[i].steps, moves[i].accel, moves[i].decel, moves[i].speed), plan_rc);
        CHECK_EQ(bus->writes, 0u);
        CHECK_EQ(bus->starts, 0u);
        CHECK_EQ(stepramp_plan(&dev, &plan, moves[i].steps, moves[i].accel, moves[i].decel, moves[i].speed), plan_rc);
    }
    {
        stepramp_t dev = fresh(1e6, 200.0, 1u);
        CHECK_EQ(stepramp_move(NULL, 200, 10.0, 10.0, 10.0), STEPRAMP_ENULL);
        CHECK_EQ(stepramp_plan(&dev, NULL, 200, 10.0, 10.0, 10.0), STEPRAMP_ENULL);
        CHECK_EQ(bus->writes, 0u);
    }
}

static void test_error_texts(void)
{
    uint32_t a, b;

    CHECK(strcmp(stepramp_strcoreerror(STEPRAMP_ERR_NONE), "no error") == 0);
    CHECK(strcmp(stepramp_strcoreerror(STEPRAMP_ERR_PRESCALE), "PRESCALE is 0") == 0);
    CHECK(strcmp(stepramp_strcoreerror(STEPRAMP_ERR_POS_BUSY),
                 "POSITION written while STATUS.BUSY (the write was ignored)") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_LATE), "LATE") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_ZERO_TICKS), "ZERO_TICKS") == 0);
    for (a = 0; a <= STEPRAMP_ERR_ESTOP; a++) {
        CHECK(strcmp(stepramp_strcoreerror(a), "unknown error code") != 0);
        CHECK(strcmp(stepramp_corename(a), "UNKNOWN") != 0);
        CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(a)), stepramp_strcoreerror(a)) != NULL);
        CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(a)), stepramp_corename(a)) != NULL);
        for (b = 0; b < a; b++) {
            CHECK(strcmp(stepramp_strcoreerror(a), stepramp_strcoreerror(b)) != 0);
        }
    }
    CHECK(strcmp(stepramp_strcoreerror(STEPRAMP_ERR_ESTOP + 1u), "unknown error code") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_LIMIT), "LIMIT") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_ESTOP), "ESTOP") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_CHANGE), "CHANGE") == 0);
    CHECK(strcmp(stepramp_corename(STEPRAMP_ERR_STAGED), "STAGED") == 0);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(STEPRAMP_ERR_STAGED)), "STATUS.PENDING") != NULL);
    CHECK(strcmp(stepramp_strcoreerror(31u), "unknown error code") == 0);
    CHECK(strcmp(stepramp_strcoreerror(UINT32_MAX), "unknown error code") == 0);
    CHECK(strcmp(stepramp_corename(99u), "UNKNOWN") == 0);
    CHECK(strcmp(stepramp_strresult(STEPRAMP_OK), "success") == 0);
    CHECK(strcmp(stepramp_strresult(STEPRAMP_EACCEL), stepramp_strerror(STEPRAMP_EACCEL)) == 0);
    CHECK(strcmp(stepramp_strresult(STEPRAMP_ENULL), stepramp_strerror(STEPRAMP_ENULL)) == 0);
    CHECK(strcmp(stepramp_strresult(STEPRAMP_ERAMP), stepramp_strerror(STEPRAMP_ERAMP)) == 0);
    CHECK(strstr(stepramp_strresult(STEPRAMP_EID), "ID") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ETIMEOUT), "DONE") != NULL);
    CHECK(strcmp(stepramp_strresult(-1), "unknown error") == 0);
    CHECK(strcmp(stepramp_strresult(STEPRAMP_ECORE(32)), "unknown error") == 0);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(31)), "unknown error code") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(16)), "STEP_SPACE") != NULL);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ECORE(15)), "CFG_BUSY") != NULL);
    /* the driver's results do not collide with the plan's errors */
    CHECK((int)STEPRAMP_ERAMP < STEPRAMP_EID && STEPRAMP_EID != STEPRAMP_ETIMEOUT);
    CHECK(STEPRAMP_ETIMEOUT < STEPRAMP_ECORE(0));
    for (a = (uint32_t)STEPRAMP_EID; a <= (uint32_t)STEPRAMP_EWINDINGS; a++) {
        CHECK(strcmp(stepramp_strresult((int)a), "unknown error") != 0);
        for (b = (uint32_t)STEPRAMP_EID; b < a; b++) {
            CHECK(strcmp(stepramp_strresult((int)a), stepramp_strresult((int)b)) != 0);
        }
    }
    CHECK(strcmp(stepramp_strresult(STEPRAMP_EWINDINGS + 1), "unknown error") == 0);
    CHECK(STEPRAMP_EWINDINGS < STEPRAMP_ECORE_BASE);
}

int main(void)
{
    test_init();
    test_move_writes();
    test_program_splits_wide_values();
    test_commands_keep_irq_enables();
    test_enable_and_outputs();
    test_no_windings();
    test_jog_writes();
    test_exact_mode_driver();
    test_program_segment();
    test_first_program_clears_segment();
    test_jog_errors();
    test_change_writes();
    test_change_to();
    test_queue_writes();
    test_status_decoding();
    test_clear_flags();
    test_wait_done();
    test_isr();
    test_position();
    test_configure_inputs();
    test_latch_and_time();
    test_events_and_estop();
    test_invalid_move_writes_nothing();
    test_error_texts();
    return test_report("test_stepramp");
}
