// Cloth simulation benchmark: the benchmark cloth (bench/README.md) simulated with CVODE.
//
//   bench_cloth N SOLVER [REPEATS] [T_END]
//
// Builds the n x n benchmark cloth (sm_add_sheet's default materials, the corners (n-1, 0) and
// (n-1, n-1) fixed), integrates it from rest to T_END (default 1 s) at the peer's tolerances
// (rtol 1e-4, atol 1e-6) with the given linear solver ("auto", "dense", "klu", "pcg",
// "cholmod"), REPEATS times (default 3), and prints the median wall time of create + advance:
//   cloth n=<n> solver=<name> wall_s=<median> steps=<v> rhs=<v> jac=<v> z_corner=<v> threads=<t>
//         lin_iters=<v> fact=<v> restarts=<v> etf=<v> ncf=<v> force_s=<v> jacobian_s=<v> linear_s=<v>
// (one line, the benchmark's agreed fields first and in their agreed order; the free corner is
// particle 0). With RESTART_EVERY=<dt> in the environment the run advances in steps of dt with
// an external force on the free corner that changes at every step (what an FMU sees with small
// communication steps), once keeping CVODE's history (restart_on_input_change false) and once
// under the default rule (true: a restart only where a change jumps by more than the history
// carries), and prints both. ATOL_VELOCITY=<a> sets the velocities' absolute tolerance alone [m/s]
// (positions keep 1e-6 m), to measure what it does to the steps.
// THREADS=<t> sets sm_simulation_def.threads (default 1), which changes the time, not the results.
// STABILITY_LIMIT_DETECTION=off switches BDF's stability limit detection off (default on), to
// measure what it changes (docs/simulation.md, "Stability limit detection"). An argument or a
// setting that is not one (a mistyped number, "of") stops it with exit status 2 before anything
// is measured; a setting left empty is as if unset.
#define _POSIX_C_SOURCE 200809L

