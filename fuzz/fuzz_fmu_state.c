// libFuzzer target for serialised FMU states (fmi2DeSerializeFMUstate in fmu/fmu_state.c), the
// bytes an FMI master hands back to the FMU: untrusted. The FMU's entry points are called directly
// on one instance. A state must either be refused with fmi2Error, a logged message and the instance
// unchanged, or be accepted; an accepted state is then set (fmi2SetFMUstate, which may refuse it
// the same way) and stepped, which must end with fmi2OK and finite outputs or with fmi2Error or
// fmi2Discard and a logged message; either way the instance must take a known-good state again
// and step from it to where it got from that state before any input, bit for bit.
//
// The input is one control byte and then the bytes of a serialised state:
//   bit 0  keep the checksum as given (else it is recomputed over the mutated bytes, since random
//          bytes would almost never pass it and the checks behind it would go unfuzzed)
//
// With SPRINGMASS_FUZZ_WRITE_SEEDS set to a folder, the target writes real states of its own model
// there as seeds (fuzz/run.sh does) and exits.
#define _XOPEN_SOURCE 700
#include "fmu_model.h"

#include "fmi2Functions.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int* argc, char*** argv);
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

#define CONTROL_KEEP_CHECKSUM 0x01u
// The step after a state was set [s]: a few solver steps, its set-up and the root functions of
// the breakable spring.
#define STEP 1e-3
// Internal steps allowed per step. A state may carry any limit up to INT32_MAX; with forces near
// the largest doubles, a step then runs for minutes to end at the limit with a clean error. A
// recomputed checksum lowers a limit above this one (a limit out of range is kept, so that its
// check is fuzzed), and the same paths are reached with fewer steps.
#define MAX_STEPS 2000
// Where fmu_state.c keeps what the target reads or rewrites (its layout comment, and the enums
// I_* and D_* there): the checksum, solver.max_steps and the time, after the magic and the GUID.
// Initialisation checks them against a state the FMU wrote, so that a change of the layout stops
// the target rather than leaving it to fuzz the checksum test alone.
#define HEADER_START 48
#define CHECKSUM_OFFSET (HEADER_START + 8 * 1)
#define MAX_STEPS_OFFSET (HEADER_START + 8 * 11)
#define TIME_OFFSET (HEADER_START + 8 * 16)
#define MIN_STATE_BYTES (TIME_OFFSET + 8)

// A rope of n = 3 segments (n sets the structure: a constant of the FMU) hung from a motion port;
// a bob, a force port, on a spring that breaks at strain "strain", and tied to a fixed anchor by a
// zero-length spring. So every part of a state has content: particles, springs that can be
// broken, parameters of each kind, and the inputs of both kinds of port.
static const char model_text[] =
    "{\n"
    "  \"springmass\": 1,\n"
    "  \"name\": \"fuzz_fmu_state\",\n"
    "  \"description\": \"A rope from a motion port, a bob on a breakable spring and a zero-length spring.\",\n"
    "  \"parameters\": { \"n\": 3, \"E\": 100.0, \"m\": 0.4, \"strain\": 0.3 },\n"
    "  \"gravity\": [0, 0, -9.81],\n"
    "  \"mass_damping\": 0.1,\n"
    "  \"particles\": [\n"
    "    { \"name\": \"anchor\", \"position\": [1.0, 0, -1.0], \"fixed\": true },\n"
    "    { \"name\": \"bob\", \"position\": [1.0, 0, -0.35], \"mass\": \"m\" }\n"
    "  ],\n"
    "  \"structures\": [\n"
    "    { \"type\": \"rope\", \"name\": \"rope\", \"start\": [0, 0, 0], \"end\": [1, 0, 0], \"segments\": \"n\",\n"
    "      \"mass\": 0.3, \"structural\": { \"strain_stiffness\": \"E\", \"strain_damping\": 0.5 } }\n"
    "  ],\n"
    "  \"springs\": [\n"
    "    { \"a\": \"rope[3]\", \"b\": \"bob\", \"stiffness\": 60, \"damping\": 0.3, \"rest_length\": 0.3,\n"
    "      \"break_strain\": \"strain\" },\n"
    "    { \"a\": \"anchor\", \"b\": \"bob\", \"kind\": \"zero_length\", \"stiffness\": 2, \"damping\": 0.1 }\n"
    "  ],\n"
    "  \"ports\": [\n"
    "    { \"name\": \"hook\", \"particle\": \"rope[0]\", \"kind\": \"motion\" },\n"
    "    { \"name\": \"tip\", \"particle\": \"bob\", \"kind\": \"force\" }\n"
    "  ],\n"
    "  \"simulation\": { \"stop_time\": 1.0, \"output_interval\": 0.01 }\n"
    "}\n";

