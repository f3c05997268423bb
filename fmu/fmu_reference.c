// springmass FMU: checking a reference result (see fmu_reference.h).
#define _POSIX_C_SOURCE 200809L  // strnlen
#include "fmu_reference.h"

#include "springmass/model_file.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Bytes of a field a message shows.
enum { shown_bytes = 60 };

// Where the reader is in the text: its position, and the line and the start of that line.
typedef struct reader {
	const char* text;
	size_t length, at, line, line_start;
	char* field;  // the last field read, unquoted (malloc'd, grown as needed)
	size_t field_capacity;
	bool out_of_memory;
	char shown[SM_TERMINAL_TEXT_CAPACITY(shown_bytes)];  // the field as a message shows it
} reader;

// The field as a message shows it: its first shown_bytes bytes, escaped where a terminal would
// act on them.
static const char* field_shown(reader* r)
{
	char start[shown_bytes + 1];
	const size_t n = strnlen(r->field, shown_bytes);
	memcpy(start, r->field, n);
	start[n] = '\0';
	sm_text_for_terminal(r->shown, start);
	return r->shown;
}

static char* problem_at(const reader* r, size_t at, const char* format, ...)
{
	char message[400];
	va_list args;
	va_start(args, format);
	vsnprintf(message, sizeof message, format, args);
	va_end(args);
	char* text = malloc(strlen(message) + 48);
	if (text != NULL)
		sprintf(text, "%zu:%zu: %s", r->line, at - r->line_start + 1, message);
	return text;
}

static bool field_append(reader* r, size_t n, char c)
{
	if (n + 2 > r->field_capacity) {
		const size_t capacity = r->field_capacity ? 2 * r->field_capacity : 64;
		char* grown = realloc(r->field, capacity);
		if (grown == NULL) {
			r->out_of_memory = true;
			return false;
		}
		r->field = grown;
		r->field_capacity = capacity;
	}
	r->field[n] = c;
	r->field[n + 1] = '\0';
	return true;
}

static bool at_line_end(const reader* r)
{
	return r->at >= r->length || r->text[r->at] == '\n' ||
	       (r->text[r->at] == '\r' && r->at + 1 < r->length && r->text[r->at + 1] == '\n');
}

// Reads one field into r->field, up to the comma or line end that follows it (not consumed).
// Returns NULL, or the problem (a quote left open or text after a closing quote).
static char* read_field(reader* r)
{
	size_t n = 0;
	if (!field_append(r, 0, '\0'))
		return NULL;
	r->field[0] = '\0';
	if (r->at < r->length && r->text[r->at] == '"') {
		const size_t open = r->at++, open_line = r->line, open_line_start = r->line_start;
		for (;;) {
			if (r->at >= r->length) {
				r->line = open_line;
				r->line_start = open_line_start;
				return problem_at(r, open, "a quoted field is not closed");
			}
			const char c = r->text[r->at++];
			if (c == '"' && (r->at >= r->length || r->text[r->at] != '"'))
				break;
			if (c == '"')
				r->at++;  // a doubled quote
			if (c == '\n') {
				r->line++;
				r->line_start = r->at;
			}
			if (!field_append(r, n++, c))
				return NULL;
		}
		if (!at_line_end(r) && r->text[r->at] != ',')
			return problem_at(r, r->at, "text after the closing quote of a field");
		return NULL;
	}
	while (!at_line_end(r) && r->text[r->at] != ',')
		if (!field_append(r, n++, r->text[r->at++]))
			return NULL;
	return NULL;
}

// Moves past the line end (LF or CRLF) the reader is at.
static void next_line(reader* r)
{
	if (r->at < r->length && r->text[r->at] == '\r')
		r->at++;
	if (r->at < r->length) {
		r->at++;
		r->line++;
		r->line_start = r->at;
	}
}

static int compare_names(const void* a, const void* b)
{
	return strcmp((*(const fmu_variable* const*)a)->name, (*(const fmu_variable* const*)b)->name);
}

// A finite number written out in full (strtod's form, without white space, inf or nan).
static bool finite_number(const char* text, double* value)
{
	if (*text == '\0' || strpbrk(text, " \t\n\v\f\r") != NULL)
		return false;
	char* end = NULL;
	*value = strtod(text, &end);
	return *end == '\0' && isfinite(*value);
}

