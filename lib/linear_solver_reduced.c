// The reduced second-order linear solver: a custom SUNLinearSolver for CVODE's BDF Newton
// systems of a spring-mass model.
//
// Derivation. With y = [x; v; e] and J = [[0, I, 0], [M^-1 K, M^-1 D, 0], [0, 0, 0]]
// (K = df/dx, D = df/dv over the free degrees of freedom, M the diagonal of masses), Newton's
// system (I - gamma J) [dx; dv; de] = [bx; bv; be] reads
//     dx - gamma dv = bx
//     -gamma M^-1 K dx + dv - gamma M^-1 D dv = bv
//     de = be.
// Substituting dx = bx + gamma dv into the second row and multiplying by M:
//     (M - gamma D - gamma^2 K) dv = M bv + gamma K bx,    dx = bx + gamma dv.
// With the definiteness-preserving Jacobian, K and D are symmetric negative semi-definite, so
// A = M - gamma D - gamma^2 K is symmetric positive definite: half the unknowns of the full
// system, and conjugate gradients or a Cholesky factorisation apply.
//
// Residuals. The residual of the full system's velocity rows is M^-1 (M bv + gamma K bx - A dv)
// (the position rows hold exactly), so conjugate gradients stop when the error-weighted norm of
// M^-1 r falls below the tolerance CVODE passes, the same test SUNDIALS' own iterative solvers
// make.
//
// Both solvers use the Newton matrix of the current step exactly: the Jacobian is that of the
// predicted state of every step attempt (evaluated by the right-hand side there, or else at the
// first solve), and products with A are formed from it with the gamma of each solve. Measured
// on the benchmark cloth (bench/README.md), a Jacobian and a factorisation kept for up to 20
// steps, as CVODE does by default for its direct solvers, made the Newton iteration fail about
// once in 15 steps (each failure cuts the step by 4) and doubled the number of steps (n = 16:
// 1263 against 684; n = 32: 2175 against 1103) for no gain in accuracy; the fresh Jacobian
// costs no pass over the springs of its own. The refresh happens inside the solve, not through
// a CVODE set-up at every step, because each set-up resets CVODE's estimate of the Newton
// convergence rate to 1, which alone cost half a Newton iteration more per step (1.5 instead of
// 1.1 right-hand sides per step).
//
// Conjugate gradients on A dv = M bv + gamma K bx, from dv = 0, over all particles (3 entries
// each, the constrained particles' entries kept at zero, so that the products with A read and
// write the particles' own arrays without gathering the free ones), preconditioned by
// - (pcg) the inverses of A's 3x3 diagonal blocks (block Jacobi), from TWO_LEVEL_MIN_PARTICLES
//   free particles on plus a coarse correction: the free particles are grouped into aggregates
//   (a particle and its spring neighbours), the Galerkin coarse matrix P^T A P (P moves each
//   aggregate as one body) is summed from the springs' blocks at the solve's gamma (the scaled
//   records the diagonal blocks' pass writes), and factorised by CHOLMOD (it is small: about a tenth of the
//   unknowns on the cloth; for a model in chunks ordered in two halves whose triangular solves
//   run at once, coarse_halves.h), and the preconditioner is block Jacobi
//   plus P A_c^-1 P^T (additive, so symmetric positive definite). Block Jacobi alone smooths
//   the short waves; the coarse correction takes the long ones, whose slow convergence made the
//   iterations grow with the model's size. From MULTILEVEL_MIN_PARTICLES on, A_c^-1 is
//   approximated by conjugate gradients preconditioned by a multilevel V-cycle over further
//   aggregation levels (preconditioner_multilevel.c), the exact solve having grown faster than
//   the model; the outer conjugate gradients are then flexible (Polak-Ribiere beta); or
// - (cholmod) a sparse Cholesky factorisation (CHOLMOD) of the Newton matrix of an earlier step:
//   while J and gamma have changed little, one or two iterations (one triangular solve pair and
//   one product each) reach CVODE's tolerance, so the factorisation, by far the costliest
//   operation, is repeated only when the iterations it saves no longer pay for it (a
//   deterministic count of floating-point operations, never a clock, decides: the same inputs
//   give the same trajectory on every machine). A factorisation at the current J and gamma makes
//   the first iterate the exact Newton correction.
// The symbolic analysis (fill-reducing ordering) is computed once.
#define _POSIX_C_SOURCE 200809L

#include "coarse_halves.h"
#include "model_internal.h"
#include "preconditioner_multilevel.h"
#include "simulation_internal.h"
#include "workers.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <suitesparse/cholmod.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

// Conjugate-gradient iterations allowed per solve with the block-Jacobi preconditioner, beyond
// which the solve counts as failed (CVODE then reduces the step).
#define PCG_MAX_ITERATIONS 400

// Iterations allowed per solve with an older Cholesky factor as the preconditioner; beyond, the
// current matrix is factorised and the solve restarted (it then converges in one iteration).
#define CHOLESKY_MAX_ITERATIONS 12

// Free particles from which conjugate gradients use the two-level preconditioner. Measured on
// the benchmark cloth (bench/README.md): it cut the iterations by 1.3 times at n = 16 (254 free
// particles; 1.2 to 1.8 times faster once the coarse factor was kept across set-ups), by 2.1
// times at n = 32 (1022) and by 2.7 times at n = 64; at n = 8 (62) it cut them by 7% for the
// same run time.
#define TWO_LEVEL_MIN_PARTICLES 100

// The coarse matrix is summed and factorised again after COARSE_MAX_AGE preconditioner set-ups
// or when gamma has changed by more than COARSE_GAMMA_CHANGE (relative) since; in between the
// older factor serves (the preconditioner stays symmetric positive definite, only its quality
// varies). Measured on the benchmark cloth n = 64 over 0.2 s: a factorisation at every set-up
// took 17% of the run in CHOLMOD; with (10, 0.3) the iterations rose by 1% (8419 to 8523) and
// the run took 0.65 times as long; (50, 0.5) cost 18% more iterations, no refresh at all 3.3
// times as many.
#define COARSE_MAX_AGE 10
#define COARSE_GAMMA_CHANGE 0.3

// Unknowns from which CHOLMOD's supernodal factorisation is used (simplicial below), for the
// Newton matrix and for the coarse matrix of the two-level preconditioner. The coarse matrix of a
// model in chunks is factorised supernodally at any size: its solves in two halves
// (coarse_halves.c) work on the supernodes (858 unknowns on the 64 x 64 benchmark cloth).
#define SUPERNODAL_MIN_DOFS 2000
#define COARSE_SUPERNODAL_MIN_DOFS 1000

// Free particles from which the coarse matrix is solved approximately, by COARSE_ITERATIONS
// conjugate-gradient iterations preconditioned by a multilevel V-cycle
// (preconditioner_multilevel.c, coarsest level at most MULTILEVEL_COARSEST_DOFS unknowns), and the
// aggregates are formed over the strong springs only (stiffness at least STRONG_FRACTION of the
// stiffest at either end). Measured on the benchmark cloth n = 256 over 0.02 s (alternating runs):
// with the exact coarse solve (CHOLMOD, 13 300 unknowns) its triangular solves took about a third
// of the run; one V-cycle instead took 30% more iterations (3199 against 2458) and gained 8%; 3
// conjugate-gradient iterations around it 2507 iterations; aggregates of 9 particles instead of 15
// (the bending springs, 20 times softer, no longer join them; 22 000 coarse unknowns) 2165, and the
// run took 0.87 times as long (medians of 7 and 11 runs: 23.0 s against 26.4 s; faster in 6 of the
// 7 pairs run side by side). Smaller aggregates alone, with the exact coarse solve, cut the
// iterations by 22% at n = 64 (4623 to 3620) for the same run time, so they come with the
// multilevel solve only. At n = 128 (16 382 free particles, over 0.1 s) the path took 20% fewer
// iterations (9008 against 11 330) but 1.15 times as long (medians of 3: 21.3 s against 18.5 s):
// the exact solve of 3 350 coarse unknowns was still cheap. Both sizes are overridable at compile
// time, so that the tests can run the path (and the V-cycle) on small models.
#ifndef MULTILEVEL_MIN_PARTICLES
#define MULTILEVEL_MIN_PARTICLES 40000
#endif
#ifndef MULTILEVEL_COARSEST_DOFS
#define MULTILEVEL_COARSEST_DOFS 2000
#endif
#define COARSE_ITERATIONS 3
#define STRONG_FRACTION 0.25

// Free particles from which the pcg solver's loops run in PARALLEL_CHUNKS chunks (below, every
// loop runs in order, as one chunk), and the largest share of springs between chunks for which
// it does (they are summed on the caller's thread after the chunks). The chunks do not depend on
// the number of threads (sm_simulation_def.threads), so neither do the results.
#ifndef PARALLEL_MIN_PARTICLES
#define PARALLEL_MIN_PARTICLES 4000
#endif
#define PARALLEL_CHUNKS 4
#ifndef PARALLEL_MAX_BOUNDARY_FRACTION
#define PARALLEL_MAX_BOUNDARY_FRACTION 0.125
#endif

// Doubles per spring of the scaled records (seven used: one 64-byte record each), laid out as the
// Jacobian's records, so that one loop forms products from either (add_spring_products).
#define SCALED_STRIDE 8
_Static_assert(SCALED_STRIDE == SPRING_JACOBIAN_STRIDE, "scaled and Jacobian records share a layout");

