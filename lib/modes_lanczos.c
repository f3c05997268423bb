// Modes: the sparse path, the lowest eigenpairs of a large model by shift-invert Lanczos on a
// CHOLMOD factorisation of K - sigma M. The dense path, what both paths do with the modes they
// find and sm_modes_compute, which chooses the path, are in modes.c; what the two share is in
// modes_internal.h.
//
// Sparse path (the lowest few modes of a large model). Shift-invert Lanczos in the M inner
// product <a, b> = a^T M b: with a shift sigma below every eigenvalue, the operator
//
//   OP = (K - sigma M)^-1 M,   OP phi = nu phi  <=>  K phi = lambda M phi,  lambda = sigma + 1/nu,
//
// is M-symmetric and positive, and maps the lowest lambda to its largest nu, well separated:
// Lanczos finds them first. K - sigma M (sparse, the pattern of sm_sparse_jacobian) is factored
// once by CHOLMOD's Cholesky LL', supernodal or simplicial as its analysis finds the fill, as in
// statics.c; each Lanczos step is one solve. Choice of sigma: all
// eigenvalues lie in [-G, G], G the Gershgorin bound of M^(-1/2) K M^(-1/2) over whole 3x3
// blocks (sm_block_row_bound; scalar rows, max_i sum_j |K_ij| / sqrt(m_i m_j), would change
// when the model is turned). sigma = -1e-6 G is below the spectrum of any positive semi-definite K
// (rigid-body modes included: they become nu = 1/|sigma|, the largest) while keeping the low
// modes' nu apart; if the Cholesky factorisation fails, K has eigenvalues below sigma (an
// unstable configuration) and sigma is lowered a hundredfold until it succeeds (at the latest
// at -2 G, the rung that takes the place of any near -G: lowered_shift), so the unstable modes come out
// first, as on the dense path. Adaptive shift: modes far below |sigma| (lambda << 1e-6 G, a long hanging
// rope's pendulum modes) have nu within a few per cent of 1/|sigma| and converge slowly. If the first run has
// not converged after a few restarts, its Ritz values theta_i <= nu_i bound the wanted eigenvalues from
// above, lambda_i <= sigma + 1/theta_i; when the highest bound lies below |sigma| / 10, K - sigma M is
// factored again at sigma = -max(bound, 1e-8 G), still below the (semi-definite) spectrum, and
// the wanted nu spread out. A failure there falls back to the fixed shift.
//
// The Krylov space is small (2 mode_count + 20 vectors), so every new vector is
// M-orthogonalised against all previous ones twice (full re-orthogonalisation, classical
// Gram-Schmidt), and the projected matrix H = V^T M OP V is kept whole. When it is full, the Ritz
// pairs (theta, V y) of H are formed; the residual of a Ritz pair of OP is
// ||OP x - theta x||_M = |beta y_m| (beta the norm of the last new vector, y_m the last entry
// of y). Thick restart: the best Ritz vectors (half the space) are kept, H becomes diagonal with
// the theta, the last new vector continues the space, and its first step recomputes the
// coupling column. A Krylov space from one start vector holds only one vector of each
// eigenspace, so a multiple eigenvalue (the six rigid-body modes, the threefold modes of a
// chain of zero-length springs) is found once per run: the converged modes are then locked
// (every new vector is also M-orthogonalised against them) and Lanczos runs again from another
// fixed start vector; modes it finds below the highest kept one replace it, until a run adds
// none. Finally a Rayleigh-Ritz step on the kept vectors (K_r = X^T K X, M_r = X^T M X, GSL's
// generalised symmetric eigensolver) gives the eigenvalues as Rayleigh quotients of the exact K
// and M-orthonormal shapes; the residual ||K phi - lambda M phi|| / (||K|| ||phi||) of every
// kept mode is checked against residual_tolerance, ||K|| bounded by sm_block_row_bound as well.
// The iteration works on K times an even power of two that brings G to [1, 4), and the
// residuals (on both paths) are formed from sums of squares scaled by powers of two, all exactly:
// stiffnesses and masses of any size the doubles hold give the modes of the model as it is.
#include "analysis_internal.h"
#include "model_internal.h"
#include "modes_internal.h"

#include <gsl/gsl_eigen.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifdef SPRINGMASS_HAVE_CHOLMOD
#include <cholmod.h>

// sigma = -shift_fraction G to start with (see the top of the file) [1].
static const double shift_fraction = 1e-6;

// The next |sigma| after a factorisation of K - sigma M failed: a hundred times the last, but
// never near G. The lowest eigenvalue may be -G itself (the bound is attained where no two free
// particles share a spring), and K + G M is then singular: whether its factorisation succeeds is
// round-off's choice, and a success gives Lanczos an operator it cannot resolve. The rung that
// would land within a factor of 2 of G is 2 G, which leaves every eigenvalue at least G above
// sigma.
static double lowered_shift(double shift, double gershgorin)
{
	const double next = 100.0 * shift;
	return next > 0.5 * gershgorin && next < 2.0 * gershgorin ? 2.0 * gershgorin : next;
}

