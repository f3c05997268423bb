// Tests of the FMU's entry points called directly (no importer), so that the sanitizers and the
// leak checker see every path: life cycle, closed form, misuse, state round trip, reset.
#define _XOPEN_SOURCE 700
#include "fmu_model.h"
#include "physics_fixtures.h"
#include "test_harness.h"

#include "fmi2Functions.h"

#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// tests/python/models/driven_oscillator.json: m = 2 kg, k = 50 N/m, l0 = 0.5 m, x0 = 0.7 m.
#define MODEL SPRINGMASS_SOURCE_DIR "/tests/python/models/driven_oscillator.json"

typedef struct log_record {
	int errors;
	char last[1024];
} log_record;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
	(void)name;
	(void)category;
	log_record* log = env;
	if (status >= fmi2Error)
		log->errors++;
	snprintf(log->last, sizeof log->last, "%s", message);
}

typedef struct fixture {
	fmu_table table;
	char guid[40];
	const char* text;  // the model file
	size_t length;
	char resources[1024];
	log_record log;
	fmi2CallbackFunctions callbacks;
} fixture;

// Writes the model file into a resources folder under the build's temporary directory and
// builds the table (for value references and the GUID).
static int setup(fixture* f)
{
	memset(f, 0, sizeof *f);
	FILE* in = fopen(MODEL, "rb");
	if (!in)
		return 1;
	static char text[1 << 16];
	size_t n = fread(text, 1, sizeof text, in);
	fclose(in);
	char dir[] = "/tmp/springmass-fmu-test-XXXXXX";
	if (!mkdtemp(dir))
		return 1;
	char path[1100];
	snprintf(path, sizeof path, "%s/model.json", dir);
	FILE* out = fopen(path, "wb");
	if (!out)
		return 1;
	fwrite(text, 1, n, out);
	fclose(out);
	snprintf(f->resources, sizeof f->resources, "file://%s", dir);
	f->text = text;
	f->length = n;
	sm_error err;
	sm_document* doc = sm_document_parse(text, n, MODEL, &err);
	if (!doc) {
		printf("  %s\n", err.message);
		return 1;
	}
	sm_status st = fmu_table_create(doc, text, n, NULL, 0, &f->table, &err);
	sm_document_destroy(doc);
	if (st != SM_OK)
		return 1;
	memcpy(f->guid, f->table.guid, 40);
	f->callbacks.logger = logger;
	f->callbacks.componentEnvironment = &f->log;
	return 0;
}

static void teardown(fixture* f)
{
	char path[1100];
	const char* dir = f->resources + strlen("file://");
	snprintf(path, sizeof path, "%s/model.json", dir);
	remove(path);
	snprintf(path, sizeof path, "%s/" FMU_PARAMETERS_RESOURCE, dir);
	remove(path);
	remove(dir);
	fmu_table_destroy(&f->table);
}

static fmi2ValueReference vr(const fixture* f, const char* name)
{
	for (int32_t i = 0; i < f->table.count; ++i) {
		if (strcmp(f->table.variables[i].name, name) == 0)
			return (fmi2ValueReference)i;
	}
	return 0xffffffffu;
}

static double get(fmi2Component c, const fixture* f, const char* name)
{
	fmi2ValueReference r = vr(f, name);
	double value = NAN;
	fmi2GetReal(c, &r, 1, &value);
	return value;
}

static fmi2Component start(fixture* f, const char* name)
{
	fmi2Component c = fmi2Instantiate(name, fmi2CoSimulation, f->guid, f->resources, &f->callbacks, fmi2False,
	                                  fmi2False);
	if (!c)
		return NULL;
	fmi2ValueReference r[3] = {vr(f, "solver.rtol"), vr(f, "solver.atol_position"), vr(f, "solver.atol_velocity")};
	double tight[3] = {1e-10, 1e-12, 1e-10};
	if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
	    fmi2EnterInitializationMode(c) != fmi2OK || fmi2SetReal(c, r, 3, tight) != fmi2OK ||
	    fmi2ExitInitializationMode(c) != fmi2OK) {
		fmi2FreeInstance(c);
		return NULL;
	}
	return c;
}

