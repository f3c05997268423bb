// The reduced second-order linear solver: a custom SUNLinearSolver for CVODE's BDF Newton
// systems of a spring-mass model. This file holds the SUNLinearSolver itself, its creation (and
// every size threshold that chooses a path), the Jacobian it holds and the solve; the other
// concepts are in the files listed in linear_solver_reduced.h.
//
// Derivation. With y = [x; v; e; w] and J = [[0, I, 0, 0], [M^-1 K, M^-1 D, 0, 0], [0, 0, 0, 0],
// [0, 0, 0, 0]] (K = df/dx, D = df/dv over the free degrees of freedom, M the diagonal of masses,
// e the dissipated energy, w the inputs' work), Newton's system (I - gamma J) [dx; dv; de; dw] =
// [bx; bv; be; bw] reads
//     dx - gamma dv = bx
//     -gamma M^-1 K dx + dv - gamma M^-1 D dv = bv
//     de = be,  dw = bw.
// Substituting dx = bx + gamma dv into the second row and multiplying by M:
//     (M - gamma D - gamma^2 K) dv = M bv + gamma K bx,    dx = bx + gamma dv.
// With the definiteness-preserving Jacobian, K and D are symmetric negative semi-definite, so
// A = M - gamma D - gamma^2 K is symmetric positive definite: half the unknowns of the full
// system, and conjugate gradients or a Cholesky factorisation apply. (Mass damping, a force
// -alpha m v, adds -alpha M to D: A's mass term is M (1 + gamma alpha).)
//
// Long steps. From gamma = LARGE_GAMMA on (an advance "until it settles") the system is solved
// for dx instead: with dv = (dx - bx) / gamma the velocity rows times gamma M read
//     (M - gamma D - gamma^2 K) dx = gamma M bv + (M - gamma D) bx,    dv = (dx - bx) / gamma,
// the same matrix. dx = bx + gamma dv cancels to DBL_EPSILON |bx| where the predicted state is far
// off (gamma times the velocities' round-off), which made the Newton iteration fail near 4e62 s
// on a damped bob; dv = (dx - bx) / gamma carries that error over gamma. Both sides are then
// multiplied by scale = 2^-floor(log2 gamma) (sm_reduced_scale), so that gamma^2 K, which
// overflowed from gamma = 1.3e154 s on, enters as (scale gamma) gamma K; products, block Jacobi,
// the coarse matrix and the Cholesky factor all carry the scale, and the stopping test unscales
// the residual (a power of two: exact). Below LARGE_GAMMA the scale is 1 and every number is as
// before, bit for bit.
//
// Residuals. The residual of the full system's velocity rows is M^-1 (M bv + gamma K bx - A dv)
// (the position rows hold exactly), and the error-weighted norm of M^-1 r is the test SUNDIALS'
// own iterative solvers make. It sees the velocities only: an error e = A^-1 r left in dv is an
// error gamma e in dx = bx + gamma dv, which it lets through where the positions are held far
// tighter than the velocities. So conjugate gradients stop when the error-weighted norm of both,
// the velocity rows' residual and gamma z with z = B^-1 r the preconditioned residual (B
// approximating A, z the iteration's own estimate of e), is below the tolerance CVODE passes
// (reduced_conjugate_gradients.c).
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
// write the particles' own arrays without gathering the free ones; reduced_conjugate_gradients.c,
// products in reduced_products.c), preconditioned by
// - (pcg) the inverses of A's 3x3 diagonal blocks (block Jacobi), from TWO_LEVEL_MIN_PARTICLES
//   free particles on plus a coarse correction over aggregates of neighbouring particles, whose
//   Galerkin coarse matrix is factorised by CHOLMOD and kept while gamma changes little, from
//   MULTILEVEL_MIN_PARTICLES on solved approximately by a multilevel V-cycle
//   (reduced_preconditioner.c, reduced_aggregates.c, preconditioner_multilevel.c); its loops run
//   in chunks on a team of threads from PARALLEL_MIN_PARTICLES on (reduced_chunks.c); or
// - (cholmod) a sparse Cholesky factorisation (CHOLMOD) of the Newton matrix of an earlier step,
//   repeated only when the iterations it saves no longer pay for it (reduced_cholesky.c).
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

