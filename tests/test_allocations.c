// Allocations while a simulation advances: once created, a simulation takes its steps and Newton
// iterations in the memory it holds (docs/simulation.md, "Memory").
//
// This executable replaces the C library's malloc, calloc, realloc, aligned_alloc and free with
// wrappers around glibc's own (__libc_malloc and its siblings) that count the allocations while a
// test asks them to. The executable's definitions are the ones every library of the process calls,
// so CVODE, CHOLMOD, KLU and BLAS are counted with springmass. CHOLMOD's numeric factorisations
// allocate workspaces of their own at every call, which the reduced solvers make at most once per
// step or every few steps: they are counted apart, through the linker's
// --wrap=cholmod_l_factorize. The sanitizer builds put allocators of their own in place of the C
// library's, which a program's definitions would displace: there, and without glibc, the tests say
// they skipped.
#include "simulation_fixtures.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"
#include "test_harness.h"

#include <cholmod.h>

#include <math.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define COUNTING 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define COUNTING 0
#endif
#endif
#if !defined(COUNTING)
#if defined(__GLIBC__)
#define COUNTING 1
#else
#define COUNTING 0
#endif
#endif

// Counts since counting was last switched on: allocations outside CHOLMOD's factorisations, and
// those factorisations. Atomic: BLAS and OpenMP threads may allocate at the same time.
static atomic_bool counting_;
static atomic_long allocations_;
static atomic_long factorizations_;
static _Thread_local int inside_factorization_;

#if COUNTING
static void count_allocation(void)
{
	if (atomic_load_explicit(&counting_, memory_order_relaxed) && inside_factorization_ == 0)
		atomic_fetch_add_explicit(&allocations_, 1, memory_order_relaxed);
}

void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* p, size_t size);
void* __libc_memalign(size_t alignment, size_t size);
void __libc_free(void* p);

void* malloc(size_t size)
{
	count_allocation();
	return __libc_malloc(size);
}

void* calloc(size_t count, size_t size)
{
	count_allocation();
	return __libc_calloc(count, size);
}

void* realloc(void* p, size_t size)
{
	count_allocation();
	return __libc_realloc(p, size);
}

void* aligned_alloc(size_t alignment, size_t size)
{
	count_allocation();
	return __libc_memalign(alignment, size);
}

void free(void* p)
{
	__libc_free(p);
}
#endif

int __real_cholmod_l_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common);
int __wrap_cholmod_l_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common);

int __wrap_cholmod_l_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common)
{
	if (atomic_load_explicit(&counting_, memory_order_relaxed))
		atomic_fetch_add_explicit(&factorizations_, 1, memory_order_relaxed);
	inside_factorization_++;
	const int ok = __real_cholmod_l_factorize(A, L, common);
	inside_factorization_--;
	return ok;
}

static void start_counting(void)
{
	atomic_store(&allocations_, 0);
	atomic_store(&factorizations_, 0);
	atomic_store(&counting_, true);
}

static void stop_counting(void)
{
	atomic_store(&counting_, false);
}

// The benchmark cloth of n x n particles (1 m, 1 kg) with its corners (n - 1, 0) fixed and
// (n - 1, n - 1) driven; the free corner (0, 0) is particle 0.
static sm_model* hanging_cloth(int32_t n, sm_structure* st)
{
	return sheet_held_at_corners(n, 0.0, SM_PARTICLE_DRIVEN, st);
}

typedef struct window {
	long allocations;     // outside CHOLMOD's factorisations
	long factorizations;  // of CHOLMOD
	int64_t steps;
	int64_t linear_iterations;
	int64_t jacobian_evaluations;
	double corner_z;  // the free corner's height at the end [m]
} window;

// One counted run: the method and linear solver, whether an input change restarts CVODE, and
// whether the communication points are interpolated (sm_simulation_advance_interpolated, CVODE
// stepping on to the window's end) rather than stepped to.
typedef struct run_def {
	sm_method method;
	sm_linear_solver solver;
	bool restart_on_input_change;
	bool interpolated;
} run_def;