static int test_closed_form(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	fmi2Component c = start(&f, "closed_form");
	ENSURE(c != NULL);
	// x(t) = l0 + (x0 - l0) cos(w t), w = sqrt(k/m): at rtol 1e-10 the error over 1 s stays well
	// below 1e-6 m.
	double w = sqrt(50.0 / 2.0);
	for (int n = 0; n < 100; ++n) {
		ENSURE_STATUS(fmi2DoStep(c, n * 0.01, 0.01, fmi2True), fmi2OK);
		double t = (n + 1) * 0.01;
		ENSURE_NEAR(get(c, &f, "tip.x"), 0.5 + 0.2 * cos(w * t), 1e-6);
		ENSURE_NEAR(get(c, &f, "base.fx"), 50.0 * (get(c, &f, "tip.x") - 0.5), 1e-9);
	}
	ENSURE_STATUS(fmi2Terminate(c), fmi2OK);
	fmi2FreeInstance(c);
	teardown(&f);
	return 0;
}

static int test_misuse(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	ENSURE(fmi2Instantiate("wrong", fmi2CoSimulation, "{00000000-0000-0000-0000-000000000000}", f.resources,
	                       &f.callbacks, fmi2False, fmi2False) == NULL);
	ENSURE(strstr(f.log.last, "does not match") != NULL);
	ENSURE(fmi2Instantiate("nores", fmi2CoSimulation, f.guid, "file:///nonexistent", &f.callbacks, fmi2False,
	                       fmi2False) == NULL);
	fmi2Component c = fmi2Instantiate("misuse", fmi2CoSimulation, f.guid, f.resources, &f.callbacks, fmi2False,
	                                  fmi2False);
	ENSURE(c != NULL);
	ENSURE_STATUS(fmi2DoStep(c, 0.0, 0.1, fmi2True), fmi2Error);
	ENSURE(strstr(f.log.last, "illegal call sequence") != NULL);
	ENSURE_STATUS(fmi2EnterInitializationMode(c), fmi2OK);
	ENSURE_STATUS(fmi2ExitInitializationMode(c), fmi2OK);
	fmi2ValueReference bad = 99999, force = vr(&f, "tip.fx");
	double value = 0.0, nan_value = NAN;
	ENSURE_STATUS(fmi2GetReal(c, &bad, 1, &value), fmi2Error);
	ENSURE_STATUS(fmi2GetReal(c, NULL, 1, NULL), fmi2Error);
	ENSURE_STATUS(fmi2SetReal(c, &force, 1, &nan_value), fmi2Error);
	ENSURE_STATUS(fmi2DoStep(c, 1.0, 0.1, fmi2True), fmi2Error);
	ENSURE(strstr(f.log.last, "does not match") != NULL);
	ENSURE_STATUS(fmi2DoStep(c, 0.0, 0.1, fmi2True), fmi2OK);
	ENSURE_STATUS(fmi2Reset(c), fmi2OK);
	ENSURE_STATUS(fmi2EnterInitializationMode(c), fmi2OK);
	ENSURE_STATUS(fmi2ExitInitializationMode(c), fmi2OK);
	ENSURE_STATUS(fmi2DoStep(c, 0.0, 0.1, fmi2True), fmi2OK);
	ENSURE_STATUS(fmi2GetReal(c, NULL, 0, NULL), fmi2OK);
	fmi2FreeInstance(c);
	fmi2FreeInstance(NULL);
	teardown(&f);
	return 0;
}