// What the instance logged: messages of status fmi2Discard or worse, and the last one.
typedef struct log_record {
	long problems;
	char last[1024];
} log_record;

// The instance every input runs against, and the state it is put back into before each input,
// so that what an input does depends on it alone. libFuzzer's entry point has no context
// argument, so the fixture is a file-scope pointer, set once in LLVMFuzzerInitialize: the rule
// against global state is for the library and the FMU, which this program only calls.
typedef struct fixture {
	fmu_table table;  // value references (indices into it) and the GUID
	fmi2ValueReference* reals;
	size_t real_count;
	fmi2ValueReference* integers;
	size_t integer_count;
	fmi2ValueReference* booleans;
	size_t boolean_count;
	fmi2ValueReference* strings;
	size_t string_count;
	log_record log;
	fmi2CallbackFunctions callbacks;
	fmi2Component instance;
	fmi2FMUstate good;  // the instance after a few steps
	double good_time;   // [s]
	// Every real after a step of STEP from the known-good state, before any input: every restore
	// of a state continues alike (fmu_state.c), so no input may change what the next one sees.
	double* good_step;
} fixture;

static fixture* the_fixture;

static void fail(const char* what, const char* message)
{
	fprintf(stderr, "fuzz_fmu_state: %s%s%s\n", what, message ? ": " : "", message ? message : "");
	abort();
}

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
	(void)name;
	(void)category;
	log_record* log = env;
	if (status >= fmi2Discard) {
		log->problems++;
		snprintf(log->last, sizeof log->last, "%s", message);
	}
}

// 64-bit FNV-1a over every byte but the checksum's own, as fmu_state.c defines it (state_checksum,
// a static helper there). The format fixes the hash, as test_fmu.c's forged states assume, so the
// target computes it itself rather than widen the FMU for it; initialisation checks it against a
// state the FMU wrote.
static uint64_t state_checksum(const unsigned char* bytes, size_t size)
{
	uint64_t hash = 14695981039346656037ull;
	for (size_t k = 0; k < size; k++)
		if (k < CHECKSUM_OFFSET || k >= CHECKSUM_OFFSET + 8)
			hash = (hash ^ bytes[k]) * 1099511628211ull;
	return hash;
}

static fmi2ValueReference reference(const fixture* f, const char* name)
{
	for (int32_t i = 0; i < f->table.count; ++i)
		if (strcmp(f->table.variables[i].name, name) == 0)
			return (fmi2ValueReference)i;
	fail("no variable", name);
	return 0;
}

static void set_real(fixture* f, const char* name, double value)
{
	const fmi2ValueReference r = reference(f, name);
	if (fmi2SetReal(f->instance, &r, 1, &value) != fmi2OK)
		fail("fmi2SetReal failed", f->log.last);
}

// A first time derivative of an input (fmi2SetRealInputDerivatives).
static void set_derivative(fixture* f, const char* name, double value)
{
	const fmi2ValueReference r = reference(f, name);
	const fmi2Integer order = 1;
	if (fmi2SetRealInputDerivatives(f->instance, &r, 1, &order, &value) != fmi2OK)
		fail("fmi2SetRealInputDerivatives failed", f->log.last);
}

