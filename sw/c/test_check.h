/* SPDX-License-Identifier: MIT */
/* test_check.h: the CHECK macro and its counters, shared by the host test programs. */
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

#endif /* STEPRAMP_TEST_CHECK_H */
