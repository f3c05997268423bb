// Arguments and settings of the benchmarks, read whole: a mistyped one ("4x", "7.5", "1e3")
// stops the benchmark instead of measuring something else under its name.
#ifndef SPRINGMASS_BENCH_ARGS_H
#define SPRINGMASS_BENCH_ARGS_H

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>

// A whole number from lo to hi that `text` reads as, in *value; false for anything else
// (trailing characters, out of range), leaving *value as it was.
static inline bool bench_read_count(const char* text, long lo, long hi, int* value)
{
	char* end = NULL;
	errno = 0;
	const long v = strtol(text, &end, 10);
	if (end == text || *end != '\0' || errno != 0 || v < lo || v > hi)
		return false;
	*value = (int)v;
	return true;
}

#endif
