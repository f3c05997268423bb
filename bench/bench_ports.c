// A co-simulation host's calls at scale (bench/README.md, "Inputs and outputs at scale"): what
// each call costs against a model with many ports, through the FMU's entry points (linked in, as
// the FMU's C test does).
//
//   bench_ports N [TRIALS] [STEPS]
//
// The model: an n x n sheet (1 m square, 1 kg, the benchmark cloth's springs), no gravity, mass
// damping c = 1 1/s (a tunable parameter), at rest; every particle of its boundary a motion port
// (4 (n - 1) of them), 100 force ports and 100 probes among the inner particles. The host holds
// every input where it starts, as a master that writes all of them at every communication point
// does, with steps of 1 ms: the sheet stays at rest and CVODE takes one internal step per
// communication step, so that the calls' own costs are not hidden behind the integration. Prints
//   ports n=<n> particles=<P> motion=<M> inputs=<I> outputs=<O> set_us=<v> step_us=<v> get_us=<v>
//     step_alone_us=<v> init_ms=<v> retune_ms=<v> derivative_ms=<v>
// each the median over TRIALS trials (default 5) of the mean per call over STEPS communication
// steps (default 50): fmi2SetReal of every input, fmi2DoStep, fmi2GetReal of every output; a
// fmi2DoStep with no input set since the last (the integration alone); instantiation to the end
// of initialisation; fmi2SetReal of c (the model built again and taken by the simulation, the
// mean of 5); and fmi2GetDirectionalDerivative of every output along a seed of 1e-3 on every
// input (the mean of 5).
#define _XOPEN_SOURCE 700
#include "bench_args.h"
#include "bench_clock.h"
#include "fmu_model.h"

#include "fmi2Functions.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
	(void)env;
	(void)name;
	(void)category;
	if (status >= fmi2Warning)
		fprintf(stderr, "bench_ports: %s\n", message);
}

// The model file's text, malloc'ed.
static char* model_text(int n)
{
	size_t capacity = 4096 + 96 * (size_t)(4 * n + 200), k = 0;
	char* t = malloc(capacity);
	if (t == NULL)
		return NULL;
	k += (size_t)snprintf(
	    t + k, capacity - k,
	    "{\"springmass\": 1, \"name\": \"ports\", \"gravity\": [0, 0, 0], \"mass_damping\": \"c\",\n"
	    " \"parameters\": {\"c\": 1.0}, \"fmu\": {\"particle_variables\": false},\n"
	    " \"structures\": [{\"type\": \"sheet\", \"name\": \"s\", \"nu\": %d, \"nv\": %d, \"mass\": 1,\n"
	    "   \"structural\": {\"strain_stiffness\": 1000, \"strain_damping\": 2},\n"
	    "   \"shear\": {\"strain_stiffness\": 1000, \"strain_damping\": 2},\n"
	    "   \"bend\": {\"strain_stiffness\": 50, \"strain_damping\": 2}}],\n"
	    " \"ports\": [",
	    n, n);
	int ports = 0;
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			if (i == 0 || j == 0 || i == n - 1 || j == n - 1) {
				k += (size_t)snprintf(
				    t + k, capacity - k,
				    "%s\n  {\"name\": \"m%d\", \"particle\": \"s[%d,%d]\", \"kind\": \"motion\"}",
				    ports > 0 ? "," : "", ports, i, j);
				ports++;
			}
	// 200 inner particles (all of them on a smaller sheet) spread over the sheet, the first half
	// force ports, the rest probes.
	const int inner = (n - 2) * (n - 2), count = inner < 200 ? inner : 200;
	for (int q = 0; q < count; q++) {
		const int at = (int)((long)q * inner / count), i = 1 + at / (n - 2), j = 1 + at % (n - 2);
		k += (size_t)snprintf(t + k, capacity - k,
		                      ",\n  {\"name\": \"%c%d\", \"particle\": \"s[%d,%d]\", \"kind\": \"%s\"}",
		                      2 * q < count ? 'f' : 'q', q, i, j, 2 * q < count ? "force" : "probe");
	}
	snprintf(t + k, capacity - k, "]}\n");
	return t;
}

typedef struct figures {
	double set, step, get, alone, init, retune, derivative;  // [s]
} figures;

