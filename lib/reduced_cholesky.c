// The cholmod variant of the reduced solver: conjugate gradients preconditioned by a sparse
// Cholesky factorisation (CHOLMOD) of the Newton matrix A = M - gamma D - gamma^2 K of an earlier
// step, assembled in the simulation's sparse pattern over the free degrees of freedom.
//
// Why an earlier factor. While J and gamma have changed little, one or two iterations (one
// triangular solve pair and one product each) reach CVODE's tolerance, so the factorisation, by
// far the costliest operation, is repeated only when the iterations it saves no longer pay for
// it. A deterministic count of floating-point operations, never a clock, decides, so that the
// same inputs give the same trajectory on every machine. A factorisation at the current J and
// gamma makes the first iterate the exact Newton correction. The symbolic analysis
// (fill-reducing ordering) is computed once.
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include "cholmod_factorize.h"

#include <stdlib.h>
#include <string.h>

// Iterations allowed per solve with an older Cholesky factor as the preconditioner; beyond, the
// current matrix is factorised and the solve restarted (it then converges in one iteration).
#define CHOLESKY_MAX_ITERATIONS 12

// Unknowns from which CHOLMOD's supernodal factorisation is used for the Newton matrix
// (simplicial below; the coarse matrix of the two-level preconditioner has its own threshold,
// reduced_aggregates.c).
#define SUPERNODAL_MIN_DOFS 2000

// The pattern's entry of each degree of freedom's diagonal block and the storage of A, at
// creation. False on out of memory or if the pattern lacks a diagonal block (it never does).
bool sm_reduced_cholesky_pattern(sm_reduced* r)
{
	const sm_simulation* sim = r->sim;
	const size_t n = (size_t)r->n + 1;
	// The assembled matrix, for the factorisations only.
	r->nonzeros = sm_sparse_jacobian_nonzeros(sim->pattern);
	r->rows = sm_sparse_jacobian_row_pointers(sim->pattern);
	r->cols = sm_sparse_jacobian_column_indices(sim->pattern);
	r->diagonal = malloc(n * sizeof(int64_t));
	r->values = malloc(((size_t)r->nonzeros + 1) * sizeof(double));
	if (!r->diagonal || !r->values)
		return false;
	for (int64_t i = 0; i < r->n; i++) {
		const int64_t first = 3 * (i / 3);
		r->diagonal[i] = -1;
		for (int64_t e = r->rows[i]; e < r->rows[i + 1]; e++)
			if (r->cols[e] == first) {
				r->diagonal[i] = e;
				break;
			}
		if (r->diagonal[i] < 0)  // the pattern always holds the diagonal blocks
			return false;
	}
	return true;
}

// CHOLMOD's copy of the pattern and its right-hand side, at creation (CHOLMOD started, r->n > 0).
// False on out of memory.
bool sm_reduced_cholesky_allocate(sm_reduced* r)
{
	const size_t n = (size_t)r->n + 1;
	// Simplicial factorisation for small systems: the supernodal one calls a multithreaded
	// BLAS whose threads spin on small blocks; from SUPERNODAL_MIN_DOFS unknowns on, the
	// supernodal one was 1.5 times faster on the benchmark cloth.
	if (r->n < SUPERNODAL_MIN_DOFS)
		r->common.supernodal = CHOLMOD_SIMPLICIAL;
	// A symmetric matrix whose upper triangle CHOLMOD reads: the CSR arrays of a symmetric
	// pattern are also its CSC arrays.
	r->matrix = cholmod_l_allocate_sparse((size_t)r->n, (size_t)r->n, (size_t)r->nonzeros, 1, 1, 1,
	                                      CHOLMOD_REAL, &r->common);
	r->b = cholmod_l_allocate_dense((size_t)r->n, 1, (size_t)r->n, CHOLMOD_REAL, &r->common);
	if (!r->matrix || !r->b)
		return false;
	memcpy(r->matrix->p, r->rows, n * sizeof(int64_t));
	memcpy(r->matrix->i, r->cols, (size_t)r->nonzeros * sizeof(int64_t));
	return true;
}

