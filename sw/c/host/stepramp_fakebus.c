/* SPDX-License-Identifier: MIT */
/*
 * A fake stepramp register bank for host tests: see stepramp_fakebus.h. Mirrors hdl/stepramp_regfile.vhd's
 * register semantics (docs/registers.md). The reset values and the bits each register stores come from the
 * generated stepramp_regs.h (STEPRAMP_<REG>_RESET, _RW_MASK, _W1C_MASK), as the register file's come from
 * hdl/stepramp_regs_pkg.vhd: a register or a field added in rdl/stepramp.rdl needs no hand copy here.
 */
#include "stepramp_fakebus.h"

#include <string.h>

#include "stepramp_hostbus.h"
#include "stepramp_regs.h"

stepramp_fakebus_t stepramp_fakebus;

#define WORD(name) (STEPRAMP_REG_##name / 4u)
#define FLAGS_MASK (STEPRAMP_STATUS_DONE_MASK | STEPRAMP_STATUS_ERROR_MASK)
/* the machine inputs' STATUS bits (levels, events, ESTOP_FAULT, LATCHED): the test sets them, writes keep them */
#define INPUT_BITS                                                                                                    \
    (STEPRAMP_STATUS_LIMIT_NEG_MASK | STEPRAMP_STATUS_LIMIT_POS_MASK | STEPRAMP_STATUS_HOME_MASK |                     \
     STEPRAMP_STATUS_ESTOP_MASK | STEPRAMP_STATUS_LIMIT_NEG_EV_MASK | STEPRAMP_STATUS_LIMIT_POS_EV_MASK |             \
     STEPRAMP_STATUS_HOME_EV_MASK | STEPRAMP_STATUS_ESTOP_FAULT_MASK | STEPRAMP_STATUS_LATCHED_MASK)
/* W1C: DONE, ERROR, the input events and LATCHED; ESTOP_FAULT only while ESTOP reads inactive */
#define W1C_MASK (STEPRAMP_STATUS_W1C_MASK & ~STEPRAMP_STATUS_ESTOP_FAULT_MASK)
#define STATE_STOP 0u /* STATUS.STATE of an idle core (docs/registers.md) */

/* per word: the bits a write stores (0: nothing stored, the register is read only or acts on write) */
#define RW_ENTRY(name) [WORD(name)] = STEPRAMP_##name##_RW_MASK,
static const uint32_t rw_mask[STEPRAMP_FAKEBUS_WORDS] = {STEPRAMP_REGISTERS(RW_ENTRY)};

/* the core side's hook (stepramp_fakebus_set_hook) and TIME bits 63:32 (a TIME_LO read copies them to TIME_HI) */
static stepramp_fakebus_hook_fn hook;
static uint32_t time_hi_live;

void stepramp_fakebus_clear_log(void)
{
    stepramp_fakebus_t *f = &stepramp_fakebus;

    memset(f->log, 0, sizeof f->log);
    f->writes = 0;
    f->reads = 0;
    f->status_reads = 0;
    f->bus_errors = 0;
    f->idles = 0;
    f->starts = 0;
    f->soft_stops = 0;
    f->hard_stops = 0;
}

void stepramp_fakebus_reset(uintptr_t base, uint32_t id)
{
    stepramp_fakebus_t *f = &stepramp_fakebus;

    memset(f, 0, sizeof *f);
    f->base = base;
#define RESET_REG(name) f->regs[WORD(name)] = STEPRAMP_##name##_RESET;
    STEPRAMP_REGISTERS(RESET_REG)
#undef RESET_REG
    f->regs[WORD(ID)] = id;
    hook = NULL;
    time_hi_live = 0u;
}

void stepramp_fakebus_set_hook(stepramp_fakebus_hook_fn fn)
{
    hook = fn;
}

void stepramp_fakebus_set_time(uint64_t time)
{
    stepramp_fakebus.regs[WORD(TIME_LO)] = (uint32_t)(time & UINT32_C(0xFFFFFFFF));
    time_hi_live = (uint32_t)(time >> 32);
}

