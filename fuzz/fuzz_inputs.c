// libFuzzer target for the input signals of `springmass run --input` (tools/cli_inputs.c): any
// bytes are read as signals for a small model with a force port, a motion port and a spring that
// breaks, and what is taken drives a short run. A refusal must name a line of the input; a run
// must end with its positions finite or with a failure that says why, never a crash, a leak or a
// hang (the run is short and its steps limited).
#include "cli_inputs.h"

#include "springmass/model_file.h"
#include "springmass/simulation.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int* argc, char*** argv);
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

// An anchor (motion port "base") holds a bob (force port "tip") on a spring that breaks at 50 %
// strain; a probe on a second bob hanging from the first.
static const char model_text[] =
    "{\n"
    "  \"springmass\": 1,\n"
    "  \"name\": \"fuzz_inputs\",\n"
    "  \"description\": \"A bob on a breakable spring from a motion port, pushed by a force port.\",\n"
    "  \"gravity\": [0, 0, -9.81],\n"
    "  \"particles\": [\n"
    "    { \"name\": \"anchor\", \"position\": [0, 0, 0], \"fixed\": true },\n"
    "    { \"name\": \"bob\", \"position\": [0.5, 0, 0], \"mass\": 0.2 },\n"
    "    { \"name\": \"low\", \"position\": [0.5, 0, -0.3], \"mass\": 0.1 }\n"
    "  ],\n"
    "  \"springs\": [\n"
    "    { \"a\": \"anchor\", \"b\": \"bob\", \"stiffness\": 80, \"damping\": 0.5, \"rest_length\": 0.5,\n"
    "      \"break_strain\": 0.5 },\n"
    "    { \"a\": \"bob\", \"b\": \"low\", \"stiffness\": 40, \"damping\": 0.2, \"rest_length\": 0.3 }\n"
    "  ],\n"
    "  \"ports\": [\n"
    "    { \"name\": \"base\", \"particle\": \"anchor\", \"kind\": \"motion\" },\n"
    "    { \"name\": \"tip\", \"particle\": \"bob\", \"kind\": \"force\" },\n"
    "    { \"name\": \"below\", \"particle\": \"low\", \"kind\": \"probe\" }\n"
    "  ]\n"
    "}\n";

// The document, parsed once and only read afterwards.
static sm_document* doc;

int LLVMFuzzerInitialize(int* argc, char*** argv)
{
	(void)argc;
	(void)argv;
	sm_error err;
	doc = sm_document_parse(model_text, sizeof model_text - 1, "fuzz_inputs.json", &err);
	if (doc == NULL) {
		fprintf(stderr, "fuzz_inputs: the model does not parse: %s\n", err.message);
		abort();
	}
	return 0;
}

// A refusal names a line of the input: "LINE:" with 1 <= LINE <= its lines.
static void check_refusal(const char* problem, const uint8_t* data, size_t size)
{
	size_t lines = 1;
	for (size_t i = 0; i < size; i++)
		lines += data[i] == '\n';
	unsigned long line = 0;
	int used = 0;
	if (sscanf(problem, "%lu:%n", &line, &used) != 1 || used == 0 || line < 1 || line > lines)
		abort();
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	char* problem = NULL;
	cli_inputs* in = cli_inputs_parse((const char*)data, size, doc, &problem);
	if (in == NULL) {
		if (problem == NULL)
			abort();  // out of memory, which a fuzzer's inputs of at most a few kB never cause
		check_refusal(problem, data, size);
		free(problem);
		return 0;
	}
	sm_model* model = NULL;
	sm_error err;
	if (sm_document_build(doc, &model, &err) != SM_OK || cli_inputs_drive(in, model) != SM_OK)
		abort();
	sm_simulation_def def = sm_default_simulation_def();
	def.max_steps = 2000;
	sm_simulation* sim = sm_simulation_create(model, &def, &err);
	if (sim == NULL)
		abort();
	char why[SM_ERROR_MESSAGE_CAPACITY + 128] = "";
	sm_status st = cli_inputs_apply(in, sim, why, sizeof why);
	// Five rows over 0.05 s, as `run --output-interval 0.01` would write them.
	for (int k = 1; k <= 5 && st == SM_OK; k++)
		st = cli_inputs_advance(in, sim, 0.01 * k, 0.05, why, sizeof why);
	if (st == SM_OK) {
		const double* x = sm_simulation_positions(sim);
		for (int i = 0; i < 9; i++)
			if (!isfinite(x[i]))
				abort();
	} else if (why[0] == '\0' && sm_simulation_last_error(sim)[0] == '\0') {
		abort();  // a failure that does not say why
	}
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	cli_inputs_destroy(in);
	return 0;
}
