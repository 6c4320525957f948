/* SPDX-License-Identifier: MIT */
/*
 * Host unit tests of the multi-axis driver (stepramp_multi.c, with stepramp.c for the axes) on a fake multi-axis top
 * defined here: a 4 KiB register bank behind the host build's register access (stepramp_hostbus.h) with the global
 * window of docs/stepramp_multi.md (ID, SYNC_START, AXES_STATUS, IRQ_MASK) and, in each axis window, ID, STATUS
 * (DONE / ERROR cleared by writing 1) and plain storage for the rest, a log of every write and the number of
 * STEPRAMP_IDLE() calls. Offsets are written out from the docs here, not taken from stepramp_multi.h. Expected plans
 * come from stepramp_plan_coordinated itself (its equality with Python's plan_coordinated is sw/tests/test_c_coord.py's).
 * Exit status 0 when every check passes.
 */
#include "stepramp_coord.h"
#include "stepramp_hostbus.h"
#include "stepramp_multi.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "test_check.h"

#define BASE ((uintptr_t)0x44A00000u)
#define WORDS 1024u /* 4 KiB: 16 windows of 256 bytes */
#define LOG_MAX 512u

/* docs/stepramp_multi.md and docs/registers.md, written out */
enum {
    G_ID = 0x000,
    G_SYNC_START = 0x004,
    G_AXES_STATUS = 0x008,
    G_IRQ_MASK = 0x00C,
    G_SYNC_SOFT_STOP = 0x010,
    WINDOW = 0x100,
    A_ID = 0x00,
    A_STATUS = 0x08,
    A_STEPS = 0x0C,
    A_STOP_RATIO = 0x54,
    A_STEP_WIDTH = 0x68,
    A_STEP_SPACE = 0x74,
    STATUS_DONE = 0x10,
    STATUS_ERROR = 0x20
};

#define CORE_ID 0x53520006u

typedef struct {
    uint32_t offset, value, be;
} write_t;

static struct {
    uint32_t regs[WORDS];
    write_t log[LOG_MAX];
    uint32_t writes;
    uint32_t idles;
    uint32_t bus_errors;
    uint32_t status_reads;
    uint32_t done_after;  /* 0: off; n: AXES_STATUS shows done_bits from the n-th read on */
    uint32_t done_bits;   /* the DONE bits it then shows (each axis's STATUS.DONE is set with them) */
    uint32_t error_bits;  /* axes whose STATUS.ERROR is set with DONE */
    uint32_t error_code;  /* their ERR_CODE */
} fake;

static void fake_reset(uint32_t id)
{
    uint32_t i;

    memset(&fake, 0, sizeof fake);
    fake.regs[G_ID / 4u] = id;
    fake.regs[G_IRQ_MASK / 4u] = 0xFFu & ((1u << (id & 0xFu)) - 1u);
    for (i = 1; i <= 8u; i++) {
        fake.regs[(i * WINDOW + A_ID) / 4u] = CORE_ID;
        fake.regs[(i * WINDOW + A_STEP_WIDTH) / 4u] = 1u;
        fake.regs[(i * WINDOW + A_STEP_SPACE) / 4u] = 1u;
    }
}

static long offset_of(uintptr_t addr)
{
    if (addr < BASE || addr - BASE >= 4u * WORDS) {
        fake.bus_errors++;
        return -1;
    }
    return (long)(addr - BASE);
}

static void log_write(uint32_t off, uint32_t value, uint32_t be)
{
    if (fake.writes < LOG_MAX) {
        fake.log[fake.writes].offset = off;
        fake.log[fake.writes].value = value;
        fake.log[fake.writes].be = be;
    }
    fake.writes++;
}

static void store(uint32_t off, uint32_t value)
{
    uint32_t word = off / 4u;

    if (off == G_SYNC_START || off == G_SYNC_SOFT_STOP || off == G_ID || off == G_AXES_STATUS) {
        return; /* strobe / read only */
    }
    if (off == G_IRQ_MASK) {
        fake.regs[word] = value & 0xFFu;
        return;
    }
    if (off >= WINDOW && off % WINDOW == A_STATUS) {
        fake.regs[word] &= ~(value & (STATUS_DONE | STATUS_ERROR)); /* W1C */
        return;
    }
    if (off >= WINDOW && off % WINDOW == A_ID) {
        return;
    }
    fake.regs[word] = value;
}