static int test_state_round_trip(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	fmi2Component c = start(&f, "state");
	ENSURE(c != NULL);
	fmi2ValueReference force = vr(&f, "tip.fx");
	double one = 1.0;
	ENSURE_STATUS(fmi2SetReal(c, &force, 1, &one), fmi2OK);
	for (int n = 0; n < 10; ++n)
		ENSURE_STATUS(fmi2DoStep(c, n * 0.01, 0.01, fmi2True), fmi2OK);
	fmi2FMUstate state = NULL;
	ENSURE_STATUS(fmi2GetFMUstate(c, &state), fmi2OK);
	size_t size = 0;
	ENSURE_STATUS(fmi2SerializedFMUstateSize(c, state, &size), fmi2OK);
	fmi2Byte* bytes = malloc(size);
	ENSURE(bytes != NULL);
	ENSURE_STATUS(fmi2SerializeFMUstate(c, state, bytes, size), fmi2OK);
	double first[20], second[20], third[20];
	for (int n = 0; n < 20; ++n) {
		ENSURE_STATUS(fmi2DoStep(c, 0.1 + n * 0.01, 0.01, fmi2True), fmi2OK);
		first[n] = get(c, &f, "tip.x");
	}
	ENSURE_STATUS(fmi2SetFMUstate(c, state), fmi2OK);
	for (int n = 0; n < 20; ++n) {
		ENSURE_STATUS(fmi2DoStep(c, 0.1 + n * 0.01, 0.01, fmi2True), fmi2OK);
		second[n] = get(c, &f, "tip.x");
	}
	// A fresh instance from the serialised bytes.
	fmi2Component d = start(&f, "restored");
	ENSURE(d != NULL);
	fmi2FMUstate restored = NULL;
	ENSURE_STATUS(fmi2DeSerializeFMUstate(d, bytes, size, &restored), fmi2OK);
	ENSURE_STATUS(fmi2SetFMUstate(d, restored), fmi2OK);
	for (int n = 0; n < 20; ++n) {
		ENSURE_STATUS(fmi2DoStep(d, 0.1 + n * 0.01, 0.01, fmi2True), fmi2OK);
		third[n] = get(d, &f, "tip.x");
	}
	// Identical continuations, bit for bit.
	ENSURE(memcmp(first, second, sizeof first) == 0);
	ENSURE(memcmp(first, third, sizeof first) == 0);
	ENSURE_STATUS(fmi2DeSerializeFMUstate(d, bytes, size - 8, &restored), fmi2Error);
	ENSURE_STATUS(fmi2FreeFMUstate(c, &state), fmi2OK);
	ENSURE_STATUS(fmi2FreeFMUstate(d, &restored), fmi2OK);
	free(bytes);
	fmi2FreeInstance(c);
	fmi2FreeInstance(d);
	teardown(&f);
	return 0;
}

static int test_model_description_lists_every_variable_once(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	char* xml = fmu_model_description(&f.table, NULL);
	ENSURE(xml != NULL);
	int count = 0;
	for (const char* p = xml; (p = strstr(p, "<ScalarVariable ")) != NULL; ++p)
		++count;
	ENSURE(count == f.table.count);
	ENSURE(strstr(xml, f.guid) != NULL);
	ENSURE(strstr(xml, "name=\"base.fx\"") != NULL && strstr(xml, "name=\"p[1].vz\"") != NULL);
	// Numbers in their shortest form that reads back exactly: the default tolerance 1e-6 as
	// "1e-06" (not 9.9999999999999995e-07), and every Real start value back bit for bit.
	ENSURE(strstr(xml, "tolerance=\"1e-06\"") != NULL);
	for (int32_t i = 0; i < f.table.count; ++i) {
		const fmu_variable* v = &f.table.variables[i];
		if (v->type != FMU_REAL || !v->has_start)
			continue;
		char reference[48];
		snprintf(reference, sizeof reference, "valueReference=\"%d\"", (int)i);
		const char* at = strstr(xml, reference);
		ENSURE(at != NULL);
		at = strstr(at, "start=\"");
		ENSURE(at != NULL);
		ENSURE(strtod(at + strlen("start=\""), NULL) == v->start_real);
	}
	free(xml);
	teardown(&f);
	return 0;
}

// Writes resources/parameters.txt (length bytes) beside the model file and sets the fixture's GUID
// to the one of both.
static int write_parameters(fixture* f, const char* parameters, size_t length)
{
	char path[1100];
	snprintf(path, sizeof path, "%s/" FMU_PARAMETERS_RESOURCE, f->resources + strlen("file://"));
	FILE* out = fopen(path, "wb");
	if (!out)
		return 1;
	const bool written = fwrite(parameters, 1, length, out) == length;
	if (fclose(out) != 0 || !written)
		return 1;
	fmu_package_guid(f->text, f->length, parameters, length, f->guid);
	return 0;
}