typedef struct reduced {
	sm_simulation* sim;
	bool use_cholmod;
	int64_t n;            // free degrees of freedom
	int64_t full;         // 3 per particle: the conjugate gradients' vectors, constrained entries 0
	int64_t nonzeros;
	const int64_t* rows;  // pattern (owned by the simulation's sparse Jacobian)
	const int64_t* cols;
	int64_t* diagonal;    // per dof i: entry index of (i, 3 floor(i/3)), its diagonal block's first column
	N_Vector weights;     // error weights CVODE gives (not owned)
	double* values;       // A in pattern order
	bool blocks_valid;    // block_inverse holds the inverses of A's diagonal blocks at blocks_gamma
	// Cholesky preconditioner: floating-point operations of one factorisation and of one
	// iteration (a product with A and a triangular solve pair), and those spent on iterations
	// beyond the first since the last factorisation.
	bool factor_valid;
	bool refactor;        // factorise at the next solve
	double factor_flops;
	double iteration_flops;
	double extra_flops;
	// Per particle (3 or 9 entries each, zero for constrained particles): A's inverted diagonal
	// blocks, the mass, the residual's weight (CVODE's error weight over the mass), and the
	// conjugate gradients' vectors.
	double* block_inverse;
	// pcg: every spring's share of A at the preconditioner's gamma, SCALED_STRIDE doubles each,
	// u[3], w[3], gamma^2 beta (see prepare_preconditioner), written in the same pass as the
	// diagonal blocks, so that each product with A computes one dot product per spring.
	double* scaled;
	double* mass;
	double* weight;
	double *r, *z, *p, *q, *rhs, *dv;
	// The Jacobian as every spring's factored blocks (sm_model_forces_and_jacobians), refreshed
	// at every step, in chunk order; products with A are formed from it without assembling A.
	sm_spring_jacobians* springs;
	double gamma;           // of the current solve
	double* full_force;     // forces of the fused pass (unused)
	double blocks_gamma;    // gamma of block_inverse; NAN after a Jacobian refresh
	// Two-level block-Jacobi preconditioner (pcg): aggregates of neighbouring free particles,
	// the Galerkin coarse matrix P^T A P (P: each aggregate moves as one) in 3x3 blocks,
	// factorised by CHOLMOD.
	bool two_level;
	int32_t aggregate_count;
	int32_t* aggregate;        // per particle, -1 for constrained ones
	int64_t* coarse_first;     // per aggregate: first index into coarse_neighbour (aggregate_count + 1)
	int32_t* coarse_neighbour; // neighbouring aggregates (itself included), sorted
	int32_t* coarse_self;      // per aggregate: position of itself in its neighbour list
	int64_t* spring_coarse;    // per spring: first entries of its blocks (I,I), (J,J), (I,J), (J,I), or -1
	double* coarse_mass;       // per aggregate [kg]
	double coarse_gamma;       // gamma of the coarse factorisation
	int coarse_age;            // preconditioner set-ups since
	cholmod_sparse* coarse;
	cholmod_factor* coarse_factor;
	cholmod_dense *coarse_b, *coarse_x, *coarse_y, *coarse_e;
	sm_multilevel* multilevel; // replaces coarse_factor from MULTILEVEL_MIN_PARTICLES on
	// Chunked models with coarse_factor: the coarse unknowns in two halves and a separator
	// (coarse_part, per unknown: 0, 1, 2), the factor's solves in two at once (coarse_halves.h).
	int8_t* coarse_part;
	sm_coarse_halves* coarse_halves;
	double* coarse_solution;
	// Parallel loops (pcg): the particles in contiguous ranges chunk_particle[c] ..
	// chunk_particle[c + 1]; the springs in chunk order: each chunk's springs with both ends in
	// its range (positions chunk_spring[c] .. chunk_spring[c + 1]), then the springs between
	// chunks (chunk_spring[chunks] .. spring_count), spring s at position slot[s], its particles
	// ordered_a and ordered_b at that position, and its scaled record there too; the aggregates in
	// ranges chunk_aggregate[c] .. chunk_aggregate[c + 1], each with its member particles in
	// increasing order (member[member_first[I] .. member_first[I + 1]]) for the restriction.
	// chunks = 1: every loop runs in order on the caller's thread, the springs in model order
	// (slot, ordered_a and ordered_b NULL: the model's own arrays serve, the model being replaced
	// by sm_simulation_update_model).
	int chunks;
	int32_t chunk_particle[PARALLEL_CHUNKS + 1];
	int32_t chunk_spring[PARALLEL_CHUNKS + 1];
	int32_t chunk_aggregate[PARALLEL_CHUNKS + 1];
	int32_t* slot;
	int32_t* ordered_a;
	int32_t* ordered_b;
	double* ordered_rest_length;  // the model's constants in chunk order (load_spring_order)
	double* ordered_stiffness;
	double* ordered_damping;
	int32_t* member_first;
	int32_t* member;
	double partial[PARALLEL_CHUNKS];  // per-chunk sums, added in chunk order
	sm_workers* workers;              // NULL: one thread
	double jacobian_time;   // CVODE's current time at the last Jacobian evaluation [s]; NAN if none
	// The state at which the right-hand side last stored the records (sm_reduced_rhs_records): a
	// solve at that time and state adopts them instead of evaluating again.
	bool rhs_records;
	double rhs_time;        // [s]
	double* rhs_state;      // the first 2 n entries of CVODE's y
	long last_flag;
	int last_iterations;
	SUNPSetupFn psetup;   // CVODE's preconditioner set-up hook: leads to reduced_pset
	void* psetup_data;
	// CHOLMOD
	cholmod_common common;
	bool common_started;
	cholmod_sparse* matrix;
	cholmod_factor* factor;
	cholmod_dense *b, *x, *y_work, *e_work;
} reduced;

// The solver presents itself to CVODE as an iterative one with a "preconditioner set-up",
// which CVODE calls with its own heuristics (every 20 steps, on large changes of gamma, after a
// convergence failure): it evaluates the Jacobian and tells CVODE that it is current. (A
// matrix-embedded solver is never set up by CVODE 6.)
static SUNLinearSolver_Type reduced_type(SUNLinearSolver ls)
{
	(void)ls;
	return SUNLINEARSOLVER_ITERATIVE;
}

static int reduced_set_atimes(SUNLinearSolver ls, void* data, SUNATimesFn atimes)
{
	(void)ls, (void)data, (void)atimes;  // products are formed from the reduced matrix
	return SUNLS_SUCCESS;
}

static int reduced_set_preconditioner(SUNLinearSolver ls, void* data, SUNPSetupFn setup, SUNPSolveFn solve)
{
	(void)solve;
	reduced* r = ls->content;
	r->psetup = setup;
	r->psetup_data = data;
	return SUNLS_SUCCESS;
}

static int reduced_num_iterations(SUNLinearSolver ls)
{
	return ((reduced*)ls->content)->last_iterations;
}

static SUNLinearSolver_ID reduced_id(SUNLinearSolver ls)
{
	(void)ls;
	return SUNLINEARSOLVER_CUSTOM;
}

static int reduced_initialize(SUNLinearSolver ls)
{
	((reduced*)ls->content)->last_flag = SUNLS_SUCCESS;
	return SUNLS_SUCCESS;
}

static int reduced_set_scaling(SUNLinearSolver ls, N_Vector s1, N_Vector s2)
{
	(void)s2;
	((reduced*)ls->content)->weights = s1;
	return SUNLS_SUCCESS;
}

static sunindextype reduced_last_flag(SUNLinearSolver ls)
{
	return ((reduced*)ls->content)->last_flag;
}

// values = M - gamma D - gamma^2 K in the pattern's order.
static void assemble(reduced* r, double gamma)
{
	const double* K = r->sim->dfdx;
	const double* D = r->sim->dfdv;
	const double g2 = gamma * gamma;
	for (int64_t e = 0; e < r->nonzeros; e++)
		r->values[e] = -gamma * D[e] - g2 * K[e];
	for (int64_t i = 0; i < r->n; i++)
		r->values[r->diagonal[i] + (i % 3)] += r->sim->mass_dof[i];
}

// Entry of the coarse matrix at row 3 I + i, column 3 J + j, J the k-th neighbour of I (the
// block layout of preconditioner_multilevel.h).
static int64_t coarse_entry(const reduced* r, int32_t I, int32_t k, int i, int j)
{
	return sm_block_entry(r->coarse_first, I, k, i, j);
}

// Adds sign B (row-major 3x3) to the coarse block whose first entry is `entry`, in block row I.
static void coarse_add(double* values, const reduced* r, int32_t I, int64_t entry, const double* B, double sign)
{
	const int64_t stride = 3 * (r->coarse_first[I + 1] - r->coarse_first[I]);
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			values[entry + stride * i + j] += sign * B[3 * i + j];
}

// The preconditioner at gamma. Each spring's share of A is
//   B = gamma^2 K + gamma D = gamma^2 beta I + u w^T,  w = gamma^2 z + gamma kd u
// (the factored records, forces.c); A's diagonal block at a free particle i is
//   A_ii = m_i (1 + gamma alpha) I + sum of B over its springs,
// inverted for block Jacobi. For the two-level preconditioner, a spring between aggregates I != J
// adds B to the coarse blocks (I, I) and (J, J) and subtracts it from (I, J) and (J, I); a spring
// to a constrained particle adds it to its free end's (I, I); one inside an aggregate adds
// nothing (P^T A P sums the aggregate's rows and columns, where +B and -B cancel). Then the
// coarse matrix M_c (1 + gamma alpha) + sums is factorised, unless the last factor is recent
// enough (COARSE_MAX_AGE).

typedef struct preconditioner_job {
	reduced* r;
	double gamma;
	bool singular[PARALLEL_CHUNKS];
} preconditioner_job;

// The diagonal blocks' sums (after the inverses' storage in block_inverse, 9 per particle).
static double* block_sums(const reduced* r)
{
	return r->block_inverse + 9 * (size_t)r->sim->model->particle_count;
}

