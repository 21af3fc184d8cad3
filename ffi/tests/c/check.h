/* check.h — the C test programs' checks: each prints one line ("ok  " or "FAIL") and counts;
 * main returns `failures` (the number of failed checks) as its exit status. Included by one
 * source file per program (the counters are static). */
#ifndef SHIKKI_TEST_CHECK_H
#define SHIKKI_TEST_CHECK_H

#include <shikki.h>

#include <stdio.h>
#include <string.h>

static int failures = 0;
static int checks = 0;

/* `status` must equal `want`; on an error the message must be non-empty, on success empty. */
static inline void expect(const char *what, ShikkiStatus status, ShikkiStatus want) {
    const char *message = shikki_last_error();
    int ok = status == want && message != NULL &&
             (want == SHIKKI_STATUS_OK ? message[0] == '\0' : message[0] != '\0');
    checks++;
    if (!ok) failures++;
    printf("%s %s: status %d (want %d): %s\n", ok ? "ok  " : "FAIL", what, (int)status,
           (int)want, message ? message : "(NULL message)");
}

#define EXPECT(call, want) expect(#call, (call), (want))

/* As expect, and the message must contain `needle` (the message names the problem). */
static inline void expect_message(const char *what, ShikkiStatus status, ShikkiStatus want,
                           const char *needle) {
    const char *message = shikki_last_error();
    if (message != NULL && strstr(message, needle) == NULL) {
        checks++;
        failures++;
        printf("FAIL %s: message lacks \"%s\": %s\n", what, needle, message);
    }
    expect(what, status, want);
}

#define EXPECT_MESSAGE(call, want, needle) expect_message(#call, (call), (want), (needle))

/* `condition` must hold. */
static inline void expect_true(const char *what, int condition) {
    checks++;
    if (!condition) failures++;
    printf("%s %s\n", condition ? "ok  " : "FAIL", what);
}

#define EXPECT_TRUE(condition) expect_true(#condition, (condition))

#endif