// A Ritz pair of OP counts as converged when |beta y_m| <= lanczos_tolerance theta [1]: well
// above the round-off of the solves, and the residual on K then comes out at 1e-12 or below
// (1e-6 is too loose: residuals of 1e-7 on the test models).
static const double lanczos_tolerance = 1e-10;
// A new Lanczos vector shorter than this fraction of the step's diagonal entry means an
// invariant subspace: the space continues from a fresh start vector [1].
static const double breakdown_fraction = 1e-13;
// Frequencies count as repeated within this fraction of the largest |omega^2| (modes.c groups the
// modes by it) [1].
static const double repeated_tolerance = SM_MODES_REPEATED_TOLERANCE;
// Restarts per Lanczos run and runs with locked modes, both bounds on the work.
static const int max_restarts = 400;
static const int max_runs = 12;
// Adaptive shift: restarts of the first run before the shift is reconsidered, and the lowest
// |sigma| it may move to, as a fraction of G [1] (at 1e-9 G the rigid-body and unstable test
// models missed the residual test; at 1e-8 G they passed it).
static const int probe_restarts = 10;
static const double adaptive_floor = 1e-8;
// Entries of each vector per stretch of the Ritz-vector products: 4 kB a vector, the 2 mode_count
// + 20 vectors of the space in 0.2 MB (10 modes) to 1 MB (60 modes), within a core's L2 cache.
static const size_t ritz_chunk = 512;

typedef struct lanczos_work {
	size_t dof;
	const double* mass;  // dof [kg]
	sm_sparse_jacobian* pattern;
	const int64_t* rows;  // CSR row pointers (symmetric pattern)
	const int64_t* cols;  // column indices
	// K, sigma, G and the eigenvalues are held scaled by 2^-exponent (lanczos_setup).
	int exponent;
	double* stiffness;  // nonzeros: K = -df/dx, scaled [N/m]
	double* shifted;    // nonzeros: K - sigma M, scaled
	int64_t* diagonal;  // dof positions of the diagonal entries
	double shift;       // sigma, scaled [1/s^2]
	double gershgorin;  // G, the bound on |lambda| of M^(-1/2) K M^(-1/2), scaled [1/s^2]
	cholmod_common common;
	int common_started;
	cholmod_factor* factor;
	size_t basis_size;     // m, Krylov vectors per run
	double* basis;         // (m + 1) x dof
	double* projected;     // m x m: H
	double* eigen_input;   // m x m: copy of H for GSL
	double* ritz;          // m x m: eigenvectors of H
	double* theta;         // m
	double* coefficients;  // m + 1
	double* products;      // m x dof: V Y on restart
	double* rhs;           // dof
	double* scratch;       // dof + want + m + 1: sm_modes_orthogonalise's (want locked at most)
	gsl_eigen_symmv_workspace* eigen;
	const sm_modes_def* def;  // on_iteration, the caller's progress callback
	int64_t steps;            // Lanczos steps (solves) so far, over every run
	bool stopped;             // on_iteration returned false
} lanczos_work;

static void lanczos_free(lanczos_work* w)
{
	sm_sparse_jacobian_destroy(w->pattern);
	free(w->stiffness);
	free(w->shifted);
	free(w->diagonal);
	if (w->common_started) {
		if (w->factor != NULL)
			cholmod_l_free_factor(&w->factor, &w->common);
		cholmod_l_finish(&w->common);
	}
	free(w->basis);
	free(w->projected);
	free(w->eigen_input);
	free(w->ritz);
	free(w->theta);
	free(w->coefficients);
	free(w->products);
	free(w->rhs);
	free(w->scratch);
	sm_modes_symmv_workspace_destroy(w->eigen);
}

// y = K x with the lower triangle of the CSR pattern (the half CHOLMOD factors), so that K is
// exactly symmetric for Lanczos and the factorisation alike.
static void stiffness_product(const lanczos_work* w, const double* x, double* y)
{
	memset(y, 0, w->dof * sizeof(double));
	for (size_t r = 0; r < w->dof; r++)
		for (int64_t k = w->rows[r]; k < w->rows[r + 1]; k++) {
			const size_t c = (size_t)w->cols[k];
			if (c > r)
				break;
			y[r] += w->stiffness[k] * x[c];
			if (c != r)
				y[c] += w->stiffness[k] * x[r];
		}
}

static double mass_dot(const lanczos_work* w, const double* a, const double* b)
{
	double s = 0.0;
	for (size_t i = 0; i < w->dof; i++)
		s += w->mass[i] * a[i] * b[i];
	return s;
}

// Factors K - sigma M with sigma = -shift; 1 if positive definite, 0 if not, -1 on failure.
static int factor_shifted(lanczos_work* w, double shift)
{
	const int64_t nnz = sm_sparse_jacobian_nonzeros(w->pattern);
	memcpy(w->shifted, w->stiffness, (size_t)nnz * sizeof(double));
	for (size_t i = 0; i < w->dof; i++)
		w->shifted[w->diagonal[i]] += shift * w->mass[i];
	cholmod_sparse A = sm_analysis_cholmod_view(w->pattern, w->dof, w->shifted);
	const int factored = sm_analysis_cholmod_factor(&A, &w->factor, &w->common);
	if (factored != 1)
		return factored;
	w->shift = -shift;
	return 1;
}

