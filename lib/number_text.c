// Numbers as text that reads back exactly.
#include "springmass/base.h"

#include <stdio.h>
#include <stdlib.h>

// 17 significant digits always read back to the same double (IEEE 754 binary64: DBL_DECIMAL_DIG);
// fewer often do. Trying 15 and 16 first gives the short form where one exists among them: every
// decimal number of at most 15 significant digits survives the round trip through a double
// (DBL_DIG), so a value that came from such text gets it back.
void sm_format_number(double value, char text[SM_NUMBER_TEXT_CAPACITY])
{
	for (int digits = 15; digits < 17; digits++) {
		snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.*g", digits, value);
		if (strtod(text, NULL) == value)
			return;
	}
	snprintf(text, SM_NUMBER_TEXT_CAPACITY, "%.17g", value);
}
