/* SPDX-License-Identifier: MIT */
/* test_check.h: the CHECK and CHECK_EQ macros, their counters and the final report, shared by the host test programs. */
#ifndef STEPRAMP_TEST_CHECK_H
#define STEPRAMP_TEST_CHECK_H

#include <stdio.h>

static int g_checks;
static int g_failures;

#define CHECK(cond)                                                                                                    \
    do {                                                                                                               \
        g_checks++;                                                                                                    \
        if (!(cond)) {                                                                                                 \
            g_failures++;                                                                                              \
            printf("%s:%d: %s: check failed: %s\n", __FILE__, __LINE__, __func__, #cond);                              \
        }                                                                                                              \
    } while (0)

/* CHECK(got == want) for 32-bit words, printing both */
#define CHECK_EQ(got, want)                                                                                            \
    do {                                                                                                               \
        unsigned long got_ = (unsigned long)(got), want_ = (unsigned long)(want);                                      \
        g_checks++;                                                                                                    \
        if (got_ != want_) {                                                                                           \
            g_failures++;                                                                                              \
            printf("%s:%d: %s: %s = 0x%08lx, expected %s = 0x%08lx\n", __FILE__, __LINE__, __func__, #got, got_,       \
                   #want, want_);                                                                                      \
        }                                                                                                              \
    } while (0)

/* prints "<name>: <n> checks, <m> failed" and returns main's exit status: 0 when every check passed */
static int test_report(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, g_checks, g_failures);
    return g_failures == 0 ? 0 : 1;
}

#endif /* STEPRAMP_TEST_CHECK_H */