// Conjugate-gradient iterations allowed per solve with the block-Jacobi preconditioner, beyond
// which the solve counts as failed (CVODE then reduces the step).
#define PCG_MAX_ITERATIONS 400

// The size thresholds that choose the paths are all here, and those the tests lower are
// overridable at compile time: a test that builds this file into itself with other values
// (tests/CMakeLists.txt) runs the paths of large models on small ones.

// Free particles from which conjugate gradients use the two-level preconditioner. Measured on
// the benchmark cloth (bench/README.md): it cut the iterations by 1.3 times at n = 16 (254 free
// particles; 1.2 to 1.8 times faster once the coarse factor was kept across set-ups), by 2.1
// times at n = 32 (1022) and by 2.7 times at n = 64; at n = 8 (62) it cut them by 7% for the
// same run time.
#define TWO_LEVEL_MIN_PARTICLES 100

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

// Free particles from which the pcg solver's loops run in PARALLEL_CHUNKS chunks (below, every
// loop runs in order, as one chunk), and the largest share of springs between chunks for which
// it does (they are summed on the caller's thread after the chunks). The chunks do not depend on
// the number of threads (sm_simulation_def.threads), so neither do the results.
#ifndef PARALLEL_MIN_PARTICLES
#define PARALLEL_MIN_PARTICLES 4000
#endif
#ifndef PARALLEL_MAX_BOUNDARY_FRACTION
#define PARALLEL_MAX_BOUNDARY_FRACTION 0.125
#endif

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
	return SM_LS_SUCCESS;
}

static int reduced_set_preconditioner(SUNLinearSolver ls, void* data, SUNPSetupFn setup, SUNPSolveFn solve)
{
	(void)solve;
	sm_reduced* r = ls->content;
	r->psetup = setup;
	r->psetup_data = data;
	return SM_LS_SUCCESS;
}

static int reduced_num_iterations(SUNLinearSolver ls)
{
	return ((sm_reduced*)ls->content)->last_iterations;
}

static SUNLinearSolver_ID reduced_id(SUNLinearSolver ls)
{
	(void)ls;
	return SUNLINEARSOLVER_CUSTOM;
}

static int reduced_initialize(SUNLinearSolver ls)
{
	((sm_reduced*)ls->content)->last_flag = SM_LS_SUCCESS;
	return SM_LS_SUCCESS;
}

static int reduced_set_scaling(SUNLinearSolver ls, N_Vector s1, N_Vector s2)
{
	(void)s2;
	((sm_reduced*)ls->content)->weights = s1;
	return SM_LS_SUCCESS;
}

static sunindextype reduced_last_flag(SUNLinearSolver ls)
{
	return ((sm_reduced*)ls->content)->last_flag;
}

static int reduced_setup(SUNLinearSolver ls, SUNMatrix unused)
{
	(void)unused;
	sm_reduced* r = ls->content;
	if (r->psetup == NULL)
		return r->last_flag = SM_LS_SUCCESS;
	int flag = r->psetup(r->psetup_data);
	r->last_flag = flag == 0 ? SM_LS_SUCCESS : flag > 0 ? SUNLS_PSET_FAIL_REC : SUNLS_PSET_FAIL_UNREC;
	return (int)r->last_flag;
}

// The masses per degree of freedom and their inverses (finite: masses are at least SM_MIN_MASS),
// zero at constrained particles: at creation and at every re-initialisation, which follows
// sm_simulation_update_model (the only way they change). Mass damping enters A as
// M (1 + gamma alpha) in the products (reduced_products.c).
static void load_masses(sm_reduced* r)
{
	const sm_model* m = r->sim->model;
	for (int32_t i = 0; i < m->particle_count; i++) {
		const bool free_particle = m->free_index[i] >= 0;
		for (int c = 0; c < 3; c++) {
			r->mass[3 * (size_t)i + c] = free_particle ? m->mass[i] : 0.0;
			r->inverse_mass[3 * (size_t)i + c] = free_particle ? 1.0 / m->mass[i] : 0.0;
		}
	}
}

