// Results and input signals as CSV files, as fmpy's write_csv writes them and its read_csv reads
// them back: the reference result `springmass fmu --reference` packs, and the input signals of
// `springmass run --input`.
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

// The values a column may hold: any finite number, whole numbers within 32 bits (an Integer
// variable's), or 0 and 1 (a Boolean variable's: false and true).
typedef enum cli_csv_values {
	CLI_CSV_REAL = 0,
	CLI_CSV_INTEGER,
	CLI_CSV_BOOLEAN,
} cli_csv_values;

// What a file's columns may name, besides "time".
typedef struct cli_csv_form {
	const char* what;  // the file in messages: "a result", "an input file"
	// Takes a column's name: NULL with *id (0 <= id < id_count) and *values (what its values may
	// be) set, or why it is refused, a text that follows the quoted name ("is not a variable of
	// the FMU"), static or in memory the context owns.
	const char* (*name_column)(void* context, const char* name, int32_t* id, cli_csv_values* values);
	void* context;
	int32_t id_count;
	bool keep_values;  // whether csv->values keeps the rows (else the file is only checked)
} cli_csv_form;

// A file read: its columns (time first, id -1) and its rows of numbers (NULL unless the form
// keeps them).
typedef struct cli_csv {
	int32_t columns;
	int32_t* id;                // per column
	cli_csv_values* values_of;  // per column
	int64_t rows;
	double* values;  // rows x columns, row by row
} cli_csv;

// Reads a CSV (fields separated by commas, a name quoted or not, with doubled quotes inside a
// quoted one; lines ending in LF or CRLF) whose first line names the columns, "time" first and
// then columns the form takes, each once, and whose every other line holds a decimal number per
// column, unquoted and finite (whole, or 0 or 1, where the form says so), time never decreasing
// (a repeated time is a step: an event); at least one row, no empty line, no byte-order mark.
// Returns NULL with csv filled (free it with cli_csv_free), else a malloc'd message "LINE:COLUMN:
// what is wrong" (1-based, the column in bytes, of the line the offending field starts on), or
// NULL with *out_of_memory set; csv is empty then.
char* cli_csv_read(const char* text, size_t length, const cli_csv_form* form, cli_csv* csv,
                   bool* out_of_memory);

void cli_csv_free(cli_csv* csv);