// values = M - gamma D - gamma^2 K, times the scale at gamma (sm_reduced_scale), in the pattern's order (the
// simulation's df/dx and df/dv, filled from the springs' records; M on the diagonal, entry (i, i) being i % 3
// entries after the first of its diagonal block).
static void assemble(sm_reduced* r, double gamma)
{
	const double* K = r->sim->dfdx;
	const double* D = r->sim->dfdv;
	const double scale = sm_reduced_scale(gamma), g1 = scale * gamma, g2 = g1 * gamma;
	for (int64_t e = 0; e < r->nonzeros; e++)
		r->values[e] = -g1 * D[e] - g2 * K[e];
	for (int64_t i = 0; i < r->n; i++)
		r->values[r->diagonal[i] + (i % 3)] += r->sim->mass_dof[i] * scale;
}

// Assembles A at the current Jacobian and gamma and factorises it. Returns 0, > 0 if A is not
// positive definite (recoverable: a state far from any physical one, CVODE retries with a
// smaller step), < 0 on failure.
static int factorize(sm_reduced* r)
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
		r->factor = sm_cholmod_analyze(r->matrix, &r->common);
		if (r->factor == NULL)
			return -1;
	}
	r->factor_valid = false;
	r->factor_scale = sm_reduced_scale(r->gamma);
	const int ok = sm_cholmod_factorize(r->matrix, r->factor, &r->common);
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

// Conjugate gradients preconditioned by the Cholesky factor of an earlier Newton matrix; if they
// do not converge in CHOLESKY_MAX_ITERATIONS, the current A is factorised and they start again.
// Iterations beyond the first are counted against the cost of a factorisation: once they have
// cost as much as one, the next solve factorises afresh.
int sm_reduced_cholesky_solve(sm_reduced* r, double* dv, double tol)
{
	int flag = SUNLS_CONV_FAIL;
	if (r->factor_valid && !r->refactor)
		flag = sm_reduced_conjugate_gradients(r, dv, tol, CHOLESKY_MAX_ITERATIONS);
	if (r->refactor || (flag != SM_LS_SUCCESS && flag != SM_LS_MEM_FAIL)) {
		const int f = factorize(r);
		if (f != 0)
			return f > 0 ? SUNLS_PACKAGE_FAIL_REC : SM_LS_MEM_FAIL;
		flag = sm_reduced_conjugate_gradients(r, dv, tol, CHOLESKY_MAX_ITERATIONS);
	}
	if (r->last_iterations > 1)
		r->extra_flops += (double)(r->last_iterations - 1) * r->iteration_flops;
	if (r->extra_flops > r->factor_flops)
		r->refactor = true;
	return flag;
}

// Applies the preconditioner, out = A_old^-1 in by the factor's triangular solves over the free
// degrees of freedom (zero at the constrained particles), and returns in . out in *dot. False if
// CHOLMOD fails.
bool sm_reduced_cholesky_apply(sm_reduced* r, const double* in, double* out, double* dot)
{
	const sm_simulation* sim = r->sim;
	double sum = 0.0;
	double* b = r->b->x;
	for (int32_t k = 0; k < sim->free_count; k++)
		memcpy(b + 3 * (size_t)k, in + 3 * (size_t)sim->free_particles[k], 3 * sizeof(double));
	if (!sm_cholmod_solve(r->factor, r->b, &r->x, &r->y_work, &r->e_work, &r->common))
		return false;
	const double* x = r->x->x;
	memset(out, 0, (size_t)r->full * sizeof(double));
	// A factor of another scale than the solve's (a power of two, sm_reduced_scale): out scaled by
	// their ratio, so that it estimates the error as one of the solve's scale would.
	const double ratio = r->factor_scale * r->unscale;
	for (int32_t k = 0; k < sim->free_count; k++) {
		const size_t i = 3 * (size_t)sim->free_particles[k];
		memcpy(out + i, x + 3 * (size_t)k, 3 * sizeof(double));
		if (ratio != 1.0)
			for (int c = 0; c < 3; c++)
				out[i + c] *= ratio;
		sum += in[i] * out[i] + in[i + 1] * out[i + 1] + in[i + 2] * out[i + 2];
	}
	*dot = sum;
	return true;
}