// out = OP v = (K - sigma M)^-1 M v; 0 on success.
static int apply_operator(lanczos_work* w, const double* v, double* out)
{
	for (size_t i = 0; i < w->dof; i++)
		w->rhs[i] = w->mass[i] * v[i];
	return sm_analysis_cholmod_solve(w->factor, &w->common, w->dof, w->rhs, out);
}

// The Gram-Schmidt and Ritz-vector loops below take the basis vectors four at a time, so that
// one pass over a vector serves four of them, and sum every dot product in eight independent
// partial sums (two per vector), which a single running sum, each addition waiting for the last,
// would serialise.

// c[i] = q_i^T u for the `count` vectors q_i (stride dof).
static void block_dots(const double* vectors, size_t count, size_t dof, const double* u, double* c)
{
	size_t i = 0;
	for (; i + 4 <= count; i += 4) {
		const double* q0 = vectors + i * dof;
		const double* q1 = q0 + dof;
		const double* q2 = q1 + dof;
		const double* q3 = q2 + dof;
		double s0[2] = {0.0, 0.0}, s1[2] = {0.0, 0.0}, s2[2] = {0.0, 0.0}, s3[2] = {0.0, 0.0};
		size_t k = 0;
		for (; k + 2 <= dof; k += 2)
			for (size_t l = 0; l < 2; l++) {
				s0[l] += q0[k + l] * u[k + l];
				s1[l] += q1[k + l] * u[k + l];
				s2[l] += q2[k + l] * u[k + l];
				s3[l] += q3[k + l] * u[k + l];
			}
		for (; k < dof; k++) {
			s0[0] += q0[k] * u[k];
			s1[0] += q1[k] * u[k];
			s2[0] += q2[k] * u[k];
			s3[0] += q3[k] * u[k];
		}
		c[i] = s0[0] + s0[1];
		c[i + 1] = s1[0] + s1[1];
		c[i + 2] = s2[0] + s2[1];
		c[i + 3] = s3[0] + s3[1];
	}
	for (; i < count; i++) {
		const double* q = vectors + i * dof;
		double s[4] = {0.0, 0.0, 0.0, 0.0};
		size_t k = 0;
		for (; k + 4 <= dof; k += 4)
			for (size_t l = 0; l < 4; l++)
				s[l] += q[k + l] * u[k + l];
		for (; k < dof; k++)
			s[0] += q[k] * u[k];
		c[i] = (s[0] + s[1]) + (s[2] + s[3]);
	}
}

// x[k] += sign sum_i c[i] q_i[k] for k in [begin, end), the `count` vectors q_i (stride dof).
static void block_combine(const double* vectors, size_t count, size_t dof, const double* c, double sign,
                          size_t begin, size_t end, double* x)
{
	size_t i = 0;
	for (; i + 4 <= count; i += 4) {
		const double* q0 = vectors + i * dof;
		const double* q1 = q0 + dof;
		const double* q2 = q1 + dof;
		const double* q3 = q2 + dof;
		const double c0 = sign * c[i], c1 = sign * c[i + 1], c2 = sign * c[i + 2], c3 = sign * c[i + 3];
		for (size_t k = begin; k < end; k++)
			x[k] += (c0 * q0[k] + c1 * q1[k]) + (c2 * q2[k] + c3 * q3[k]);
	}
	for (; i < count; i++) {
		const double* q = vectors + i * dof;
		const double ci = sign * c[i];
		for (size_t k = begin; k < end; k++)
			x[k] += ci * q[k];
	}
}

// CGS2 over two sets: see modes_internal.h. Both sets in every pass, because each basis vector
// carries round-off of the locked vectors, which subtracting it adds back: a v made orthogonal to
// the locked vectors first and to the basis after them kept sum_i c_i times the basis vectors'
// share of them, and the next vector, that divided by its norm beta, more: the share grew from
// step to step (from 1e-16 to 0.4 in 70 steps of the jelly block's second run), turning the run
// meant to find modes missed by the first back towards the modes it had locked.
void sm_modes_orthogonalise(const double* mass, size_t dof, double* v, const double* locked,
                            size_t locked_count, const double* basis, size_t count, double* coefficients,
                            double* scratch)
{
	if (locked_count + count == 0)
		return;
	double* weighted = scratch;
	double* c_locked = scratch + dof;
	double* c = c_locked + locked_count;
	for (int pass = 0; pass < 2; pass++) {
		for (size_t k = 0; k < dof; k++)
			weighted[k] = mass[k] * v[k];
		block_dots(locked, locked_count, dof, weighted, c_locked);
		block_dots(basis, count, dof, weighted, c);
		block_combine(locked, locked_count, dof, c_locked, -1.0, 0, dof, v);
		block_combine(basis, count, dof, c, -1.0, 0, dof, v);
		if (coefficients != NULL)
			for (size_t i = 0; i < count; i++)
				coefficients[i] += c[i];
	}
}

// A fixed pseudo-random number in [-1, 1) from (index, seed): a 64-bit mix (splitmix64's
// finaliser), so that every run starts from the same vector and no global state is used.
static double start_value(uint64_t index, uint64_t seed)
{
	uint64_t z = index * 0x9E3779B97F4A7C15u + (seed + 1) * 0xD1B54A32D192ED03u;
	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
	z ^= z >> 31;
	return (double)(z >> 11) * 0x1.0p-52 - 1.0;
}

