// `springmass run` on every bundled model completes, and its CSV matches the library's own
// results: the test simulates the same file through the public API (same settings, the same
// output times) and compares every column of every row, for the rows interpolated from the
// solver's steps (the default: sm_simulation_advance_interpolated up to the end time) and for
// steps ended at every output time (--stop-at-outputs: sm_simulation_advance).
#define _POSIX_C_SOURCE 200809L

#include "springmass/model_file.h"
#include "springmass/simulation.h"
#include "test_harness.h"

#include <dirent.h>
#include <sys/wait.h>
#include <stdlib.h>

#ifndef SPRINGMASS_CLI
#error "SPRINGMASS_CLI must name the springmass executable"
#endif
#ifndef SPRINGMASS_MODELS_DIR
#error "SPRINGMASS_MODELS_DIR must name the bundled models"
#endif

// Simulated time per model: short, so that the whole test takes seconds.
#define T_END 0.2
#define INTERVAL 0.05

static int check_model(const char* path, bool stop_at_outputs)
{
	char csv_path[] = "/tmp/springmass_run_XXXXXX";
	int fd = mkstemp(csv_path);
	ENSURE(fd >= 0);
	char command[4096];
	snprintf(command, sizeof command, "'%s' run '%s' --t-end %g --output-interval %g --output '%s' --quiet%s",
	         SPRINGMASS_CLI, path, T_END, INTERVAL, csv_path, stop_at_outputs ? " --stop-at-outputs" : "");
	const int rc = system(command);
	if (rc != 0)
		printf("  %s: exit status %d\n", path, rc);
	ENSURE(rc == 0);

	sm_error err;
	sm_document* doc = sm_document_load(path, &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	sm_document_settings settings = sm_document_get_settings(doc);
	sm_simulation* sim = sm_simulation_create(model, &settings.solver, &err);
	ENSURE(sim != NULL);
	const int32_t n = sm_model_particle_count(model);
	double* forces = malloc(sizeof(double) * 3 * (size_t)n);

	FILE* csv = fopen(csv_path, "r");
	ENSURE(csv != NULL);
	char line[1 << 16];
	ENSURE(fgets(line, sizeof line, csv) != NULL);
	ENSURE(strncmp(line, "time,", 5) == 0 && strstr(line, "energy.dissipated") != NULL);
	int rows = 0;
	while (fgets(line, sizeof line, csv) != NULL) {
		char* p = line;
		const double t = strtod(p, &p);
		if (rows > 0)
			ENSURE_STATUS(stop_at_outputs ? sm_simulation_advance(sim, t) : sm_simulation_advance_interpolated(sim, t, T_END),
			              SM_OK);
		ENSURE(sm_simulation_time(sim) == t);
		const double* x = sm_simulation_positions(sim);
		const double* v = sm_simulation_velocities(sim);
		sm_simulation_forces(sim, forces);
		// The same computation in the same order: the values agree to the last digit printed
		// (17 significant digits round-trip a double exactly).
		for (int32_t k = 0; k < sm_document_port_count(doc); k++) {
			const sm_port port = sm_document_port(doc, k);
			const size_t i = 3 * (size_t)port.particle;
			const double* expected[2] = {port.kind == SM_PORT_MOTION ? forces + i : x + i, v + i};
			const int groups = port.kind == SM_PORT_MOTION ? 1 : 2;
			for (int g = 0; g < groups; g++)
				for (int c = 0; c < 3; c++) {
					ENSURE(*p == ',');
					ENSURE_NEAR(strtod(p + 1, &p), expected[g][c], 0.0);
				}
		}
		const sm_energies e = sm_simulation_energies(sim);
		const double energies[4] = {e.kinetic, e.elastic, e.gravity, sm_simulation_dissipated_energy(sim)};
		for (int c = 0; c < 4; c++) {
			ENSURE(*p == ',');
			ENSURE_NEAR(strtod(p + 1, &p), energies[c], 0.0);
		}
		rows++;
	}
	// Rows at 0, 0.05, ..., 0.2 s.
	ENSURE(rows == (int)(T_END / INTERVAL + 0.5) + 1);
	ENSURE(sm_simulation_time(sim) == T_END);
	fclose(csv);
	remove(csv_path);
	free(forces);
	sm_simulation_destroy(sim);
	sm_model_destroy(model);
	sm_document_destroy(doc);
	return 0;
}

static int test_every_bundled_model(void)
{
	DIR* dir = opendir(SPRINGMASS_MODELS_DIR);
	ENSURE(dir != NULL);
	int models = 0;
	struct dirent* entry;
	while ((entry = readdir(dir)) != NULL) {
		const size_t len = strlen(entry->d_name);
		if (len < 5 || strcmp(entry->d_name + len - 5, ".json") != 0)
			continue;
		char path[2048];
		snprintf(path, sizeof path, "%s/%s", SPRINGMASS_MODELS_DIR, entry->d_name);
		for (int stop = 0; stop < 2; stop++) {
			if (check_model(path, stop) != 0) {
				printf("  model %s%s\n", entry->d_name, stop ? ", --stop-at-outputs" : "");
				closedir(dir);
				return 1;
			}
		}
		models++;
	}
	closedir(dir);
	ENSURE(models >= 1);
	return 0;
}

// Usage errors exit with status 2, a bad model file with 1.
static int test_errors(void)
{
	char command[4096];
	snprintf(command, sizeof command, "'%s' run --no-such-option >/dev/null 2>&1", SPRINGMASS_CLI);
	int rc = system(command);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
	snprintf(command, sizeof command, "'%s' run '%s/oscillator.json' --set nothere=1 --output /dev/null 2>/dev/null",
	         SPRINGMASS_CLI, SPRINGMASS_MODELS_DIR);
	rc = system(command);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
	snprintf(command, sizeof command, "'%s' run /nonexistent/model.json 2>/dev/null", SPRINGMASS_CLI);
	rc = system(command);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
	snprintf(command, sizeof command, "'%s' run --help >/dev/null", SPRINGMASS_CLI);
	ENSURE(system(command) == 0);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_every_bundled_model);
	RUN_TEST(test_errors);
	return TEST_SUMMARY();
}
