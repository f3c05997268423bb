// Timing for the benchmarks: a monotonic clock and the median of a set of times.
#ifndef SPRINGMASS_BENCH_CLOCK_H
#define SPRINGMASS_BENCH_CLOCK_H

#include <stdlib.h>
#include <time.h>

// Seconds on a monotonic clock [s] (only differences mean anything).
static inline double bench_now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static inline int bench_compare_doubles(const void* a, const void* b)
{
	const double x = *(const double*)a, y = *(const double*)b;
	return (x > y) - (x < y);
}

// The median of n > 0 values, sorting them in place: the middle one, or the mean of the two
// middle ones for an even count.
static inline double bench_median(double* v, int n)
{
	qsort(v, (size_t)n, sizeof *v, bench_compare_doubles);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif
