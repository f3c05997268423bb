// Preconditioned conjugate gradients on the reduced Newton system A dv = rhs (both variants).
//
// A is symmetric positive definite (linear_solver_reduced.c), and so is either preconditioner
// (block Jacobi with the coarse correction, reduced_preconditioner.c; the Cholesky factor of an
// earlier A, reduced_cholesky.c), which is what conjugate gradients need. The iteration runs over
// all particles, the constrained particles' entries staying zero: the right-hand side, every
// product and the preconditioner are zero there.
//
// Stopping test. The residual of the full system's velocity rows is M^-1 (rhs - A dv) (the position
// rows hold exactly): its error-weighted norm is the test SUNDIALS' own iterative solvers make. The
// positions' part of the Newton correction, dx = bx + gamma dv, carries gamma times the error
// e = A^-1 res left in dv, which that test does not see. Where the positions are held far tighter
// than the velocities it let errors through, both before the first iteration (dv = 0 returned for a
// right-hand side small in the velocities: a bob on a zero-length spring, at 1e-10 m against
// 1e-5 m/s, took 910 steps with pcg where the direct solvers take 390, now 376; the damped
// oscillator of the bundled models, at 1e-10 m against 1e-2 m/s, went up to 3.7e-2 m off its path,
// now 4e-6 m) and after iterations of a preconditioner that is not exact (the benchmark cloth
// n = 12 over 0.5 s at 1e-10 m and 1e-2 m/s took 9614 steps with pcg and 3642 with cholmod, more
// than the 1138 and 1052 at 1e-10 m/s; now 620 and 481). So once the velocity rows' test passes,
// the position error is checked too. A >= M (A's mass term; the definite Jacobian's terms add to
// it), so M^-1 res overstates e: the iteration stops when the weighted norm of M^-1 res and
// gamma M^-1 res is within the tolerance CVODE passes (all a solve whose positions are held no
// tighter than its velocities over a step needs: the benchmark cloth's iterations are those of the
// velocity rows alone). Otherwise the preconditioned residual z = B^-1 res (B approximating A: its diagonal
// blocks, or the Cholesky factor of an earlier A), computed for the next direction anyway,
// estimates e, and the iteration stops when the norm of M^-1 res and gamma z is within the
// tolerance: M^-1 res alone is far too pessimistic once gamma^2 k / m is large (an advance to
// 1e300 s failed on it).
//
// Flexible variant. With the multilevel coarse solve the preconditioner is a few inner
// conjugate-gradient iterations, not a fixed linear map, and the usual beta = z' r' / (z r) loses
// the conjugacy it rests on; the Polak-Ribiere beta = z' (r' - r) / (z r), which equals it when
// the preconditioner is linear (z' r = 0 then), is the usual remedy (flexible conjugate
// gradients), at one more dot product per iteration.
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include <math.h>
#include <string.h>

// Sum of squares of the error-weighted velocity rows' residual M^-1 res (weight = CVODE's error
// weight, inverse_mass zero at constrained particles).
static double residual_squares(const sm_reduced* r, const double* res)
{
	double s = 0.0;
	for (int64_t i = 0; i < r->full; i++) {
		const double t = res[i] * r->inverse_mass[i] * r->weight[i];
		s += t * t;
	}
	return s;
}

// Sum of squares of the error-weighted position error gamma e, with e estimated as M^-1 res
// (bound, res, unscaled) or as the preconditioned residual z (position_weight = gamma times CVODE's
// error weight, zero at constrained particles). Solving for dx (long steps: linear_solver_reduced.c),
// e is the position error itself and position_weight CVODE's weight.
static double position_squares(const sm_reduced* r, const double* e, bool bound)
{
	double s = 0.0;
	for (int64_t i = 0; i < r->full; i++) {
		const double t = (bound ? e[i] * r->inverse_mass[i] * r->unscale : e[i]) * r->position_weight[i];
		s += t * t;
	}
	return s;
}

typedef struct update_job {
	sm_reduced* r;
	double *dv, *res, *p;
	const double *q, *z;
	double step;  // alpha, then beta
} update_job;

// Chunk c of dv += alpha p, res -= alpha q, with the squares of the weighted residual.
static void update_chunk(void* context, int c)
{
	const update_job* j = context;
	sm_reduced* r = j->r;
	double* restrict dv = j->dv;
	double* restrict res = j->res;
	const double* restrict p = j->p;
	const double* restrict q = j->q;
	const double* restrict weight = r->weight;
	const double* restrict inverse_mass = r->inverse_mass;
	const double alpha = j->step;
	double squares = 0.0;
	for (int64_t i = 3 * (int64_t)r->chunk_particle[c]; i < 3 * (int64_t)r->chunk_particle[c + 1]; i++) {
		dv[i] += alpha * p[i];
		res[i] -= alpha * q[i];
		const double t = res[i] * inverse_mass[i] * weight[i];
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

// The variant's preconditioner, out = B in, with in . out in *dot.
static bool apply_preconditioner(sm_reduced* r, const double* in, double* out, double* dot)
{
	if (r->use_cholmod)
		return sm_reduced_cholesky_apply(r, in, out, dot);
	return sm_reduced_apply_preconditioner(r, in, out, dot);
}

// Preconditioned conjugate gradients on A dv = rhs (r->rhs) from dv = 0, at most max_iterations,
// over all particles (the constrained entries stay zero), flexible with the multilevel coarse
// solve. Returns SM_LS_SUCCESS once the stopping test's norm (above) is at most tol, else
// SUNLS_RES_REDUCED or SUNLS_CONV_FAIL after max_iterations, SUNLS_PACKAGE_FAIL_REC if A p . p is
// not positive (A not positive definite: a state far from any physical one), SM_LS_MEM_FAIL if the
// preconditioner fails.
int sm_reduced_conjugate_gradients(sm_reduced* r, double* dv, double tol, int max_iterations)
{
	const int64_t n = r->full;
	double *res = r->r, *z = r->z, *p = r->p, *q = r->q;
	memcpy(res, r->rhs, (size_t)n * sizeof(double));
	r->last_iterations = 0;
	memset(dv, 0, (size_t)n * sizeof(double));
	const double squares = residual_squares(r, res);
	const double initial = sqrt(squares);
	double norm = initial;
	if (norm <= tol && sqrt(squares + position_squares(r, res, true)) <= tol)
		return SM_LS_SUCCESS;
	double rz;
	if (!apply_preconditioner(r, res, z, &rz))
		return SM_LS_MEM_FAIL;
	if (norm <= tol && sqrt(squares + position_squares(r, z, false)) <= tol)
		return SM_LS_SUCCESS;
	memcpy(p, z, (size_t)n * sizeof(double));
	for (int iteration = 1; iteration <= max_iterations; iteration++) {
		const double pq = sm_reduced_multiply(r, p, q);
		if (!(pq > 0.0) || !isfinite(pq))
			return SUNLS_PACKAGE_FAIL_REC;
		const double alpha = rz / pq;
		update_job job = {r, dv, res, p, q, z, alpha};
		sm_workers_run(r->workers, update_chunk, &job, r->chunks);
		r->sim->linear_iterations++;
		r->last_iterations++;
		const double velocity_squares = sm_reduced_sum_partials(r);
		norm = sqrt(velocity_squares);
		if (norm <= tol && sqrt(velocity_squares + position_squares(r, res, true)) <= tol)
			return SM_LS_SUCCESS;
		double rz_next;
		if (!apply_preconditioner(r, res, z, &rz_next))
			return SM_LS_MEM_FAIL;
		if (norm <= tol && sqrt(velocity_squares + position_squares(r, z, false)) <= tol)
			return SM_LS_SUCCESS;
		// Flexible (Polak-Ribiere) when the preconditioner is not linear: beta = z' (r' - r) / (z r)
		// with r' - r = -alpha q.
		job.step = r->multilevel != NULL ? -alpha * sm_reduced_dot(r, z, q) / rz : rz_next / rz;
		rz = rz_next;
		sm_workers_run(r->workers, direction_chunk, &job, r->chunks);
	}
	return norm < initial ? SUNLS_RES_REDUCED : SUNLS_CONV_FAIL;
}
