// Numbers as text that reads back exactly, and messages whose numbers read the same in any locale.
#define _POSIX_C_SOURCE 200809L

#include "model_internal.h"

#include <locale.h>
#include <stdio.h>
#include <stdlib.h>

// Text in the C locale whatever LC_NUMERIC the program chose: under a decimal comma (de_DE)
// printf writes 0.5 as "0,5", which a message's list ("n = 0,5, m = 2") makes ambiguous and a
// command it suggests ("--set l0=0,5") wrong. uselocale() switches the calling thread only, for
// the call; glibc's "C" locale object is static (no allocation, freelocale does nothing). Should
// it be refused all the same, the text is the program's locale's.
typedef struct c_locale_scope {
	locale_t c, previous;
} c_locale_scope;

static c_locale_scope enter_c_locale(void)
{
	c_locale_scope scope = {newlocale(LC_ALL_MASK, "C", (locale_t)0), (locale_t)0};
	if (scope.c != (locale_t)0)
		scope.previous = uselocale(scope.c);
	return scope;
}

static void leave_c_locale(c_locale_scope scope)
{
	if (scope.c != (locale_t)0) {
		uselocale(scope.previous);
		freelocale(scope.c);
	}
}

int sm_vformat_c_locale(char* text, size_t size, const char* format, va_list args)
{
	const c_locale_scope scope = enter_c_locale();
	const int written = vsnprintf(text, size, format, args);
	leave_c_locale(scope);
	return written;
}

int sm_format_c_locale(char* text, size_t size, const char* format, ...)
{
	va_list args;
	va_start(args, format);
	const int written = sm_vformat_c_locale(text, size, format, args);
	va_end(args);
	return written;
}

// 17 significant digits always read back to the same double (IEEE 754 binary64: DBL_DECIMAL_DIG);
// fewer often do. Trying 15 and 16 first gives the short form where one exists among them: every
// decimal number of at most 15 significant digits survives the round trip through a double
// (DBL_DIG), so a value that came from such text gets it back. Written and read back in the C
// locale, as above: with a '.' whatever the program's locale, as the model file's parser reads it.
void sm_format_number(double value, char text[SM_NUMBER_TEXT_CAPACITY])
{
	const c_locale_scope scope = enter_c_locale();
	int digits = 15;
	for (; digits < 17; digits++) {
		snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.*g", digits, value);
		if (strtod(text, NULL) == value)
			break;
	}
	if (digits == 17)
		snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.17g", value);
	leave_c_locale(scope);
}