// Advances the cloth to 0.02 s, where the solver has met every kind of call it makes, then to 0.1 s
// in communication steps of 0.01 s, counting. At each, as a co-simulation master does, the driven
// corner continues its path (1 m/s along x from where it is: no input change) and the free corner
// gets a new external force (a change: CVODE restarts there if restart_on_input_change).
static int advance_counting(const sm_model* model, const sm_structure* st, run_def run, window* out)
{
	const sm_linear_solver solver = run.solver;
	const bool restart_on_input_change = run.restart_on_input_change;
	sm_simulation_def d = sm_default_simulation_def();
	d.method = run.method;
	d.solver = solver;
	d.relative_tolerance = 1e-4;
	d.absolute_tolerance_position = d.absolute_tolerance_velocity = 1e-6;
	d.restart_on_input_change = restart_on_input_change;
	sm_simulation* sim = sm_simulation_create(model, &d, NULL);
	ENSURE(sim != NULL);
	const int32_t driven = sm_structure_particle(st, st->shape[1] - 1, st->shape[0] - 1, 0);
	sm_statistics before = {0};
	for (int k = 1; k <= 10; k++) {
		if (k == 3) {
			before = sm_simulation_statistics(sim);
			start_counting();
		}
		const double t = 0.01 * (k - 1);
		const double* x = sm_simulation_positions(sim);
		const double position[3] = {x[3 * driven], x[3 * driven + 1], x[3 * driven + 2]};
		const double velocity[3] = {1.0, 0.0, 0.0};
		// Interpolated runs keep the force: an input change would end the advance's last step at
		// the communication point, as a stepped advance does.
		const double force[3] = {0.0, 0.0, run.interpolated ? 0.0 : 0.05 * sin(20.0 * t)};
		if (sm_simulation_set_driven(sim, driven, position, velocity) != SM_OK ||
		    sm_simulation_set_external_force(sim, 0, force) != SM_OK ||
		    (run.interpolated ? sm_simulation_advance_interpolated(sim, 0.01 * k, 0.1)
		                      : sm_simulation_advance(sim, 0.01 * k)) != SM_OK) {
			stop_counting();
			printf("  %s: %s\n", sm_linear_solver_name(solver), sm_simulation_last_error(sim));
			sm_simulation_destroy(sim);
			return 1;
		}
	}
	stop_counting();
	const sm_statistics after = sm_simulation_statistics(sim);
	out->allocations = atomic_load(&allocations_);
	out->factorizations = atomic_load(&factorizations_);
	out->steps = after.steps - before.steps;
	out->linear_iterations = after.linear_iterations - before.linear_iterations;
	out->jacobian_evaluations = after.jacobian_evaluations - before.jacobian_evaluations;
	out->corner_z = sm_simulation_positions(sim)[2];
	sm_simulation_destroy(sim);
	printf("  %s%s (restarts %s): %lld steps, %lld Jacobians, %lld linear iterations, %ld allocations, %ld "
	       "CHOLMOD factorisations\n",
	       run.method == SM_METHOD_ADAMS ? "adams" : sm_linear_solver_name(solver),
	       run.interpolated ? ", interpolated" : "", restart_on_input_change ? "on" : "off",
	       (long long)out->steps, (long long)out->jacobian_evaluations, (long long)out->linear_iterations,
	       out->allocations, out->factorizations);
	return 0;
}

// The reduced solvers on a 12 x 12 cloth (142 free particles): pcg with its coarse correction
// (from 100 free particles on), cholmod with its Cholesky preconditioner, both factorised by
// CHOLMOD's simplicial method at this size. Every iteration solves with the factor; only the
// factorisations may allocate.
static int test_reduced_solvers_iterate_without_allocating(void)
{
	if (!COUNTING) {
		printf("  skipped: the allocator is the sanitizer's or not glibc's\n");
		return 0;
	}
	sm_structure st;
	sm_model* model = hanging_cloth(12, &st);
	ENSURE(model != NULL);
	const sm_linear_solver solvers[] = {SM_SOLVER_REDUCED_PCG, SM_SOLVER_REDUCED_CHOLMOD};
	for (size_t s = 0; s < sizeof solvers / sizeof solvers[0]; s++) {
		for (int restart = 0; restart < 2; restart++) {
			window w;
			const run_def run = {SM_METHOD_BDF, solvers[s], restart == 1, false};
			if (advance_counting(model, &st, run, &w) != 0) {
				sm_model_destroy(model);
				return 1;
			}
			// The window holds the work under test: steps, an iteration or more each.
			ENSURE(w.steps > 10);
			ENSURE(w.linear_iterations >= w.steps);
			ENSURE(w.allocations == 0);
			// The free corner fell under gravity (it starts at z = 0).
			ENSURE(w.corner_z < 0.0);
		}
	}
	sm_model_destroy(model);
	return 0;
}

