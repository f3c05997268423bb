// Every bundled model has a reference result, tests/references/<model>.csv: what `springmass run`
// writes at rtol 1e-10 and atol 1e-12, 21 rows from 0 to the model's stop time (or a shorter
// horizon), with the command that made it as the file's first line (tests/references/update.sh
// writes them all). For each model in models/:
//
// - the reference is right: its rows conserve energy (kinetic + elastic + gravitational +
//   dissipated, as no bundled model has inputs or driven particles), and where no spring can
//   break, GSL's explicit rk8pd, an integrator independent of CVODE, gives the same columns;
// - the library reproduces it at the same tolerances, so that a change that moves any bundled
//   model's results fails here and must come with updated references;
// - the model's own settings (its file's tolerances) stay close to it.
#define _POSIX_C_SOURCE 200809L

#include "gsl_reference.h"
#include "springmass/model_file.h"
#include "springmass/simulation.h"
#include "test_harness.h"

#include <dirent.h>
#include <stdlib.h>

#ifndef SPRINGMASS_MODELS_DIR
#error "SPRINGMASS_MODELS_DIR must name the bundled models"
#endif
#ifndef SPRINGMASS_REFERENCES_DIR
#error "SPRINGMASS_REFERENCES_DIR must name the reference results"
#endif

// The tolerances the references are computed at, as update.sh passes them to `springmass run`.
#define REFERENCE_RTOL 1e-10
#define REFERENCE_ATOL 1e-12

// Right-hand sides GSL's integrator may evaluate per model (check_model says why).
#define GSL_BUDGET 120000L

enum { MAX_COLUMNS = 256, MAX_ROWS = 64 };

// The energy columns that end every row: kinetic, elastic, gravitational, dissipated, and the
// inputs' work [J].
enum { ENERGY_COLUMNS = 5 };

// A CSV of `springmass run`: column names, then rows of numbers (time first).
typedef struct table {
	char command[512];
	int columns;
	int rows;
	char names[MAX_COLUMNS][64];
	double values[MAX_ROWS][MAX_COLUMNS];
} table;

// The scale a column's bounds are relative to, that of the quantity it is a component of: the
// largest length over the rows of the port's position, velocity or force vector whose x, y or z
// it is (a component that stays near zero is as accurate as the others), or the largest of the
// energies.
static double column_scale(const table* t, int column)
{
	const int energies = t->columns - ENERGY_COLUMNS;
	double scale = 0.0;
	for (int r = 0; r < t->rows; r++) {
		if (column >= energies) {
			for (int q = energies; q < t->columns; q++)
				scale = fmax(scale, fabs(t->values[r][q]));
			continue;
		}
		const double* vector = t->values[r] + 1 + 3 * ((column - 1) / 3);
		scale = fmax(scale, sqrt(vector[0] * vector[0] + vector[1] * vector[1] + vector[2] * vector[2]));
	}
	return scale;
}

static int read_reference(const char* model, table* t)
{
	char path[2048];
	snprintf(path, sizeof path, "%s/%s.csv", SPRINGMASS_REFERENCES_DIR, model);
	FILE* f = fopen(path, "r");
	if (f == NULL)
		printf("  %s: no reference result; tests/references/update.sh writes it\n", path);
	ENSURE(f != NULL);
	static char line[1 << 16];
	ENSURE(fgets(line, sizeof line, f) != NULL);
	line[strcspn(line, "\n")] = '\0';
	ENSURE(strlen(line) < sizeof t->command);
	strcpy(t->command, line);
	char expected[512];
	snprintf(expected, sizeof expected, "# springmass run models/%s.json --t-end ", model);
	ENSURE(strncmp(line, expected, strlen(expected)) == 0);
	ENSURE(strstr(line, "--rtol 1e-10 --atol 1e-12") != NULL);
	ENSURE(fgets(line, sizeof line, f) != NULL);
	line[strcspn(line, "\n")] = '\0';
	t->columns = 0;
	for (char* name = strtok(line, ","); name != NULL; name = strtok(NULL, ",")) {
		ENSURE(t->columns < MAX_COLUMNS && strlen(name) < sizeof t->names[0]);
		strcpy(t->names[t->columns++], name);
	}
	ENSURE(t->columns >= 5 && strcmp(t->names[0], "time") == 0);
	t->rows = 0;
	while (fgets(line, sizeof line, f) != NULL) {
		ENSURE(t->rows < MAX_ROWS);
		char* p = line;
		for (int c = 0; c < t->columns; c++) {
			if (c > 0) {
				ENSURE(*p == ',');
				p++;
			}
			char* end;
			t->values[t->rows][c] = strtod(p, &end);
			ENSURE(end != p);
			p = end;
		}
		t->rows++;
	}
	fclose(f);
	ENSURE(t->rows >= 2 && t->values[0][0] == 0.0);
	return 0;
}

