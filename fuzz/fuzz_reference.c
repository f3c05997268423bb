// libFuzzer target for the reference results `springmass fmu --reference` checks before it packs
// them (fmu_reference_problem in fmu/fmu_reference.c), against the variables of the bundled
// hanging rope's FMU. Any bytes must be either taken or refused with a message that starts with
// "LINE:COLUMN: " within the input's lines; what is taken must start with a "time" column and
// hold a line after the header.
#define _XOPEN_SOURCE 700
#include "fmu_model.h"
#include "fmu_reference.h"
#include "text_file.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int* argc, char*** argv);
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

// The FMU's variable table, made once and only read afterwards.
static fmu_table table;

int LLVMFuzzerInitialize(int* argc, char*** argv)
{
	(void)argc;
	(void)argv;
	const char* path = SPRINGMASS_FUZZ_MODEL;
	size_t length = 0;
	const char* problem = NULL;
	char* text = text_file_read(path, &length, &problem);
	sm_error err;
	sm_document* doc = text != NULL ? sm_document_parse(text, length, path, &err) : NULL;
	if (doc == NULL || fmu_table_create(doc, text, length, NULL, 0, &table, &err) != SM_OK) {
		fprintf(stderr, "fuzz_reference: cannot make the table of %s\n", path);
		abort();
	}
	sm_document_destroy(doc);
	free(text);
	return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	bool out_of_memory = false;
	char* problem = fmu_reference_problem((const char*)data, size, &table, &out_of_memory);
	if (out_of_memory)
		abort();
	if (problem != NULL) {
		// "LINE:COLUMN: " with LINE at most the input's lines and COLUMN at least 1.
		size_t lines = 1;
		for (size_t i = 0; i < size; i++)
			lines += data[i] == '\n';
		unsigned long line = 0, column = 0;
		int used = 0;
		if (sscanf(problem, "%lu:%lu: %n", &line, &column, &used) != 2 || used == 0 || line < 1 ||
		    line > lines || column < 1)
			abort();
		// COLUMN within its line: at most one past the line's last byte (its LF).
		size_t line_start = 0;
		for (unsigned long l = 1; l < line; l++)
			line_start =
			    (size_t)((const uint8_t*)memchr(data + line_start, '\n', size - line_start) - data) + 1;
		const uint8_t* end = memchr(data + line_start, '\n', size - line_start);
		const size_t line_length = (end != NULL ? (size_t)(end - data) : size) - line_start;
		if (column > line_length + 1)
			abort();
		free(problem);
		return 0;
	}
	// Taken: no NUL byte, a header that starts with time, plain or quoted, and a line after it.
	const bool plain =
	    size >= 5 && memcmp(data, "time", 4) == 0 && (data[4] == ',' || data[4] == '\r' || data[4] == '\n');
	const bool quoted = size >= 7 && memcmp(data, "\"time\"", 6) == 0;
	if (memchr(data, '\0', size) != NULL || !(plain || quoted) || memchr(data, '\n', size) == NULL)
		abort();
	return 0;
}