static void step(fixture* f, double* t, double h)
{
	if (fmi2DoStep(f->instance, *t, h, fmi2True) != fmi2OK)
		fail("a step of the seed run failed", f->log.last);
	*t += h;
}

// The instance's state as bytes (malloc'd, *size set).
static unsigned char* serialized_state(fixture* f, size_t* size)
{
	fmi2FMUstate state = NULL;
	if (fmi2GetFMUstate(f->instance, &state) != fmi2OK ||
	    fmi2SerializedFMUstateSize(f->instance, state, size) != fmi2OK)
		fail("cannot get the instance's state", f->log.last);
	unsigned char* bytes = malloc(*size);
	if (bytes == NULL || fmi2SerializeFMUstate(f->instance, state, (fmi2Byte*)bytes, *size) != fmi2OK)
		fail("cannot serialise the instance's state", f->log.last);
	fmi2FreeFMUstate(f->instance, &state);
	return bytes;
}

// The instance's state now as a seed file in `folder` (none when folder is NULL) with the given
// control byte.
static void write_seed(fixture* f, const char* folder, int number, unsigned control)
{
	if (folder == NULL)
		return;
	size_t size = 0;
	unsigned char* bytes = serialized_state(f, &size);
	char path[4096];
	snprintf(path, sizeof path, "%s/fmu-state-%d", folder, number);
	const unsigned char first = (unsigned char)control;
	FILE* out = fopen(path, "wb");
	if (out == NULL || fwrite(&first, 1, 1, out) != 1 || fwrite(bytes, 1, size, out) != size ||
	    fclose(out) != 0)
		fail("cannot write a seed", path);
	free(bytes);
}

// Instantiates the model from a resources folder of its own, as an importer would an unzipped
// FMU; the folder is removed once the instance has read the model file.
static void instantiate(fixture* f)
{
	sm_error err = {SM_OK, ""};
	sm_document* doc = sm_document_parse(model_text, sizeof model_text - 1, "fuzz_fmu_state.json", &err);
	if (doc == NULL)
		fail("the model does not load", err.message);
	if (fmu_table_create(doc, model_text, sizeof model_text - 1, NULL, 0, &f->table, &err) != SM_OK)
		fail("no variable table", err.message);
	sm_document_destroy(doc);
	char dir[] = "/tmp/springmass-fuzz-fmu-state-XXXXXX";
	if (mkdtemp(dir) == NULL)
		fail("cannot make a resources folder", NULL);
	char path[sizeof dir + 16], location[sizeof dir + 16];
	snprintf(path, sizeof path, "%s/model.json", dir);
	snprintf(location, sizeof location, "file://%s", dir);
	FILE* out = fopen(path, "wb");
	if (out == NULL || fwrite(model_text, 1, sizeof model_text - 1, out) != sizeof model_text - 1 ||
	    fclose(out) != 0)
		fail("cannot write the model file", path);
	f->callbacks.logger = logger;
	f->callbacks.componentEnvironment = &f->log;
	f->instance = fmi2Instantiate("fuzz", fmi2CoSimulation, f->table.guid, location, &f->callbacks, fmi2False,
	                              fmi2False);
	remove(path);
	remove(dir);
	if (f->instance == NULL)
		fail("fmi2Instantiate failed", f->log.last);
	f->reals = malloc((size_t)f->table.count * sizeof *f->reals);
	f->integers = malloc((size_t)f->table.count * sizeof *f->integers);
	f->booleans = malloc((size_t)f->table.count * sizeof *f->booleans);
	f->strings = malloc((size_t)f->table.count * sizeof *f->strings);
	if (f->reals == NULL || f->integers == NULL || f->booleans == NULL || f->strings == NULL)
		abort();
	for (int32_t i = 0; i < f->table.count; ++i) {
		if (f->table.variables[i].type == FMU_REAL)
			f->reals[f->real_count++] = (fmi2ValueReference)i;
		else if (f->table.variables[i].type == FMU_INTEGER)
			f->integers[f->integer_count++] = (fmi2ValueReference)i;
		else if (f->table.variables[i].type == FMU_BOOLEAN)
			f->booleans[f->boolean_count++] = (fmi2ValueReference)i;
		else
			f->strings[f->string_count++] = (fmi2ValueReference)i;
	}
}