// A start vector M-orthonormal to the locked vectors and to basis[0, count); 0 on success, -1
// if the space is exhausted.
static int fresh_vector(const lanczos_work* w, uint64_t seed, const double* locked, size_t locked_count,
                        const double* basis, size_t count, double* v)
{
	for (int attempt = 0; attempt < 4; attempt++) {
		for (size_t i = 0; i < w->dof; i++)
			v[i] = start_value(i, seed + 7919u * (uint64_t)attempt);
		const double before = sqrt(mass_dot(w, v, v));
		sm_modes_orthogonalise(w->mass, w->dof, v, locked, locked_count, basis, count, NULL, w->scratch);
		const double norm = sqrt(mass_dot(w, v, v));
		if (norm > 1e-8 * before) {
			for (size_t i = 0; i < w->dof; i++)
				v[i] /= norm;
			return 0;
		}
	}
	return -1;
}

// One Lanczos run: the `want` largest eigenvalues nu of OP on the M-orthogonal complement of
// the locked vectors, into nu[] (descending) and vectors (want x dof, M-orthonormal), with at
// most `restarts` thick restarts. Returns 1 when converged, 0 when the restarts ran out (nu and
// vectors then hold the current Ritz pairs), -1 on a failed solve or when the caller's
// on_iteration stopped it (w->stopped).
static int lanczos_run(lanczos_work* w, size_t want, const double* locked, size_t locked_count, uint64_t seed,
                       int restarts, double* nu, double* vectors)
{
	const size_t dof = w->dof;
	const size_t m = w->basis_size;
	double* V = w->basis;
	double* H = w->projected;
	memset(H, 0, m * m * sizeof(double));
	if (fresh_vector(w, seed, locked, locked_count, V, 0, V) != 0)
		return -1;
	size_t kept = 0;
	double beta = 0.0;
	for (int restart = 0;; restart++) {
		for (size_t j = kept; j < m; j++) {
			double* next = V + (j + 1) * dof;
			if (apply_operator(w, V + j * dof, next) != 0)
				return -1;
			w->steps++;
			memset(w->coefficients, 0, (j + 1) * sizeof(double));
			sm_modes_orthogonalise(w->mass, dof, next, locked, locked_count, V, j + 1, w->coefficients,
			                       w->scratch);
			for (size_t i = 0; i <= j; i++)
				H[i * m + j] = H[j * m + i] = w->coefficients[i];
			beta = sqrt(mass_dot(w, next, next));
			if (!(beta > breakdown_fraction * fabs(w->coefficients[j]))) {
				beta = 0.0;
				if (fresh_vector(w, seed + 1000u + (uint64_t)restart * m + j, locked, locked_count, V, j + 1,
				                 next) != 0)
					return -1;
			} else {
				for (size_t k = 0; k < dof; k++)
					next[k] /= beta;
			}
		}
		// Ritz pairs of H, largest theta first.
		memcpy(w->eigen_input, H, m * m * sizeof(double));
		gsl_matrix_view A = gsl_matrix_view_array(w->eigen_input, m, m);
		gsl_matrix_view Y = gsl_matrix_view_array(w->ritz, m, m);
		gsl_vector_view T = gsl_vector_view_array(w->theta, m);
		if (gsl_eigen_symmv(&A.matrix, &T.vector, &Y.matrix, w->eigen) != GSL_SUCCESS ||
		    gsl_eigen_symmv_sort(&T.vector, &Y.matrix, GSL_EIGEN_SORT_VAL_DESC) != GSL_SUCCESS)
			return -1;
		size_t converged_pairs = 0;
		for (size_t i = 0; i < want; i++)
			if (!(fabs(beta * w->ritz[(m - 1) * m + i]) > lanczos_tolerance * fabs(w->theta[i])))
				converged_pairs++;
		const int converged = converged_pairs == want;
		if (w->def->on_iteration != NULL && !w->def->on_iteration(w->def->on_iteration_context, w->steps,
		                                                          (int32_t)converged_pairs, (int32_t)want)) {
			w->stopped = true;
			return -1;
		}
		const int last = converged || restart == restarts;
		size_t keep = last ? want : want + (m - want) / 2;
		if (keep > m - 2)
			keep = m - 2;
		// Ritz vectors V y_i, a stretch of ritz_chunk entries of every one at a time, over which
		// the m basis vectors stay in cache. The y_i, columns of Y, as rows of its transpose
		// (into eigen_input, which gsl_eigen_symmv has overwritten).
		for (size_t i = 0; i < keep; i++)
			for (size_t j = 0; j < m; j++)
				w->eigen_input[i * m + j] = w->ritz[j * m + i];
		memset(w->products, 0, keep * dof * sizeof(double));
		for (size_t begin = 0; begin < dof; begin += ritz_chunk) {
			const size_t end = dof - begin > ritz_chunk ? begin + ritz_chunk : dof;
			for (size_t i = 0; i < keep; i++)
				block_combine(V, m, dof, w->eigen_input + i * m, 1.0, begin, end, w->products + i * dof);
		}
		if (last) {
			memcpy(vectors, w->products, want * dof * sizeof(double));
			memcpy(nu, w->theta, want * sizeof(double));
			return converged;
		}
		// Thick restart: V = [Ritz vectors, last new vector], H = diag(theta).
		memmove(V + keep * dof, V + m * dof, dof * sizeof(double));
		memcpy(V, w->products, keep * dof * sizeof(double));
		memset(H, 0, m * m * sizeof(double));
		for (size_t i = 0; i < keep; i++)
			H[i * m + i] = w->theta[i];
		kept = keep;
	}
}