void stepramp_fakebus_set_status(uint32_t state, uint32_t busy, uint32_t dir, uint32_t err_code, uint32_t flags)
{
    uint32_t *st = &stepramp_fakebus.regs[WORD(STATUS)];

    *st = (*st & (FLAGS_MASK | INPUT_BITS)) | (flags & FLAGS_MASK);
    *st |= (state << STEPRAMP_STATUS_STATE_SHIFT) & STEPRAMP_STATUS_STATE_MASK;
    *st |= busy ? STEPRAMP_STATUS_BUSY_MASK : 0u;
    *st |= (dir << STEPRAMP_STATUS_DIR_SHIFT) & STEPRAMP_STATUS_DIR_MASK;
    *st |= (err_code << STEPRAMP_STATUS_ERR_CODE_SHIFT) & STEPRAMP_STATUS_ERR_CODE_MASK;
}

void stepramp_fakebus_finish_after(uint32_t n, uint32_t err_code)
{
    stepramp_fakebus.finish_after = n;
    stepramp_fakebus.finish_err_code = err_code;
}

/* byte offset of addr in the window, or -1 (a bus error) outside it */
static long window_offset(uintptr_t addr)
{
    if (addr < stepramp_fakebus.base || addr - stepramp_fakebus.base >= 4u * STEPRAMP_FAKEBUS_WORDS) {
        stepramp_fakebus.bus_errors++;
        return -1;
    }
    return (long)(addr - stepramp_fakebus.base);
}

static int mapped(uint32_t word)
{
    return word <= WORD(TIME_HI);
}

static uint32_t merge(uint32_t old, uint32_t data, uint32_t be)
{
    uint32_t b, out = old;

    for (b = 0; b < 4u; b++) {
        if (be >> b & 1u) {
            out = (out & ~(UINT32_C(0xFF) << (8u * b))) | (data & (UINT32_C(0xFF) << (8u * b)));
        }
    }
    return out;
}

static void write_word(uint32_t off, uint32_t data, uint32_t be)
{
    stepramp_fakebus_t *f = &stepramp_fakebus;
    uint32_t word = off / 4u;
    uint32_t *reg = &f->regs[word];
    uint32_t status = f->regs[WORD(STATUS)];
    uint32_t bits = merge(0u, data, be);

    if (f->writes < STEPRAMP_FAKEBUS_LOG_MAX) {
        f->log[f->writes].offset = off;
        f->log[f->writes].value = bits;
        f->log[f->writes].be = be;
    }
    f->writes++;
    if (!mapped(word)) {
        f->bus_errors++;
    } else if (word == WORD(CTRL)) {
        f->starts += (bits & STEPRAMP_CTRL_START_MASK) != 0u;
        f->soft_stops += (bits & STEPRAMP_CTRL_SOFT_STOP_MASK) != 0u;
        f->hard_stops += (bits & STEPRAMP_CTRL_HARD_STOP_MASK) != 0u;
        *reg = merge(*reg, data, be) & rw_mask[word]; /* the interrupt enables and ENABLE; commands read 0 */
    } else if (word == WORD(STATUS)) {
        *reg &= ~(bits & W1C_MASK);
        if ((*reg & STEPRAMP_STATUS_ESTOP_MASK) == 0u) { /* the fault is kept while ESTOP is active */
            *reg &= ~(bits & STEPRAMP_STATUS_ESTOP_FAULT_MASK);
        }
    } else if (word == WORD(POSITION)) {
        if (status & STEPRAMP_STATUS_BUSY_MASK) { /* ignored, flagged */
            stepramp_fakebus_set_status((status & STEPRAMP_STATUS_STATE_MASK) >> STEPRAMP_STATUS_STATE_SHIFT, 1u,
                                        (status & STEPRAMP_STATUS_DIR_MASK) != 0u, STEPRAMP_ERR_POS_BUSY,
                                        STEPRAMP_STATUS_ERROR_MASK);
        } else {
            *reg = merge(*reg, data, be) & rw_mask[word];
        }
    } else if ((word >= WORD(DRIVE) && word <= WORD(STEP_SPACE)) || word == WORD(INPUT_FILTER) ||
               word == WORD(INPUT_CFG)) {
        if (status & STEPRAMP_STATUS_BUSY_MASK) { /* stepping and input configuration: only while stopped */
            stepramp_fakebus_set_status((status & STEPRAMP_STATUS_STATE_MASK) >> STEPRAMP_STATUS_STATE_SHIFT, 1u,
                                        (status & STEPRAMP_STATUS_DIR_MASK) != 0u, STEPRAMP_ERR_CFG_BUSY,
                                        STEPRAMP_STATUS_ERROR_MASK);
        } else {
            *reg = merge(*reg, data, be) & rw_mask[word];
        }
    } else { /* the motion and the segment registers: at any time; ID, CUR_DELAY, STEP_COUNT, LATCH_POS ..
              * TIME_HI: read only (no RW bits) */
        *reg = (merge(*reg, data, be) & rw_mask[word]) | (*reg & ~rw_mask[word]);
    }
    if (hook != NULL) {
        hook(off, 1);
    }
}