// The runs on the 5 x 5 cloth (23 free particles): each takes its steps (and, with jacobians,
// evaluates the Jacobian) in the window without allocating, its free corner falling.
static int small_cloth_runs_allocate_nothing(const run_def* runs, size_t count, bool jacobians)
{
	if (!COUNTING) {
		printf("  skipped: the allocator is the sanitizer's or not glibc's\n");
		return 0;
	}
	sm_structure st;
	sm_model* model = hanging_cloth(5, &st);
	ENSURE(model != NULL);
	for (size_t k = 0; k < count; k++) {
		window w;
		if (advance_counting(model, &st, runs[k], &w) != 0) {
			sm_model_destroy(model);
			return 1;
		}
		ENSURE(w.steps > 10);
		ENSURE(!jacobians || w.jacobian_evaluations > 0);
		ENSURE(w.allocations == 0);
		ENSURE(w.corner_z < 0.0);
	}
	sm_model_destroy(model);
	return 0;
}

// The matrix-based solvers on the 5 x 5 cloth: CVODE evaluates the Jacobian (dense at every step,
// klu every few steps) and at every restart, and the solver factorises the Newton matrix. KLU runs
// without restarts: SUNDIALS' KLU module analyses the matrix afresh after each (CVODE
// initialises its linear solver again), and that analysis allocates.
static int test_matrix_solvers_evaluate_jacobians_without_allocating(void)
{
	const run_def runs[] = {{SM_METHOD_BDF, SM_SOLVER_DENSE, false, false},
	                        {SM_METHOD_BDF, SM_SOLVER_DENSE, true, false},
	                        {SM_METHOD_BDF, SM_SOLVER_KLU, false, false}};
	return small_cloth_runs_allocate_nothing(runs, sizeof runs / sizeof runs[0], true);
}

// Adams (fixed-point iteration, no linear solver), restarting at every input change and not, and
// communication points interpolated from CVODE's last step (inputs unchanged, CVODE stepping on to
// 0.1 s: fewer steps than stepping to each point) with Adams, the dense and the pcg solver, on the
// 5 x 5 cloth: none of them allocates either.
static int test_adams_and_interpolated_outputs_without_allocating(void)
{
	const run_def runs[] = {{SM_METHOD_ADAMS, SM_SOLVER_AUTO, false, false},
	                        {SM_METHOD_ADAMS, SM_SOLVER_AUTO, true, false},
	                        {SM_METHOD_ADAMS, SM_SOLVER_AUTO, false, true},
	                        {SM_METHOD_BDF, SM_SOLVER_DENSE, false, true},
	                        {SM_METHOD_BDF, SM_SOLVER_REDUCED_PCG, false, true}};
	return small_cloth_runs_allocate_nothing(runs, sizeof runs / sizeof runs[0], false);
}

// Adams iterates without a Jacobian: a simulation created for it allocates alike whichever linear
// solver its options name (before, dense, klu and cholmod also built the sparse Jacobian's
// pattern and values, and dense and klu the springs' blocks, all unused).
static int test_adams_allocates_no_jacobian(void)
{
	if (!COUNTING) {
		printf("  skipped: the allocator is the sanitizer's or not glibc's\n");
		return 0;
	}
	sm_structure st;
	sm_model* model = hanging_cloth(5, &st);
	ENSURE(model != NULL);
	const sm_linear_solver solvers[] = {SM_SOLVER_REDUCED_PCG, SM_SOLVER_DENSE, SM_SOLVER_KLU,
	                                    SM_SOLVER_REDUCED_CHOLMOD};
	long counts[4];
	for (size_t k = 0; k < 4; k++) {
		sm_simulation_def d = sm_default_simulation_def();
		d.method = SM_METHOD_ADAMS;
		d.solver = solvers[k];
		start_counting();
		sm_simulation* sim = sm_simulation_create(model, &d, NULL);
		stop_counting();
		ENSURE(sim != NULL);
		counts[k] = atomic_load(&allocations_);
		printf("  adams, %s named: %ld allocations to create\n", sm_linear_solver_name(solvers[k]),
		       counts[k]);
		sm_simulation_destroy(sim);
	}
	for (size_t k = 1; k < 4; k++)
		ENSURE(counts[k] == counts[0]);
	sm_model_destroy(model);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_reduced_solvers_iterate_without_allocating);
	RUN_TEST(test_matrix_solvers_evaluate_jacobians_without_allocating);
	RUN_TEST(test_adams_and_interpolated_outputs_without_allocating);
	RUN_TEST(test_adams_allocates_no_jacobian);
	return TEST_SUMMARY();
}