// Values set at packaging (resources/parameters.txt) are the model's at instantiation and after
// every reset: k = 200 N/m gives w = sqrt(k/m) = 10 rad/s.
static int test_parameter_values(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	char plain[40];
	memcpy(plain, f.guid, 40);
	ENSURE(write_parameters(&f, "k=200\nd=0\n", 10) == 0);
	ENSURE(strcmp(plain, f.guid) != 0);
	ENSURE(fmi2Instantiate("plain", fmi2CoSimulation, plain, f.resources, &f.callbacks, fmi2False, fmi2False) == NULL);
	ENSURE(strstr(f.log.last, "with its parameter values resources/parameters.txt") != NULL);
	fmi2Component c = start(&f, "set");
	ENSURE(c != NULL);
	ENSURE(get(c, &f, "k") == 200.0);
	for (int n = 0; n < 10; ++n)
		ENSURE_STATUS(fmi2DoStep(c, n * 0.01, 0.01, fmi2True), fmi2OK);
	ENSURE_NEAR(get(c, &f, "tip.x"), 0.5 + 0.2 * cos(1.0), 1e-6);
	fmi2ValueReference k = vr(&f, "k");
	double eighty = 80.0;
	ENSURE_STATUS(fmi2SetReal(c, &k, 1, &eighty), fmi2OK);
	ENSURE_STATUS(fmi2Reset(c), fmi2OK);
	ENSURE_STATUS(fmi2EnterInitializationMode(c), fmi2OK);
	ENSURE(get(c, &f, "k") == 200.0);
	fmi2FreeInstance(c);
	// Under a decimal comma (where the machine has one) the values are read as written.
	if (setlocale(LC_NUMERIC, "de_DE.UTF-8") != NULL) {
		ENSURE(write_parameters(&f, "k=62.5\n", 7) == 0);
		c = fmi2Instantiate("comma", fmi2CoSimulation, f.guid, f.resources, &f.callbacks, fmi2False, fmi2False);
		setlocale(LC_NUMERIC, "C");
		ENSURE(c != NULL);
		ENSURE(get(c, &f, "k") == 62.5);
		fmi2FreeInstance(c);
	}
	teardown(&f);
	return 0;
}

// A file of parameter values edited by hand (with the GUID made to match) is refused by
// fmi2Instantiate with a message naming its line, never taken in part.
static int test_parameter_values_refused(void)
{
#define TEXT(literal) literal, sizeof literal - 1
	static const struct {
		const char* text;
		size_t length;
		const char* message;
	} cases[] = {
	    {TEXT(""), "parameters.txt:1: empty"},
	    {TEXT("k200\n"), "parameters.txt:1: expected NAME=VALUE, got \"k200\""},
	    {TEXT("=5\n"), "parameters.txt:1: expected NAME=VALUE"},
	    {TEXT("k=60\n\n"), "parameters.txt:2: expected NAME=VALUE, got \"\""},
	    {TEXT("k=6\0\n"), "parameters.txt:1: expected NAME=VALUE, got \"k=6\\x00\""},
	    {TEXT("k=abc\n"), "parameters.txt:1: \"k=abc\": the value is not a finite number"},
	    {TEXT("k=1e999\n"), "not a finite number"},
	    {TEXT("k=60\r\n"), "\"k=60\\x0d\": the value is not a finite number"},
	    {TEXT("k= 60\n"), "\"k= 60\": the value is not written as the packager writes it (60)"},
	    {TEXT("k=+60\n"), "\"k=+60\": the value is not written as the packager writes it (60)"},
	    {TEXT("k=0x3c\n"), "\"k=0x3c\": the value is not written as the packager writes it (60)"},
	    {TEXT("k=60.0\n"), "\"k=60.0\": the value is not written as the packager writes it (60)"},
	    {TEXT("k=1e-400\n"), "\"k=1e-400\": the value is not written as the packager writes it (0)"},
	    {TEXT("k=" "1111111111" "1111111111" "1111111111" "1111111111" "1111111111" "1111111111"
	          "1111111111" "1111111111" "1111111111" "1111111111" "1111111111" "1111111111" "1111111111" "\n"),
	     "the value is longer than 127 bytes"},
	    {TEXT("zz=1\n"), "parameters.txt:1: \"zz=1\": the model has no parameter named \"zz\""},
	    {TEXT("k=60\nm=1\nk=70"), "parameters.txt:3: parameter k is set again (first on line 1)"},
	    {TEXT("d=1\nm=-1\n"),
	     "parameters.txt:2: \"m=-1\": resources/model.json: particles[1].mass: parameter m = -1 must be > 0"},
	};
#undef TEXT
	fixture f;
	ENSURE(setup(&f) == 0);
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
		ENSURE(write_parameters(&f, cases[i].text, cases[i].length) == 0);
		f.log.last[0] = '\0';
		ENSURE(fmi2Instantiate("edited", fmi2CoSimulation, f.guid, f.resources, &f.callbacks, fmi2False, fmi2False) ==
		       NULL);
		if (strstr(f.log.last, cases[i].message) == NULL) {
			printf("  case %zu: logged '%s', expected '%s'\n", i, f.log.last, cases[i].message);
			return 1;
		}
	}
	teardown(&f);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// Random call sequences against the FMI 2.0 Co-Simulation state machine
