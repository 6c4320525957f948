/* SPDX-License-Identifier: MIT */
/*
 * A fake stepramp register bank for host tests (not for the target): a uint32_t array behind the driver's
 * STEPRAMP_READ32 / STEPRAMP_WRITE32 / STEPRAMP_WRITE8, with the core's register semantics -- byte-lane
 * writes (little-endian lanes: byte address offset b is bits 8b+7:8b), each register keeping only its RW bits
 * and starting from its reset value (STEPRAMP_<REG>_RW_MASK, _RESET of stepramp_regs.h), ID and the status fields
 * read only,
 * CTRL command bits act on write and read 0, STATUS.DONE / ERROR / the input events / LATCHED cleared by writing 1
 * (ESTOP_FAULT only while STATUS.ESTOP reads 0), POSITION writes ignored (ERROR, POS_BUSY) while busy, the stepping
 * and input configuration (DRIVE .. STEP_SPACE, INPUT_FILTER, INPUT_CFG) too (CFG_BUSY), LATCH_POS .. TIME_HI read
 * only (a TIME_LO read copies TIME bits 63:32 into TIME_HI), bus errors counted for addresses outside the 256-byte
 * window (or past TIME_HI, the last register) -- and
 * a log of every write and a count of the driver's STEPRAMP_IDLE() calls. The "core" side is driven by the test:
 * stepramp_fakebus_set_status(), stepramp_fakebus_finish_after(), stepramp_fakebus_set_time(), the registers
 * themselves, and a hook called at every access (stepramp_fakebus_set_hook: a test's model of the core).
 *
 * The bank implements the host build's register access (stepramp_hostbus.h): the driver reaches it through that
 * header alone, and the bank does not know the driver. The ctypes entry points that run the driver on the bank
 * are in stepramp_ctypes.c.
 */
#ifndef STEPRAMP_FAKEBUS_H
#define STEPRAMP_FAKEBUS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Registers of the 256-byte window (STEPRAMP_ADDR_BITS = 8). */
#define STEPRAMP_FAKEBUS_WORDS 64u
/** Entries of the write log (later writes are counted, not logged). */
#define STEPRAMP_FAKEBUS_LOG_MAX 256u

/** One bus write as the core sees it. */
typedef struct {
    uint32_t offset; /**< byte offset of the register (word aligned) */
    uint32_t value;  /**< the 32-bit data word, written bytes in their lanes, the other lanes 0 */
    uint32_t be;     /**< byte enables, bit b = bits 8b+7:8b */
} stepramp_fakebus_write_t;

/** The fake core's state, all visible to the tests. */
typedef struct {
    uintptr_t base;                                         /**< bus address of offset 0 */
    uint32_t regs[STEPRAMP_FAKEBUS_WORDS];                  /**< register contents (CTRL holds the enables only) */
    stepramp_fakebus_write_t log[STEPRAMP_FAKEBUS_LOG_MAX]; /**< the first writes since the last clear */
    uint32_t writes;                                        /**< writes since the last clear (may exceed LOG_MAX) */
    uint32_t reads;                                         /**< reads since the last clear */
    uint32_t status_reads;                                  /**< STATUS reads since the last clear */
    uint32_t bus_errors;                                    /**< accesses outside the window or misaligned words */
    uint32_t idles;                                         /**< STEPRAMP_IDLE() calls since the last clear */
    uint32_t starts, soft_stops, hard_stops;                /**< CTRL commands received */
    uint32_t finish_after;                                  /**< 0: off; n: the move ends at the n-th STATUS read */
    uint32_t finish_err_code;                               /**< ERR_CODE it ends with (0: no error) */
} stepramp_fakebus_t;

/** The one fake core. */
extern stepramp_fakebus_t stepramp_fakebus;

/** Reset the fake core at bus address base: registers at their reset values, ID = id, log and counters clear. */
void stepramp_fakebus_reset(uintptr_t base, uint32_t id);

/** Clear the write log and the access counters (not the registers). */
void stepramp_fakebus_clear_log(void);

/** Core side: set STATUS's read-only fields (STATE, BUSY, DIR, ERR_CODE) and, with flags, raise DONE / ERROR. */
void stepramp_fakebus_set_status(uint32_t state, uint32_t busy, uint32_t dir, uint32_t err_code, uint32_t flags);

/**
 * Core side: the move ends at the n-th STATUS read from now (that read sees it): STATE STOP, BUSY 0, DONE 1, and
 * ERROR with ERR_CODE err_code when err_code != 0 (with 0, ERR_CODE and ERROR stay as they are). n = 0 disarms.
 */
void stepramp_fakebus_finish_after(uint32_t n, uint32_t err_code);

/**
 * Core side: a function called at every access of the driver with the register's byte offset and write = 1 for a
 * write (called after the write took effect) or 0 for a read (called before the value is read), so that a test can
 * model the core (move, raise flags) between two accesses. NULL removes it; stepramp_fakebus_reset() does too.
 */
typedef void (*stepramp_fakebus_hook_fn)(uint32_t offset, int write);
void stepramp_fakebus_set_hook(stepramp_fakebus_hook_fn fn);

/** Core side: TIME (TIME_LO now; bits 63:32 reach TIME_HI at the next TIME_LO read, as in the core). */
void stepramp_fakebus_set_time(uint64_t time);

/* Bus side: the bank defines the functions of stepramp_hostbus.h. */

/* ---- ctypes access to the bank (sw/tests/test_c_driver.py, tb/test_plb_c.py) ---- */

/** Writes logged since the last clear (at most STEPRAMP_FAKEBUS_LOG_MAX). */
uint32_t stepramp_fakebus_log_count(void);

/**
 * Log entry i: its offset, data word and byte enables (outputs may be NULL).
 * @return 0, or -1 (outputs untouched) when i >= stepramp_fakebus_log_count()
 */
int stepramp_fakebus_log_entry(uint32_t i, uint32_t *offset, uint32_t *value, uint32_t *be);

/** Pointer to the fake core's state (for ctypes). */
stepramp_fakebus_t *stepramp_fakebus_state(void);

/** sizeof(stepramp_fakebus_t): lets ctypes check its structure layout. */
size_t stepramp_fakebus_sizeof_state(void);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_FAKEBUS_H */
