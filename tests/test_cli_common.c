// The command-line tool's helpers that shape what a user reads: library messages with the model
// file's names put beside the indices they give (cli_write_named).
#define _POSIX_C_SOURCE 200809L

#include "cli_common.h"
#include "test_harness.h"

#include <stdlib.h>

// Particles a (index 0), b (1) and an unnamed one (2); springs 0 (a - b) and 1 (b - 2).
static const char model_text[] =
    "{\"springmass\": 1, \"name\": \"x\", \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0]},"
    " {\"name\": \"b\", \"position\": [1, 0, 0]}, {\"position\": [2, 0, 0]}],"
    " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 1}, {\"a\": \"b\", \"b\": 2, \"stiffness\": 1}]}";

// message as cli_write_named writes it, in a malloc'ed string.
static char* named(const sm_document* doc, const sm_model* model, const char* message)
{
	char* text = NULL;
	size_t size = 0;
	FILE* f = open_memstream(&text, &size);
	if (f == NULL)
		return NULL;
	cli_write_named(f, doc, model, message);
	fclose(f);
	return text;
}

// Whole indices after "particle", "particles" (each of a list joined by ", " and " and ") and
// "spring" get the names; a number that is not a whole index (1.5, 1e3, 2x), an index out of range
// (the particle or spring count itself), a word that only ends in "particle" and a sentence's full
// stop are left alone.
static int test_names_follow_whole_indices(void)
{
	sm_error err;
	sm_document* doc = sm_document_parse(model_text, sizeof model_text - 1, "x.json", &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	static const struct {
		const char* message;
		const char* expected;
	} cases[] = {
	    {"particle 0 is stuck", "particle 0 (a) is stuck"},
	    {"particles 0 and 1 meet", "particles 0 (a) and 1 (b) meet"},
	    {"particles 0, 2 and 1", "particles 0 (a), 2 and 1 (b)"},
	    {"spring 1 broke", "spring 1 (between b and particle 2) broke"},
	    {"at spring 0.", "at spring 0 (between a and b)."},
	    {"particle 1.5 m", "particle 1.5 m"},
	    {"spring 0.25 N", "spring 0.25 N"},
	    {"particle 1e3 N", "particle 1e3 N"},
	    {"particle 2x", "particle 2x"},
	    {"particle 3 of 3", "particle 3 of 3"},
	    {"spring 2 of 2", "spring 2 of 2"},
	    {"particles 1 and 3", "particles 1 (b) and 3"},
	    {"spring 99999999999999999999", "spring 99999999999999999999"},
	    {"subparticle 0", "subparticle 0"},
	    {"particle", "particle"},
	    {"particle 1", "particle 1 (b)"},
	};
	int failures = 0;
	for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
		char* text = named(doc, model, cases[c].message);
		ENSURE(text != NULL);
		if (strcmp(text, cases[c].expected) != 0) {
			printf("  \"%s\" gave \"%s\", expected \"%s\"\n", cases[c].message, text, cases[c].expected);
			failures++;
		}
		free(text);
	}
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return failures > 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_names_follow_whole_indices);
	return TEST_SUMMARY();
}