#include "bench_args.h"
#include "bench_clock.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static sm_model* benchmark_cloth(int32_t n)
{
	sm_model_def md = sm_default_model_def();
	sm_model* model = sm_model_create(&md, NULL);
	sm_sheet_def sd = sm_default_sheet_def();
	sd.nu = sd.nv = n;
	sm_structure st;
	if (!model || sm_add_sheet(model, &sd, &st) != SM_OK ||
	    sm_set_motion_at(model, &st, n - 1, 0, 0, SM_PARTICLE_FIXED) != SM_OK ||
	    sm_set_motion_at(model, &st, n - 1, n - 1, 0, SM_PARTICLE_FIXED) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// What the environment sets (above), read once before anything is measured.
typedef struct settings {
	double interval;       // RESTART_EVERY [s]; 0: one advance to T_END
	double atol_velocity;  // ATOL_VELOCITY [m/s]; 0: that of the positions
	int threads;           // THREADS
	bool detection;        // STABILITY_LIMIT_DETECTION
} settings;

// The number `text` reads as whole, in *value: false for anything else (trailing characters, out
// of range, not finite), so that a mistyped setting stops the benchmark instead of measuring
// something else under its name.
static bool read_number(const char* text, double* value)
{
	char* end = NULL;
	errno = 0;
	*value = strtod(text, &end);
	return end != text && *end == '\0' && errno == 0 && isfinite(*value);
}

// The value of environment variable `name`; NULL if it is unset or empty.
static const char* setting(const char* name)
{
	const char* value = getenv(name);
	return value && value[0] ? value : NULL;
}

// The settings of the environment for a run to t_end [s]; false, with a message, for a value that
// is not one (a variable unset or empty keeps its default).
static bool read_settings(double t_end, settings* s)
{
	*s = (settings){0.0, 0.0, 1, true};
	const char* every = setting("RESTART_EVERY");
	// Its count of advances, t_end / interval, must be an int.
	if (every && !(read_number(every, &s->interval) && s->interval >= 0.0 &&
	               (s->interval == 0.0 || t_end / s->interval < 1e9))) {
		fprintf(stderr, "bench_cloth: RESTART_EVERY=%s: give a time step of 0 (none) or above T_END / 1e9\n",
		        every);
		return false;
	}
	const char* atol_velocity = setting("ATOL_VELOCITY");
	if (atol_velocity && !(read_number(atol_velocity, &s->atol_velocity) && s->atol_velocity > 0.0)) {
		fprintf(stderr, "bench_cloth: ATOL_VELOCITY=%s: give a tolerance above 0 [m/s]\n", atol_velocity);
		return false;
	}
	const char* threads = setting("THREADS");
	if (threads && !bench_read_count(threads, 1, 1024, &s->threads)) {
		fprintf(stderr, "bench_cloth: THREADS=%s: give a count from 1 to 1024\n", threads);
		return false;
	}
	const char* detection = setting("STABILITY_LIMIT_DETECTION");
	if (detection && strcmp(detection, "on") != 0 && strcmp(detection, "off") != 0) {
		fprintf(stderr, "bench_cloth: STABILITY_LIMIT_DETECTION=%s: give on or off\n", detection);
		return false;
	}
	s->detection = !(detection && strcmp(detection, "off") == 0);
	return true;
}

typedef struct run_result {
	double wall;
	sm_statistics stats;
	double z_corner;
	sm_linear_solver solver;
	int threads;  // sm_simulation_def.threads asked for
} run_result;

// One run; set->interval > 0 advances in steps of it with a force on the free corner that
// changes at every step.
static int run(const sm_model* model, sm_linear_solver solver, double t_end, const settings* set,
               bool restart, run_result* out)
{
	const double interval = set->interval;
	sm_simulation_def d = sm_default_simulation_def();
	d.solver = solver;
	d.relative_tolerance = 1e-4;
	d.absolute_tolerance_position = d.absolute_tolerance_velocity = 1e-6;
	if (set->atol_velocity > 0.0)
		d.absolute_tolerance_velocity = set->atol_velocity;
	d.threads = set->threads;
	d.stability_limit_detection = set->detection;
	d.restart_on_input_change = restart;
	const double start = bench_now();
	sm_error err;
	sm_simulation* sim = sm_simulation_create(model, &d, &err);
	if (!sim) {
		fprintf(stderr, "bench_cloth: %s\n", err.message);
		return 1;
	}
	sm_status st = SM_OK;
	if (interval > 0.0) {
		const int steps = (int)lround(t_end / interval);
		for (int k = 1; k <= steps && st == SM_OK; k++) {
			// A smooth input sampled at the communication points: 0.05 N sin(2 pi t).
			const double t = (k - 1) * interval;
			const double force[3] = {0.0, 0.0, 0.05 * sin(6.283185307179586 * t)};
			sm_simulation_set_external_force(sim, 0, force);
			st = sm_simulation_advance(sim, k * interval);
		}
	} else {
		st = sm_simulation_advance(sim, t_end);
	}
	out->wall = bench_now() - start;
	if (st != SM_OK) {
		fprintf(stderr, "bench_cloth: %s\n", sm_simulation_last_error(sim));
		sm_simulation_destroy(sim);
		return 1;
	}
	out->stats = sm_simulation_statistics(sim);
	out->z_corner = sm_simulation_positions(sim)[2];
	out->solver = sm_simulation_solver(sim);
	out->threads = d.threads;
	sm_simulation_destroy(sim);
	return 0;
}

static int compare_wall(const void* a, const void* b)
{
	const double x = ((const run_result*)a)->wall, y = ((const run_result*)b)->wall;
	return (x > y) - (x < y);
}

// The median wall time of `repeats` runs (the mean of the two middle ones for an even count), with
// the statistics of the median run (the faster middle one for an even count): the times on a
// line belong to one run, one whose wall time is at most the median.
static int measure(const sm_model* model, sm_linear_solver solver, int repeats, double t_end,
                   const settings* set, bool restart, run_result* result)
{
	run_result* runs = malloc(sizeof(run_result) * (size_t)repeats);
	if (!runs)
		return 1;
	for (int r = 0; r < repeats; r++) {
		if (run(model, solver, t_end, set, restart, &runs[r]) != 0) {
			free(runs);
			return 1;
		}
	}
	qsort(runs, (size_t)repeats, sizeof(run_result), compare_wall);
	*result = runs[(repeats - 1) / 2];
	result->wall =
	    repeats % 2 ? runs[repeats / 2].wall : 0.5 * (runs[repeats / 2 - 1].wall + runs[repeats / 2].wall);
	free(runs);
	return 0;
}

int main(int argc, char** argv)
{
	if (argc < 3) {
		fprintf(stderr, "usage: bench_cloth N SOLVER [REPEATS] [T_END]\n");
		return 2;
	}
	int n = 0, repeats = 3;
	double t_end = 1.0;
	sm_linear_solver solver = SM_SOLVER_AUTO;
	if (!bench_read_count(argv[1], 2, 4096, &n) || sm_linear_solver_from_name(argv[2], &solver) != SM_OK ||
	    (argc > 3 && !bench_read_count(argv[3], 1, 1000, &repeats)) ||
	    (argc > 4 && !(read_number(argv[4], &t_end) && t_end > 0.0))) {
		fprintf(stderr,
		        "bench_cloth: bad arguments: N from 2 to 4096, SOLVER a linear solver's name, REPEATS "
		        "from 1 to 1000, T_END above 0 [s]\n");
		return 2;
	}
	settings set;
	if (!read_settings(t_end, &set))
		return 2;
	const double interval = set.interval;
	sm_model* model = benchmark_cloth(n);
	if (!model)
		return 1;
	for (int pass = 0; pass < (interval > 0.0 ? 2 : 1); pass++) {
		run_result r;
		if (measure(model, solver, repeats, t_end, &set, pass == 1, &r) != 0) {
			sm_model_destroy(model);
			return 1;
		}
		printf(
		    "cloth n=%d solver=%s wall_s=%.4g steps=%lld rhs=%lld jac=%lld z_corner=%.6f threads=%d lin_iters=%lld "
		    "fact=%lld restarts=%lld etf=%lld ncf=%lld force_s=%.3g jacobian_s=%.3g linear_s=%.3g",
		    (int)n, sm_linear_solver_name(r.solver), r.wall, (long long)r.stats.steps,
		    (long long)r.stats.rhs_evaluations, (long long)r.stats.jacobian_evaluations, r.z_corner,
		    r.threads, (long long)r.stats.linear_iterations, (long long)r.stats.factorizations,
		    (long long)r.stats.restarts, (long long)r.stats.error_test_failures,
		    (long long)r.stats.convergence_failures, r.stats.force_seconds, r.stats.jacobian_seconds,
		    r.stats.linear_solve_seconds);
		if (interval > 0.0)
			printf(" interval=%g inputs=%s", interval, pass == 1 ? "restart" : "keep-history");
		printf("\n");
	}
	sm_model_destroy(model);
	return 0;
}