uint32_t stepramp_hostbus_read32(uintptr_t addr)
{
    long off = offset_of(addr);

    if (off < 0) {
        return 0xDEADBEEFu;
    }
    if (off == G_AXES_STATUS) {
        fake.status_reads++;
        if (fake.done_after != 0u && fake.status_reads >= fake.done_after) {
            uint32_t i;
            fake.done_after = 0u;
            fake.regs[G_AXES_STATUS / 4u] = fake.done_bits << 8;
            for (i = 0; i < 8u; i++) {
                if ((fake.done_bits >> i) & 1u) {
                    uint32_t *st = &fake.regs[((i + 1u) * WINDOW + A_STATUS) / 4u];
                    *st |= STATUS_DONE;
                    if ((fake.error_bits >> i) & 1u) {
                        *st = (*st & ~0x1F00u) | STATUS_ERROR | (fake.error_code << 8);
                    }
                }
            }
        }
    }
    return fake.regs[(uint32_t)off / 4u];
}

void stepramp_hostbus_write32(uintptr_t addr, uint32_t value)
{
    long off = offset_of(addr);

    if (off < 0) {
        return;
    }
    log_write((uint32_t)off, value, 0xFu);
    store((uint32_t)off, value);
}

void stepramp_hostbus_write8(uintptr_t addr, uint8_t value)
{
    long off = offset_of(addr);

    if (off < 0) {
        return;
    }
    /* byte lanes little-endian: the lane is the address's low two bits */
    log_write((uint32_t)off & ~3u, (uint32_t)value << (8u * ((uint32_t)off & 3u)), 1u << ((uint32_t)off & 3u));
}

void stepramp_hostbus_idle(void)
{
    fake.idles++;
}

#define MULTI_ID(axes) (0x534D0100u | (axes))

/* A fresh fake top of `axes` axes (fake_reset) and stepramp_multi_init's result on it (fclk 1 MHz, 200 steps/rev) */
static int init_top(stepramp_multi_t *m, uint32_t axes, uint32_t prescale)
{
    fake_reset(MULTI_ID(axes));
    return stepramp_multi_init(m, BASE, 1e6, 200.0, prescale);
}

static void test_init(void)
{
    stepramp_multi_t m;
    uint32_t i;

    CHECK_EQ(init_top(&m, 3u, 2u), STEPRAMP_OK);
    CHECK_EQ(m.axes, 3u);
    CHECK_EQ(m.version, 1u);
    for (i = 0; i < 3u; i++) {
        CHECK_EQ(m.axis[i].base, BASE + WINDOW * (i + 1u));
        CHECK_EQ(m.axis[i].prescale, 2u);
        CHECK(stepramp_multi_axis(&m, i) == &m.axis[i]);
    }
    CHECK(stepramp_multi_axis(&m, 3u) == NULL);
    CHECK(stepramp_multi_axis(NULL, 0u) == NULL);
    CHECK_EQ(fake.writes, 0u);

    fake_reset(0x53520006u); /* a single core at this address */
    CHECK_EQ(stepramp_multi_init(&m, BASE, 1e6, 200.0, 1u), STEPRAMP_EMULTI_ID);
    CHECK_EQ(init_top(&m, 0u, 1u), STEPRAMP_EMULTI_ID);
    CHECK_EQ(init_top(&m, 9u, 1u), STEPRAMP_EMULTI_ID);
    fake_reset(MULTI_ID(2u));
    fake.regs[(2u * WINDOW + A_ID) / 4u] = 0u; /* axis 1's window holds no core */
    CHECK_EQ(stepramp_multi_init(&m, BASE, 1e6, 200.0, 1u), STEPRAMP_EMULTI_ID);
    CHECK_EQ(stepramp_multi_init(NULL, BASE, 1e6, 200.0, 1u), STEPRAMP_ENULL);
    CHECK_EQ(fake.bus_errors, 0u);
}

/* each axis learns from its own window's ID whether its core has windings (ID bit 14 set: G_WINDINGS false), as
 * MultiAxis.probe's per-axis check_id: a winding mode is refused on that axis only */