// The error of a Lanczos run that returned -1.
static sm_status lanczos_failure(const lanczos_work* w, sm_error* err)
{
	if (w->stopped)
		return sm_error_set(err, SM_ERROR_NOT_CONVERGED,
		                    "modes: stopped by the caller (on_iteration) after %lld Lanczos steps",
		                    (long long)w->steps);
	return sm_error_set(err, SM_ERROR_SOLVER, "modes: a sparse solve failed in the Lanczos iteration");
}

// Sorts `count` eigenvalues ascending and their vectors (stride dof) along (insertion sort:
// count is small).
static void sort_pairs(double* lambda, double* vectors, size_t count, size_t dof, double* scratch)
{
	for (size_t i = 1; i < count; i++)
		for (size_t j = i; j > 0 && lambda[j] < lambda[j - 1]; j--) {
			const double t = lambda[j];
			lambda[j] = lambda[j - 1];
			lambda[j - 1] = t;
			memcpy(scratch, vectors + j * dof, dof * sizeof(double));
			memcpy(vectors + j * dof, vectors + (j - 1) * dof, dof * sizeof(double));
			memcpy(vectors + (j - 1) * dof, scratch, dof * sizeof(double));
		}
}

static sm_status lanczos_setup(lanczos_work* w, modes_problem* p, double* gershgorin, sm_error* err)
{
	w->pattern = sm_sparse_jacobian_create(p->model);
	if (w->pattern == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		                    "modes: out of memory for the sparse stiffness pattern");
	if ((size_t)sm_sparse_jacobian_dimension(w->pattern) != p->dof)
		return sm_error_set(err, SM_ERROR_SOLVER,
		                    "modes: the sparse pattern does not match the free particles");
	const int64_t nnz = sm_sparse_jacobian_nonzeros(w->pattern);
	w->rows = sm_sparse_jacobian_row_pointers(w->pattern);
	w->cols = sm_sparse_jacobian_column_indices(w->pattern);
	w->stiffness = malloc((size_t)(nnz > 0 ? nnz : 1) * sizeof(double));
	w->shifted = malloc((size_t)(nnz > 0 ? nnz : 1) * sizeof(double));
	w->diagonal = malloc(p->dof * sizeof(int64_t));
	if (w->stiffness == NULL || w->shifted == NULL || w->diagonal == NULL)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the sparse stiffness");
	const sm_status fill =
	    sm_sparse_jacobian_fill(w->pattern, p->model, p->x0, NULL, SM_JACOBIAN_EXACT, w->stiffness, NULL);
	if (fill != SM_OK)
		return sm_error_set(err, fill, "modes: the sparse stiffness could not be assembled");
	if (!sm_analysis_all_finite(w->stiffness, (size_t)nnz))
		return sm_error_set(err, SM_ERROR_NOT_FINITE, "modes: the stiffness matrix is not finite");
	// K = -df/dx.
	for (size_t r = 0; r < p->dof; r++) {
		w->diagonal[r] = -1;
		for (int64_t k = w->rows[r]; k < w->rows[r + 1]; k++) {
			w->stiffness[k] = -w->stiffness[k];
			if ((size_t)w->cols[k] == r)
				w->diagonal[r] = k;
		}
		if (w->diagonal[r] < 0)
			return sm_error_set(err, SM_ERROR_SOLVER, "modes: the sparse pattern lacks a diagonal entry");
	}
	// The bound G on |lambda| of M^(-1/2) K M^(-1/2) and the bound on ||K|| (sm_block_row_bound),
	// block row by block row: the pattern's rows come in threes of 3 blocks entries each.
	*gershgorin = 0.0;
	for (size_t r = 0; r < p->dof; r += 3) {
		const int64_t base = w->rows[r];
		const size_t blocks = (size_t)(w->rows[r + 1] - base) / 3;
		const sm_block_row row = {w->stiffness + base, 3 * blocks, blocks,
		                          (size_t)(w->diagonal[r] - base) / 3, w->cols + base};
		const double scaled = sm_block_row_bound(&row, p->dof_mass);
		if (!isfinite(scaled))
			return sm_modes_overflow_error(p, r, err);
		*gershgorin = fmax(*gershgorin, scaled);
		p->stiffness_norm = fmax(p->stiffness_norm, sm_block_row_bound(&row, NULL));
	}
	// K scaled by 2^-exponent, an even power of two that brings G to [1, 4), and with it every
	// eigenvalue, sigma and 1/nu. The Lanczos vectors are M-normalised, of the size of
	// 1/sqrt(m), but the new ones before normalisation are of the size of nu/sqrt(m), up to
	// 1/(|sigma| sqrt(m)) = 1e6/(G sqrt(m)): their squared M-norms overflowed for G below
	// about 1e-148 1/s^2 (springs of 1e-150 N/m on 1 kg: beta came out infinite, the vectors 0,
	// and the modes wrong) and underflowed for G above about 1e155 1/s^2. Scaled, they are of
	// the size of 1e6/sqrt(m) whatever G. The scaling is exact, and even so that the Cholesky
	// factor of K - sigma M scales exactly by its square root: the modes are those of K as it is,
	// to the bit.
	w->exponent = 0;
	if (*gershgorin > 0.0) {
		const int k = ilogb(*gershgorin);
		w->exponent = k % 2 == 0 ? k : k - 1;
	}
	if (w->exponent != 0) {
		for (int64_t k = 0; k < nnz; k++)
			w->stiffness[k] = scalbn(w->stiffness[k], -w->exponent);
		*gershgorin = scalbn(*gershgorin, -w->exponent);
	}
	return SM_OK;
}