// ---------------------------------------------------------------------------------------------

// The states of FMI 2.0's table of allowed calls (section 4.2.4 of the standard) that this FMU
// reaches (its fmi2DoStep is synchronous: no stepInProgress, no stepCanceled).
enum { S_INSTANTIATED, S_INITIALIZATION, S_STEP_COMPLETE, S_STEP_FAILED, S_TERMINATED };
#define IN(state, ...) state_in((state), (const int[]){__VA_ARGS__, -1})
static bool state_in(int state, const int* states)
{
	for (; *states >= 0; ++states)
		if (*states == state)
			return true;
	return false;
}

// What the test expects of the instance: its state, its start time and time, whether the force input is one no
// step can take, and the saved FMU states (the state machine's state, the times and the inputs
// are part of what fmi2GetFMUstate saves).
#define SLOTS 3
typedef struct expectation {
	int state;
	double start, time;  // [s]; time NAN after a discarded step (the FMU knows where it stopped)
	bool huge;
	fmi2FMUstate slot[SLOTS];
	int slot_state[SLOTS];
	double slot_start[SLOTS], slot_time[SLOTS];
	bool slot_huge[SLOTS];
} expectation;

enum {
	OP_SETUP, OP_ENTER, OP_EXIT, OP_STEP, OP_STEP_AT_WRONG_TIME, OP_STEP_NEGATIVE, OP_SET_FORCE, OP_SET_HUGE, OP_SET_NAN,
	OP_GET, OP_GET_UNKNOWN, OP_TERMINATE, OP_RESET, OP_GET_STATE, OP_SET_STATE, OP_FREE_STATE, OP_SERIALIZE,
	OP_STATUS, OP_DERIVATIVE, OP_LOGGING, OP_CANCEL, OP_INPUT_DERIVATIVES, OP_OUTPUT_DERIVATIVES, OP_COUNT
};

// 500 internal steps per communication step at most (the file's 100 000 would make each
// discarded step take a tenth of a second), set where the fixed parameter can be set.
static fmi2Status limit_steps(fmi2Component c, const fixture* f)
{
	const fmi2ValueReference max_steps = vr(f, "solver.max_steps");
	const fmi2Integer limit = 500;
	return fmi2SetInteger(c, &max_steps, 1, &limit);
}

