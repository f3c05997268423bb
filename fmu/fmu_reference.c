// springmass FMU: checking a reference result (see fmu_reference.h).
#include "fmu_reference.h"

#include "cli_csv.h"

#include <stdlib.h>
#include <string.h>

// The table's variables by name, for the columns of a result.
typedef struct table_names {
	const fmu_table* table;
	const fmu_variable** sorted;
} table_names;

static int compare_names(const void* a, const void* b)
{
	return strcmp((*(const fmu_variable* const*)a)->name, (*(const fmu_variable* const*)b)->name);
}

// A result's column: a Real, Integer or Boolean variable of the FMU (whole values for an Integer
// one; 0 or 1, false and true as numbers, for a Boolean one: fmpy's read_csv reads those back,
// not the True and False its write_csv writes).
static const char* name_column(void* context, const char* name, int32_t* id, cli_csv_values* values)
{
	const table_names* names = context;
	const fmu_variable key = {.name = (char*)name};
	const fmu_variable* pointer = &key;
	const fmu_variable** found =
	    bsearch(&pointer, names->sorted, (size_t)names->table->count, sizeof *names->sorted, compare_names);
	if (found == NULL)
		return "is not a variable of the FMU";
	if ((*found)->type == FMU_STRING)
		return "is a String variable: a result holds numbers";
	*id = (int32_t)(*found - names->table->variables);
	*values = (*found)->type == FMU_INTEGER   ? CLI_CSV_INTEGER
	          : (*found)->type == FMU_BOOLEAN ? CLI_CSV_BOOLEAN
	                                          : CLI_CSV_REAL;
	return NULL;
}

char* fmu_reference_problem(const char* text, size_t length, const fmu_table* table, bool* out_of_memory)
{
	table_names names = {table, malloc(((size_t)table->count + 1) * sizeof *names.sorted)};
	if (names.sorted == NULL) {
		*out_of_memory = true;
		return NULL;
	}
	for (int32_t i = 0; i < table->count; i++)
		names.sorted[i] = &table->variables[i];
	qsort(names.sorted, (size_t)table->count, sizeof *names.sorted, compare_names);
	const cli_csv_form form = {"a result", name_column, &names, table->count, false};
	cli_csv csv;
	char* problem = cli_csv_read(text, length, &form, &csv, out_of_memory);
	cli_csv_free(&csv);
	free(names.sorted);
	return problem;
}