// The springs at positions begin .. end of the chunk order: their scaled records (u, w,
// gamma^2 beta) from the Jacobian's, and B added to the diagonal sums of both ends.
static void add_spring_shares(reduced* r, double gamma, int32_t begin, int32_t end)
{
	const sm_model* m = r->sim->model;
	const int32_t* first = r->slot != NULL ? r->ordered_a : m->spring_a;
	const int32_t* second = r->slot != NULL ? r->ordered_b : m->spring_b;
	const double g2 = gamma * gamma;
	double* diag = block_sums(r);
	for (int32_t k = begin; k < end; k++) {
		const double* q = r->springs->data + SPRING_JACOBIAN_STRIDE * (size_t)k;
		const double w[3] = {g2 * q[3] + gamma * q[7] * q[0], g2 * q[4] + gamma * q[7] * q[1],
		                     g2 * q[5] + gamma * q[7] * q[2]};
		const double d = g2 * q[6];
		double* record = r->scaled + SCALED_STRIDE * (size_t)k;
		record[0] = q[0], record[1] = q[1], record[2] = q[2];
		record[3] = w[0], record[4] = w[1], record[5] = w[2];
		record[6] = d;
		const double B[9] = {q[0] * w[0] + d, q[0] * w[1],     q[0] * w[2],
		                     q[1] * w[0],     q[1] * w[1] + d, q[1] * w[2],
		                     q[2] * w[0],     q[2] * w[1],     q[2] * w[2] + d};
		const int32_t ends[2] = {first[k], second[k]};
		for (int e = 0; e < 2; e++) {
			double* sum = diag + 9 * (size_t)ends[e];
			for (int i = 0; i < 9; i++)
				sum[i] += B[i];
		}
	}
}

