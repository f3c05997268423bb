// Numbers as text that reads back exactly, and messages whose numbers read the same in any locale.
#define _POSIX_C_SOURCE 200809L

#include "c_locale.h"
#include "model_internal.h"

#include <stdio.h>
#include <stdlib.h>

// Messages are formatted in the C locale (c_locale.h): their numbers read the same in any locale.
int sm_vformat_c_locale(char* text, size_t size, const char* format, va_list args)
{
	const sm_c_locale_scope scope = sm_enter_c_locale();
	const int written = vsnprintf(text, size, format, args);
	sm_leave_c_locale(scope);
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
// locale (c_locale.h): with a '.' whatever the program's locale, as the model file's parser reads it.
void sm_format_number(double value, char text[SM_NUMBER_TEXT_CAPACITY])
{
	const sm_c_locale_scope scope = sm_enter_c_locale();
	int digits = 15;
	for (; digits < 17; digits++) {
		snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.*g", digits, value);
		if (strtod(text, NULL) == value)
			break;
	}
	if (digits == 17)
		snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.17g", value);
	sm_leave_c_locale(scope);
}
