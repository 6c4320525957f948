/* SPDX-License-Identifier: MIT */
/* test_check.h: the CHECK macro, its counters and the final report, shared by the host test programs. */
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

/* prints "<name>: <n> checks, <m> failed" and returns main's exit status: 0 when every check passed */
static int test_report(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, g_checks, g_failures);
    return g_failures == 0 ? 0 : 1;
}

#endif /* STEPRAMP_TEST_CHECK_H */