// The columns `springmass run` writes for a state, after the time: each port's (a motion port:
// the force f the model exerts on its particle [N]; the others: position x [m] and velocity v
// [m/s]), then the kinetic, elastic, gravitational and dissipated energies and the inputs' work [J].
// The names must be the reference's, in its order.
static int state_columns(const sm_document* doc, const double* x, const double* v, const double* f,
                         const double energies[ENERGY_COLUMNS], const table* reference, double* out)
{
	int c = 1;
	static const char* const axes[6] = {"x", "y", "z", "vx", "vy", "vz"};
	static const char* const force_axes[3] = {"fx", "fy", "fz"};
	for (int32_t k = 0; k < sm_document_port_count(doc); k++) {
		const sm_port port = sm_document_port(doc, k);
		const size_t i = 3 * (size_t)port.particle;
		const bool motion = port.kind == SM_PORT_MOTION;
		for (int q = 0; q < (motion ? 3 : 6); q++) {
			char name[128];
			snprintf(name, sizeof name, "%s.%s", port.name, motion ? force_axes[q] : axes[q]);
			ENSURE(c < reference->columns && strcmp(reference->names[c], name) == 0);
			out[c++] = motion ? f[i + (size_t)q] : q < 3 ? x[i + (size_t)q] : v[i + (size_t)q - 3];
		}
	}
	static const char* const energy_names[ENERGY_COLUMNS] = {
	    "energy.kinetic", "energy.elastic", "energy.gravity", "energy.dissipated", "energy.input"};
	for (int q = 0; q < ENERGY_COLUMNS; q++) {
		ENSURE(c < reference->columns && strcmp(reference->names[c], energy_names[q]) == 0);
		out[c++] = energies[q];
	}
	ENSURE(c == reference->columns);
	return 0;
}

// The model simulated by the library with the given settings to the reference's row times, each
// row interpolated from the steps of one advance to the last (as `springmass run` does).
static int simulate(const sm_document* doc, const sm_model* model, const sm_simulation_def* settings,
                    const table* reference, table* out)
{
	sm_error err;
	sm_simulation* sim = sm_simulation_create(model, settings, &err);
	if (sim == NULL)
		printf("  %s\n", err.message);
	ENSURE(sim != NULL);
	double* f = malloc(sizeof(double) * 3 * (size_t)sm_model_particle_count(model));
	ENSURE(f != NULL);
	const double t_end = reference->values[reference->rows - 1][0];
	*out = *reference;
	for (int r = 0; r < reference->rows; r++) {
		const double t = reference->values[r][0];
		if (r > 0 && sm_simulation_advance_interpolated(sim, t, t_end) != SM_OK)
			printf("  t = %g s: %s\n", t, sm_simulation_last_error(sim));
		ENSURE(sm_simulation_time(sim) == t);
		out->values[r][0] = t;
		// The simulation's own forces and energies: a broken spring is gone from its copy of
		// the model only.
		sm_simulation_forces(sim, f);
		const sm_energies e = sm_simulation_energies(sim);
		const double energies[ENERGY_COLUMNS] = {e.kinetic, e.elastic, e.gravity,
		                                         sm_simulation_dissipated_energy(sim),
		                                         sm_simulation_input_work(sim)};
		ENSURE(state_columns(doc, sm_simulation_positions(sim), sm_simulation_velocities(sim), f, energies,
		                     reference, out->values[r]) == 0);
	}
	free(f);
	sm_simulation_destroy(sim);
	return 0;
}

// Every column of the computed rows (the first computed->rows of the reference's) within relative
// * (the column's scale in the reference) + absolute, in the column's unit; reports the worst
// difference against its bound and where it is.
static int compare(const char* what, const table* computed, const table* reference, double relative,
                   double absolute)
{
	int failures = 0;
	double worst = 0.0;
	int worst_row = 0, worst_column = 1;
	for (int c = 1; c < reference->columns; c++) {
		const double scale = column_scale(reference, c);
		for (int r = 0; r < computed->rows; r++) {
			const double difference = fabs(computed->values[r][c] - reference->values[r][c]);
			const double bound = relative * scale + absolute;
			if (!(difference <= bound))
				failures++;
			if (!(difference / bound <= worst)) {
				worst = difference / bound;
				worst_row = r;
				worst_column = c;
			}
		}
	}
	if (failures > 0 || getenv("SPRINGMASS_REFERENCES_VERBOSE"))
		printf(
		    "  %s: %d values out of bounds; the worst, %s at t = %g s, is %.3g of its bound (%.17g against "
		    "%.17g)\n",
		    what, failures, reference->names[worst_column], reference->values[worst_row][0], worst,
		    computed->values[worst_row][worst_column], reference->values[worst_row][worst_column]);
	return failures > 0;
}