// The header: "time", then Real or Integer variables of the table, each once. sorted: the
// table's variables by name; named: a flag per variable, false on entry.
static char* read_header(reader* r, const fmu_table* table, const fmu_variable** sorted, bool* named,
                         int32_t* columns)
{
	for (*columns = 0;; ++*columns) {
		const size_t start = r->at;
		char* problem = read_field(r);
		if (problem != NULL || r->out_of_memory)
			return problem;
		if (*columns == 0 && strcmp(r->field, "time") != 0)
			return problem_at(r, start, "the first column is \"%s\", not \"time\"", field_shown(r));
		if (*columns > 0) {
			const fmu_variable key = {.name = r->field};
			const fmu_variable* pointer = &key;
			const fmu_variable** found =
			    bsearch(&pointer, sorted, (size_t)table->count, sizeof *sorted, compare_names);
			if (found == NULL)
				return problem_at(r, start, "\"%s\" is not a variable of the FMU", field_shown(r));
			if ((*found)->type == FMU_STRING)
				return problem_at(r, start, "\"%s\" is a String variable: a result holds numbers",
				                  field_shown(r));
			const size_t index = (size_t)(*found - table->variables);
			if (named[index])
				return problem_at(r, start, "\"%s\" is named twice", field_shown(r));
			named[index] = true;
		}
		if (at_line_end(r)) {
			++*columns;
			return NULL;
		}
		r->at++;  // the comma
	}
}

// The rows: as many finite numbers as columns, time never decreasing; empty lines only at the end.
static char* read_rows(reader* r, int32_t columns)
{
	double previous_time = -INFINITY;
	size_t rows = 0;
	while (r->at < r->length) {
		if (at_line_end(r)) {  // an empty line: only empty lines may follow
			const size_t line = r->line, start = r->at;
			while (r->at < r->length && at_line_end(r))
				next_line(r);
			if (r->at < r->length) {
				r->line = line;
				r->line_start = start;
				return problem_at(r, start, "an empty line before the end of the result");
			}
			break;
		}
		for (int32_t c = 0; c < columns; c++) {
			const size_t start = r->at;
			char* problem = read_field(r);
			if (problem != NULL || r->out_of_memory)
				return problem;
			double value;
			if (!finite_number(r->field, &value))
				return problem_at(r, start, "\"%s\" is not a finite number", field_shown(r));
			if (c == 0 && value < previous_time)
				return problem_at(r, start, "time %.17g s is before the previous row's %.17g s", value,
				                  previous_time);
			if (c == 0)
				previous_time = value;
			const bool last = c == columns - 1;
			if (at_line_end(r) != last)
				return problem_at(r, r->at, "%s: the header names %d columns",
				                  last ? "more fields than columns" : "fewer fields than columns",
				                  (int)columns);
			if (!last)
				r->at++;  // the comma
		}
		rows++;
		next_line(r);
	}
	if (rows == 0)
		return problem_at(r, r->at, "no rows after the header");
	return NULL;
}

char* fmu_reference_problem(const char* text, size_t length, const fmu_table* table, bool* out_of_memory)
{
	reader r = {.text = text, .length = length, .line = 1};
	*out_of_memory = false;
	if (length == 0)
		return problem_at(&r, 0, "an empty file");
	const char* nul = memchr(text, '\0', length);
	if (nul != NULL) {
		for (const char* c = text; c < nul; c++)
			if (*c == '\n') {
				r.line++;
				r.line_start = (size_t)(c + 1 - text);
			}
		return problem_at(&r, (size_t)(nul - text), "a NUL byte: not a text file");
	}
	const fmu_variable** sorted = malloc(((size_t)table->count + 1) * sizeof *sorted);
	bool* named = calloc((size_t)table->count + 1, sizeof *named);
	if (sorted == NULL || named == NULL) {
		free(sorted);
		free(named);
		*out_of_memory = true;
		return NULL;
	}
	for (int32_t i = 0; i < table->count; i++)
		sorted[i] = &table->variables[i];
	qsort(sorted, (size_t)table->count, sizeof *sorted, compare_names);
	int32_t columns = 0;
	char* problem = read_header(&r, table, sorted, named, &columns);
	free(sorted);
	free(named);
	if (problem == NULL && !r.out_of_memory) {
		next_line(&r);
		problem = read_rows(&r, columns);
	}
	free(r.field);
	*out_of_memory = r.out_of_memory;
	if (r.out_of_memory) {
		free(problem);
		return NULL;
	}
	return problem;
}
