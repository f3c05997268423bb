// The reduced second-order linear solver's state and the functions its files share (internal).
//
// The solver (derivation in linear_solver_reduced.c) is spread over one file per concept:
//   linear_solver_reduced.c          the SUNLinearSolver: creation, the Jacobian it holds, the solve
//   reduced_chunks.c                 the chunks of the parallel loops, the springs in chunk order,
//                                    the forces and Jacobian records evaluated in that order
//   reduced_products.c               products with A and with -K from the springs' records
//   reduced_conjugate_gradients.c    preconditioned conjugate gradients
//   reduced_preconditioner.c         block Jacobi and the two-level coarse correction (pcg): their
//                                    preparation at each gamma and their application
//   reduced_aggregates.c             the two-level preconditioner's aggregates and coarse pattern
//   reduced_cholesky.c               the cholmod variant: the factor of an earlier Newton matrix
// and, below them, preconditioner_multilevel.c (the coarse solve of large models) and
// coarse_halves.c (the exact coarse solve of a model in chunks in two halves at once).
//
// Vectors over all particles. The solver's vectors hold 3 entries per particle, the constrained
// particles' entries kept at zero, so that products read and write the particles' own arrays
// without gathering the free ones; CVODE's vectors hold the free particles only.
#ifndef SPRINGMASS_LINEAR_SOLVER_REDUCED_H
#define SPRINGMASS_LINEAR_SOLVER_REDUCED_H

#include "coarse_halves.h"
#include "model_internal.h"
#include "preconditioner_multilevel.h"
#include "simulation_internal.h"
#include "workers.h"

#include <suitesparse/cholmod.h>

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

// The number of chunks the pcg solver's loops run in for a large model (linear_solver_reduced.c
// says from which size on). Fixed, whatever the number of threads, so that the chunks, and with
// them the order of every sum, depend on the model alone.
#define PARALLEL_CHUNKS 4

// Doubles per spring of the scaled records (seven used: one 64-byte record each), laid out as the
// Jacobian's records, so that one loop forms products from either (reduced_products.c).
#define SCALED_STRIDE 8
_Static_assert(SCALED_STRIDE == SPRING_JACOBIAN_STRIDE, "scaled and Jacobian records share a layout");

// The pcg loops' SSE2 pairs (reduced_products.c, reduced_preconditioner.c): only where double
// arithmetic is SSE2's too (x86-64; 32-bit x86 with -mfpmath=sse). With x87 arithmetic
// (-m32 -msse2 alone) the scalar z lane would keep extended precision within expressions and the
// pairs' x and y would not: not the scalar loops' bits. A compiler without SSE2 math takes the
// scalar loops, the same operations in the same order; so does the sanitizer build
// (SPRINGMASS_SCALAR_LOOPS), whose tests run them.
#if defined(__SSE2__) && defined(__SSE2_MATH__) && !defined(SPRINGMASS_SCALAR_LOOPS)
#define SM_REDUCED_SSE2 1
#endif