static void test_axis_windings(void)
{
    stepramp_multi_t m;
    stepramp_outputs_t out = {2u, 0u, 1u, 0u, 0u, 0u, 1u};
    uint32_t i;

    fake_reset(MULTI_ID(3u));
    fake.regs[(2u * WINDOW + A_ID) / 4u] = CORE_ID | 0x4000u; /* axis 1: no windings */
    CHECK_EQ(stepramp_multi_init(&m, BASE, 1e6, 200.0, 1u), STEPRAMP_OK);
    for (i = 0; i < 3u; i++) {
        CHECK_EQ(m.axis[i].windings, i == 1u ? 0u : 1u);
        CHECK_EQ(m.axis[i].version, CORE_ID & 0x3FFFu);
        CHECK_EQ(stepramp_configure_outputs(&m.axis[i], &out), i == 1u ? STEPRAMP_EWINDINGS : STEPRAMP_OK);
    }
    out.mode = 0u;
    CHECK_EQ(stepramp_configure_outputs(&m.axis[1], &out), STEPRAMP_OK);
}

static void test_global_registers(void)
{
    stepramp_multi_t m;
    stepramp_axes_status_t st;

    CHECK_EQ(init_top(&m, 3u, 1u), STEPRAMP_OK);
    CHECK_EQ(stepramp_multi_sync_start(&m, 0x5u), STEPRAMP_OK);
    CHECK_EQ(fake.writes, 1u);
    CHECK_EQ(fake.log[0].offset, G_SYNC_START);
    CHECK_EQ(fake.log[0].value, 0x5u);
    CHECK_EQ(fake.log[0].be, 0xFu);
    CHECK_EQ(stepramp_multi_sync_start(&m, 0x8u), STEPRAMP_EMULTI_AXES); /* axis 3 of 3 */
    CHECK_EQ(stepramp_multi_set_irq_mask(&m, 0x10u), STEPRAMP_EMULTI_AXES);
    CHECK_EQ(fake.writes, 1u);
    CHECK_EQ(stepramp_multi_set_irq_mask(&m, 0x2u), STEPRAMP_OK);
    CHECK_EQ(fake.log[1].offset, G_IRQ_MASK);
    CHECK_EQ(stepramp_multi_irq_mask(&m), 0x2u);

    fake.regs[G_AXES_STATUS / 4u] = 0x00050603u;
    CHECK_EQ(stepramp_multi_status(&m, &st), 0x00050603u);
    CHECK_EQ(st.busy, 0x03u);
    CHECK_EQ(st.done, 0x06u);
    CHECK_EQ(st.irq, 0x05u);
    CHECK_EQ(stepramp_multi_status(&m, NULL), 0x00050603u);
    CHECK_EQ(stepramp_multi_sync_start(NULL, 1u), STEPRAMP_ENULL);
    CHECK_EQ(stepramp_multi_set_irq_mask(NULL, 1u), STEPRAMP_ENULL);

    /* SYNC_SOFT_STOP: one whole-word write of the mask; a bit past the axes writes nothing. */
    CHECK_EQ(stepramp_multi_sync_soft_stop(&m, 0x6u), STEPRAMP_OK);
    CHECK_EQ(fake.writes, 3u);
    CHECK_EQ(fake.log[2].offset, G_SYNC_SOFT_STOP);
    CHECK_EQ(fake.log[2].value, 0x6u);
    CHECK_EQ(fake.log[2].be, 0xFu);
    CHECK_EQ(stepramp_multi_sync_soft_stop(&m, 0x9u), STEPRAMP_EMULTI_AXES);
    CHECK_EQ(fake.writes, 3u);
    CHECK_EQ(stepramp_multi_sync_soft_stop(NULL, 1u), STEPRAMP_ENULL);
}

/* The path of the tests: the lead's accel, decel and speed, spr 200, 1 MHz, prescale 2. */
#define ACCEL 2200.0
#define DECEL 1800.0
#define SPEED 52.0