// Chunk c: its particles' diagonal sums cleared, then its springs' shares added (they reach no
// other chunk's particles).
static void spring_shares_chunk(void* context, int c)
{
	preconditioner_job* j = context;
	reduced* r = j->r;
	double* diag = block_sums(r);
	memset(diag + 9 * (size_t)r->chunk_particle[c], 0,
	       9 * (size_t)(r->chunk_particle[c + 1] - r->chunk_particle[c]) * sizeof(double));
	add_spring_shares(r, j->gamma, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

// Chunk c: the mass term added to its free particles' diagonal blocks, which are inverted.
static void invert_chunk(void* context, int c)
{
	preconditioner_job* j = context;
	reduced* r = j->r;
	const sm_model* m = r->sim->model;
	const double damping = 1.0 + j->gamma * m->def.mass_damping;
	double* diag = block_sums(r);
	j->singular[c] = false;
	for (int32_t i = r->chunk_particle[c]; i < r->chunk_particle[c + 1]; i++) {
		double* inv = r->block_inverse + 9 * (size_t)i;
		if (m->free_index[i] < 0) {
			memset(inv, 0, 9 * sizeof(double));
			continue;
		}
		double* a = diag + 9 * (size_t)i;
		const double mass = m->mass[i] * damping;
		a[0] += mass, a[4] += mass, a[8] += mass;
		j->singular[c] = j->singular[c] || !sm_invert3(a, inv);
	}
}

// The coarse matrix at gamma from the scaled records (B = u w^T + gamma^2 beta I, the numbers
// add_spring_shares summed), the springs in the model's order; then factorised. Returns 0, 1 if
// it is not positive definite, -1 if out of memory (no symbolic analysis could be made).
static int refresh_coarse(reduced* r, double gamma)
{
	const sm_model* m = r->sim->model;
	const double damping = 1.0 + gamma * m->def.mass_damping;
	double* coarse = r->coarse->x;
	memset(coarse, 0, 9 * (size_t)r->coarse_first[r->aggregate_count] * sizeof(double));
	r->coarse_gamma = gamma;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int64_t* entry = r->spring_coarse + 4 * (size_t)s;
		if (entry[0] < 0 && entry[1] < 0)
			continue;
		const double* e = r->scaled + SCALED_STRIDE * (size_t)(r->slot != NULL ? r->slot[s] : s);
		const double B[9] = {e[0] * e[3] + e[6], e[0] * e[4],        e[0] * e[5],
		                     e[1] * e[3],        e[1] * e[4] + e[6], e[1] * e[5],
		                     e[2] * e[3],        e[2] * e[4],        e[2] * e[5] + e[6]};
		const int32_t I = r->aggregate[m->spring_a[s]], J = r->aggregate[m->spring_b[s]];
		if (entry[0] >= 0)
			coarse_add(coarse, r, I, entry[0], B, 1.0);
		if (entry[1] >= 0)
			coarse_add(coarse, r, J, entry[1], B, 1.0);
		if (entry[2] >= 0) {
			// B is symmetric (the definite variant): the (J, I) block is the same.
			coarse_add(coarse, r, I, entry[2], B, -1.0);
			coarse_add(coarse, r, J, entry[3], B, -1.0);
		}
	}
	memset(r->coarse_mass, 0, (size_t)r->aggregate_count * sizeof(double));
	for (int32_t i = 0; i < m->particle_count; i++)
		if (r->aggregate[i] >= 0)
			r->coarse_mass[r->aggregate[i]] += m->mass[i];
	for (int32_t I = 0; I < r->aggregate_count; I++)
		for (int i = 0; i < 3; i++)
			coarse[coarse_entry(r, I, r->coarse_self[I], i, i)] += r->coarse_mass[I] * damping;
	int status;
	if (r->multilevel != NULL) {
		status = sm_multilevel_refresh(r->multilevel, coarse, &r->common) ? 0 : 1;
	} else {
		// The symbolic analysis, once: in halves for a model in chunks (split_coarse). Without it
		// (out of memory) nothing can be factorised at any step size: an error, not a matrix that
		// is not positive definite, which a smaller step may mend.
		if (r->coarse_factor == NULL && r->coarse_part != NULL)
			r->coarse_halves = sm_coarse_halves_create(r->coarse, r->coarse_part, &r->coarse_factor, &r->common);
		else if (r->coarse_factor == NULL)
			r->coarse_factor = cholmod_l_analyze(r->coarse, &r->common);
		if (r->coarse_factor == NULL)
			status = -1;
		else if (cholmod_l_factorize(r->coarse, r->coarse_factor, &r->common) && r->common.status == CHOLMOD_OK)
			status = 0;
		else
			status = 1;
	}
	// A failed refresh is retried at the next set-up.
	r->coarse_age = status == 0 ? 0 : COARSE_MAX_AGE;
	return status;
}

// The scaled records and the inverted diagonal blocks, chunk by chunk (the springs between
// chunks on the caller's thread in between), then the coarse matrix if it is due. Returns 0, 1 if
// a block is singular or the coarse matrix is not positive definite, -1 if out of memory.
static int prepare_preconditioner(reduced* r, double gamma)
{
	preconditioner_job job = {.r = r, .gamma = gamma};
	sm_workers_run(r->workers, spring_shares_chunk, &job, r->chunks);
	add_spring_shares(r, gamma, r->chunk_spring[r->chunks], r->sim->model->spring_count);
	sm_workers_run(r->workers, invert_chunk, &job, r->chunks);
	for (int c = 0; c < r->chunks; c++)
		if (job.singular[c])
			return 1;
	if (!r->two_level)
		return 0;
	if (r->coarse_age >= COARSE_MAX_AGE || !(fabs(gamma / r->coarse_gamma - 1.0) <= COARSE_GAMMA_CHANGE))
		return refresh_coarse(r, gamma);
	r->coarse_age++;
	return 0;
}

// The springs at positions begin .. end of the chunk order added to q from their records, u[3],
// w[3], c (stride 8): with r = p_b - p_a, u (w . r) + c r subtracted at a and added at b. The
// scaled records give the share of A (w = gamma^2 z + gamma kd u, c = gamma^2 beta); the
// Jacobian's own give that of -K (w = z, c = beta; kd, the eighth entry, unread).
static void add_spring_products(const reduced* r, const double* records, const double* p, double* restrict q,
                                int32_t begin, int32_t end)
{
	const int32_t* restrict first = r->slot != NULL ? r->ordered_a : r->sim->model->spring_a;
	const int32_t* restrict second = r->slot != NULL ? r->ordered_b : r->sim->model->spring_b;
	const double* restrict scaled = records;
	if (begin >= end)
		return;
	// Structures list their springs particle by particle, so consecutive springs often share
	// their first particle: its sum and its p are kept in registers until the particle changes
	// (holding p too: 1.6 % faster at n = 16, 1 - 2 % at n = 64 and 128).
	size_t held = 3 * (size_t)first[begin];
	double hx = 0.0, hy = 0.0, hz = 0.0;
	double px = p[held], py = p[held + 1], pz = p[held + 2];
	for (int32_t s = begin; s < end; s++) {
		const double* restrict e = scaled + SCALED_STRIDE * (size_t)s;
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		if (a != held) {
			q[held] -= hx;
			q[held + 1] -= hy;
			q[held + 2] -= hz;
			hx = hy = hz = 0.0;
			held = a;
			px = p[a], py = p[a + 1], pz = p[a + 2];
		}
		const double rx = p[b] - px, ry = p[b + 1] - py, rz = p[b + 2] - pz;
		const double c = e[3] * rx + e[4] * ry + e[5] * rz;
		const double fx = e[0] * c + e[6] * rx, fy = e[1] * c + e[6] * ry, fz = e[2] * c + e[6] * rz;
		hx += fx;
		hy += fy;
		hz += fz;
		q[b] += fx;
		q[b + 1] += fy;
		q[b + 2] += fz;
	}
	q[held] -= hx;
	q[held + 1] -= hy;
	q[held + 2] -= hz;
}

typedef struct product_job {
	reduced* r;
	const double* p;
	double* q;
} product_job;

// Chunk c of q = A p (pcg): the mass term at its particles, then its springs, which reach no
// other chunk's particles.
static void product_chunk(void* context, int c)
{
	const product_job* j = context;
	const reduced* r = j->r;
	const double damping = 1.0 + r->gamma * r->sim->model->def.mass_damping;
	const double* restrict p = j->p;
	const double* restrict mass = r->mass;
	double* restrict q = j->q;
	for (int64_t i = 3 * (int64_t)r->chunk_particle[c]; i < 3 * (int64_t)r->chunk_particle[c + 1]; i++)
		q[i] = mass[i] * damping * p[i];
	add_spring_products(r, r->scaled, p, q, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

// Chunk c of q = -K p (the Jacobian's records): zero at its particles, then its springs.
static void stiffness_chunk(void* context, int c)
{
	const product_job* j = context;
	const reduced* r = j->r;
	memset(j->q + 3 * (size_t)r->chunk_particle[c], 0,
	       3 * (size_t)(r->chunk_particle[c + 1] - r->chunk_particle[c]) * sizeof(double));
	add_spring_products(r, r->springs->data, j->p, j->q, r->chunk_spring[c], r->chunk_spring[c + 1]);
}

typedef struct dot_job {
	reduced* r;
	const double* a;
	const double* b;
} dot_job;

static void dot_chunk(void* context, int c)
{
	const dot_job* j = context;
	const double* restrict a = j->a;
	const double* restrict b = j->b;
	double s = 0.0;
	for (int64_t i = 3 * (int64_t)j->r->chunk_particle[c]; i < 3 * (int64_t)j->r->chunk_particle[c + 1]; i++)
		s += a[i] * b[i];
	j->r->partial[c] = s;
}

// The chunks' partial sums, added in chunk order (with one chunk: the sum in order).
static double sum_partials(const reduced* r)
{
	double s = r->partial[0];
	for (int c = 1; c < r->chunks; c++)
		s += r->partial[c];
	return s;
}

// a . b over all particles, chunk by chunk.
static double dot(reduced* r, const double* a, const double* b)
{
	dot_job job = {r, a, b};
	sm_workers_run(r->workers, dot_chunk, &job, r->chunks);
	return sum_partials(r);
}

// q = A p = M (1 + gamma alpha) p - gamma D p - gamma^2 K p over all particles (p is zero at the
// constrained ones, whose entries of q are set to zero); returns p . q.
//
// With pcg, each spring's share comes from its scaled record: with r = p_b - p_a,
//   (gamma^2 K + gamma D) r = u (w . r) + gamma^2 beta r,
// subtracted at a and added at b: one dot product per spring where the unscaled records need
// two and four more multiplications. Measured on the benchmark cloth's springs (definite
// variant, medians of 9 timings): 0.78 - 0.79 of the time of
// sm_spring_jacobians_combined_product at n = 16, 64 and 128; the records cost nothing extra to
// write, being summed into the preconditioner in the same pass anyway. With cholmod (no
// preconditioner pass) the unscaled records serve.
static double multiply(reduced* r, const double* p, double* restrict q)
{
	const double g = r->gamma;
	const sm_simulation* sim = r->sim;
	if (r->use_cholmod) {
		sm_spring_jacobians_combined_product(r->springs, sim->model, g * g, g, p, q);
		for (int64_t i = 0; i < r->full; i++)
			q[i] = r->mass[i] * p[i] - q[i];
	} else {
		product_job job = {r, p, q};
		sm_workers_run(r->workers, product_chunk, &job, r->chunks);
		add_spring_products(r, r->scaled, p, q, r->chunk_spring[r->chunks], sim->model->spring_count);
	}
	for (int32_t k = 0; k < sim->constrained_count; k++)
		memset(q + 3 * (size_t)sim->constrained[k], 0, 3 * sizeof(double));
	return dot(r, p, q);
}

static int reduced_setup(SUNLinearSolver ls, SUNMatrix unused)
{
	(void)unused;
	reduced* r = ls->content;
	if (r->psetup == NULL)
		return r->last_flag = SUNLS_SUCCESS;
	int flag = r->psetup(r->psetup_data);
	r->last_flag = flag == 0 ? SUNLS_SUCCESS : flag > 0 ? SUNLS_PSET_FAIL_REC : SUNLS_PSET_FAIL_UNREC;
	return (int)r->last_flag;
}

// Assembles A at the current Jacobian and gamma and factorises it. Returns 0, > 0 if A is not
// positive definite (recoverable: a state far from any physical one, CVODE retries with a
// smaller step), < 0 on failure.
static int factorize(reduced* r)
{
	sm_simulation* sim = r->sim;
	const double start = sm_simulation_clock();
	const sm_status st =
		sm_sparse_jacobian_fill_from_springs(sim->pattern, sim->model, r->springs, sim->dfdx, sim->dfdv);
	sim->base.jacobian_seconds += sm_simulation_clock() - start;
	if (st != SM_OK)
		return -1;
	assemble(r, r->gamma);
	memcpy(r->matrix->x, r->values, (size_t)r->nonzeros * sizeof(double));
	if (r->factor == NULL) {
		r->factor = cholmod_l_analyze(r->matrix, &r->common);
		if (r->factor == NULL)
			return -1;
	}
	r->factor_valid = false;
	const int ok = cholmod_l_factorize(r->matrix, r->factor, &r->common);
	if (!ok || r->common.status == CHOLMOD_OUT_OF_MEMORY)
		return -1;
	if (r->common.status != CHOLMOD_OK)
		return 1;
	r->sim->factorizations++;
	r->factor_valid = true;
	r->refactor = false;
	r->extra_flops = 0.0;
	// CHOLMOD counts the factorisation's operations (common.fl) and the factor's entries
	// (common.lnz): a solve pair reads L twice (4 lnz operations), the product A p 2 nnz(A).
	r->factor_flops = r->common.fl > 0.0 ? r->common.fl : 1.0;
	r->iteration_flops = 4.0 * r->common.lnz + 2.0 * (double)r->nonzeros;
	return 0;
}

// The masses per degree of freedom, zero at constrained particles: at creation and at every
// re-initialisation, which follows sm_simulation_update_model (the only way they change). Mass
// damping enters A as M (1 + gamma alpha) through the combined product.
static void load_masses(reduced* r)
{
	const sm_model* m = r->sim->model;
	for (int32_t i = 0; i < m->particle_count; i++)
		for (int c = 0; c < 3; c++)
			r->mass[3 * (size_t)i + c] = m->free_index[i] >= 0 ? m->mass[i] : 0.0;
}

typedef struct forces_job {
	reduced* r;
	const double *x, *v, *f_external;
	double* f;
	sm_spring_order order;
} forces_job;

// Chunk c of the forces: its particles' body forces, then its springs, with their records.
static void forces_chunk(void* context, int c)
{
	const forces_job* j = context;
	reduced* r = j->r;
	const double body = sm_model_body_forces_range(r->sim->model, j->v, j->f_external, j->f, r->chunk_particle[c],
	                                               r->chunk_particle[c + 1]);
	r->partial[c] = sm_spring_order_forces_and_jacobians(&j->order, r->chunk_spring[c], r->chunk_spring[c + 1], j->x,
	                                                     j->v, j->f, r->springs->data) +
	                body;
}

// sm_model_forces_power_and_jacobians at x, v into f and the solver's records, chunk by chunk
// (the springs between chunks after, on the caller's thread, and the chunks' powers added in
// chunk order) when the model is split into chunks; returns the dissipated power [W].
static double forces_and_records(reduced* r, const double* x, const double* v, const double* f_external, double* f)
{
	const sm_model* m = r->sim->model;
	if (r->slot == NULL)
		return sm_model_forces_power_and_jacobians(m, x, v, f_external, f, r->springs);
	forces_job job = {r, x, v, f_external, f,
	                  {r->ordered_a, r->ordered_b, r->ordered_rest_length, r->ordered_stiffness, r->ordered_damping}};
	sm_workers_run(r->workers, forces_chunk, &job, r->chunks);
	const double boundary = sm_spring_order_forces_and_jacobians(&job.order, r->chunk_spring[r->chunks],
	                                                             m->spring_count, x, v, f, r->springs->data);
	r->springs->variant = SM_JACOBIAN_DEFINITE;
	r->springs->evaluated = 1;
	return sum_partials(r) + boundary;
}

// The model's spring constants in chunk order: when the chunks are built and at every
// invalidation, which follows every change of them (a break, a restore, a reset, a new model).
static void load_spring_order(reduced* r)
{
	const sm_model* m = r->sim->model;
	if (r->slot == NULL)
		return;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t k = r->slot[s];
		r->ordered_rest_length[k] = m->rest_length[s];
		r->ordered_stiffness[k] = m->stiffness[s];
		r->ordered_damping[k] = m->damping[s];
	}
}

// Makes the Jacobian current at CVODE's state y (time t): adopts the records the right-hand side
// stored if they were evaluated at exactly this time and state, evaluates the forces and every
// spring's Jacobian blocks there otherwise.
static void current_jacobian(reduced* r, double t, const double* y)
{
	sm_simulation* sim = r->sim;
	if (!(r->rhs_records && r->rhs_time == t && memcmp(r->rhs_state, y, 2 * (size_t)r->n * sizeof(double)) == 0)) {
		double* x = sim->work_position;
		double* v = sim->work_velocity;
		sm_simulation_unpack(sim, t, y, x, v);
		const double start = sm_simulation_clock();
		forces_and_records(r, x, v, sim->external_force, r->full_force);
		sim->base.jacobian_seconds += sm_simulation_clock() - start;
	}
	sim->jacobian_evaluations++;
	r->blocks_gamma = NAN;
	r->jacobian_time = t;
	r->rhs_records = false;
}

int sm_reduced_solver_product(SUNLinearSolver ls, double gamma, const double* p, double* q)
{
	reduced* r = ls->content;
	sm_simulation* sim = r->sim;
	if (r->n == 0) {
		memset(q, 0, (size_t)r->full * sizeof(double));
		return 0;
	}
	load_spring_order(r);  // the model may have changed since the last invalidation
	current_jacobian(r, sim->time, N_VGetArrayPointer(sim->y));
	r->gamma = gamma;
	int status = 0;
	if (!r->use_cholmod && prepare_preconditioner(r, gamma) != 0)
		status = -1;
	else
		multiply(r, p, q);
	sm_reduced_solver_invalidate(ls, false);  // the next solve evaluates and prepares afresh
	return status;
}

// CVODE evaluates the right-hand side at the predicted state of every step attempt and then
// solves at that state, where the solver evaluates the Jacobian: the right-hand side computes
// both in one pass over the springs instead (sm_reduced_rhs_forces), which spares one force
// evaluation per step. Its records are adopted only if the solve's time and state are exactly
// those of the evaluation, so the order of CVODE's calls decides only what is spared, never the
// result: the trajectory is the same, bit for bit.
bool sm_reduced_rhs_wants_records(SUNLinearSolver ls, double t)
{
	const reduced* r = ls->content;
	return r->n > 0 && !(t == r->jacobian_time);
}

double sm_reduced_rhs_forces(SUNLinearSolver ls, double t, const double* y, const double* x, const double* v,
                             const double* f_external, double* f)
{
	reduced* r = ls->content;
	const double power = forces_and_records(r, x, v, f_external, f);
	memcpy(r->rhs_state, y, 2 * (size_t)r->n * sizeof(double));
	r->rhs_time = t;
	r->rhs_records = true;
	r->jacobian_time = NAN;  // the records are no longer those of the last solve
	r->blocks_gamma = NAN;
	return power;
}

int sm_reduced_pset(sunrealtype t, N_Vector y, N_Vector fy, sunbooleantype jok, sunbooleantype* jcur,
                    sunrealtype gamma, void* user_data)
{
	(void)fy, (void)gamma, (void)jok;
	sm_simulation* sim = user_data;
	reduced* r = sim->linear_solver->content;
	*jcur = SUNFALSE;
	if (r->n == 0)
		return 0;
	// Always the Jacobian at this state: the right-hand side's records, or one pass over the
	// springs.
	current_jacobian(r, t, N_VGetArrayPointer(y));
	*jcur = SUNTRUE;
	return 0;
}

int sm_reduced_psolve(sunrealtype t, N_Vector y, N_Vector fy, N_Vector rv, N_Vector z, sunrealtype gamma,
                      sunrealtype delta, int lr, void* user_data)
{
	(void)t, (void)y, (void)fy, (void)gamma, (void)delta, (void)lr, (void)user_data;
	N_VScale(1.0, rv, z);  // never called: the reduced solver preconditions internally
	return 0;
}

// Error-weighted 2-norm of the velocity rows' residual M^-1 res (weight = CVODE's error weight
// over the mass, zero at constrained particles).
static double residual_norm(const reduced* r, const double* res)
{
	double s = 0.0;
	for (int64_t i = 0; i < r->full; i++) {
		const double t = res[i] * r->weight[i];
		s += t * t;
	}
	return sqrt(s);
}

typedef struct precondition_job {
	reduced* r;
	const double* in;
	double* out;
	const double* yc;  // the coarse solution, for the prolongation
} precondition_job;

// Chunk c of block Jacobi (out_i = A_ii^-1 in_i, zero blocks at constrained particles) at its
// particles, with in . out when there is no coarse correction, and of the restriction
// P^T in at its aggregates, each summed over its members in order.
static void block_jacobi_chunk(void* context, int c)
{
	const precondition_job* j = context;
	reduced* r = j->r;
	const double* restrict inverse = r->block_inverse;
	const double* restrict in = j->in;
	double* restrict out = j->out;
	double sum = 0.0;
	for (int64_t k = r->chunk_particle[c]; k < r->chunk_particle[c + 1]; k++) {
		const double* m = inverse + 9 * k;
		const double* a = in + 3 * k;
		double* o = out + 3 * k;
		o[0] = m[0] * a[0] + m[1] * a[1] + m[2] * a[2];
		o[1] = m[3] * a[0] + m[4] * a[1] + m[5] * a[2];
		o[2] = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
		sum += a[0] * o[0] + a[1] * o[1] + a[2] * o[2];
	}
	r->partial[c] = sum;
	if (!r->two_level)
		return;
	double* restrict rc = r->coarse_b->x;
	const int32_t* restrict member = r->member;
	for (int32_t I = r->chunk_aggregate[c]; I < r->chunk_aggregate[c + 1]; I++) {
		double x = 0.0, y = 0.0, z = 0.0;
		for (int32_t e = r->member_first[I]; e < r->member_first[I + 1]; e++) {
			const double* a = in + 3 * (size_t)member[e];
			x += a[0], y += a[1], z += a[2];
		}
		rc[3 * (size_t)I] = x, rc[3 * (size_t)I + 1] = y, rc[3 * (size_t)I + 2] = z;
	}
}

// Chunk c of the prolongation out += P yc at its particles, with in . out.
static void prolongation_chunk(void* context, int c)
{
	const precondition_job* j = context;
	reduced* r = j->r;
	const int32_t* restrict aggregate = r->aggregate;
	const double* restrict in = j->in;
	const double* restrict yc = j->yc;
	double* restrict out = j->out;
	double sum = 0.0;
	for (int64_t k = r->chunk_particle[c]; k < r->chunk_particle[c + 1]; k++) {
		const int32_t I = aggregate[k];
		if (I < 0)
			continue;
		const double* a = in + 3 * k;
		double* o = out + 3 * k;
		o[0] += yc[3 * (size_t)I];
		o[1] += yc[3 * (size_t)I + 1];
		o[2] += yc[3 * (size_t)I + 2];
		sum += a[0] * o[0] + a[1] * o[1] + a[2] * o[2];
	}
	r->partial[c] = sum;
}

// Applies the preconditioner, out = B in, and returns in . out in *dot: block Jacobi plus the
// coarse correction P A_c^-1 P^T in (additive), or a solve with the Cholesky factor (over the
// free degrees of freedom). The restriction is summed in the block-Jacobi pass and the dot
// product in the prolongation's, so that each pass over the particles does all it can.
static bool apply_preconditioner(reduced* r, const double* in, double* out, double* dot)
{
	const sm_simulation* sim = r->sim;
	double sum = 0.0;
	if (!r->use_cholmod) {
		precondition_job job = {r, in, out, NULL};
		sm_workers_run(r->workers, block_jacobi_chunk, &job, r->chunks);
		if (!r->two_level) {
			*dot = sum_partials(r);
			return true;
		}
		if (r->multilevel != NULL) {
			job.yc = sm_multilevel_solve(r->multilevel, r->coarse_b->x, COARSE_ITERATIONS, r->workers, &r->common);
			if (job.yc == NULL)
				return false;
		} else if (r->coarse_halves != NULL) {
			sm_coarse_halves_solve(r->coarse_halves, r->coarse_factor, r->coarse_b->x, r->coarse_solution, r->workers);
			job.yc = r->coarse_solution;
		} else {
			if (!cholmod_l_solve2(CHOLMOD_A, r->coarse_factor, r->coarse_b, NULL, &r->coarse_x, NULL, &r->coarse_y,
			                      &r->coarse_e, &r->common))
				return false;
			job.yc = r->coarse_x->x;
		}
		sm_workers_run(r->workers, prolongation_chunk, &job, r->chunks);
		*dot = sum_partials(r);
		return true;
	}
	double* b = r->b->x;
	for (int32_t k = 0; k < sim->free_count; k++)
		memcpy(b + 3 * (size_t)k, in + 3 * (size_t)sim->free_particles[k], 3 * sizeof(double));
	if (!cholmod_l_solve2(CHOLMOD_A, r->factor, r->b, NULL, &r->x, NULL, &r->y_work, &r->e_work, &r->common))
		return false;
	const double* x = r->x->x;
	memset(out, 0, (size_t)r->full * sizeof(double));
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k];
		memcpy(out + i, x + 3 * (size_t)k, 3 * sizeof(double));
		sum += in[i] * out[i] + in[i + 1] * out[i + 1] + in[i + 2] * out[i + 2];
	}
	*dot = sum;
	return true;
}