// Makes the Jacobian current at CVODE's state y (time t): adopts the records the right-hand side
// stored if they were evaluated at exactly this time and state, evaluates the forces and every
// spring's Jacobian blocks there otherwise.
static void current_jacobian(sm_reduced* r, double t, const double* y)
{
	sm_simulation* sim = r->sim;
	if (!(r->rhs_records && r->rhs_time == t &&
	      memcmp(r->rhs_state, y, 2 * (size_t)r->n * sizeof(double)) == 0)) {
		double* x = sim->work_position;
		double* v = sim->work_velocity;
		sm_simulation_unpack(sim, t, y, x, v);
		const double start = sm_simulation_clock();
		sm_reduced_forces_and_records(r, x, v, sm_simulation_external_forces(sim, t), r->full_force);
		sim->base.jacobian_seconds += sm_simulation_clock() - start;
	}
	sim->jacobian_evaluations++;
	r->blocks_gamma = NAN;
	r->jacobian_time = t;
	r->rhs_records = false;
}

int sm_reduced_solver_product(SUNLinearSolver ls, double gamma, const double* p, double* q)
{
	sm_reduced* r = ls->content;
	sm_simulation* sim = r->sim;
	if (r->n == 0) {
		memset(q, 0, (size_t)r->full * sizeof(double));
		return 0;
	}
	sm_reduced_load_spring_order(r);  // the model may have changed since the last invalidation
	current_jacobian(r, sm_simulation_cvode_time(sim, sim->time), N_VGetArrayPointer(sim->y));
	r->gamma = gamma;
	r->scale = sm_reduced_scale(gamma);
	r->unscale = 1.0 / r->scale;
	int status = 0;
	if (!r->use_cholmod && sm_reduced_prepare_preconditioner(r, gamma) != 0)
		status = -1;
	else {
		sm_reduced_multiply(r, p, q);
		for (int64_t i = 0; i < r->full; i++)
			q[i] *= r->unscale;  // A p itself
	}
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
	const sm_reduced* r = ls->content;
	return r->n > 0 && !(t == r->jacobian_time);
}

double sm_reduced_rhs_forces(SUNLinearSolver ls, double t, const double* y, const double* x, const double* v,
                             const double* f_external, double* f)
{
	sm_reduced* r = ls->content;
	const double power = sm_reduced_forces_and_records(r, x, v, f_external, f);
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
	sm_reduced* r = sim->linear_solver->content;
	*jcur = SUNFALSE;
	if (r->n == 0)
		return 0;
	// Always the Jacobian at this state: the right-hand side's records, or one pass over the
	// springs.
	current_jacobian(r, t, N_VGetArrayPointer(y));
	*jcur = SUNTRUE;
	return 0;
}

