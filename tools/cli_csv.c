// Results and input signals as CSV files, as fmpy writes and reads them (see cli_csv.h).
#define _POSIX_C_SOURCE 200809L  // strnlen, strdup
#include "cli_csv.h"

#include "springmass/model_file.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Bytes of a field a message shows.
enum { shown_bytes = 60 };

// A line of the text: its number (from 1) and where it starts.
typedef struct line_place {
	size_t line, start;
} line_place;

// Where the reader is in the text: its position and its line.
typedef struct reader {
	const char* text;
	size_t length, at;
	line_place here;
	line_place field_place;  // the line the last field started on (a quoted one may span lines)
	char* field;             // the last field read, unquoted (malloc'd, grown as needed)
	bool quoted;             // it was quoted
	size_t field_capacity;
	bool out_of_memory;
	char shown[SM_TERMINAL_TEXT_CAPACITY(shown_bytes) + 5];  // the field as a message shows it
} reader;

// The field as a message shows it: quoted, escaped where a terminal would act on it, and one
// longer than shown_bytes bytes cut at a character with "..." after the quote, as the model file's
// messages show a name.
static const char* field_shown(reader* r)
{
	char start[shown_bytes + 1];
	size_t n = strnlen(r->field, shown_bytes + 1);
	const bool cut = n > shown_bytes;
	if (cut)
		for (n = shown_bytes; n > 0 && ((unsigned char)r->field[n] & 0xc0) == 0x80;)
			--n;  // not inside a UTF-8 character
	memcpy(start, r->field, n);
	start[n] = '\0';
	r->shown[0] = '"';
	sm_text_for_terminal(r->shown + 1, start);
	strcat(r->shown, cut ? "\"..." : "\"");
	return r->shown;
}