typedef struct update_job {
	reduced* r;
	double *dv, *res, *p;
	const double *q, *z;
	double step;  // alpha, then beta
} update_job;

// Chunk c of dv += alpha p, res -= alpha q, with the squares of the weighted residual.
static void update_chunk(void* context, int c)
{
	const update_job* j = context;
	reduced* r = j->r;
	double* restrict dv = j->dv;
	double* restrict res = j->res;
	const double* restrict p = j->p;
	const double* restrict q = j->q;
	const double* restrict weight = r->weight;
	const double alpha = j->step;
	double squares = 0.0;
	for (int64_t i = 3 * (int64_t)r->chunk_particle[c]; i < 3 * (int64_t)r->chunk_particle[c + 1]; i++) {
		dv[i] += alpha * p[i];
		res[i] -= alpha * q[i];
		const double t = res[i] * weight[i];
		squares += t * t;
	}
	r->partial[c] = squares;
}

// Chunk c of p = z + beta p.
static void direction_chunk(void* context, int c)
{
	const update_job* j = context;
	double* restrict p = j->p;
	const double* restrict z = j->z;
	const double beta = j->step;
	for (int64_t i = 3 * (int64_t)j->r->chunk_particle[c]; i < 3 * (int64_t)j->r->chunk_particle[c + 1]; i++)
		p[i] = z[i] + beta * p[i];
}

// Preconditioned conjugate gradients on A dv = rhs from dv = 0, at most max_iterations, over
// all particles (the constrained entries stay zero), flexible with the multilevel coarse solve.
// Returns a SUNLS flag.
static int conjugate_gradients(reduced* r, double* dv, double tol, int max_iterations)
{
	const int64_t n = r->full;
	double *res = r->r, *z = r->z, *p = r->p, *q = r->q;
	memcpy(res, r->rhs, (size_t)n * sizeof(double));
	r->last_iterations = 0;
	memset(dv, 0, (size_t)n * sizeof(double));
	const double initial = residual_norm(r, res);
	double norm = initial;
	if (norm <= tol)
		return SUNLS_SUCCESS;
	double rz;
	if (!apply_preconditioner(r, res, z, &rz))
		return SUNLS_MEM_FAIL;
	memcpy(p, z, (size_t)n * sizeof(double));
	for (int iteration = 1; iteration <= max_iterations; iteration++) {
		const double pq = multiply(r, p, q);
		if (!(pq > 0.0) || !isfinite(pq))
			return SUNLS_PACKAGE_FAIL_REC;
		const double alpha = rz / pq;
		update_job job = {r, dv, res, p, q, z, alpha};
		sm_workers_run(r->workers, update_chunk, &job, r->chunks);
		r->sim->linear_iterations++;
		r->last_iterations++;
		norm = sqrt(sum_partials(r));
		if (norm <= tol)
			return SUNLS_SUCCESS;
		double rz_next;
		if (!apply_preconditioner(r, res, z, &rz_next))
			return SUNLS_MEM_FAIL;
		// Flexible (Polak-Ribiere) when the preconditioner is not linear: beta = z' (r' - r) / (z r)
		// with r' - r = -alpha q.
		job.step = r->multilevel != NULL ? -alpha * dot(r, z, q) / rz : rz_next / rz;
		rz = rz_next;
		sm_workers_run(r->workers, direction_chunk, &job, r->chunks);
	}
	return norm < initial ? SUNLS_RES_REDUCED : SUNLS_CONV_FAIL;
}

