// The command-line tool's helpers that shape what a user reads: library messages with the model
// file's names put beside the indices they give (cli_write_named).
#define _POSIX_C_SOURCE 200809L

#include "cli_common.h"
#include "test_harness.h"

#include <stdlib.h>
#include <string.h>

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

// Whether cli_warn_coarse_tolerances warns about text's model at the default tolerances (1e-8 m,
// 1e-6 m/s), spring `disabled` (when >= 0) disabled first; what it writes goes to *written.
static int warns(const char* text, int32_t disabled, char** written)
{
	sm_error err;
	sm_document* doc = sm_document_parse(text, strlen(text), "x.json", &err);
	sm_model* model = NULL;
	if (doc == NULL || sm_document_build(doc, &model, &err) != SM_OK) {
		sm_document_destroy(doc);
		return -1;
	}
	if (disabled >= 0)
		sm_model_set_spring_enabled(model, disabled, false);
	const sm_simulation_def def = sm_default_simulation_def();
	size_t size = 0;
	*written = NULL;
	FILE* f = open_memstream(written, &size);
	const bool warned = f != NULL && cli_warn_coarse_tolerances(f, "w: ", model, &def);
	if (f != NULL)
		fclose(f);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return warned;
}

// The model's scales are those of its shortest enabled spring (sm_motion_scales): its rest length,
// or its initial length for a zero-length one (the particles' distance, skipped where it is 0),
// and that length times the bound of the highest angular frequency. A 1 kg bob 1 m from a fixed
// anchor on a 1 N/m spring of rest length 1 um (omega of order 1 rad/s: speeds of order 1e-6 m/s)
// is resolved to the default tolerances only at 1e-8 m / 1e-6 m = 1e-2 of its scale, above
// SM_COARSE_TOLERANCE (1e-4) for both: warned about, its length being the rest length, not the
// 1 m the particles start apart. A zero-length spring between coincident particles beside it
// has no length to go by and changes nothing; the same spring disabled leaves only one of 1 m
// (1e-8 of it), and a position tolerance below 1e-4 of 1 um (1e-11 m) alone is resolved: no
// warning in either case, as both tolerances must be coarse.
static int test_coarse_tolerances_go_by_the_shortest_enabled_spring(void)
{
	static const char short_spring[] =
	    "{\"springmass\": 1, \"name\": \"x\", \"gravity\": [0, 0, 0], \"particles\": [{\"name\": \"a\", "
	    "\"position\": [0, 0, 0], \"fixed\": true}, {\"name\": \"b\", \"position\": [1, 0, 0], \"mass\": 1}, "
	    "{\"name\": \"c\", \"position\": [1, 0, 0], \"fixed\": true}, {\"name\": \"d\", \"position\": [2, 0, 0], "
	    "\"fixed\": true}], \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 1, \"rest_length\": 1e-6}, "
	    "{\"a\": \"b\", \"b\": \"c\", \"stiffness\": 1, \"rest_length\": 0}, {\"a\": \"b\", \"b\": \"d\", "
	    "\"stiffness\": 1}]}";
	char* written = NULL;
	ENSURE(warns(short_spring, -1, &written) == 1);
	// The bob's Gershgorin row is 3 x (1 N/m) / (1 kg): it moves at up to 1e-6 sqrt(3) m/s, and
	// the tolerances that suit it are 1e-8 of its scales.
	ENSURE(written != NULL &&
	       strcmp(written,
	              "w: the absolute tolerances, 1e-08 m and 1e-06 m/s, are coarse for this model: its "
	              "shortest spring is 1e-06 m and moves at up to 1.73e-06 m/s at its highest frequency, "
	              "so its motion is resolved only to them (about 1e-8 of these scales: atol_position "
	              "1e-14 m, atol_velocity 2e-14 m/s)\n") == 0);
	free(written);
	ENSURE(warns(short_spring, 0, &written) == 0);
	ENSURE(written != NULL && written[0] == '\0');
	free(written);
	sm_error err;
	sm_document* doc = sm_document_parse(short_spring, sizeof short_spring - 1, "x.json", &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	sm_simulation_def def = sm_default_simulation_def();
	def.absolute_tolerance_position = 1e-11;
	ENSURE(!cli_warn_coarse_tolerances(stderr, "", model, &def));
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_names_follow_whole_indices);
	RUN_TEST(test_coarse_tolerances_go_by_the_shortest_enabled_spring);
	return TEST_SUMMARY();
}