// The generalised eigensolver's workspace, allocated here for the reason given at
// sm_modes_symmv_workspace_create (modes.c).
static gsl_eigen_gensymmv_workspace* gensymmv_workspace_create(size_t n)
{
	gsl_eigen_gensymmv_workspace* w = malloc(sizeof *w);
	gsl_eigen_symmv_workspace* inner = sm_modes_symmv_workspace_create(n);
	if (w == NULL || inner == NULL) {
		free(w);
		sm_modes_symmv_workspace_destroy(inner);
		return NULL;
	}
	*w = (gsl_eigen_gensymmv_workspace){n, inner};
	return w;
}

static void gensymmv_workspace_destroy(gsl_eigen_gensymmv_workspace* w)
{
	if (w != NULL) {
		sm_modes_symmv_workspace_destroy(w->symmv_workspace_p);
		free(w);
	}
}

// Buffers of the Lanczos runs and the final Rayleigh-Ritz step, want the kept modes.
typedef struct lanczos_pairs {
	size_t want;
	double* lambda;   // 2 want: kept eigenvalues, then a run's new ones
	double* found;    // 2 want x dof
	double* nu;       // want
	double* fresh;    // want x dof
	double* reduced;  // 4 want^2: K_r, M_r, their eigenvectors, and K x
	gsl_eigen_gensymmv_workspace* general;
} lanczos_pairs;