// Conjugate gradients preconditioned by the Cholesky factor of an earlier Newton matrix; if they
// do not converge in CHOLESKY_MAX_ITERATIONS, the current A is factorised and they start again.
// Iterations beyond the first are counted against the cost of a factorisation: once they have
// cost as much as one, the next set-up factorises afresh.
static int cholesky_solve(reduced* r, double* dv, double tol)
{
	int flag = SUNLS_CONV_FAIL;
	if (r->factor_valid && !r->refactor)
		flag = conjugate_gradients(r, dv, tol, CHOLESKY_MAX_ITERATIONS);
	if (r->refactor || (flag != SUNLS_SUCCESS && flag != SUNLS_MEM_FAIL)) {
		const int f = factorize(r);
		if (f != 0)
			return f > 0 ? SUNLS_PACKAGE_FAIL_REC : SUNLS_MEM_FAIL;
		flag = conjugate_gradients(r, dv, tol, CHOLESKY_MAX_ITERATIONS);
	}
	if (r->last_iterations > 1)
		r->extra_flops += (double)(r->last_iterations - 1) * r->iteration_flops;
	if (r->extra_flops > r->factor_flops)
		r->refactor = true;
	return flag;
}

static int reduced_solve(SUNLinearSolver ls, SUNMatrix unused, N_Vector xv, N_Vector bv, sunrealtype tol)
{
	(void)unused;
	reduced* r = ls->content;
	sm_simulation* sim = r->sim;
	const int64_t n = r->n;
	const double* b = N_VGetArrayPointer(bv);
	double* x = N_VGetArrayPointer(xv);
	double gamma;
	if (CVodeGetCurrentGamma(sim->cvode, &gamma) != CV_SUCCESS)
		return r->last_flag = SUNLS_MEM_FAIL;
	x[2 * n] = b[2 * n];
	if (n == 0)
		return r->last_flag = SUNLS_SUCCESS;
	// A new step (or a new attempt at one) since the Jacobian was evaluated: evaluate it at the
	// current iterate, the predicted state at the first Newton iteration.
	double t_current;
	N_Vector y_current;
	if (CVodeGetCurrentTime(sim->cvode, &t_current) != CV_SUCCESS ||
	    CVodeGetCurrentState(sim->cvode, &y_current) != CV_SUCCESS)
		return r->last_flag = SUNLS_MEM_FAIL;
	if (!(t_current == r->jacobian_time))
		current_jacobian(r, t_current, N_VGetArrayPointer(y_current));
	const double start = sm_simulation_clock();
	r->gamma = gamma;
	// Over all particles: p = bx, rhs = M bv + gamma K bx, and the residual's weights (p and
	// weight stay zero at constrained particles from their allocation on).
	const double* w = r->weights ? N_VGetArrayPointer(r->weights) + n : NULL;
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
		for (int c = 0; c < 3; c++) {
			r->p[i + c] = b[f + c];
			r->weight[i + c] = (w ? w[f + c] : 1.0) / r->mass[i + c];
		}
	}
	product_job stiffness = {r, r->p, r->rhs};  // rhs = -K bx first
	sm_workers_run(r->workers, stiffness_chunk, &stiffness, r->chunks);
	add_spring_products(r, r->springs->data, r->p, r->rhs, r->chunk_spring[r->chunks], sim->model->spring_count);
	for (int32_t k = 0; k < sim->constrained_count; k++)
		memset(r->rhs + 3 * (size_t)sim->constrained[k], 0, 3 * sizeof(double));
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
		for (int c = 0; c < 3; c++)
			r->rhs[i + c] = r->mass[i + c] * b[n + f + c] - gamma * r->rhs[i + c];
	}
	// Out of memory, the solve fails (unrecoverably: CVODE stops) and the next one prepares again.
	int prepared = 0;
	if (!r->use_cholmod && !(r->blocks_gamma == gamma)) {
		prepared = prepare_preconditioner(r, gamma);
		r->blocks_valid = prepared == 0;
		r->blocks_gamma = prepared < 0 ? NAN : gamma;
	}
	int flag;
	if (r->use_cholmod)
		flag = cholesky_solve(r, r->dv, tol);
	else if (prepared < 0)
		flag = SUNLS_MEM_FAIL;
	else
		flag = r->blocks_valid ? conjugate_gradients(r, r->dv, tol, PCG_MAX_ITERATIONS) : SUNLS_PACKAGE_FAIL_REC;
	if (flag == SUNLS_SUCCESS || flag == SUNLS_RES_REDUCED)
		for (int32_t k = 0; k < sim->free_count; k++) {
			const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
			for (int c = 0; c < 3; c++) {
				x[n + f + c] = r->dv[i + c];
				x[f + c] = b[f + c] + gamma * r->dv[i + c];
			}
		}
	sim->base.linear_solve_seconds += sm_simulation_clock() - start;
	return r->last_flag = flag;
}