static void test_plan_coordinated(void)
{
    stepramp_multi_t m;
    stepramp_plan_t got[4], want[4];
    /* STEP width + space per axis: 1000 clocks fit axis 2's shortest interval (about 1,770 clocks) but not the
     * lead's (about 600); 2000 fit neither */
    stepramp_outputs_t fits = {0u, 0u, 500u, 0u, 0u, 0u, 500u};
    stepramp_outputs_t wide = {0u, 0u, 1000u, 0u, 0u, 0u, 1000u};
    const int64_t steps[4] = {48, -29, 0, 17};
    uint32_t i;

    CHECK_EQ(init_top(&m, 4u, 2u), STEPRAMP_OK);
    CHECK_EQ(stepramp_plan_coordinated(want, steps, 4u, ACCEL, DECEL, SPEED, 200.0, 1e6, 2u), STEPRAMP_OK);
    memset(got, 0, sizeof got);
    CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, steps, 4u, ACCEL, DECEL, SPEED), STEPRAMP_OK);
    for (i = 0; i < 4u; i++) {
        CHECK(memcmp(&got[i], &want[i], sizeof got[i]) == 0);
    }
    CHECK_EQ(stepramp_multi_started(got, 4u), 0xBu);
    CHECK_EQ(fake.writes, 0u);
    /* the planner's own error passes through; too many axes */
    CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, steps, 0u, ACCEL, DECEL, SPEED), STEPRAMP_ECOORD_AXES);
    CHECK_EQ(init_top(&m, 3u, 2u), STEPRAMP_OK);
    CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, steps, 4u, ACCEL, DECEL, SPEED), STEPRAMP_EMULTI_AXES);
    {
        const int64_t three[3] = {48, -29, 17};
        stepramp_plan_t before;
        CHECK_EQ(stepramp_configure_outputs(&m.axis[2], &fits), STEPRAMP_OK);
        CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, three, 3u, ACCEL, DECEL, SPEED), STEPRAMP_OK);
        CHECK_EQ(stepramp_configure_outputs(&m.axis[2], &wide), STEPRAMP_OK);
        before = got[0];
        CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, three, 3u, ACCEL, DECEL, SPEED), STEPRAMP_EGAP);
        CHECK(memcmp(&got[0], &before, sizeof before) == 0); /* untouched on error */
        CHECK_EQ(stepramp_configure_outputs(&m.axis[0], &fits), STEPRAMP_OK);
        CHECK_EQ(stepramp_configure_outputs(&m.axis[2], &fits), STEPRAMP_OK);
        CHECK_EQ(stepramp_multi_plan_coordinated(&m, got, three, 3u, ACCEL, DECEL, SPEED), STEPRAMP_EGAP);
    }
    CHECK_EQ(stepramp_multi_plan_coordinated(&m, NULL, steps, 3u, ACCEL, DECEL, SPEED), STEPRAMP_ENULL);
}

/* The STEPS word of a plan (two's complement of the signed count). */
static uint32_t steps_word(const stepramp_plan_t *p)
{
    return p->direction ? (uint32_t)(0u - p->steps) : p->steps;
}

static void test_move_coordinated(void)
{
    stepramp_multi_t m;
    stepramp_plan_t plans[3], want[3];
    const int64_t steps[3] = {0, 48, -29};
    uint32_t i, last_axis_write[3] = {0u, 0u, 0u}, writes_in[3] = {0u, 0u, 0u};

    CHECK_EQ(init_top(&m, 3u, 2u), STEPRAMP_OK);
    CHECK_EQ(stepramp_plan_coordinated(want, steps, 3u, ACCEL, DECEL, SPEED, 200.0, 1e6, 2u), STEPRAMP_OK);
    CHECK_EQ(stepramp_multi_move_coordinated(&m, plans, steps, 3u, ACCEL, DECEL, SPEED), STEPRAMP_OK);
    CHECK(memcmp(plans, want, sizeof want) == 0);
    CHECK(fake.writes >= 2u && fake.writes < LOG_MAX);
    for (i = 0; i + 1u < fake.writes && i < LOG_MAX; i++) {
        uint32_t off = fake.log[i].offset;
        uint32_t axis = off / WINDOW - 1u;
        CHECK(off >= WINDOW && axis < 3u);
        if (axis < 3u) {
            writes_in[axis]++;
            last_axis_write[axis] = i;
            if (off % WINDOW == A_STEPS) {
                CHECK_EQ(fake.log[i].value, steps_word(&want[axis]));
            }
            if (off % WINDOW == A_STOP_RATIO) {
                CHECK_EQ(fake.log[i].value, want[axis].stop_ratio);
            }
        }
    }
    CHECK_EQ(writes_in[0], 0u); /* 0 steps: left alone */
    CHECK(writes_in[1] >= 19u && writes_in[2] == writes_in[1]);
    CHECK(last_axis_write[1] < last_axis_write[2]);
    CHECK_EQ(fake.log[fake.writes - 1u].offset, G_SYNC_START); /* the start comes last, one write */
    CHECK_EQ(fake.log[fake.writes - 1u].value, 0x6u);
    CHECK_EQ(fake.regs[(2u * WINDOW + A_STEPS) / 4u], 48u);
    CHECK_EQ(fake.regs[(3u * WINDOW + A_STEPS) / 4u], (uint32_t)-29);

    /* a plan error writes nothing */
    fake.writes = 0u;
    CHECK(stepramp_multi_move_coordinated(&m, plans, steps, 3u, -1.0, DECEL, SPEED) != STEPRAMP_OK);
    CHECK_EQ(fake.writes, 0u);
    CHECK_EQ(stepramp_multi_program_sync(&m, plans, 4u), STEPRAMP_EMULTI_AXES);
    CHECK_EQ(fake.writes, 0u);
}

