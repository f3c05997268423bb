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
#include <fcntl.h>
#include <stdarg.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef SPRINGMASS_CLI
#error "SPRINGMASS_CLI must name the springmass executable"
#endif
#ifndef SPRINGMASS_MODELS_DIR
#error "SPRINGMASS_MODELS_DIR must name the bundled models"
#endif

// Simulated time per model: short, so that the whole test takes seconds.
#define T_END 0.2
#define INTERVAL 0.05

// Runs the springmass executable with the arguments given (up to 15, then NULL), its standard
// output and error written to the files named ("/dev/null" to drop them; NULL: left as they are).
// No shell reads the command, so a path is passed as it is, whatever its folders' names hold (a
// quote, '$', '&'). Returns the status as waitpid gives it (0: exit status 0), or -1.
static int run_cli(const char* out_path, const char* err_path, ...)
{
	char* args[17] = {(char*)SPRINGMASS_CLI};
	va_list list;
	va_start(list, err_path);
	int n = 1;
	for (const char* arg; n < 16 && (arg = va_arg(list, const char*)) != NULL;)
		args[n++] = (char*)arg;
	va_end(list);
	args[n] = NULL;
	fflush(NULL);
	const pid_t child = fork();
	if (child < 0)
		return -1;
	if (child == 0) {
		const char* paths[2] = {out_path, err_path};
		for (int k = 0; k < 2; k++) {
			if (paths[k] == NULL)
				continue;
			const int fd = open(paths[k], O_WRONLY | O_CREAT | O_TRUNC, 0666);
			if (fd < 0 || dup2(fd, k + 1) < 0)
				_exit(127);
			close(fd);
		}
		execv(SPRINGMASS_CLI, args);
		_exit(127);
	}
	int status;
	return waitpid(child, &status, 0) == child ? status : -1;
}