// The SUNLinearSolver's content.
typedef struct sm_reduced {
	sm_simulation* sim;
	bool use_cholmod;
	int64_t n;     // free degrees of freedom
	int64_t full;  // 3 per particle: the conjugate gradients' vectors, constrained entries 0
	int64_t nonzeros;
	const int64_t* rows;  // pattern (owned by the simulation's sparse Jacobian)
	const int64_t* cols;
	int64_t* diagonal;  // per dof i: entry index of (i, 3 floor(i/3)), its diagonal block's first column
	N_Vector weights;   // error weights CVODE gives (not owned)
	double* values;     // A in pattern order
	bool blocks_valid;  // block_inverse holds the inverses of A's diagonal blocks at blocks_gamma
	// Cholesky preconditioner: floating-point operations of one factorisation and of one
	// iteration (a product with A and a triangular solve pair), and those spent on iterations
	// beyond the first since the last factorisation.
	bool factor_valid;
	bool refactor;  // factorise at the next solve
	double factor_flops;
	double iteration_flops;
	double extra_flops;
	// Per particle, zero for constrained particles: block_inverse, 18 doubles each (A's inverted
	// 3x3 diagonal blocks, 9 per particle, stored by column pairs (t00, t10), (t01, t11), (t02, t12),
	// then the last row t20, t21, t22 (invert_chunk, for block Jacobi's pairs); then their sums
	// before the inversion, 9 per particle, row-major),
	// and 3 doubles each: mass [kg], inverse_mass [1/kg], weight (CVODE's error weight of the
	// velocities, for the residual M^-1 r), position_weight (gamma times the positions' error weight:
	// the error an iterate leaves in dx = bx + gamma dv, reduced_conjugate_gradients.c) and the
	// conjugate gradients' vectors r, z, p, q, rhs, dv. The weights are kept apart from the inverse
	// masses: a weight of up to 1e150 s/m (atol_velocity down to 1e-150 m/s) over a mass down to
	// SM_MIN_MASS would overflow, where 1 / SM_MIN_MASS = 4.5e307 does not.
	double* block_inverse;
	// pcg: every spring's share of A at the preconditioner's gamma, SCALED_STRIDE doubles each,
	// u[3], w[3], gamma^2 beta (reduced_preconditioner.c), written in the same pass as the
	// diagonal blocks, so that each product with A computes one dot product per spring.
	double* scaled;
	double* mass;
	double* inverse_mass;
	double* weight;
	double* position_weight;
	double *r, *z, *p, *q, *rhs, *dv;
	// The Jacobian as every spring's factored blocks (sm_model_forces_and_jacobians), refreshed
	// at every step, in chunk order; products with A are formed from it without assembling A.
	sm_spring_jacobians* springs;
	double gamma;  // of the current solve [s]
	// The factor, a power of two, by which the current solve's system is multiplied: 1 below
	// LARGE_GAMMA, about 1 / gamma from it on, where the solve is for dx rather than dv
	// (sm_reduced_scale, linear_solver_reduced.c). Every product, the preconditioner, the coarse
	// matrix and the Cholesky factor carry it; unscale = 1 / scale.
	double scale;
	double unscale;
	double factor_scale;  // scale of the Cholesky factor (cholmod)
	double coarse_scale;  // scale of the coarse factorisation (pcg)
	double* full_force;   // forces of the fused pass (unused)
	double blocks_gamma;  // gamma of block_inverse; NAN after a Jacobian refresh [s]
	// Two-level block-Jacobi preconditioner (pcg): aggregates of neighbouring free particles,
	// the Galerkin coarse matrix P^T A P (P: each aggregate moves as one) in 3x3 blocks,
	// factorised by CHOLMOD.
	bool two_level;
	int32_t aggregate_count;
	int32_t* aggregate;         // per particle, -1 for constrained ones
	int64_t* coarse_first;      // per aggregate: first index into coarse_neighbour (aggregate_count + 1)
	int32_t* coarse_neighbour;  // neighbouring aggregates (itself included), sorted
	int32_t* coarse_self;       // per aggregate: position of itself in its neighbour list
	int64_t* spring_coarse;     // per spring: first entries of its blocks (I,I), (J,J), (I,J), (J,I), or -1
	double* coarse_mass;        // per aggregate [kg]
	double coarse_gamma;        // gamma of the coarse factorisation [s]
	int coarse_age;             // preconditioner preparations since (sm_reduced_prepare_preconditioner)
	cholmod_sparse* coarse;
	cholmod_factor* coarse_factor;
	cholmod_dense *coarse_b, *coarse_x, *coarse_y, *coarse_e;
	sm_multilevel* multilevel;  // replaces coarse_factor from MULTILEVEL_MIN_PARTICLES on
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
	// The first vector entries of each spring's particles (3 a, 3 b; a model holds at most
	// INT32_MAX / 4 particles, so they fit) at its position of the chunk order, for the products
	// (reduced_products.c); loaded with the constants (sm_reduced_load_spring_order).
	int32_t* entry_a;
	int32_t* entry_b;
	double* ordered_rest_length;  // the model's constants in chunk order (sm_reduced_load_spring_order)
	double* ordered_stiffness;
	double* ordered_damping;
	int32_t* member_first;
	int32_t* member;
	double partial[PARALLEL_CHUNKS];  // per-chunk sums, added in chunk order
	sm_workers* workers;              // NULL: one thread
	double jacobian_time;             // CVODE's current time at the last Jacobian evaluation [s]; NAN if none
	// The state at which the right-hand side last stored the records (sm_reduced_rhs_forces): a
	// solve at that time and state adopts them instead of evaluating again.
	bool rhs_records;
	double rhs_time;    // [s]
	double* rhs_state;  // the first 2 n entries of CVODE's y
	long last_flag;
	int last_iterations;
	SUNPSetupFn psetup;  // CVODE's preconditioner set-up hook: leads to sm_reduced_pset
	void* psetup_data;
	// CHOLMOD
	cholmod_common common;
	bool common_started;
	cholmod_sparse* matrix;
	cholmod_factor* factor;
	cholmod_dense *b, *x, *y_work, *e_work;
} sm_reduced;

// The step (CVODE's gamma) from which the reduced system is solved for the positions' correction
// and scaled by about 1 / gamma [s] (linear_solver_reduced.c, "Long steps").
#define LARGE_GAMMA 2.0