// The reference's rows integrated by GSL's rk8pd (gsl_reference.h) at relative and absolute
// tolerance eps, as far as `budget` right-hand sides take it: out->rows is the number of rows
// reached. Nothing does work on the model (no inputs, nothing driven), so the dissipated energy
// is what the other energies lost since t = 0, and the inputs' work is 0.
static int gsl_simulate(const sm_document* doc, const sm_model* model, const table* reference, double eps,
                        long budget, table* out)
{
	gsl_reference g;
	ENSURE(gsl_reference_init(&g, model, eps));
	*out = *reference;
	out->rows = 0;
	double initial_energy = 0.0;
	int status = GSL_SUCCESS;
	while (out->rows < reference->rows && g.evaluations <= budget) {
		const int r = out->rows;
		if ((status = gsl_reference_advance(&g, reference->values[r][0])) != GSL_SUCCESS)
			break;
		sm_model_forces(model, g.x, g.v, NULL, g.f);
		const sm_energies e = sm_model_energies(model, g.x, g.v);
		const double total = e.kinetic + e.elastic + e.gravity;
		if (r == 0)
			initial_energy = total;
		const double energies[ENERGY_COLUMNS] = {e.kinetic, e.elastic, e.gravity, initial_energy - total,
		                                         0.0};
		out->values[r][0] = g.t;
		if (state_columns(doc, g.x, g.v, g.f, energies, reference, out->values[r]) != 0) {
			status = GSL_FAILURE;
			break;
		}
		out->rows++;
	}
	if (getenv("SPRINGMASS_REFERENCES_VERBOSE"))
		printf("  GSL: %ld right-hand sides\n", g.evaluations);
	gsl_reference_free(&g);
	ENSURE(status == GSL_SUCCESS);
	return 0;
}

// ---------------------------------------------------------------------------------------------
// The checks, per model
// ---------------------------------------------------------------------------------------------

static bool springs_can_break(const sm_model* model)
{
	for (int32_t k = 0; k < sm_model_spring_count(model); k++) {
		sm_spring_def s;
		sm_model_get_spring(model, k, &s);
		if (isfinite(s.break_strain))
			return true;
	}
	return false;
}