static void test_wait_done(void)
{
    stepramp_multi_t m;
    uint32_t i;

    CHECK_EQ(init_top(&m, 3u, 1u), STEPRAMP_OK);
    fake.done_after = 4u;
    fake.done_bits = 0x5u;
    CHECK_EQ(stepramp_multi_wait_done(&m, 0x5u, 10u), STEPRAMP_OK);
    CHECK_EQ(fake.status_reads, 4u);
    CHECK_EQ(fake.idles, 3u);
    CHECK_EQ(m.failed_mask, 0u);
    for (i = 0; i < 3u; i++) { /* flags cleared on the waited axes */
        CHECK_EQ(fake.regs[((i + 1u) * WINDOW + A_STATUS) / 4u] & (STATUS_DONE | STATUS_ERROR), 0u);
    }

    /* one axis fails: every waited axis is cleared, the result names it */
    fake_reset(MULTI_ID(3u));
    fake.done_after = 1u;
    fake.done_bits = 0x7u;
    fake.error_bits = 0x2u;
    fake.error_code = 21u;
    CHECK_EQ(stepramp_multi_wait_done(&m, 0x7u, 3u), STEPRAMP_EMULTI_AXIS);
    CHECK_EQ(m.failed_mask, 0x2u);
    CHECK_EQ(m.results[0], STEPRAMP_OK);
    CHECK_EQ(m.results[1], STEPRAMP_ECORE(21u));
    CHECK_EQ(m.results[2], STEPRAMP_OK);
    for (i = 0; i < 3u; i++) {
        CHECK_EQ(fake.regs[((i + 1u) * WINDOW + A_STATUS) / 4u] & (STATUS_DONE | STATUS_ERROR), 0u);
    }

    /* no DONE: timeout, nothing written */
    fake_reset(MULTI_ID(3u));
    fake.done_after = 0u;
    CHECK_EQ(stepramp_multi_wait_done(&m, 0x1u, 5u), STEPRAMP_ETIMEOUT);
    CHECK_EQ(fake.status_reads, 5u);
    CHECK_EQ(fake.writes, 0u);
    CHECK_EQ(stepramp_multi_wait_done(&m, 0x8u, 5u), STEPRAMP_EMULTI_AXES);
    CHECK_EQ(stepramp_multi_wait_done(&m, 0x0u, 5u), STEPRAMP_OK); /* no axis to wait for */
}

static void test_strresult(void)
{
    CHECK(strstr(stepramp_multi_strresult(STEPRAMP_EMULTI_ID), "multi-axis") != NULL);
    CHECK(strstr(stepramp_multi_strresult(STEPRAMP_EMULTI_AXES), "axes") != NULL);
    CHECK(strstr(stepramp_multi_strresult(STEPRAMP_EMULTI_AXIS), "failed_mask") != NULL);
    CHECK(strcmp(stepramp_multi_strresult(STEPRAMP_ETIMEOUT), stepramp_strresult(STEPRAMP_ETIMEOUT)) == 0);
    CHECK(strcmp(stepramp_multi_strresult(STEPRAMP_ECORE(3u)), stepramp_strresult(STEPRAMP_ECORE(3u))) == 0);
}

int main(void)
{
    test_init();
    test_axis_windings();
    test_global_registers();
    test_plan_coordinated();
    test_move_coordinated();
    test_wait_done();
    test_strresult();
    return test_report("test_stepramp_multi");
}