// The lowest pairs at the factored shift: Lanczos runs, the kept modes locked, until a run adds
// none below them (the first run's result already in pairs->nu and pairs->fresh if
// first_done), then Rayleigh-Ritz. Leaves omega^2 in pairs->nu and the M-orthonormal shapes
// (free degrees of freedom) in pairs->fresh, and the largest ||K phi - omega^2 M phi|| /
// (||K|| ||phi||) in *residual.
static sm_status lowest_pairs(lanczos_work* w, const modes_problem* p, lanczos_pairs* pairs, bool first_done,
                              double* residual, sm_error* err)
{
	const size_t dof = w->dof;
	const size_t want = pairs->want;
	double* lambda = pairs->lambda;
	double* found = pairs->found;
	double* nu = pairs->nu;
	double* fresh = pairs->fresh;
	size_t count = 0;
	for (int run = 0; run < max_runs; run++) {
		const int r = run == 0 && first_done
		                  ? 1
		                  : lanczos_run(w, want, found, count, (uint64_t)run, max_restarts, nu, fresh);
		if (r < 0)
			return lanczos_failure(w, err);
		// Modes at the round-off of the stiffness (omega^2 about 1e-13 G: the near-zero modes of a
		// stiff model) have nu within round-off of 1/|sigma| and may never converge; the dense
		// solver resolves them as zeros.
		if (r == 0)
			return sm_error_set(
			    err, SM_ERROR_NOT_CONVERGED,
			    "modes: Lanczos did not converge to %zu modes%s in %d restarts (run %d, shift %.3g "
			    "1/s^2); modes with omega^2 near the round-off of the largest (about 1e-12 of the "
			    "Gershgorin bound %.3g 1/s^2, as in a stiff model) may not converge: the dense solver "
			    "resolves them (SM_MODES_DENSE, springmass modes --solver dense)",
			    want, want > p->kept ? " (those asked for and the next one)" : "", max_restarts, run + 1,
			    scalbn(w->shift, w->exponent), scalbn(w->gershgorin, w->exponent));
		// lambda = sigma + 1/nu. A mode is new if it lies below the highest kept one by more than
		// the lesser of the round-off of the operator (1e-9 of its scale 1/nu) and the
		// repeated_tolerance G within which modes.c counts frequencies as repeated: with the first
		// alone, higher up (lambda above 1e-3 G) a copy of a frequency distinct by that measure but
		// within 1e-9 of the highest was dropped, and the next frequency's mode kept in its place
		// (two blocks, one 1e-10 heavier: 3e-12 G apart at 3e-2 G). Lambda's own round-off is
		// about eps G.
		const double highest = count > 0 ? lambda[count - 1] : INFINITY;
		const double margin = fmin(1e-9 * (highest - w->shift), repeated_tolerance * w->gershgorin);
		size_t added = 0;
		for (size_t i = 0; i < want; i++) {
			const double l = w->shift + 1.0 / nu[i];
			if (count < want || l < highest - margin) {
				lambda[count + added] = l;
				memcpy(found + (count + added) * dof, fresh + i * dof, dof * sizeof(double));
				added++;
			}
		}
		if (added == 0)
			break;
		sort_pairs(lambda, found, count + added, dof, w->rhs);
		count = count + added < want ? count + added : want;
		if (run == max_runs - 1)
			return sm_error_set(err, SM_ERROR_NOT_CONVERGED,
			                    "modes: multiple eigenvalues still being found after %d Lanczos runs",
			                    max_runs);
	}

	// Rayleigh-Ritz on the kept vectors X: K_r = X^T K X, M_r = X^T M X, K_r z = lambda M_r z.
	double* Kr = pairs->reduced;
	double* Mr = pairs->reduced + want * want;
	double* Z = pairs->reduced + 2 * want * want;
	for (size_t j = 0; j < want; j++) {
		stiffness_product(w, found + j * dof, w->rhs);
		for (size_t i = 0; i <= j; i++) {
			const double* xi = found + i * dof;
			double k = 0.0;
			for (size_t q = 0; q < dof; q++)
				k += xi[q] * w->rhs[q];
			Kr[i * want + j] = Kr[j * want + i] = k;
			Mr[i * want + j] = Mr[j * want + i] = mass_dot(w, xi, found + j * dof);
		}
	}
	gsl_matrix_view KrV = gsl_matrix_view_array(Kr, want, want);
	gsl_matrix_view MrV = gsl_matrix_view_array(Mr, want, want);
	gsl_matrix_view ZV = gsl_matrix_view_array(Z, want, want);
	gsl_vector_view LV = gsl_vector_view_array(nu, want);
	if (gsl_eigen_gensymmv(&KrV.matrix, &MrV.matrix, &LV.vector, &ZV.matrix, pairs->general) != GSL_SUCCESS ||
	    gsl_eigen_gensymmv_sort(&LV.vector, &ZV.matrix, GSL_EIGEN_SORT_VAL_ASC) != GSL_SUCCESS)
		return sm_error_set(err, SM_ERROR_SOLVER, "modes: the Rayleigh-Ritz eigensolver failed");
	// phi_j = X z_j, scaled to phi^T M phi = 1 (gensymmv normalises z^T M_r z = 1 already; the
	// scaling removes its round-off).
	*residual = 0.0;
	for (size_t j = 0; j < want; j++) {
		double* phi = fresh + j * dof;
		memset(phi, 0, dof * sizeof(double));
		for (size_t i = 0; i < want; i++) {
			const double z = Z[i * want + j];
			const double* xi = found + i * dof;
			for (size_t q = 0; q < dof; q++)
				phi[q] += z * xi[q];
		}
		const double norm = sqrt(mass_dot(w, phi, phi));
		for (size_t q = 0; q < dof; q++)
			phi[q] /= norm;
		stiffness_product(w, phi, w->rhs);
		for (size_t q = 0; q < dof; q++)
			w->rhs[q] -= nu[j] * w->mass[q] * phi[q];
		// K and its bound on ||K|| both scaled by 2^-exponent: the ratio is K's own.
		*residual = fmax(
		    *residual, sm_modes_relative_residual(w->rhs, phi, dof, scalbn(p->stiffness_norm, -w->exponent)));
	}
	return SM_OK;
}