// Groups the free particles into aggregates (each a particle and its spring neighbours not yet
// taken, over the strong springs only if strong_only; particles left over join a neighbouring
// aggregate) and builds the coarse pattern (over all springs). Returns false on out of memory.
static bool build_two_level(reduced* r, bool strong_only)
{
	sm_simulation* sim = r->sim;
	const sm_model* m = sim->model;
	const int32_t nf = sim->free_count;
	bool ok = false;
	// Neighbours of every free particle among the free particles (CSR, duplicates allowed).
	int64_t* first = calloc((size_t)nf + 1, sizeof(int64_t));
	int32_t* neighbour = malloc(2 * (size_t)m->spring_count * sizeof(int32_t) + sizeof(int32_t));
	int64_t* fill = malloc(((size_t)nf + 1) * sizeof(int64_t));
	int32_t* mark = malloc(((size_t)nf + 1) * sizeof(int32_t));
	int32_t* group = malloc(((size_t)nf + 1) * sizeof(int32_t));  // aggregate per free particle
	bool* strong = malloc(2 * (size_t)m->spring_count * sizeof(bool) + 1);  // per neighbour entry
	double* strongest = calloc((size_t)nf + 1, sizeof(double));
	r->aggregate = malloc(((size_t)m->particle_count + 1) * sizeof(int32_t));
	r->spring_coarse = malloc(4 * (size_t)m->spring_count * sizeof(int64_t) + sizeof(int64_t));
	if (!first || !neighbour || !fill || !mark || !group || !r->aggregate || !r->spring_coarse || !strong ||
	    !strongest)
		goto done;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			strongest[a] = fmax(strongest[a], m->stiffness[s]);
			strongest[b] = fmax(strongest[b], m->stiffness[s]);
		}
	}
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			first[a + 1]++;
			first[b + 1]++;
		}
	}
	for (int32_t q = 0; q < nf; q++)
		first[q + 1] += first[q];
	memcpy(fill, first, ((size_t)nf + 1) * sizeof(int64_t));
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			const double stiffest = fmax(strongest[a], strongest[b]);
			strong[fill[a]] = strong[fill[b]] = !strong_only || m->stiffness[s] >= STRONG_FRACTION * stiffest;
			neighbour[fill[a]++] = b;
			neighbour[fill[b]++] = a;
		}
	}
	// Pass 1: a particle whose neighbours are all free of aggregates starts one with them.
	int32_t count = 0;
	for (int32_t q = 0; q < nf; q++)
		group[q] = -1;
	for (int32_t q = 0; q < nf; q++) {
		if (group[q] >= 0)
			continue;
		bool all_free = true;
		for (int64_t e = first[q]; e < first[q + 1] && all_free; e++)
			all_free = !strong[e] || group[neighbour[e]] < 0;
		if (!all_free)
			continue;
		group[q] = count;
		for (int64_t e = first[q]; e < first[q + 1]; e++)
			if (strong[e])
				group[neighbour[e]] = count;
		count++;
	}
	// Pass 2: the others join a neighbour's aggregate (from pass 1), or start their own.
	for (int32_t q = 0; q < nf; q++)
		mark[q] = group[q];
	for (int32_t q = 0; q < nf; q++) {
		if (group[q] >= 0)
			continue;
		for (int64_t e = first[q]; e < first[q + 1] && group[q] < 0; e++)
			if (strong[e] && mark[neighbour[e]] >= 0)
				group[q] = mark[neighbour[e]];
		if (group[q] < 0)
			group[q] = count++;
	}
	r->aggregate_count = count;
	// Coarse pattern: the aggregates linked by springs, each list sorted, itself included.
	r->coarse_first = calloc((size_t)count + 1, sizeof(int64_t));
	r->coarse_self = malloc(((size_t)count + 1) * sizeof(int32_t));
	r->coarse_mass = calloc((size_t)count + 1, sizeof(double));
	if (!r->coarse_first || !r->coarse_self || !r->coarse_mass)
		goto done;
	// Members of each aggregate (reusing fill as the member list, mark as positions).
	int64_t* member_first = calloc((size_t)count + 1, sizeof(int64_t));
	int32_t* member = malloc(((size_t)nf + 1) * sizeof(int32_t));
	int32_t* seen = malloc(((size_t)count + 1) * sizeof(int32_t));
	int32_t* list = malloc(((size_t)count + 1) * sizeof(int32_t));
	if (!member_first || !member || !seen || !list) {
		free(member_first), free(member), free(seen), free(list);
		goto done;
	}
	for (int32_t q = 0; q < nf; q++)
		member_first[group[q] + 1]++;
	for (int32_t I = 0; I < count; I++)
		member_first[I + 1] += member_first[I];
	for (int32_t I = 0; I <= count; I++)
		fill[I] = member_first[I];
	for (int32_t q = 0; q < nf; q++)
		member[fill[group[q]]++] = q;
	for (int32_t I = 0; I < count; I++)
		seen[I] = -1;
	// Two passes over the aggregates: count the neighbour lists, then fill them.
	int32_t* lists = NULL;
	for (int pass = 0; pass < 2; pass++) {
		int64_t total = 0;
		for (int32_t I = 0; I < count; I++) {
			int32_t degree = 0;
			list[degree++] = I;
			seen[I] = I;
			for (int64_t k = member_first[I]; k < member_first[I + 1]; k++) {
				const int32_t q = member[k];
				for (int64_t e = first[q]; e < first[q + 1]; e++) {
					const int32_t J = group[neighbour[e]];
					if (seen[J] != I) {
						seen[J] = I;
						list[degree++] = J;
					}
				}
			}
			// Insertion sort: the lists are short.
			for (int32_t i = 1; i < degree; i++)
				for (int32_t j = i; j > 0 && list[j - 1] > list[j]; j--) {
					const int32_t t = list[j];
					list[j] = list[j - 1];
					list[j - 1] = t;
				}
			if (pass == 0) {
				r->coarse_first[I + 1] = degree;
			} else {
				for (int32_t i = 0; i < degree; i++) {
					lists[total + i] = list[i];
					if (list[i] == I)
						r->coarse_self[I] = i;
				}
			}
			total += degree;
		}
		for (int32_t I = 0; I < count; I++)
			seen[I] = -1;
		if (pass == 0) {
			for (int32_t I = 0; I < count; I++)
				r->coarse_first[I + 1] += r->coarse_first[I];
			lists = malloc(((size_t)total + 1) * sizeof(int32_t));
			if (!lists)
				break;
		}
	}
	free(member_first), free(member), free(seen), free(list);
	r->coarse_neighbour = lists;
	if (!lists)
		goto done;
	// Per particle: its aggregate (-1 if constrained). Per spring between aggregates I != J:
	// the first entries of its blocks (I, I), (J, J) (-1 for a constrained end), (I, J), (J, I)
	// (-1 unless both ends are free).
	for (int32_t i = 0; i < m->particle_count; i++)
		r->aggregate[i] = m->free_index[i] >= 0 ? group[m->free_index[i]] : -1;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t I = r->aggregate[m->spring_a[s]], J = r->aggregate[m->spring_b[s]];
		int64_t* entry = r->spring_coarse + 4 * (size_t)s;
		entry[0] = entry[1] = entry[2] = entry[3] = -1;
		if (I == J)
			continue;  // inside an aggregate (or between two constrained particles)
		if (I >= 0)
			entry[0] = coarse_entry(r, I, r->coarse_self[I], 0, 0);
		if (J >= 0)
			entry[1] = coarse_entry(r, J, r->coarse_self[J], 0, 0);
		if (I < 0 || J < 0)
			continue;
		for (int64_t k = r->coarse_first[I]; k < r->coarse_first[I + 1]; k++)
			if (lists[k] == J)
				entry[2] = coarse_entry(r, I, (int32_t)(k - r->coarse_first[I]), 0, 0);
		for (int64_t k = r->coarse_first[J]; k < r->coarse_first[J + 1]; k++)
			if (lists[k] == I)
				entry[3] = coarse_entry(r, J, (int32_t)(k - r->coarse_first[J]), 0, 0);
	}
	// The coarse matrix: 3 rows per aggregate, 3 deg(I) entries each, symmetric storage.
	const size_t nc = 3 * (size_t)count;
	if (nc < COARSE_SUPERNODAL_MIN_DOFS)
		r->common.supernodal = CHOLMOD_SIMPLICIAL;
	const size_t nonzeros = 9 * (size_t)r->coarse_first[count];
	r->coarse = cholmod_l_allocate_sparse(nc, nc, nonzeros, 1, 1, 1, CHOLMOD_REAL, &r->common);
	r->coarse_b = cholmod_l_allocate_dense(nc, 1, nc, CHOLMOD_REAL, &r->common);
	if (!r->coarse || !r->coarse_b)
		goto done;
	sm_block_pattern_fill(count, r->coarse_first, lists, r->coarse->p, r->coarse->i);
	ok = true;
done:
	free(first);
	free(neighbour);
	free(fill);
	free(mark);
	free(group);
	free(strong);
	free(strongest);
	return ok;
}

void sm_reduced_solver_invalidate(SUNLinearSolver ls, bool forget_factor)
{
	if (ls == NULL || ls->content == NULL)
		return;
	reduced* r = ls->content;
	r->jacobian_time = NAN;
	r->rhs_records = false;
	r->blocks_gamma = NAN;
	r->coarse_age = COARSE_MAX_AGE;  // masses or springs may have changed
	if (forget_factor) {
		r->factor_valid = false;
		r->refactor = false;
		r->extra_flops = 0.0;
	}
	load_masses(r);
	load_spring_order(r);
}

static void reduced_content_free(reduced* r)
{
	if (r == NULL)
		return;
	if (r->common_started) {
		cholmod_l_free_sparse(&r->coarse, &r->common);
		cholmod_l_free_factor(&r->coarse_factor, &r->common);
		sm_multilevel_destroy(r->multilevel, &r->common);
		cholmod_l_free_dense(&r->coarse_b, &r->common);
		cholmod_l_free_dense(&r->coarse_x, &r->common);
		cholmod_l_free_dense(&r->coarse_y, &r->common);
		cholmod_l_free_dense(&r->coarse_e, &r->common);
		cholmod_l_free_sparse(&r->matrix, &r->common);
		cholmod_l_free_factor(&r->factor, &r->common);
		cholmod_l_free_dense(&r->b, &r->common);
		cholmod_l_free_dense(&r->x, &r->common);
		cholmod_l_free_dense(&r->y_work, &r->common);
		cholmod_l_free_dense(&r->e_work, &r->common);
		cholmod_l_finish(&r->common);
	}
	sm_coarse_halves_destroy(r->coarse_halves);
	free(r->coarse_part);
	free(r->coarse_solution);
	sm_workers_destroy(r->workers);
	free(r->slot);
	free(r->ordered_a);
	free(r->ordered_b);
	free(r->ordered_rest_length);
	free(r->ordered_stiffness);
	free(r->ordered_damping);
	free(r->member_first);
	free(r->member);
	free(r->diagonal);
	free(r->values);
	free(r->block_inverse);
	free(r->scaled);
	free(r->rhs_state);
	free(r->r);
	free(r->z);
	free(r->p);
	free(r->q);
	free(r->rhs);
	sm_spring_jacobians_destroy(r->springs);
	free(r->full_force);
	free(r->aggregate);
	free(r->coarse_first);
	free(r->coarse_neighbour);
	free(r->coarse_self);
	free(r->spring_coarse);
	free(r->mass);
	free(r->weight);
	free(r->dv);
	free(r->coarse_mass);
	free(r);
}

static int reduced_free(SUNLinearSolver ls)
{
	if (ls == NULL)
		return 0;
	reduced_content_free(ls->content);
	ls->content = NULL;
	SUNLinSolFreeEmpty(ls);
	return 0;
}

// The chunks of the parallel loops (see reduced): one, or PARALLEL_CHUNKS of equal particle
// counts for pcg from PARALLEL_MIN_PARTICLES free particles on, when at most
// PARALLEL_MAX_BOUNDARY_FRACTION of the springs join two chunks (particles numbered along the
// structure, as structures and meshes number them); the aggregates' member lists; and the team
// of sm_simulation_def.threads threads, at most one per chunk and per processor the process may
// run on (none if it cannot be had: the chunks then run in turn, with the same results). Returns
// false on out of memory.
static bool build_chunks(reduced* r)
{
	const sm_model* m = r->sim->model;
	const int32_t np = m->particle_count, ns = m->spring_count;
	r->chunks = 1;
	r->chunk_particle[0] = 0, r->chunk_particle[1] = np;
	r->chunk_spring[0] = 0, r->chunk_spring[1] = ns;
	r->chunk_aggregate[0] = 0, r->chunk_aggregate[1] = r->aggregate_count;
	if (r->two_level) {
		r->member_first = calloc((size_t)r->aggregate_count + 2, sizeof(int32_t));
		r->member = malloc(((size_t)np + 1) * sizeof(int32_t));
		if (!r->member_first || !r->member)
			return false;
		for (int32_t i = 0; i < np; i++)
			if (r->aggregate[i] >= 0)
				r->member_first[r->aggregate[i] + 2]++;
		for (int32_t I = 0; I < r->aggregate_count; I++)
			r->member_first[I + 2] += r->member_first[I + 1];
		for (int32_t i = 0; i < np; i++)
			if (r->aggregate[i] >= 0)
				r->member[r->member_first[r->aggregate[i] + 1]++] = i;
	}
	if (r->use_cholmod || r->sim->free_count < PARALLEL_MIN_PARTICLES)
		return true;
	const int chunks = PARALLEL_CHUNKS;
	int32_t* key = malloc(((size_t)ns + 1) * sizeof(int32_t));
	if (key == NULL)
		return false;
	int32_t count[PARALLEL_CHUNKS + 2] = {0};
	for (int c = 0; c <= chunks; c++)
		r->chunk_particle[c] = (int32_t)((int64_t)np * c / chunks);
	for (int32_t s = 0; s < ns; s++) {
		const int32_t a = m->spring_a[s], b = m->spring_b[s];
		int ca = 0, cb = 0;
		while (a >= r->chunk_particle[ca + 1])
			ca++;
		while (b >= r->chunk_particle[cb + 1])
			cb++;
		key[s] = ca == cb ? ca : chunks;
		count[key[s] + 1]++;
	}
	if (count[chunks + 1] > PARALLEL_MAX_BOUNDARY_FRACTION * ns) {
		free(key);
		r->chunk_particle[1] = np;
		return true;
	}
	r->slot = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_a = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_b = malloc(((size_t)ns + 1) * sizeof(int32_t));
	r->ordered_rest_length = malloc(((size_t)ns + 1) * sizeof(double));
	r->ordered_stiffness = malloc(((size_t)ns + 1) * sizeof(double));
	r->ordered_damping = malloc(((size_t)ns + 1) * sizeof(double));
	if (!r->slot || !r->ordered_a || !r->ordered_b || !r->ordered_rest_length || !r->ordered_stiffness ||
	    !r->ordered_damping) {
		free(key);
		return false;
	}
	for (int c = 0; c <= chunks; c++)
		count[c + 1] += count[c];
	for (int c = 0; c <= chunks; c++)
		r->chunk_spring[c] = count[c];
	for (int32_t s = 0; s < ns; s++) {
		const int32_t k = count[key[s]]++;
		r->slot[s] = k;
		r->ordered_a[k] = m->spring_a[s];
		r->ordered_b[k] = m->spring_b[s];
	}
	free(key);
	load_spring_order(r);
	for (int c = 0; c <= chunks; c++)
		r->chunk_aggregate[c] = (int32_t)((int64_t)r->aggregate_count * c / chunks);
	r->chunks = chunks;
	// More threads than processors would only wait for each other.
	int threads = r->sim->def.threads < chunks ? r->sim->def.threads : chunks;
	const int processors = sm_workers_processors();
	if (threads > processors)
		threads = processors;
	r->workers = sm_workers_create(threads);
	return true;
}