// The factor by which the reduced system at gamma is multiplied: 1 below LARGE_GAMMA, else the
// power of two 2^-floor(log2 gamma), so that scale gamma lies in [1, 2).
static inline double sm_reduced_scale(double gamma)
{
	return gamma >= LARGE_GAMMA ? ldexp(1.0, -ilogb(gamma)) : 1.0;
}

// The chunks' partial sums (partial), added in chunk order (with one chunk: the sum in order).
static inline double sm_reduced_sum_partials(const sm_reduced* r)
{
	double s = r->partial[0];
	for (int c = 1; c < r->chunks; c++)
		s += r->partial[c];
	return s;
}

// Entry of the coarse matrix at row 3 I + i, column 3 J + j, J the k-th neighbour of I (the
// block layout of preconditioner_multilevel.h).
static inline int64_t sm_reduced_coarse_entry(const sm_reduced* r, int32_t I, int32_t k, int i, int j)
{
	return sm_block_entry(r->coarse_first, I, k, i, j);
}

// reduced_chunks.c

// The chunks of the parallel loops (see sm_reduced): one, or PARALLEL_CHUNKS of equal particle
// counts for pcg from min_particles free particles on, when at most max_boundary_fraction of the
// springs join two chunks; the aggregates' member lists; and the team of threads. False on out of
// memory.
bool sm_reduced_build_chunks(sm_reduced* r, int32_t min_particles, double max_boundary_fraction);
// The springs' entries and the model's spring constants in chunk order (the constants only with
// chunks): when the chunks are built and at every invalidation, which follows every change of them.
void sm_reduced_load_spring_order(sm_reduced* r);
// sm_model_forces_power_and_jacobians at x, v into f and the solver's records, in chunk order;
// returns the dissipated power [W].
double sm_reduced_forces_and_records(sm_reduced* r, const double* x, const double* v,
                                     const double* f_external, double* f);

// reduced_products.c

// a . b over all particles, chunk by chunk.
double sm_reduced_dot(sm_reduced* r, const double* a, const double* b);
// q = A p at r->gamma over all particles (q zero at the constrained ones); returns p . q. pcg
// reads the scaled records: the preconditioner must have been prepared at r->gamma.
double sm_reduced_multiply(sm_reduced* r, const double* p, double* restrict q);
// q = -K p from the Jacobian's records over all particles (constrained entries not cleared).
void sm_reduced_stiffness_product(sm_reduced* r, const double* p, double* q);

// reduced_conjugate_gradients.c

// Preconditioned conjugate gradients on A dv = r->rhs from dv = 0, at most max_iterations, stopped
// at the weighted residual norm tol. Returns a SUNLS flag.
int sm_reduced_conjugate_gradients(sm_reduced* r, double* dv, double tol, int max_iterations);

// reduced_preconditioner.c

// Block Jacobi (and the coarse matrix if due) at gamma [s]. Returns 0, 1 if a block is singular or
// the coarse matrix is not positive definite, -1 if out of memory.
int sm_reduced_prepare_preconditioner(sm_reduced* r, double gamma);
// Makes the next preparation sum and factorise the coarse matrix afresh.
void sm_reduced_forget_coarse(sm_reduced* r);
// out = B in (block Jacobi, plus the coarse correction), *dot = in . out. False on failure.
bool sm_reduced_apply_preconditioner(sm_reduced* r, const double* in, double* out, double* dot);

// reduced_aggregates.c

// The aggregates (over the strong springs only if strong_only) and the coarse pattern (over all
// springs). False on out of memory.
bool sm_reduced_build_two_level(sm_reduced* r, bool strong_only);
// The coarse unknowns of a chunked model in two halves and a separator. False on out of memory.
bool sm_reduced_split_coarse(sm_reduced* r);

// reduced_cholesky.c

// The pattern's diagonal entries and the storage of A (at creation). False on out of memory or
// a pattern without its diagonal blocks.
bool sm_reduced_cholesky_pattern(sm_reduced* r);
// CHOLMOD's matrix and right-hand side (at creation, CHOLMOD started). False on out of memory.
bool sm_reduced_cholesky_allocate(sm_reduced* r);
// Solves A dv = r->rhs by conjugate gradients preconditioned by the Cholesky factor of an earlier
// Newton matrix, factorising afresh when needed. Returns a SUNLS flag.
int sm_reduced_cholesky_solve(sm_reduced* r, double* dv, double tol);
// out = A_old^-1 in with the Cholesky factor (zero at constrained particles), *dot = in . out.
// False on failure.
bool sm_reduced_cholesky_apply(sm_reduced* r, const double* in, double* out, double* dot);

#endif
