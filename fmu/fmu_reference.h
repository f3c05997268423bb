// A reference result packed into an FMU (`springmass fmu --reference`), checked against the FMU's
// variables before it is packed.
#pragma once

#include "fmu_model.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Checks the text of a reference result: a CSV (RFC 4180: fields separated by commas, quoted
/// with doubled quotes inside where needed, lines ending in LF or CRLF, as fmpy writes it) whose
/// first line names the columns, "time" first and then Real or Integer variables of the FMU
/// described by `table`, each once, and whose every other line holds a finite number per column,
/// time never decreasing (a step may repeat a time at an event); empty lines only at the end, at
/// least one row. Returns NULL if it is such a result, else a malloc'd message "LINE:COLUMN: what
/// is wrong" (1-based, the column in bytes), or NULL with *out_of_memory set.
char* fmu_reference_problem(const char* text, size_t length, const fmu_table* table, bool* out_of_memory);

#ifdef __cplusplus
}
#endif