static int trial(const char* guid, const char* location, const fmi2ValueReference* in, const double* start,
                 int ni, const fmi2ValueReference* out, int no, fmi2ValueReference c, int steps, figures* f)
{
	fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
	double t0 = bench_now();
	fmi2Component fmu =
	    fmi2Instantiate("bench", fmi2CoSimulation, guid, location, &callbacks, fmi2False, fmi2False);
	if (fmu == NULL || fmi2SetupExperiment(fmu, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
	    fmi2EnterInitializationMode(fmu) != fmi2OK || fmi2ExitInitializationMode(fmu) != fmi2OK)
		return 1;
	f->init = bench_now() - t0;
	const double h = 1e-3;
	double t = 0.0, *values = malloc(((size_t)no + 1) * sizeof *values);
	if (values == NULL)
		return 1;
	*f = (figures){0.0, 0.0, 0.0, 0.0, f->init, 0.0, 0.0};
	// A few steps first: CVODE's first steps from rest are short.
	for (int k = -5; k < steps; k++, t += h) {
		const double a = bench_now();
		if (fmi2SetReal(fmu, in, (size_t)ni, start) != fmi2OK)
			return 1;
		const double b = bench_now();
		if (fmi2DoStep(fmu, t, h, fmi2True) != fmi2OK)
			return 1;
		const double d = bench_now();
		if (fmi2GetReal(fmu, out, (size_t)no, values) != fmi2OK)
			return 1;
		const double e = bench_now();
		if (k >= 0) {
			f->set += (b - a) / steps;
			f->step += (d - b) / steps;
			f->get += (e - d) / steps;
		}
	}
	for (int k = 0; k < steps; k++, t += h) {
		const double a = bench_now();
		if (fmi2DoStep(fmu, t, h, fmi2True) != fmi2OK)
			return 1;
		f->alone += (bench_now() - a) / steps;
	}
	double* seeds = malloc((size_t)ni * sizeof *seeds);
	if (seeds == NULL)
		return 1;
	for (int i = 0; i < ni; i++)
		seeds[i] = 1e-3;
	for (int k = 0; k < 5; k++) {
		const double a = bench_now();
		if (fmi2GetDirectionalDerivative(fmu, out, (size_t)no, in, (size_t)ni, seeds, values) != fmi2OK)
			return 1;
		f->derivative += (bench_now() - a) / 5;
	}
	free(seeds);
	for (int k = 0; k < 5; k++) {
		const double value = k % 2 ? 1.0 : 1.0 + 1e-6, a = bench_now();
		if (fmi2SetReal(fmu, &c, 1, &value) != fmi2OK)
			return 1;
		f->retune += (bench_now() - a) / 5;
	}
	free(values);
	fmi2FreeInstance(fmu);
	return 0;
}

int main(int argc, char** argv)
{
	int n = 64, trials = 5, steps = 50;
	if ((argc > 1 && !bench_read_count(argv[1], 16, 4096, &n)) ||
	    (argc > 2 && !bench_read_count(argv[2], 1, 1000, &trials)) ||
	    (argc > 3 && !bench_read_count(argv[3], 1, 1000000, &steps))) {
		fprintf(stderr, "usage: bench_ports N [TRIALS] [STEPS] (N from 16 to 4096, TRIALS from 1 to 1000, "
		                "STEPS from 1 to 1000000)\n");
		return 2;
	}
	char* text = model_text(n);
	char dir[] = "/tmp/springmass-bench-ports-XXXXXX";
	if (text == NULL || mkdtemp(dir) == NULL)
		return 1;
	char path[1100], location[1100];
	snprintf(path, sizeof path, "%s/model.json", dir);
	snprintf(location, sizeof location, "file://%s", dir);
	// From here on every way out removes the model file and its folder (done:).
	int status = 1;
	fmi2ValueReference *in = NULL, *out = NULL;
	double *start = NULL, *set = NULL;
	bool have_table = false;
	fmu_table table;
	FILE* file = fopen(path, "wb");
	if (file == NULL || fputs(text, file) == EOF || fclose(file) != 0) {
		fprintf(stderr, "bench_ports: cannot write %s\n", path);
		goto done;
	}
	sm_error err;
	sm_document* doc = sm_document_parse(text, strlen(text), "ports", &err);
	if (doc == NULL || fmu_table_create(doc, text, strlen(text), NULL, 0, &table, &err) != SM_OK) {
		fprintf(stderr, "bench_ports: %s\n", err.message);
		sm_document_destroy(doc);
		goto done;
	}
	have_table = true;
	const int particles = (int)sm_document_particle_count(doc);
	sm_document_destroy(doc);
	in = malloc((size_t)table.count * sizeof *in);
	out = malloc((size_t)table.count * sizeof *out);
	start = malloc((size_t)table.count * sizeof *start);
	set = malloc((size_t)trials * 7 * sizeof *set);
	if (in == NULL || out == NULL || start == NULL || set == NULL) {
		fprintf(stderr, "bench_ports: out of memory\n");
		goto done;
	}
	fmi2ValueReference c = 0;
	int ni = 0, no = 0;
	for (int32_t i = 0; i < table.count; i++) {
		const fmu_variable* v = &table.variables[i];
		if (v->type == FMU_REAL && v->causality == FMU_INPUT) {
			start[ni] = v->start_real;
			in[ni++] = (fmi2ValueReference)i;
		} else if (v->type == FMU_REAL && v->causality == FMU_OUTPUT) {
			out[no++] = (fmi2ValueReference)i;
		} else if (strcmp(v->name, "c") == 0) {
			c = (fmi2ValueReference)i;
		}
	}
	double *step = set + trials, *get = step + trials, *alone = get + trials, *init = alone + trials,
	       *retune = init + trials, *derivative = retune + trials;
	for (int r = 0; r < trials; r++) {
		figures f = {0};
		if (trial(table.guid, location, in, start, ni, out, no, c, steps, &f) != 0) {
			fprintf(stderr, "bench_ports: a call failed\n");
			goto done;
		}
		set[r] = f.set, step[r] = f.step, get[r] = f.get, alone[r] = f.alone, init[r] = f.init,
		retune[r] = f.retune, derivative[r] = f.derivative;
	}
	printf("ports n=%d particles=%d motion=%d inputs=%d outputs=%d set_us=%.1f step_us=%.1f get_us=%.1f "
	       "step_alone_us=%.1f init_ms=%.2f retune_ms=%.2f derivative_ms=%.2f\n",
	       n, particles, 4 * (n - 1), ni, no, 1e6 * bench_median(set, trials),
	       1e6 * bench_median(step, trials), 1e6 * bench_median(get, trials),
	       1e6 * bench_median(alone, trials), 1e3 * bench_median(init, trials),
	       1e3 * bench_median(retune, trials), 1e3 * bench_median(derivative, trials));
	status = 0;
done:
	remove(path);
	remove(dir);
	if (have_table)
		fmu_table_destroy(&table);
	free(text), free(in), free(out), free(start), free(set);
	return status;
}