static int reduced_solve(SUNLinearSolver ls, SUNMatrix unused, N_Vector xv, N_Vector bv, sunrealtype tol)
{
	(void)unused;
	sm_reduced* r = ls->content;
	sm_simulation* sim = r->sim;
	const int64_t n = r->n;
	const double* b = N_VGetArrayPointer(bv);
	double* x = N_VGetArrayPointer(xv);
	double gamma;
	if (CVodeGetCurrentGamma(sim->cvode, &gamma) != CV_SUCCESS)
		return r->last_flag = SM_LS_MEM_FAIL;
	for (int c = 0; c < SM_ENERGY_COMPONENTS; c++)
		x[2 * n + c] = b[2 * n + c];  // the energies' rows: de = be, dw = bw
	if (n == 0)
		return r->last_flag = SM_LS_SUCCESS;
	// A new step (or a new attempt at one) since the Jacobian was evaluated: evaluate it at the
	// current iterate, the predicted state at the first Newton iteration.
	double t_current;
	N_Vector y_current;
	if (CVodeGetCurrentTime(sim->cvode, &t_current) != CV_SUCCESS ||
	    CVodeGetCurrentState(sim->cvode, &y_current) != CV_SUCCESS)
		return r->last_flag = SM_LS_MEM_FAIL;
	if (!(t_current == r->jacobian_time))
		current_jacobian(r, t_current, N_VGetArrayPointer(y_current));
	// The cholmod solver's factorisation assembles the matrices inside the solve, timed as
	// Jacobian evaluation: that share is taken out of the solve's time, so the two do not overlap.
	const double start = sm_simulation_clock(), jacobian_start = sim->base.jacobian_seconds;
	r->gamma = gamma;
	r->scale = sm_reduced_scale(gamma);
	r->unscale = 1.0 / r->scale;
	const bool solve_positions = r->scale != 1.0;
	const double scaled = r->scale * gamma;  // gamma below LARGE_GAMMA, in [1, 2) from it on
	// Over all particles: p = bx, the right-hand side and the weights of the stopping test (p and
	// both weights stay zero at constrained particles from their allocation on): rhs = M bv +
	// gamma K bx; for long steps, rhs = scale (gamma M bv + M bx - gamma D bx) (D = df/dv, mass
	// damping included: M (1 + gamma alpha) bx - gamma D_s bx), the velocity rows' weights divided by scale
	// gamma (their residual is M^-1 res / gamma) and the positions' weights CVODE's own.
	const double* w = r->weights ? N_VGetArrayPointer(r->weights) : NULL;
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
		for (int c = 0; c < 3; c++) {
			r->p[i + c] = b[f + c];
			r->weight[i + c] = w ? w[n + f + c] : 1.0;
			r->position_weight[i + c] = gamma * (w ? w[f + c] : 1.0);
			if (solve_positions) {
				r->weight[i + c] /= scaled;
				r->position_weight[i + c] = w ? w[f + c] : 1.0;
			}
		}
	}
	if (solve_positions)
		sm_spring_jacobians_combined_product(r->springs, sim->model, 0.0, 1.0, r->p, r->rhs);  // D bx first
	else
		sm_reduced_stiffness_product(r, r->p, r->rhs);  // rhs = -K bx first
	for (int32_t k = 0; k < sim->constrained_count; k++)
		memset(r->rhs + 3 * (size_t)sim->constrained[k], 0, 3 * sizeof(double));
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
		for (int c = 0; c < 3; c++)
			if (solve_positions)
				r->rhs[i + c] = scaled * (r->mass[i + c] * b[n + f + c] - r->rhs[i + c]) +
				                r->scale * r->mass[i + c] * b[f + c];
			else
				r->rhs[i + c] = r->mass[i + c] * b[n + f + c] - gamma * r->rhs[i + c];
	}
	// pcg: the preconditioner, and with it the scaled records the products read, at this gamma,
	// unless prepared for it since the last Jacobian evaluation (which sets blocks_gamma to NAN).
	// Out of memory, the solve fails (unrecoverably: CVODE stops) and the next one prepares again.
	int prepared = 0;
	if (!r->use_cholmod && !(r->blocks_gamma == gamma)) {
		prepared = sm_reduced_prepare_preconditioner(r, gamma);
		r->blocks_valid = prepared == 0;
		r->blocks_gamma = prepared < 0 ? NAN : gamma;
	}
	int flag;
	if (r->use_cholmod)
		flag = sm_reduced_cholesky_solve(r, r->dv, tol);
	else if (prepared < 0)
		flag = SM_LS_MEM_FAIL;
	else
		flag = r->blocks_valid ? sm_reduced_conjugate_gradients(r, r->dv, tol, PCG_MAX_ITERATIONS)
		                       : SUNLS_PACKAGE_FAIL_REC;
	if (flag == SM_LS_SUCCESS || flag == SUNLS_RES_REDUCED)
		for (int32_t k = 0; k < sim->free_count; k++) {
			const size_t i = 3 * (size_t)sim->free_particles[k], f = 3 * (size_t)k;
			for (int c = 0; c < 3; c++)
				if (solve_positions) {  // the solution is dx
					x[f + c] = r->dv[i + c];
					x[n + f + c] = (r->dv[i + c] - b[f + c]) / gamma;
				} else {
					x[n + f + c] = r->dv[i + c];
					x[f + c] = b[f + c] + gamma * r->dv[i + c];
				}
		}
	sim->base.linear_solve_seconds +=
	    sm_simulation_clock() - start - (sim->base.jacobian_seconds - jacobian_start);
	return r->last_flag = flag;
}