// One call of kind op with arguments drawn from r. Returns the FMU's status and sets *expected to
// what the standard's table and the arguments call for, updating the expectation for the calls
// that succeed; `value` receives a value read (NAN if none).
static fmi2Status call(fmi2Component c, const fixture* f, int op, rng* r, expectation* e, fmi2Status* expected,
                       double* value)
{
	const int st = e->state;
	const bool running = IN(st, S_INITIALIZATION, S_STEP_COMPLETE, S_STEP_FAILED, S_TERMINATED);
	const bool settable = IN(st, S_INSTANTIATED, S_INITIALIZATION, S_STEP_COMPLETE);
	const bool stepped = IN(st, S_STEP_COMPLETE, S_STEP_FAILED, S_TERMINATED);
	const int k = (int)rng_uniform(r, 0.0, SLOTS - 1e-9);
	fmi2ValueReference force = vr(f, "tip.fx"), position = vr(f, "tip.x"), unknown = 0xfffffff0u;
	fmi2ValueReference base_force = vr(f, "base.fx"), base_position = vr(f, "base.x");
	*value = NAN;
	*expected = fmi2Error;
	fmi2Status status;
	switch (op) {
	case OP_SETUP: {
		const double start = rng_uniform(r, 0.0, 1.0) < 0.5 ? 0.0 : 0.25;
		status = fmi2SetupExperiment(c, fmi2False, 0.0, start, fmi2False, 0.0);
		if (st == S_INSTANTIATED) {
			*expected = fmi2OK;
			e->start = start;
		}
		return status;
	}
	case OP_ENTER:
		status = fmi2EnterInitializationMode(c);
		if (st == S_INSTANTIATED) {
			*expected = fmi2OK;
			e->state = S_INITIALIZATION;
			e->time = e->start;
		}
		return status;
	case OP_EXIT:
		status = fmi2ExitInitializationMode(c);
		if (st == S_INITIALIZATION) {
			*expected = fmi2OK;
			e->state = S_STEP_COMPLETE;
		}
		return status;
	case OP_STEP: {
		const double h = rng_uniform(r, 0.0, 1.0) < 0.5 ? 0.01 : 0.05;
		status = fmi2DoStep(c, e->time, h, fmi2False);
		if (st == S_STEP_COMPLETE && e->huge) {
			*expected = fmi2Discard;
			e->state = S_STEP_FAILED;
			e->time = NAN;
		} else if (st == S_STEP_COMPLETE) {
			*expected = fmi2OK;
			e->time += h;
		}
		return status;
	}
	case OP_STEP_AT_WRONG_TIME:
		return fmi2DoStep(c, e->time + 0.5, 0.01, fmi2False);
	case OP_STEP_NEGATIVE:
		return fmi2DoStep(c, e->time, -0.01, fmi2False);
	case OP_SET_FORCE: {
		const double fx = rng_uniform(r, -1.0, 1.0);  // [N]: the bob stays within a few cm
		if (settable) {
			*expected = fmi2OK;
			e->huge = false;
		}
		return fmi2SetReal(c, &force, 1, &fx);
	}
	case OP_SET_HUGE: {
		// 1e200 N on 2 kg: the next step cannot be integrated and ends in a discard.
		const double fx = 1e200;
		if (settable) {
			*expected = fmi2OK;
			e->huge = true;
		}
		return fmi2SetReal(c, &force, 1, &fx);
	}
	case OP_SET_NAN: {
		const double nan_value = NAN;
		return fmi2SetReal(c, &force, 1, &nan_value);
	}
	case OP_GET:
		if (running)
			*expected = fmi2OK;
		return fmi2GetReal(c, &position, 1, value);
	case OP_GET_UNKNOWN: {
		double ignored;
		return fmi2GetReal(c, &unknown, 1, &ignored);
	}
	case OP_TERMINATE:
		status = fmi2Terminate(c);
		if (IN(st, S_STEP_COMPLETE, S_STEP_FAILED)) {
			*expected = fmi2OK;
			e->state = S_TERMINATED;
		}
		return status;
	case OP_RESET:
		*expected = fmi2OK;
		e->state = S_INSTANTIATED;
		e->start = e->time = 0.0;
		e->huge = false;
		status = fmi2Reset(c);
		return status == fmi2OK ? limit_steps(c, f) : status;
	case OP_GET_STATE:
		*expected = fmi2OK;
		status = fmi2GetFMUstate(c, &e->slot[k]);
		e->slot_state[k] = st;
		e->slot_start[k] = e->start;
		e->slot_time[k] = e->time;
		e->slot_huge[k] = e->huge;
		return status;
	case OP_SET_STATE:
		if (e->slot[k] == NULL)
			return fmi2SetFMUstate(c, NULL);
		*expected = fmi2OK;
		e->state = e->slot_state[k];
		e->start = e->slot_start[k];
		e->time = e->slot_time[k];
		e->huge = e->slot_huge[k];
		return fmi2SetFMUstate(c, e->slot[k]);
	case OP_FREE_STATE:
		*expected = fmi2OK;  // freeing a NULL state is a no-op
		return fmi2FreeFMUstate(c, &e->slot[k]);
	case OP_SERIALIZE: {
		// Round trip of slot k through its bytes into slot (k + 1) % SLOTS.
		const int to = (k + 1) % SLOTS;
		if (e->slot[k] == NULL || e->slot[to] != NULL)
			return fmi2SerializedFMUstateSize(c, NULL, &(size_t){0});
		size_t size = 0;
		if ((status = fmi2SerializedFMUstateSize(c, e->slot[k], &size)) != fmi2OK)
			return status;
		fmi2Byte* bytes = malloc(size);
		if (bytes == NULL)
			return fmi2Fatal;
		status = fmi2SerializeFMUstate(c, e->slot[k], bytes, size);
		if (status == fmi2OK)
			status = fmi2DeSerializeFMUstate(c, bytes, size, &e->slot[to]);
		free(bytes);
		*expected = fmi2OK;
		e->slot_state[to] = e->slot_state[k];
		e->slot_start[to] = e->slot_start[k];
		e->slot_time[to] = e->slot_time[k];
		e->slot_huge[to] = e->slot_huge[k];
		return status;
	}
	case OP_STATUS: {
		fmi2Status step_status = fmi2Fatal;
		if (IN(st, S_STEP_COMPLETE, S_STEP_FAILED, S_TERMINATED))
			*expected = fmi2OK;
		status = fmi2GetStatus(c, fmi2DoStepStatus, &step_status);
		if (status == fmi2OK && step_status != (st == S_STEP_FAILED ? fmi2Discard : fmi2OK))
			return fmi2Fatal;
		return status;
	}
	case OP_DERIVATIVE: {
		// d base.fx / d base.x: minus the stiffness along the spring, which stays on the x axis
		// (the force port pushes along x only): -k = -50 N/m, up to the rounding of the factored
		// blocks (K_xx = beta + (k - beta) with beta = k (1 - l0/L)): a few ulps, 1e-12 relative.
		const double seed = 1.0;
		if (running)
			*expected = fmi2OK;
		status = fmi2GetDirectionalDerivative(c, &base_force, 1, &base_position, 1, &seed, value);
		if (status == fmi2OK && !(fabs(*value + 50.0) <= 1e-12 * 50.0)) {
			printf("  d base.fx / d base.x = %.17g N/m, expected -50\n", *value);
			return fmi2Fatal;
		}
		*value = NAN;
		return status;
	}
	case OP_LOGGING: {
		// On for events, solver statistics and errors, or off for the statistics alone: errors
		// stay reported (logging on with categories logs those categories only).
		const fmi2String categories[] = {"logSolver", "logEvents", "logStatusError"};
		*expected = fmi2OK;
		const bool on = rng_uniform(r, 0.0, 1.0) < 0.5;
		return fmi2SetDebugLogging(c, on, on ? 3 : 1, categories);
	}
	case OP_CANCEL:  // there is never a step in progress
		return fmi2CancelStep(c);
	case OP_INPUT_DERIVATIVES: {
		// None taken (canInterpolateInputs is false): an empty call is allowed where setting is.
		const size_t n = rng_uniform(r, 0.0, 1.0) < 0.5 ? 0 : 1;
		const fmi2Integer order = 1;
		const double slope = 1.0;
		if (settable && n == 0)
			*expected = fmi2OK;
		return fmi2SetRealInputDerivatives(c, &force, n, &order, &slope);
	}
	case OP_OUTPUT_DERIVATIVES: {
		const fmi2Integer order = 1;
		double slope;
		if (stepped)
			*expected = fmi2OK;
		return fmi2GetRealOutputDerivatives(c, &position, 0, &order, &slope);
	}
	}
	return fmi2Fatal;
}

