// A tiny test harness: one executable per area, each test a function returning 0 on success.
//
//   static int test_something(void) { ENSURE(x == 1); ENSURE_NEAR(a, b, 1e-9); return 0; }
//   int main(int argc, char** argv) { RUN_TEST(test_something); return TEST_SUMMARY(); }
//
// Run an executable with a substring as its first argument to run only the tests whose name
// contains it. Every failed check prints its file, line, expression and values.
#pragma once

#include <math.h>
#include <stdio.h>
#include <string.h>

static int test_failures_ = 0;
static int test_passes_ = 0;
static const char* test_filter_ = NULL;

#define TEST_INIT(argc, argv) (test_filter_ = (argc) > 1 ? (argv)[1] : NULL)

#define RUN_TEST(fn)                                                                                         \
	do {                                                                                                     \
		if (test_filter_ == NULL || strstr(#fn, test_filter_) != NULL) {                                     \
			int result_ = fn();                                                                              \
			printf("%-60s %s\n", #fn, result_ == 0 ? "ok" : "FAILED");                                       \
			fflush(stdout);                                                                                  \
			if (result_ == 0)                                                                                \
				test_passes_++;                                                                              \
			else                                                                                             \
				test_failures_++;                                                                            \
		}                                                                                                    \
	} while (0)

#define TEST_SUMMARY()                                                                                       \
	(printf("%d passed, %d failed\n", test_passes_, test_failures_), test_failures_ == 0 ? 0 : 1)

#define ENSURE(cond)                                                                                         \
	do {                                                                                                     \
		if (!(cond)) {                                                                                       \
			printf("  %s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);                                \
			return 1;                                                                                        \
		}                                                                                                    \
	} while (0)

/// The larger of a running worst error and a new one, and NaN once either is NaN: fmax drops a
/// NaN, so an error gathered with it would take a NaN state for no error at all.
static inline double worst_of(double worst, double error)
{
	return isnan(error) || error > worst ? error : worst;
}

/// |a - b| <= tol, with both values printed on failure.
#define ENSURE_NEAR(a, b, tol)                                                                               \
	do {                                                                                                     \
		double a_ = (a), b_ = (b), t_ = (tol);                                                               \
		if (!(fabs(a_ - b_) <= t_)) {                                                                        \
			printf("  %s:%d: |%s - %s| = |%.17g - %.17g| = %.3g > %.3g\n", __FILE__, __LINE__, #a, #b, a_,   \
			       b_, fabs(a_ - b_), t_);                                                                   \
			return 1;                                                                                        \
		}                                                                                                    \
	} while (0)

/// |a - b| <= tol * max(|a|, |b|, floor): relative comparison with an absolute floor.
#define ENSURE_REL(a, b, tol, floor)                                                                         \
	do {                                                                                                     \
		double a_ = (a), b_ = (b);                                                                           \
		double s_ = fmax(fmax(fabs(a_), fabs(b_)), (floor));                                                 \
		if (!(fabs(a_ - b_) <= (tol) * s_)) {                                                                \
			printf("  %s:%d: %s = %.17g vs %s = %.17g: relative difference %.3g > %.3g\n", __FILE__,         \
			       __LINE__, #a, a_, #b, b_, fabs(a_ - b_) / s_, (double)(tol));                             \
			return 1;                                                                                        \
		}                                                                                                    \
	} while (0)

/// A status-returning call must give the expected status.
#define ENSURE_STATUS(call, expected)                                                                        \
	do {                                                                                                     \
		int st_ = (int)(call);                                                                               \
		if (st_ != (int)(expected)) {                                                                        \
			printf("  %s:%d: %s returned %d, expected %s (%d)\n", __FILE__, __LINE__, #call, st_, #expected, \
			       (int)(expected));                                                                         \
			return 1;                                                                                        \
		}                                                                                                    \
	} while (0)