void sm_reduced_solver_invalidate(SUNLinearSolver ls, bool forget_factor)
{
	if (ls == NULL || ls->content == NULL)
		return;
	sm_reduced* r = ls->content;
	r->jacobian_time = NAN;
	r->rhs_records = false;
	r->blocks_gamma = NAN;
	sm_reduced_forget_coarse(r);  // masses or springs may have changed
	if (forget_factor) {
		r->factor_valid = false;
		r->refactor = false;
		r->extra_flops = 0.0;
	}
	load_masses(r);
	sm_reduced_load_spring_order(r);
}

static void reduced_content_free(sm_reduced* r)
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
	free(r->entry_a);
	free(r->entry_b);
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
	free(r->inverse_mass);
	free(r->weight);
	free(r->position_weight);
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

// The solver's content for the simulation's current model, or NULL when out of memory.
static sm_reduced* reduced_content_create(sm_simulation* sim, bool use_cholmod)
{
	sm_reduced* r = calloc(1, sizeof *r);
	if (r == NULL)
		return NULL;
	r->sim = sim;
	r->use_cholmod = use_cholmod;
	r->n = sim->dofs;
	r->blocks_gamma = NAN;
	r->jacobian_time = NAN;
	r->scale = r->unscale = r->factor_scale = 1.0;
	const size_t n = (size_t)r->n + 1;
	r->full = 3 * (int64_t)sim->particle_count;
	const size_t full = (size_t)r->full + 1;
	r->springs = sm_spring_jacobians_create(sim->model);
	r->full_force = calloc(full, sizeof(double));
	r->block_inverse = calloc(6 * full, sizeof(double));  // inverses, then the sums (9 each)
	r->mass = calloc(full, sizeof(double));
	r->inverse_mass = calloc(full, sizeof(double));
	r->weight = calloc(full, sizeof(double));
	r->position_weight = calloc(full, sizeof(double));
	r->r = calloc(full, sizeof(double));
	r->z = calloc(full, sizeof(double));
	r->p = calloc(full, sizeof(double));
	r->q = calloc(full, sizeof(double));
	r->rhs = calloc(full, sizeof(double));
	r->dv = calloc(full, sizeof(double));
	r->rhs_state = malloc(2 * n * sizeof(double));
	if (!use_cholmod)
		r->scaled = malloc(SCALED_STRIDE * ((size_t)sim->model->spring_count + 1) * sizeof(double));
	if (!r->springs || !r->full_force || !r->block_inverse || !r->mass || !r->inverse_mass || !r->weight ||
	    !r->position_weight || !r->r || !r->z || !r->p || !r->q || !r->rhs || !r->dv || !r->rhs_state ||
	    (!use_cholmod && !r->scaled)) {
		reduced_content_free(r);
		return NULL;
	}
	load_masses(r);
	if (use_cholmod && !sm_reduced_cholesky_pattern(r)) {
		reduced_content_free(r);
		return NULL;
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
	if (r->two_level && !sm_reduced_build_two_level(r, multilevel)) {
		reduced_content_free(r);
		return NULL;
	}
	if (!sm_reduced_build_chunks(r, PARALLEL_MIN_PARTICLES, PARALLEL_MAX_BOUNDARY_FRACTION) ||
	    (r->two_level && !multilevel && r->chunks > 1 && !sm_reduced_split_coarse(r))) {
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
	if (use_cholmod && r->n > 0 && !sm_reduced_cholesky_allocate(r)) {
		reduced_content_free(r);
		return NULL;
	}
	return r;
}

bool sm_reduced_solver_rebuild(SUNLinearSolver ls)
{
	sm_reduced* old = ls->content;
	if (old->multilevel == NULL)
		return true;  // the aggregates follow the springs alone: nothing depends on the constants
	sm_reduced* r = reduced_content_create(old->sim, old->use_cholmod);
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
	sm_reduced* r = reduced_content_create(sim, use_cholmod);
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