// For the exact coarse solve of a chunked model: the aggregates in two halves, those whose first
// member lies in the first two chunks and the others, and a separator, the aggregates of the
// second half that neighbour the first (so that no coarse entry joins the two halves left). The
// coarse factor's triangular solves then run in two at once (coarse_halves.h). Returns false on
// out of memory.
static bool split_coarse(reduced* r)
{
	const int32_t count = r->aggregate_count;
	r->coarse_part = malloc(3 * ((size_t)count + 1) * sizeof(int8_t));
	r->coarse_solution = malloc(3 * ((size_t)count + 1) * sizeof(double));
	if (r->coarse_part == NULL || r->coarse_solution == NULL)
		return false;
	for (int32_t I = 0; I < count; I++)
		r->coarse_part[3 * (size_t)I] = r->member[r->member_first[I]] < r->chunk_particle[2] ? 0 : 1;
	for (int32_t I = 0; I < count; I++) {
		if (r->coarse_part[3 * (size_t)I] != 1)
			continue;
		for (int64_t k = r->coarse_first[I]; k < r->coarse_first[I + 1]; k++)
			if (r->coarse_part[3 * (size_t)r->coarse_neighbour[k]] == 0) {
				r->coarse_part[3 * (size_t)I] = 2;
				break;
			}
	}
	for (int32_t I = 0; I < count; I++)
		r->coarse_part[3 * (size_t)I + 1] = r->coarse_part[3 * (size_t)I + 2] = r->coarse_part[3 * (size_t)I];
	return true;
}

// The solver's content for the simulation's current model, or NULL when out of memory.
static reduced* reduced_content_create(sm_simulation* sim, bool use_cholmod)
{
	reduced* r = calloc(1, sizeof *r);
	if (r == NULL)
		return NULL;
	r->sim = sim;
	r->use_cholmod = use_cholmod;
	r->n = sim->dofs;
	r->blocks_gamma = NAN;
	r->jacobian_time = NAN;
	const size_t n = (size_t)r->n + 1;
	r->full = 3 * (int64_t)sim->particle_count;
	const size_t full = (size_t)r->full + 1;
	r->springs = sm_spring_jacobians_create(sim->model);
	r->full_force = calloc(full, sizeof(double));
	r->block_inverse = calloc(6 * full, sizeof(double));  // inverses, then the sums (9 each)
	r->mass = calloc(full, sizeof(double));
	r->weight = calloc(full, sizeof(double));
	r->r = calloc(full, sizeof(double));
	r->z = calloc(full, sizeof(double));
	r->p = calloc(full, sizeof(double));
	r->q = calloc(full, sizeof(double));
	r->rhs = calloc(full, sizeof(double));
	r->dv = calloc(full, sizeof(double));
	r->rhs_state = malloc(2 * n * sizeof(double));
	if (!use_cholmod)
		r->scaled = malloc(SCALED_STRIDE * ((size_t)sim->model->spring_count + 1) * sizeof(double));
	if (!r->springs || !r->full_force || !r->block_inverse || !r->mass || !r->weight || !r->r || !r->z || !r->p ||
	    !r->q || !r->rhs || !r->dv || !r->rhs_state || (!use_cholmod && !r->scaled)) {
		reduced_content_free(r);
		return NULL;
	}
	load_masses(r);
	if (use_cholmod) {
		// The assembled matrix, for the factorisations only.
		r->nonzeros = sm_sparse_jacobian_nonzeros(sim->pattern);
		r->rows = sm_sparse_jacobian_row_pointers(sim->pattern);
		r->cols = sm_sparse_jacobian_column_indices(sim->pattern);
		r->diagonal = malloc(n * sizeof(int64_t));
		r->values = malloc(((size_t)r->nonzeros + 1) * sizeof(double));
		if (!r->diagonal || !r->values) {
			reduced_content_free(r);
			return NULL;
		}
		for (int64_t i = 0; i < r->n; i++) {
			const int64_t first = 3 * (i / 3);
			r->diagonal[i] = -1;
			for (int64_t e = r->rows[i]; e < r->rows[i + 1]; e++)
				if (r->cols[e] == first) {
					r->diagonal[i] = e;
					break;
				}
			if (r->diagonal[i] < 0) {  // the pattern always holds the diagonal blocks
				reduced_content_free(r);
				return NULL;
			}
		}
	}
	r->two_level = !use_cholmod && sim->free_count >= TWO_LEVEL_MIN_PARTICLES;
	if ((use_cholmod || r->two_level) && r->n > 0) {
		if (!cholmod_l_start(&r->common)) {
			reduced_content_free(r);
			return NULL;
		}
		r->common_started = true;
		r->common.print = 0;  // failures are reported through the simulation, never printed
	}
	const bool multilevel = r->two_level && sim->free_count >= MULTILEVEL_MIN_PARTICLES;
	if (r->two_level && !build_two_level(r, multilevel)) {
		reduced_content_free(r);
		return NULL;
	}
	if (!build_chunks(r) || (r->two_level && !multilevel && r->chunks > 1 && !split_coarse(r))) {
		reduced_content_free(r);
		return NULL;
	}
	if (multilevel) {
		r->multilevel = sm_multilevel_create(r->aggregate_count, r->coarse_first, r->coarse_neighbour,
		                                     MULTILEVEL_COARSEST_DOFS, &r->common);
		if (r->multilevel == NULL) {
			reduced_content_free(r);
			return NULL;
		}
	}
	if (use_cholmod && r->n > 0) {
		// Simplicial factorisation for small systems: the supernodal one calls a multithreaded
		// BLAS whose threads spin on small blocks; from SUPERNODAL_MIN_DOFS unknowns on, the
		// supernodal one was 1.5 times faster on the benchmark cloth.
		if (r->n < SUPERNODAL_MIN_DOFS)
			r->common.supernodal = CHOLMOD_SIMPLICIAL;
		// A symmetric matrix whose upper triangle CHOLMOD reads: the CSR arrays of a symmetric
		// pattern are also its CSC arrays.
		r->matrix = cholmod_l_allocate_sparse((size_t)r->n, (size_t)r->n, (size_t)r->nonzeros, 1, 1, 1, CHOLMOD_REAL,
		                                      &r->common);
		r->b = cholmod_l_allocate_dense((size_t)r->n, 1, (size_t)r->n, CHOLMOD_REAL, &r->common);
		if (!r->matrix || !r->b) {
			reduced_content_free(r);
			return NULL;
		}
		memcpy(r->matrix->p, r->rows, n * sizeof(int64_t));
		memcpy(r->matrix->i, r->cols, (size_t)r->nonzeros * sizeof(int64_t));
	}
	return r;
}

bool sm_reduced_solver_rebuild(SUNLinearSolver ls)
{
	reduced* old = ls->content;
	if (old->multilevel == NULL)
		return true;  // the aggregates follow the springs alone: nothing depends on the constants
	reduced* r = reduced_content_create(old->sim, old->use_cholmod);
	if (r == NULL)
		return false;
	// What CVODE gave the solver when it was attached.
	r->weights = old->weights;
	r->psetup = old->psetup;
	r->psetup_data = old->psetup_data;
	r->last_flag = old->last_flag;
	reduced_content_free(old);
	ls->content = r;
	return true;
}

SUNLinearSolver sm_reduced_solver_create(sm_simulation* sim, bool use_cholmod)
{
	reduced* r = reduced_content_create(sim, use_cholmod);
	if (r == NULL)
		return NULL;
	SUNLinearSolver ls = SUNLinSolNewEmpty(sim->context);
	if (ls == NULL) {
		reduced_content_free(r);
		return NULL;
	}
	ls->content = r;
	ls->ops->gettype = reduced_type;
	ls->ops->getid = reduced_id;
	ls->ops->initialize = reduced_initialize;
	ls->ops->setup = reduced_setup;
	ls->ops->solve = reduced_solve;
	ls->ops->setscalingvectors = reduced_set_scaling;
	ls->ops->setatimes = reduced_set_atimes;
	ls->ops->setpreconditioner = reduced_set_preconditioner;
	ls->ops->numiters = reduced_num_iterations;
	ls->ops->lastflag = reduced_last_flag;
	ls->ops->free = reduced_free;
	return ls;
}