static int check_model(const char* model_name)
{
	static table reference, computed;
	ENSURE(read_reference(model_name, &reference) == 0);
	char path[2048];
	snprintf(path, sizeof path, "%s/%s.json", SPRINGMASS_MODELS_DIR, model_name);
	sm_error err;
	sm_document* doc = sm_document_load(path, &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	int failures = 0;
	char what[1024];

	// No inputs and no driven particles: nothing does work on the model (the inputs' work column
	// is 0), so the total energy stays what it is at t = 0. CVODE integrates the dissipated energy with the
	// motion; the sum drifts by the run's global error, measured up to 4.2e-8 of the largest energy (the
	// two-mass chain over 5 s, 20 periods): 1e-6.
	for (int32_t i = 0; i < sm_model_particle_count(model); i++) {
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		ENSURE(p.motion != SM_PARTICLE_DRIVEN);
	}
	const int energy = reference.columns - ENERGY_COLUMNS;
	const double energy_scale = column_scale(&reference, energy);
	double worst_drift = 0.0;
	for (int r = 0; r < reference.rows; r++) {
		double total[2] = {0.0, 0.0};
		for (int q = 0; q < ENERGY_COLUMNS; q++) {
			// kinetic + elastic + gravitational + dissipated - the inputs' work
			const double sign = q == ENERGY_COLUMNS - 1 ? -1.0 : 1.0;
			total[0] += sign * reference.values[0][energy + q];
			total[1] += sign * reference.values[r][energy + q];
		}
		worst_drift = worst_of(worst_drift, fabs(total[1] - total[0]) / energy_scale);
		if (!(fabs(total[1] - total[0]) <= 1e-6 * energy_scale)) {
			printf("  %s at t = %g s: the total energy changed by %.3g J (scale %.3g J)\n", model_name,
			       reference.values[r][0], total[1] - total[0], energy_scale);
			failures++;
		}
	}
	if (getenv("SPRINGMASS_REFERENCES_VERBOSE"))
		printf("  %s: total energy within %.3g of the energies' scale\n", model_name, worst_drift);

	// GSL's rk8pd at 1e-12 against the reference at rtol 1e-10: they agree to the reference's
	// global error, which a run at rtol 1e-12 puts at up to 5e-8 of a quantity's scale (the flag's
	// velocities; the hanging rope's up to 1.2 s, 4e-8 m/s): 1e-6 of the scale plus 1e-9 (measured:
	// at most 0.08 of that). GSL has no event location, so models whose springs can break get the
	// energy balance alone. rk8pd's steps on the stiff springs of the cloth are 2e-5 s: it gets
	// 120 000 right-hand sides, which take it through every row of the other models and the
	// cloth's first 0.3 s.
	if (!springs_can_break(model)) {
		ENSURE(gsl_simulate(doc, model, &reference, 1e-12, GSL_BUDGET, &computed) == 0);
		if (getenv("SPRINGMASS_REFERENCES_VERBOSE"))
			printf("  %s: GSL reached t = %g s\n", model_name, computed.values[computed.rows - 1][0]);
		// A model too stiff for the budget to reach its first rows needs a larger one (or a
		// shorter horizon): a comparison of the initial state alone checks nothing.
		if (computed.rows < 4)
			printf("  %s: GSL reached %d rows within its budget\n", model_name, computed.rows);
		ENSURE(computed.rows >= 4);
		snprintf(what, sizeof what, "%s, GSL rk8pd against the reference", model_name);
		failures += compare(what, &computed, &reference, 1e-6, 1e-9);
	}

	// The library at the reference's tolerances: the same computation gives the same bits; a
	// change that only rounds differently (another order of sums) moves the results by the
	// global error, as above.
	sm_document_settings settings = sm_document_get_settings(doc);
	sm_simulation_def tight = settings.solver;
	tight.relative_tolerance = REFERENCE_RTOL;
	tight.absolute_tolerance_position = tight.absolute_tolerance_velocity = REFERENCE_ATOL;
	ENSURE(simulate(doc, model, &tight, &reference, &computed) == 0);
	snprintf(what, sizeof what, "%s at rtol %g against the reference (%s)", model_name, REFERENCE_RTOL,
	         reference.command);
	failures += compare(what, &computed, &reference, 1e-6, 1e-9);

	// The model file's own settings: what a user gets from `springmass run` or the FMU. Their
	// global error over the horizon, measured: up to 2e-3 of a quantity's scale (the jelly
	// block's and the trampoline's velocities; the benchmark cloth, at rtol 1e-4, 9e-5): within
	// 2e-2 of the scale plus 1e-6.
	ENSURE(simulate(doc, model, &settings.solver, &reference, &computed) == 0);
	snprintf(what, sizeof what, "%s at the file's settings against the reference", model_name);
	failures += compare(what, &computed, &reference, 2e-2, 1e-6);

	sm_model_destroy(model);
	sm_document_destroy(doc);
	return failures > 0;
}

static int compare_names(const void* a, const void* b)
{
	return strcmp(*(const char* const*)a, *(const char* const*)b);
}

// Every model file in models/ has a reference and passes its checks.
static int test_every_bundled_model_against_its_reference(void)
{
	DIR* dir = opendir(SPRINGMASS_MODELS_DIR);
	ENSURE(dir != NULL);
	char* names[64];
	int count = 0;
	struct dirent* entry;
	while ((entry = readdir(dir)) != NULL) {
		const size_t length = strlen(entry->d_name);
		if (length > 5 && strcmp(entry->d_name + length - 5, ".json") == 0) {
			ENSURE(count < 64);  // room for more bundled models: enlarge names
			names[count++] = strndup(entry->d_name, length - 5);
		}
	}
	closedir(dir);
	ENSURE(count >= 8);
	qsort(names, (size_t)count, sizeof names[0], compare_names);
	int failures = 0;
	for (int k = 0; k < count; k++) {
		if (check_model(names[k]) != 0) {
			printf("  model %s\n", names[k]);
			failures++;
		}
		free(names[k]);
	}
	return failures > 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	gsl_set_error_handler_off();
	RUN_TEST(test_every_bundled_model_against_its_reference);
	return TEST_SUMMARY();
}