sm_status sm_modes_sparse(modes_problem* p, sm_modes* modes, sm_error* err)
{
	const size_t dof = p->dof;
	// One mode more than kept where the Krylov space has room for it, to tell whether the kept
	// modes end inside a group of repeated frequencies.
	const size_t want = p->kept + 1 <= (dof - SM_MODES_SPARSE_MARGIN) / 4 ? p->kept + 1 : p->kept;
	lanczos_work w;
	memset(&w, 0, sizeof w);
	w.dof = dof;
	w.mass = p->dof_mass;
	w.def = p->def;
	double gershgorin = 0.0;
	sm_status st = lanczos_setup(&w, p, &gershgorin, err);
	w.gershgorin = gershgorin;
	lanczos_pairs pairs;
	memset(&pairs, 0, sizeof pairs);
	pairs.want = want;
	if (st != SM_OK)
		goto done;

	cholmod_l_start(&w.common);
	w.common_started = 1;
	w.common.print = 0;
	w.common.error_handler = NULL;
	// LL' stops at the first non-positive pivot: a failure means sigma is not below the spectrum.
	// Supernodal on sheets and blocks, simplicial in LL' form (final_ll, which stops there too)
	// on ropes and chains, whose supernodes hold a few columns each and whose solves, one per
	// Lanczos step, are faster simplicial (the lowest 10 modes of a 10 000-segment rope at its
	// equilibrium in 1.10 s instead of 1.35 s, docs/analysis.md).
	w.common.supernodal = CHOLMOD_AUTO;
	w.common.final_ll = 1;
	double shift = gershgorin > 0.0 ? shift_fraction * gershgorin : 1.0;
	int factored = 0, lowered = 0;
	for (int attempt = 0; attempt < 8 && factored == 0; attempt++) {
		factored = factor_shifted(&w, shift);
		if (factored == 0) {
			shift = lowered_shift(shift, gershgorin);
			lowered = 1;
		}
	}
	if (factored != 1) {
		st = sm_error_set(err, SM_ERROR_SOLVER,
		                  "modes: CHOLMOD could not factor K - sigma M (sigma = %.3g 1/s^2; status %d)",
		                  -scalbn(shift, w.exponent), (int)w.common.status);
		goto done;
	}

	w.basis_size = 2 * want + 20;
	const size_t m = w.basis_size;
	w.basis = malloc((m + 1) * dof * sizeof(double));
	w.projected = malloc(m * m * sizeof(double));
	w.eigen_input = malloc(m * m * sizeof(double));
	w.ritz = malloc(m * m * sizeof(double));
	w.theta = malloc(m * sizeof(double));
	w.coefficients = malloc((m + 1) * sizeof(double));
	w.products = malloc(m * dof * sizeof(double));
	w.rhs = malloc(dof * sizeof(double));
	w.scratch = malloc((dof + want + m + 1) * sizeof(double));
	w.eigen = sm_modes_symmv_workspace_create(m);
	pairs.lambda = malloc(2 * want * sizeof(double));
	pairs.found = malloc(2 * want * dof * sizeof(double));
	pairs.nu = malloc(want * sizeof(double));
	pairs.fresh = malloc(want * dof * sizeof(double));
	pairs.reduced = malloc(4 * want * want * sizeof(double));
	pairs.general = gensymmv_workspace_create(want);
	if (w.basis == NULL || w.projected == NULL || w.eigen_input == NULL || w.ritz == NULL ||
	    w.theta == NULL || w.coefficients == NULL || w.products == NULL || w.rhs == NULL ||
	    w.scratch == NULL || w.eigen == NULL || pairs.lambda == NULL || pairs.found == NULL ||
	    pairs.nu == NULL || pairs.fresh == NULL || pairs.reduced == NULL || pairs.general == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		                  "modes: out of memory for a Krylov space of %zu vectors of %zu degrees of freedom",
		                  m, dof);
		goto done;
	}

	// Adaptive shift (see the top of the file): the first run gets probe_restarts restarts. If
	// it converges, it is the first run. If not, its Ritz values theta, below OP's largest
	// eigenvalues, bound the wanted eigenvalues from above by sigma + 1/theta; when that bound
	// lies below a tenth of |sigma|, the wanted nu crowd near 1/|sigma| and the shift moves up
	// to -max(bound, adaptive_floor G), with a new factorisation (K - sigma M stays definite:
	// sigma is below zero and K was semi-definite, or the shift would have been lowered). Should
	// that fail to converge or to pass the residual test, the fixed shift is used after all.
	bool first_done = false, moved = false;
	if (!lowered) {
		const int r = lanczos_run(&w, want, NULL, 0, 0, probe_restarts, pairs.nu, pairs.fresh);
		if (r < 0) {
			st = lanczos_failure(&w, err);
			goto done;
		}
		first_done = r == 1;
		const double bound = w.shift + 1.0 / pairs.nu[want - 1];
		const double target = fmax(bound, adaptive_floor * gershgorin);
		if (r == 0 && bound > 0.0 && target < 0.1 * shift) {
			moved = factor_shifted(&w, target) == 1;
			if (!moved && factor_shifted(&w, shift) != 1) {
				st = sm_error_set(err, SM_ERROR_SOLVER, "modes: CHOLMOD could not factor K - sigma M again");
				goto done;
			}
		}
	}
	double residual = 0.0;
	st = lowest_pairs(&w, p, &pairs, first_done, &residual, err);
	if (moved && st != SM_ERROR_OUT_OF_MEMORY && !w.stopped &&
	    (st != SM_OK || !(residual <= p->def->residual_tolerance))) {
		if (factor_shifted(&w, shift) != 1) {
			st = sm_error_set(err, SM_ERROR_SOLVER, "modes: CHOLMOD could not factor K - sigma M again");
			goto done;
		}
		st = lowest_pairs(&w, p, &pairs, false, &residual, err);
	}
	if (st != SM_OK)
		goto done;
	// Back from the scaling of K (lanczos_setup).
	for (size_t j = 0; j < want; j++)
		pairs.nu[j] = scalbn(pairs.nu[j], w.exponent);
	gershgorin = scalbn(gershgorin, w.exponent);
	const size_t n3 = 3 * (size_t)p->particle_count;
	for (size_t j = 0; j < p->kept; j++) {
		sm_modes_scatter_shape(p, pairs.fresh + j * dof, 1, NULL, modes->shapes + j * n3);
		modes->omega_squared[j] = pairs.nu[j];
	}
	const double zero_level = p->def->zero_tolerance * gershgorin;
	sm_modes_classify(modes->omega_squared, p->kept, zero_level, modes);
	p->next_omega_squared =
	    want > p->kept ? (fabs(pairs.nu[p->kept]) <= zero_level ? 0.0 : pairs.nu[p->kept]) : NAN;
	modes->omega_max = sqrt(fmax(gershgorin, pairs.nu[want - 1]));
	modes->shift = scalbn(w.shift, w.exponent);

done:
	lanczos_free(&w);
	free(pairs.lambda);
	free(pairs.found);
	free(pairs.nu);
	free(pairs.fresh);
	free(pairs.reduced);
	gensymmv_workspace_destroy(pairs.general);
	return st;
}
#endif