uint32_t stepramp_hostbus_read32(uintptr_t addr)
{
    stepramp_fakebus_t *f = &stepramp_fakebus;
    long off = window_offset(addr);

    f->reads++;
    if (off < 0) {
        return 0u;
    }
    if ((off & 3) != 0 || !mapped((uint32_t)off / 4u)) {
        f->bus_errors++;
        return 0u;
    }
    if (hook != NULL) {
        hook((uint32_t)off, 0);
    }
    if ((uint32_t)off == STEPRAMP_REG_TIME_LO) {
        f->regs[WORD(TIME_HI)] = time_hi_live;
    }
    if ((uint32_t)off == STEPRAMP_REG_STATUS) {
        f->status_reads++;
        if (f->finish_after != 0u && --f->finish_after == 0u) {
            uint32_t st = f->regs[WORD(STATUS)];
            uint32_t err = f->finish_err_code;
            uint32_t dir = (st & STEPRAMP_STATUS_DIR_MASK) != 0u;
            uint32_t code = err ? err : (st & STEPRAMP_STATUS_ERR_CODE_MASK) >> STEPRAMP_STATUS_ERR_CODE_SHIFT;

            /* a normal end keeps ERR_CODE (the cause of an earlier error, as in the core) */
            stepramp_fakebus_set_status(STATE_STOP, 0u, dir, code,
                                        STEPRAMP_STATUS_DONE_MASK | (err ? STEPRAMP_STATUS_ERROR_MASK : 0u));
        }
    }
    return f->regs[(uint32_t)off / 4u];
}

void stepramp_hostbus_write32(uintptr_t addr, uint32_t value)
{
    long off = window_offset(addr);

    if (off < 0) {
        return;
    }
    if ((off & 3) != 0) {
        stepramp_fakebus.bus_errors++;
        return;
    }
    write_word((uint32_t)off, value, 0xFu);
}

void stepramp_hostbus_write8(uintptr_t addr, uint8_t value)
{
    long off = window_offset(addr);
    uint32_t lane;

    if (off < 0) {
        return;
    }
    lane = (uint32_t)off & 3u;
    write_word((uint32_t)off & ~3u, (uint32_t)value << (8u * lane), 1u << lane);
}

void stepramp_hostbus_idle(void)
{
    stepramp_fakebus.idles++;
}

uint32_t stepramp_fakebus_log_count(void)
{
    uint32_t n = stepramp_fakebus.writes;

    return n < STEPRAMP_FAKEBUS_LOG_MAX ? n : STEPRAMP_FAKEBUS_LOG_MAX;
}

int stepramp_fakebus_log_entry(uint32_t i, uint32_t *offset, uint32_t *value, uint32_t *be)
{
    const stepramp_fakebus_write_t *w;

    if (i >= stepramp_fakebus_log_count()) {
        return -1;
    }
    w = &stepramp_fakebus.log[i];
    if (offset != NULL) {
        *offset = w->offset;
    }
    if (value != NULL) {
        *value = w->value;
    }
    if (be != NULL) {
        *be = w->be;
    }
    return 0;
}

stepramp_fakebus_t *stepramp_fakebus_state(void)
{
    return &stepramp_fakebus;
}

size_t stepramp_fakebus_sizeof_state(void)
{
    return sizeof(stepramp_fakebus_t);
}