// One run of the model, with a state written as a seed at each stage: instantiated, in
// initialisation mode, under way with inputs and their derivatives set and not yet stepped with, after the
// bob's spring broke, terminated, and with other solver settings; one with its checksum kept. Keeps the state
// after a few steps as the fixture's known-good one.
static void run(fixture* f, const char* seeds)
{
	write_seed(f, seeds, 0, 0);
	if (fmi2SetupExperiment(f->instance, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
	    fmi2EnterInitializationMode(f->instance) != fmi2OK)
		fail("initialisation failed", f->log.last);
	set_real(f, "E", 120.0);
	write_seed(f, seeds, 1, 0);
	if (fmi2ExitInitializationMode(f->instance) != fmi2OK)
		fail("initialisation failed", f->log.last);
	double t = 0.0;
	for (int k = 0; k < 5; ++k)
		step(f, &t, 0.01);
	f->good_time = t;
	if (fmi2GetFMUstate(f->instance, &f->good) != fmi2OK)
		fail("cannot get the known-good state", f->log.last);
	set_real(f, "hook.x", 0.02);
	set_real(f, "hook.vx", 0.5);
	set_real(f, "tip.fx", 0.3);
	set_derivative(f, "hook.vx", -2.0);  // the hook decelerates, the force ramps
	set_derivative(f, "tip.fx", 5.0);
	write_seed(f, seeds, 2, 0);
	write_seed(f, seeds, 3, CONTROL_KEEP_CHECKSUM);
	step(f, &t, 0.01);
	// A force on the bob that breaks its spring within a few steps.
	set_real(f, "tip.fz", -40.0);
	set_real(f, "m", 0.5);
	for (int k = 0; k < 10; ++k)
		step(f, &t, 0.01);
	write_seed(f, seeds, 4, 0);
	if (fmi2Terminate(f->instance) != fmi2OK)
		fail("fmi2Terminate failed", f->log.last);
	write_seed(f, seeds, 5, 0);
	// Again from the start with other solver settings (fixed parameters: set in initialisation).
	const fmi2ValueReference method = reference(f, "solver.method");
	const fmi2ValueReference solver = reference(f, "solver.linear_solver");
	const fmi2ValueReference detection = reference(f, "solver.stability_limit_detection");
	const fmi2String adams = "adams", klu = "klu";
	const fmi2Boolean off = fmi2False;
	if (fmi2Reset(f->instance) != fmi2OK || fmi2EnterInitializationMode(f->instance) != fmi2OK ||
	    fmi2SetString(f->instance, &method, 1, &adams) != fmi2OK ||
	    fmi2SetString(f->instance, &solver, 1, &klu) != fmi2OK ||
	    fmi2SetBoolean(f->instance, &detection, 1, &off) != fmi2OK)
		fail("cannot change the solver", f->log.last);
	set_real(f, "solver.max_step", 0.002);
	if (fmi2ExitInitializationMode(f->instance) != fmi2OK)
		fail("initialisation failed", f->log.last);
	t = 0.0;
	step(f, &t, 0.01);
	write_seed(f, seeds, 6, 0);
}

int LLVMFuzzerInitialize(int* argc, char*** argv)
{
	(void)argc;
	(void)argv;
	fixture* f = calloc(1, sizeof *f);
	if (f == NULL)
		abort();
	instantiate(f);
	const char* seeds = getenv("SPRINGMASS_FUZZ_WRITE_SEEDS");
	if (seeds != NULL && seeds[0] != '\0') {
		run(f, seeds);
		fmi2FreeFMUstate(f->instance, &f->good);
		fmi2FreeInstance(f->instance);
		fmu_table_destroy(&f->table);
		free(f->reals);
		free(f->integers);
		free(f->booleans);
		free(f->strings);
		free(f);
		exit(0);
	}
	run(f, NULL);
	// The layout as the target reads it: the checksum, the time and the step limit of the state
	// kept.
	if (fmi2SetFMUstate(f->instance, f->good) != fmi2OK)
		fail("the known-good state does not restore", f->log.last);
	size_t size = 0;
	unsigned char* bytes = serialized_state(f, &size);
	uint64_t written;
	double time;
	int64_t max_steps;
	memcpy(&written, bytes + CHECKSUM_OFFSET, 8);
	memcpy(&time, bytes + TIME_OFFSET, 8);
	memcpy(&max_steps, bytes + MAX_STEPS_OFFSET, 8);
	const fmi2ValueReference r = reference(f, "solver.max_steps");
	fmi2Integer steps = 0;
	if (size < MIN_STATE_BYTES || written != state_checksum(bytes, size) || time != f->good_time ||
	    fmi2GetInteger(f->instance, &r, 1, &steps) != fmi2OK || max_steps != steps)
		fail("the FMU state's layout or checksum is no longer what the target reads; update the target",
		     NULL);
	free(bytes);
	f->good_step = malloc((f->real_count + 1) * sizeof *f->good_step);
	if (f->good_step == NULL || fmi2SetFMUstate(f->instance, f->good) != fmi2OK ||
	    fmi2DoStep(f->instance, f->good_time, STEP, fmi2True) != fmi2OK ||
	    fmi2GetReal(f->instance, f->reals, f->real_count, f->good_step) != fmi2OK)
		fail("no step from the known-good state", f->log.last);
	the_fixture = f;
	return 0;
}

// What a master can see of the instance: every variable (the strings are the solver settings,
// whose names are static: the pointers compare as the texts).
typedef struct observed {
	fmi2Status status;
	double* reals;
	fmi2Integer* integers;
	fmi2Boolean* booleans;
	fmi2String* strings;
} observed;

static observed observe(fixture* f)
{
	observed o;
	o.reals = malloc((f->real_count + 1) * sizeof *o.reals);
	o.integers = malloc((f->integer_count + 1) * sizeof *o.integers);
	o.booleans = malloc((f->boolean_count + 1) * sizeof *o.booleans);
	o.strings = malloc((f->string_count + 1) * sizeof *o.strings);
	if (o.reals == NULL || o.integers == NULL || o.booleans == NULL || o.strings == NULL)
		abort();
	o.status = fmi2GetReal(f->instance, f->reals, f->real_count, o.reals);
	if (o.status == fmi2OK)
		o.status = fmi2GetInteger(f->instance, f->integers, f->integer_count, o.integers);
	if (o.status == fmi2OK)
		o.status = fmi2GetBoolean(f->instance, f->booleans, f->boolean_count, o.booleans);
	if (o.status == fmi2OK)
		o.status = fmi2GetString(f->instance, f->strings, f->string_count, o.strings);
	return o;
}

static bool same(const fixture* f, const observed* a, const observed* b)
{
	return a->status == fmi2OK && b->status == fmi2OK &&
	       memcmp(a->reals, b->reals, f->real_count * sizeof *a->reals) == 0 &&
	       memcmp(a->integers, b->integers, f->integer_count * sizeof *a->integers) == 0 &&
	       memcmp(a->booleans, b->booleans, f->boolean_count * sizeof *a->booleans) == 0 &&
	       memcmp(a->strings, b->strings, f->string_count * sizeof *a->strings) == 0;
}

static void forget(observed* o)
{
	free(o->reals);
	free(o->integers);
	free(o->booleans);
	free(o->strings);
}

// A refusal is fmi2Error with a message, and leaves the instance as `before`.
static void check_refusal(fixture* f, fmi2Status status, long problems, const observed* before,
                          const char* what)
{
	if (status != fmi2Error || f->log.problems == problems)
		fail(what, "refused without fmi2Error and a message");
	observed after = observe(f);
	if (!same(f, before, &after))
		fail(what, f->log.last);
	forget(&after);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
	fixture* f = the_fixture;
	if (size < 1)
		return 0;
	const unsigned control = data[0];
	const size_t n = size - 1;
	unsigned char* bytes = malloc(n > 0 ? n : 1);
	if (bytes == NULL)
		abort();
	memcpy(bytes, data + 1, n);
	if (!(control & CONTROL_KEEP_CHECKSUM) && n >= MIN_STATE_BYTES) {
		int64_t max_steps;
		memcpy(&max_steps, bytes + MAX_STEPS_OFFSET, 8);
		if (max_steps > MAX_STEPS && max_steps <= INT32_MAX) {
			max_steps = MAX_STEPS;
			memcpy(bytes + MAX_STEPS_OFFSET, &max_steps, 8);
		}
		const uint64_t hash = state_checksum(bytes, n);
		memcpy(bytes + CHECKSUM_OFFSET, &hash, 8);
	}
	if (fmi2SetFMUstate(f->instance, f->good) != fmi2OK)
		fail("the known-good state does not restore", f->log.last);
	observed before = observe(f);
	if (before.status != fmi2OK)
		fail("the known-good state cannot be read", f->log.last);

	fmi2FMUstate state = NULL;
	long problems = f->log.problems;
	const fmi2Status read = fmi2DeSerializeFMUstate(f->instance, (const fmi2Byte*)bytes, n, &state);
	if (read != fmi2OK) {
		if (state != NULL)
			fail("a refused state was handed out", NULL);
		check_refusal(f, read, problems, &before, "fmi2DeSerializeFMUstate");
	} else {
		problems = f->log.problems;
		const fmi2Status set = fmi2SetFMUstate(f->instance, state);
		if (set != fmi2OK) {
			check_refusal(f, set, problems, &before, "fmi2SetFMUstate");
		} else {
			double time;
			memcpy(&time, bytes + TIME_OFFSET, 8);
			problems = f->log.problems;
			const fmi2Status stepped = fmi2DoStep(f->instance, time, STEP, fmi2True);
			if (stepped == fmi2OK) {
				observed after = observe(f);
				if (after.status != fmi2OK)
					fail("the outputs after a step cannot be read", f->log.last);
				for (size_t k = 0; k < f->real_count; ++k)
					if (!isfinite(after.reals[k]))
						fail("a step from a set state succeeded with outputs not finite",
						     f->table.variables[f->reals[k]].name);
				forget(&after);
			} else if ((stepped != fmi2Error && stepped != fmi2Discard) || f->log.problems == problems) {
				fail("a step from a set state failed without fmi2Error or fmi2Discard and a message", NULL);
			}
		}
		// Whatever happened, the instance takes the known-good state again and steps from it to
		// where it got before any input, bit for bit.
		if (fmi2SetFMUstate(f->instance, f->good) != fmi2OK ||
		    fmi2DoStep(f->instance, f->good_time, STEP, fmi2True) != fmi2OK)
			fail("the instance is no longer usable after a state was set", f->log.last);
		observed again = observe(f);
		if (again.status != fmi2OK)
			fail("the outputs after a step from the known-good state cannot be read", f->log.last);
		for (size_t k = 0; k < f->real_count; ++k)
			if (memcmp(&again.reals[k], &f->good_step[k], sizeof again.reals[k]) != 0)
				fail("after a state was set, a step from the known-good state ends elsewhere than before",
				     f->table.variables[f->reals[k]].name);
		forget(&again);
	}
	if (fmi2FreeFMUstate(f->instance, &state) != fmi2OK || state != NULL)
		fail("fmi2FreeFMUstate failed", f->log.last);
	forget(&before);
	free(bytes);
	return 0;
}