// The bob's x over 20 steps of 0.01 s with tip.fx = 0.3 N from a reset instance.
static int reference_run(fmi2Component c, const fixture* f, double* x)
{
	fmi2ValueReference force = vr(f, "tip.fx");
	const double fx = 0.3;
	if (fmi2Reset(c) != fmi2OK || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
	    fmi2EnterInitializationMode(c) != fmi2OK || fmi2SetReal(c, &force, 1, &fx) != fmi2OK ||
	    fmi2ExitInitializationMode(c) != fmi2OK)
		return 1;
	for (int n = 0; n < 20; ++n) {
		if (fmi2DoStep(c, n * 0.01, 0.01, fmi2True) != fmi2OK)
			return 1;
		x[n] = get(c, f, "tip.x");
	}
	return 0;
}

// Random sequences of FMI calls, right and wrong, in every state the FMU reaches: every call the
// standard's table does not allow in the current state, and every call with a bad argument,
// returns fmi2Error with a logged message and changes nothing (the next calls behave as if it had
// not been made); every allowed call with good arguments succeeds, and the values read are finite.
// After each sequence the instance, reset, repeats a fresh instance's run bit for bit. 1000
// sequences of 60 calls, with the sanitizers in CI.
static int test_random_call_sequences_follow_the_state_machine(void)
{
	fixture f;
	ENSURE(setup(&f) == 0);
	fmi2Component fresh = fmi2Instantiate("fresh", fmi2CoSimulation, f.guid, f.resources, &f.callbacks, fmi2False,
	                                      fmi2False);
	ENSURE(fresh != NULL);
	double expected_x[20], x[20];
	ENSURE(reference_run(fresh, &f, expected_x) == 0);
	fmi2FreeInstance(fresh);
	static const char* const names[OP_COUNT] = {"SetupExperiment",
	                                            "EnterInitializationMode",
	                                            "ExitInitializationMode",
	                                            "DoStep",
	                                            "DoStep at a wrong time",
	                                            "DoStep of a negative size",
	                                            "SetReal",
	                                            "SetReal 1e200 N",
	                                            "SetReal NaN",
	                                            "GetReal",
	                                            "GetReal of an unknown reference",
	                                            "Terminate",
	                                            "Reset",
	                                            "GetFMUstate",
	                                            "SetFMUstate",
	                                            "FreeFMUstate",
	                                            "Serialize and DeSerialize",
	                                            "GetStatus",
	                                            "GetDirectionalDerivative",
	                                            "SetDebugLogging",
	                                            "CancelStep",
	                                            "SetRealInputDerivatives",
	                                            "GetRealOutputDerivatives"};
	static const char* const state_names[] = {"instantiated", "initialization mode", "step complete", "step failed",
	                                          "terminated"};
	rng r = {20261201};
	int visits[S_TERMINATED + 1] = {0}, discards = 0;  // calls made in each state; steps discarded
	for (int sequence = 0; sequence < 1000; ++sequence) {
		fmi2Component c = fmi2Instantiate("random", fmi2CoSimulation, f.guid, f.resources, &f.callbacks, fmi2False,
		                                  fmi2False);
		ENSURE(c != NULL);
		ENSURE_STATUS(limit_steps(c, &f), fmi2OK);
		expectation e = {.state = S_INSTANTIATED};
		for (int n = 0; n < 60; ++n) {
			// The life cycle's calls twice as often as the others, so that sequences get far.
			int op = (int)rng_uniform(&r, 0.0, OP_COUNT + 4 - 1e-9);
			if (op >= OP_COUNT)
				op = op - OP_COUNT;  // SETUP, ENTER, EXIT, STEP again
			const int errors = f.log.errors, before = e.state;
			visits[before]++;
			fmi2Status expected;
			double value;
			const fmi2Status status = call(c, &f, op, &r, &e, &expected, &value);
			const bool logged = f.log.errors > errors;
			if (status != expected || (expected == fmi2Error) != logged || (!isnan(value) && !isfinite(value)) ||
			    (expected == fmi2OK && op == OP_GET && !isfinite(value))) {
				printf("  sequence %d, call %d: %s in state %s returned %d, expected %d (%s); last message: %s\n",
				       sequence, n, names[op], state_names[before], (int)status, (int)expected,
				       logged ? "an error logged" : "no error logged", f.log.last);
				return 1;
			}
			discards += expected == fmi2Discard;
		}
		ENSURE(reference_run(c, &f, x) == 0);
		ENSURE(memcmp(x, expected_x, sizeof x) == 0);
		for (int k = 0; k < SLOTS; ++k)
			ENSURE_STATUS(fmi2FreeFMUstate(c, &e.slot[k]), fmi2OK);
		fmi2FreeInstance(c);
	}
	// Every state was visited often, and steps were discarded: the sequences went everywhere.
	for (int state = S_INSTANTIATED; state <= S_TERMINATED; ++state)
		ENSURE(visits[state] >= 1000);
	ENSURE(discards >= 100);
	teardown(&f);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_closed_form);
	RUN_TEST(test_misuse);
	RUN_TEST(test_state_round_trip);
	RUN_TEST(test_model_description_lists_every_variable_once);
	RUN_TEST(test_parameter_values);
	RUN_TEST(test_parameter_values_refused);
	RUN_TEST(test_random_call_sequences_follow_the_state_machine);
	return TEST_SUMMARY();
}