static int check_model(const char* path, bool stop_at_outputs)
{
	char csv_path[] = "/tmp/springmass_run_XXXXXX";
	int fd = mkstemp(csv_path);
	ENSURE(fd >= 0);
	char err_path[] = "/tmp/springmass_run_err_XXXXXX";
	int err_fd = mkstemp(err_path);
	ENSURE(err_fd >= 0);
	close(err_fd);
	char t_end[32], interval[32];
	snprintf(t_end, sizeof t_end, "%g", T_END);
	snprintf(interval, sizeof interval, "%g", INTERVAL);
	const int rc =
	    run_cli(NULL, err_path, "run", path, "--t-end", t_end, "--output-interval", interval, "--output",
		        csv_path, "--quiet", stop_at_outputs ? "--stop-at-outputs" : NULL, NULL);
	if (rc != 0)
		printf("  %s: exit status %d\n", path, rc);
	ENSURE(rc == 0);
	// --quiet: errors only, and there are none.
	FILE* err_file = fopen(err_path, "r");
	ENSURE(err_file != NULL);
	ENSURE(fgetc(err_file) == EOF);
	fclose(err_file);
	remove(err_path);

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
			ENSURE_STATUS(stop_at_outputs ? sm_simulation_advance(sim, t)
			                              : sm_simulation_advance_interpolated(sim, t, T_END),
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
		const double energies[5] = {e.kinetic, e.elastic, e.gravity, sm_simulation_dissipated_energy(sim),
		                            sm_simulation_input_work(sim)};
		for (int c = 0; c < 5; c++) {
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

// Without --quiet, `springmass run` ends with a summary on stderr: the solver and the counts of
// the run's statistics, then each spring that broke. They are the library's own for the same
// file simulated to the same output times (the counts exactly: the same calls in the same order;
// the break times too, printed to the digit that reads them back). A run shorter than a second
// shows no progress line before it.
static int check_summary(const char* path, double t_end, double interval)
{
	char csv_path[] = "/tmp/springmass_run_XXXXXX", err_path[] = "/tmp/springmass_run_err_XXXXXX";
	int fd = mkstemp(csv_path);
	ENSURE(fd >= 0);
	close(fd);
	fd = mkstemp(err_path);
	ENSURE(fd >= 0);
	close(fd);
	char t_end_text[32], interval_text[32];
	snprintf(t_end_text, sizeof t_end_text, "%.17g", t_end);
	snprintf(interval_text, sizeof interval_text, "%.17g", interval);
	ENSURE(run_cli(NULL, err_path, "run", path, "--t-end", t_end_text, "--output-interval", interval_text,
	               "--output", csv_path, NULL) == 0);

	sm_error err;
	sm_document* doc = sm_document_load(path, &err);
	ENSURE(doc != NULL);
	sm_model* model = NULL;
	ENSURE_STATUS(sm_document_build(doc, &model, &err), SM_OK);
	sm_document_settings settings = sm_document_get_settings(doc);
	sm_simulation* sim = sm_simulation_create(model, &settings.solver, &err);
	ENSURE(sim != NULL);
	FILE* csv = fopen(csv_path, "r");
	ENSURE(csv != NULL);
	static char line[1 << 16];
	ENSURE(fgets(line, sizeof line, csv) != NULL);
	for (int rows = 0; fgets(line, sizeof line, csv) != NULL; rows++)
		if (rows > 0)
			ENSURE_STATUS(sm_simulation_advance_interpolated(sim, strtod(line, NULL), t_end), SM_OK);
	fclose(csv);
	remove(csv_path);
	ENSURE(sm_simulation_time(sim) == t_end);

	FILE* log = fopen(err_path, "r");
	ENSURE(log != NULL);
	int progress = 0;
	while (fgets(line, sizeof line, log) != NULL && strncmp(line, "springmass run: t = ", 20) == 0)
		progress++;
	char start[512], end_time[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(t_end, end_time);  // as the CSV's last row gives it
	snprintf(start, sizeof start, "springmass run: %s to t = %s s with ", sm_document_name(doc), end_time);
	if (strncmp(line, start, strlen(start)) != 0)
		printf("  summary '%s', expected to start with '%s'\n", line, start);
	ENSURE(strncmp(line, start, strlen(start)) == 0);
	char solver[256];
	snprintf(solver, sizeof solver, "%s: ",
	         settings.solver.method == SM_METHOD_ADAMS ? "Adams (fixed point, no linear solver)"
	                                                   : "BDF, solver ");
	if (settings.solver.method != SM_METHOD_ADAMS)
		snprintf(solver, sizeof solver, "BDF, solver %s: ", sm_linear_solver_name(sm_simulation_solver(sim)));
	const char* counts = line + strlen(start);
	ENSURE(strncmp(counts, solver, strlen(solver)) == 0);
	long long c[7];
	int broke = -1;
	double wall = -1.0;
	int counted = 0;
	ENSURE(
	    sscanf(
	        counts + strlen(solver),
	        "%lld steps, %lld right-hand sides, %lld Jacobians, %lld linear iterations, %lld error-test and "
	        "%lld convergence failures, %lld restarts, %d spring%n",
	        &c[0], &c[1], &c[2], &c[3], &c[4], &c[5], &c[6], &broke, &counted) == 8 &&
	    counted > 0);
	// "1 spring broke", "0 springs broke", "2 springs broke"
	const char* rest = counts + strlen(solver) + counted;
	const char* plural = broke == 1 ? "" : "s";
	ENSURE(strncmp(rest, plural, strlen(plural)) == 0);
	ENSURE(sscanf(rest + strlen(plural), " broke; wall %lf s", &wall) == 1);
	const sm_statistics st = sm_simulation_statistics(sim);
	const long long expected[7] = {st.steps,
	                               st.rhs_evaluations,
	                               st.jacobian_evaluations,
	                               st.linear_iterations,
	                               st.error_test_failures,
	                               st.convergence_failures,
	                               st.restarts};
	for (int k = 0; k < 7; k++) {
		if (c[k] != expected[k])
			printf("  count %d of the summary: %lld, the library's %lld\n", k, c[k], expected[k]);
		ENSURE(c[k] == expected[k]);
	}
	ENSURE(broke == sm_simulation_break_count(sim));
	// A progress line comes after more than 1 s; the summary gives the wall time to 1 ms, so a run of
	// 1.0002 s that showed one reads 1.000.
	ENSURE(progress == 0 || wall >= 1.0);
	for (int32_t b = 0; b < broke; b++) {
		const sm_break_event e = sm_simulation_break(sim, b);
		ENSURE(fgets(line, sizeof line, log) != NULL);
		int spring = -1;
		ENSURE(sscanf(line, "  spring %d ", &spring) == 1 && spring == e.spring);
		const char* at = strstr(line, " broke at t = ");
		ENSURE(at != NULL);
		ENSURE(strtod(at + 14, NULL) == e.time);
	}
	// The energy balance, at the start (the model's initial state) and at the end, the library's to
	// the 9 significant digits printed; where the model has loads, their potential is said to count
	// with gravity's.
	bool loaded = false;
	for (int32_t i = 0; i < sm_model_particle_count(model); i++) {
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		loaded = loaded || p.load[0] != 0.0 || p.load[1] != 0.0 || p.load[2] != 0.0;
	}
	double at_start = NAN, at_end = NAN, drift = NAN;
	ENSURE(fgets(line, sizeof line, log) != NULL);
	ENSURE(sscanf(line,
	              loaded
	                  ? "springmass run: kinetic + elastic + gravitational (with the loads') + dissipated "
	                    "energy - input work: %lf J at the start, %lf J at the end (%lf J)"
					  : "springmass run: kinetic + elastic + gravitational + dissipated energy - input work: "
					    "%lf J at the start, %lf J at the end (%lf J)",
	              &at_start, &at_end, &drift) == 3);
	const sm_energies end = sm_simulation_energies(sim);
	ENSURE_REL(at_end,
	           end.kinetic + end.elastic + end.gravity + sm_simulation_dissipated_energy(sim) -
	               sm_simulation_input_work(sim),
	           5e-9, 1e-300);
	ENSURE_STATUS(sm_simulation_reset(sim), SM_OK);
	const sm_energies begin = sm_simulation_energies(sim);
	ENSURE_REL(at_start, begin.kinetic + begin.elastic + begin.gravity, 5e-9, 1e-300);
	// The drift is the balance's change from the start to the end, printed to 3 significant digits:
	// within 5e-3 of itself, where the two balances printed to 9 digits would leave 1e-9 of them.
	const double change = at_end - at_start;
	ENSURE(fabs(drift - change) <= 5e-3 * fabs(change) + 1e-9 * (fabs(at_start) + fabs(at_end)));
	ENSURE(fgets(line, sizeof line, log) == NULL);
	fclose(log);
	remove(err_path);
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
		if (check_summary(path, T_END, INTERVAL) != 0) {
			printf("  model %s, the summary\n", entry->d_name);
			closedir(dir);
			return 1;
		}
		models++;
	}
	closedir(dir);
	ENSURE(models >= 1);
	return 0;
}

// The tearing cloth: springs break from about 0.4 s on, each listed as the library has it.
static int test_summary_lists_the_breaks(void)
{
	return check_summary(SPRINGMASS_MODELS_DIR "/tearing_cloth.json", 1.0, 0.1);
}

// A model with loads (the bundled ones have none): its CSV is the library's, and its summary's
// balance counts the loads' potential with gravity's, and says so. The file's name holds what a
// shell would read (quotes, '$', '&', parentheses), which the command is given as it is.
static int test_a_model_with_loads(void)
{
	const char* path = "test_cmd_run 'loads' \"$HOME\" (1) & `x`.json";
	FILE* f = fopen(path, "w");
	ENSURE(f != NULL);
	fputs("{\"springmass\": 1, \"name\": \"loaded\", \"parameters\": {\"F\": 2},"
	      " \"particles\": [{\"name\": \"a\", \"position\": [0, 0, 0], \"fixed\": true},"
	      " {\"name\": \"b\", \"position\": [1, 0, 0]}],"
	      " \"springs\": [{\"a\": \"a\", \"b\": \"b\", \"stiffness\": 40, \"damping\": 0.5}],"
	      " \"loads\": [{\"particle\": \"b\", \"force\": [\"F\", 0, 1]}],"
	      " \"ports\": [{\"name\": \"tip\", \"particle\": \"b\", \"kind\": \"probe\"}]}\n",
	      f);
	ENSURE(fclose(f) == 0);
	const int failed = check_model(path, false) != 0 || check_summary(path, 1.0, 0.1) != 0;
	remove(path);
	ENSURE(!failed);
	return 0;
}

// Usage errors exit with status 2, a bad model file with 1.
static int test_errors(void)
{
	int rc = run_cli("/dev/null", "/dev/null", "run", "--no-such-option", NULL);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
	rc = run_cli(NULL, "/dev/null", "run", SPRINGMASS_MODELS_DIR "/oscillator.json", "--set", "nothere=1",
	             "--output", "/dev/null", NULL);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
	rc = run_cli(NULL, "/dev/null", "run", "/nonexistent/model.json", NULL);
	ENSURE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
	ENSURE(run_cli("/dev/null", NULL, "run", "--help", NULL) == 0);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_every_bundled_model);
	RUN_TEST(test_summary_lists_the_breaks);
	RUN_TEST(test_a_model_with_loads);
	RUN_TEST(test_errors);
	return TEST_SUMMARY();
}
