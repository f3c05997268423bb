// libFuzzer target for the model-file loader: any input must either be refused with a message
// or load; a loaded document must build, and its canonical form must load again to a model of
// the same size (the writer and the loader agree on every file the loader accepts).
#include "model_file_internal.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Models larger than this are refused early: the fuzzer looks for wrong handling of input,
// not for the time it takes to build a cloth of millions of particles.
#define FUZZ_MAX_ELEMENTS 20000

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc =
	    sm_document_parse_limited((const char*)data, size, "fuzz.json", FUZZ_MAX_ELEMENTS, &err);
	if (doc == NULL) {
		if (err.status == SM_OK || err.message[0] == '\0')
			abort();  // a refusal must say why
		return 0;
	}
	sm_model* model = NULL;
	if (sm_document_build(doc, &model, &err) != SM_OK)
		abort();
	char* text = sm_document_to_json(doc, &err);
	if (text == NULL)
		abort();
	sm_document* again = sm_document_parse_limited(text, strlen(text), "saved.json", FUZZ_MAX_ELEMENTS, &err);
	if (again == NULL) {
		fprintf(stderr, "canonical form does not load: %s\n", err.message);
		abort();
	}
	sm_model* rebuilt = NULL;
	if (sm_document_build(again, &rebuilt, &err) != SM_OK ||
	    sm_model_particle_count(rebuilt) != sm_model_particle_count(model) ||
	    sm_model_spring_count(rebuilt) != sm_model_spring_count(model) ||
	    sm_document_port_count(again) != sm_document_port_count(doc))
		abort();
	// Changing a parameter either works or is refused with the document unchanged.
	if (sm_document_parameter_count(doc) > 0) {
		const double before = sm_document_parameter_value(doc, 0);
		if (sm_document_set_parameter(doc, 0, before * 2.0 + 1.0, &err) != SM_OK &&
		    sm_document_parameter_value(doc, 0) != before)
			abort();
	}
	sm_model_destroy(rebuilt);
	sm_model_destroy(model);
	sm_document_destroy(again);
	free(text);
	sm_document_destroy(doc);
	return 0;
}
