// A reference result packed into an FMU (`springmass fmu --reference`), checked against the FMU's
// variables before it is packed.
#pragma once

#include "fmu_model.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Checks the text of a reference result as fmpy's write_csv writes one and its read_csv reads
/// it back: a CSV (fields separated by commas, a name quoted or not, with doubled quotes inside a
/// quoted one; lines ending in LF or CRLF) whose first line names the columns, "time" first and
/// then Real, Integer or Boolean variables of the FMU described by `table`, each once, and whose
/// every other line holds a decimal number per column, unquoted and finite (a whole one within 32
/// bits for an Integer variable, 0 or 1 for a Boolean one), time never decreasing (a step may repeat a time
/// at an event); at least one row, no empty line, no byte-order mark. Returns NULL if it is such a result,
/// else a malloc'd message "LINE:COLUMN: what is wrong" (1-based, the column in bytes, of the line the
/// offending field starts on), or NULL with *out_of_memory set.
char* fmu_reference_problem(const char* text, size_t length, const fmu_table* table, bool* out_of_memory);

#ifdef __cplusplus
}
#endif