// A problem at `at` on the line that starts at place.start, line place.line; NULL, with
// r->out_of_memory set, when its message cannot be allocated (a NULL problem is no problem).
static char* problem_at(reader* r, line_place place, size_t at, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static char* problem_at(reader* r, line_place place, size_t at, const char* format, ...)
{
	char message[640];  // a field as field_shown shows it (365 bytes at most), a variable and the rule
	va_list args;
	va_start(args, format);
	vsnprintf(message, sizeof message, format, args);
	va_end(args);
	char* text = malloc(strlen(message) + 48);
	if (text != NULL)
		sprintf(text, "%zu:%zu: %s", place.line, at - place.start + 1, message);
	else
		r->out_of_memory = true;
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
	r->field_place = r->here;
	if (!field_append(r, 0, '\0'))
		return NULL;
	r->field[0] = '\0';
	r->quoted = r->at < r->length && r->text[r->at] == '"';
	if (r->quoted) {
		const size_t open = r->at++;
		for (;;) {
			if (r->at >= r->length)
				return problem_at(r, r->field_place, open, "a quoted field is not closed");
			const char c = r->text[r->at++];
			if (c == '"' && (r->at >= r->length || r->text[r->at] != '"'))
				break;
			if (c == '"')
				r->at++;  // a doubled quote
			if (c == '\n') {
				r->here.line++;
				r->here.start = r->at;
			}
			if (!field_append(r, n++, c))
				return NULL;
		}
		if (!at_line_end(r) && r->text[r->at] != ',')
			return problem_at(r, r->here, r->at, "text after the closing quote of a field");
		return NULL;
	}
	while (!at_line_end(r) && r->text[r->at] != ',') {
		if (r->text[r->at] == '\r')
			return problem_at(r, r->here, r->at,
			                  "a carriage return without a line feed: lines end in LF or CRLF");
		if (!field_append(r, n++, r->text[r->at++]))
			return NULL;
	}
	return NULL;
}

// Moves past the line end (LF or CRLF) the reader is at.
static void next_line(reader* r)
{
	if (r->at < r->length && r->text[r->at] == '\r')
		r->at++;
	if (r->at < r->length) {
		r->at++;
		r->here.line++;
		r->here.start = r->at;
	}
}

static size_t digits(const char* text)
{
	size_t n = 0;
	while (text[n] >= '0' && text[n] <= '9')
		n++;
	return n;
}

// A finite decimal number as a result writes one: an optional sign, digits with an optional
// decimal point (at least one digit), an optional exponent; no white space, hexadecimal, inf or
// nan, which strtod would take.
static bool decimal_number(const char* text, double* value)
{
	const char* c = text + (*text == '+' || *text == '-');
	const size_t whole = digits(c);
	c += whole;
	size_t fraction = 0;
	if (*c == '.') {
		fraction = digits(c + 1);
		c += 1 + fraction;
	}
	if (whole + fraction == 0)
		return false;
	if (*c == 'e' || *c == 'E') {
		c += 1 + (c[1] == '+' || c[1] == '-');
		const size_t exponent = digits(c);
		if (exponent == 0)
			return false;
		c += exponent;
	}
	if (*c != '\0')
		return false;
	*value = strtod(text, NULL);
	return isfinite(*value);
}

// The header: "time", then columns the namer takes, each once, into csv->id[1 .. columns - 1]
// and names[]. named: a flag per id, false on entry.
static char* read_header(reader* r, const cli_csv_form* form, bool* named, cli_csv* csv, char** names)
{
	for (csv->columns = 0;; ++csv->columns) {
		const size_t start = r->at;
		char* problem = read_field(r);
		if (problem != NULL || r->out_of_memory)
			return problem;
		if (csv->columns == 0 && strcmp(r->field, "time") != 0)
			return problem_at(r, r->field_place, start, "the first column is %s, not \"time\"",
			                  field_shown(r));
		if (csv->columns > 0) {
			int32_t id = -1;
			cli_csv_values values = CLI_CSV_REAL;
			const char* refused = form->name_column(form->context, r->field, &id, &values);
			if (refused != NULL)
				return problem_at(r, r->field_place, start, "%s %s", field_shown(r), refused);
			if (named[id])
				return problem_at(r, r->field_place, start, "%s is named twice", field_shown(r));
			named[id] = true;
			csv->id[csv->columns] = id;
			csv->values_of[csv->columns] = values;
			names[csv->columns] = strdup(r->field);
			if (names[csv->columns] == NULL) {
				r->out_of_memory = true;
				return NULL;
			}
		}
		if (at_line_end(r)) {
			++csv->columns;
			return NULL;
		}
		r->at++;  // the comma
	}
}

// Appends a value to csv->values, grown as needed.
static bool append_value(reader* r, cli_csv* csv, size_t* capacity, size_t count, double value)
{
	if (count == *capacity) {
		const size_t grown = *capacity ? 2 * *capacity : 1024;
		double* values = realloc(csv->values, grown * sizeof(double));
		if (values == NULL) {
			r->out_of_memory = true;
			return false;
		}
		csv->values = values;
		*capacity = grown;
	}
	csv->values[count] = value;
	return true;
}

// The rows: a number per column (a whole one, or 0 or 1, where the namer said so), time never
// decreasing; no empty line (fmpy's read_csv takes none).
static char* read_rows(reader* r, const cli_csv_form* form, cli_csv* csv, char* const* names)
{
	double previous_time = -INFINITY;
	size_t capacity = 0, count = 0;
	csv->rows = 0;
	while (r->at < r->length) {
		if (at_line_end(r))
			return problem_at(r, r->here, r->at, "an empty line: %s has none", form->what);
		for (int32_t c = 0; c < csv->columns; c++) {
			const size_t start = r->at;
			char* problem = read_field(r);
			if (problem != NULL || r->out_of_memory)
				return problem;
			double value;
			if (r->quoted)
				return problem_at(r, r->field_place, start,
				                  "%s is quoted: %s writes its numbers without quotes", field_shown(r),
				                  form->what);
			if (!decimal_number(r->field, &value))
				return problem_at(r, r->field_place, start, "%s is not a finite decimal number",
				                  field_shown(r));
			if (c > 0 && csv->values_of[c] == CLI_CSV_INTEGER &&
			    !(value == floor(value) && value >= INT32_MIN && value <= INT32_MAX))
				return problem_at(r, r->field_place, start, "%s is an Integer variable: %s is no such value",
				                  names[c], field_shown(r));
			if (c > 0 && csv->values_of[c] == CLI_CSV_BOOLEAN && value != 0.0 && value != 1.0)
				return problem_at(r, r->field_place, start, "%s is a Boolean variable: %s is neither 0 nor 1",
				                  names[c], field_shown(r));
			// The times as the file gives them (0.1, not 0.10000000000000001): the fewest digits that
			// read back to them.
			if (c == 0 && value < previous_time) {
				char time[SM_NUMBER_TEXT_CAPACITY], previous[SM_NUMBER_TEXT_CAPACITY];
				sm_format_number(value, time);
				sm_format_number(previous_time, previous);
				return problem_at(r, r->field_place, start, "time %s s is before the previous row's %s s",
				                  time, previous);
			}
			if (c == 0)
				previous_time = value;
			const bool last = c == csv->columns - 1;
			if (at_line_end(r) != last)
				return problem_at(r, r->here, r->at, "%s: the header names %d columns",
				                  last ? "more fields than columns" : "fewer fields than columns",
				                  (int)csv->columns);
			if (!last)
				r->at++;  // the comma
			if (form->keep_values && !append_value(r, csv, &capacity, count++, value))
				return NULL;
		}
		csv->rows++;
		next_line(r);
	}
	if (csv->rows == 0)
		return problem_at(r, r->here, r->at, "no rows after the header");
	return NULL;
}

void cli_csv_free(cli_csv* csv)
{
	free(csv->id);
	free(csv->values_of);
	free(csv->values);
	memset(csv, 0, sizeof *csv);
}

// What is wrong with the text as a whole: empty, not text, or with a byte-order mark.
static char* whole_text_problem(reader* r)
{
	if (r->length == 0)
		return problem_at(r, r->here, 0, "an empty file");
	const char* nul = memchr(r->text, '\0', r->length);
	if (nul != NULL) {
		for (const char* c = r->text; c < nul; c++)
			if (*c == '\n') {
				r->here.line++;
				r->here.start = (size_t)(c + 1 - r->text);
			}
		return problem_at(r, r->here, (size_t)(nul - r->text), "a NUL byte: not a text file");
	}
	if (r->length >= 3 && memcmp(r->text, "\xEF\xBB\xBF", 3) == 0)
		return problem_at(r, r->here, 0, "a byte-order mark before the header: write the file without one");
	return NULL;
}

char* cli_csv_read(const char* text, size_t length, const cli_csv_form* form, cli_csv* csv,
                   bool* out_of_memory)
{
	reader r = {.text = text, .length = length, .here = {1, 0}};
	memset(csv, 0, sizeof *csv);
	char* refused = whole_text_problem(&r);
	*out_of_memory = r.out_of_memory;
	if (refused != NULL || r.out_of_memory)
		return refused;
	// At most one column per id, and time.
	const size_t most = (size_t)form->id_count + 1;
	bool* named = calloc(most, sizeof *named);
	char** names = calloc(most, sizeof *names);
	csv->id = calloc(most, sizeof *csv->id);
	csv->values_of = calloc(most, sizeof *csv->values_of);
	char* problem = NULL;
	if (named == NULL || names == NULL || csv->id == NULL || csv->values_of == NULL) {
		r.out_of_memory = true;
	} else {
		csv->id[0] = -1;
		problem = read_header(&r, form, named, csv, names);
		if (problem == NULL && !r.out_of_memory) {
			next_line(&r);
			problem = read_rows(&r, form, csv, names);
		}
	}
	for (size_t c = 0; names != NULL && c < most; c++)
		free(names[c]);
	free(names);
	free(named);
	free(r.field);
	*out_of_memory = r.out_of_memory;
	if (r.out_of_memory) {
		free(problem);
		problem = NULL;
	}
	if (problem != NULL || r.out_of_memory)
		cli_csv_free(csv);
	return problem;
}
