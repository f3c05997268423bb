// Natural frequencies, mode shapes and modal damping.
//
// Linearising M x'' = f(x, v) about a configuration x0 at rest, with x = x0 + u:
//
//   M u'' = (df/dx) u + (df/dv) u' + f(x0, 0)   =>   M u'' + C u' + K u = f(x0, 0),
//   K = -df/dx [N/m],  C = -df/dv [N s/m],  M = diag(m) [kg],
//
// over the free degrees of freedom (constrained particles do not move: their rows and columns
// drop out). At zero velocity the exact df/dx is the negative Hessian of the potential energy,
// so K is symmetric; if x0 is not an equilibrium the constant f(x0, 0) only shifts the rest
// point and does not change the frequencies.
//
// Undamped modes: K phi = omega^2 M phi. With M = diag(m) the substitution phi = M^(-1/2) y
// gives the standard symmetric problem
//
//   A y = omega^2 y,   A = M^(-1/2) K M^(-1/2),
//
// solved for all eigenpairs by gsl_eigen_symmv (Householder tridiagonalisation and implicit QR).
// The y are orthonormal, so the phi are mass-normalised: phi_i^T M phi_j = delta_ij.
//
// Rigid-body modes have omega^2 = 0 in exact arithmetic and about 1e-15 max|omega^2| after
// round-off, of either sign: eigenvalues within zero_tolerance * max|omega^2| are set to 0
// (default 1e-12: physical modes can lie far below 1e-9 of the largest, e.g. a long rope's
// pendulum modes, whose ratio to its axial modes falls as N^-2).
// An eigenvalue below that is a true instability (x0 is not a stable rest shape).
//
// Damping: with mass-normalised phi, the modal damping matrix is Phi^T C Phi. When it is
// diagonal (proportional or "classical" damping, e.g. C = a M + b K) each mode decays
// independently as exp(-zeta omega t) with 2 zeta_i omega_i = phi_i^T C phi_i (within a repeated
// frequency, in the basis that diagonalises the damping: diagonalise_repeated_groups). The largest
// off-diagonal entry, normalised by the geometric mean of the two diagonal ones, measures how far
// the damping is from proportional; C phi is computed without assembling C through the model's
// Jacobian-vector product (df/dv times phi).
//
// The sparse path (the lowest few modes of a large model, by shift-invert Lanczos) is in
// modes_lanczos.c, with its derivation; what the two paths share is in modes_internal.h.
#include "analysis_internal.h"
#include "model_internal.h"
#include "modes_internal.h"

#include <float.h>
#include <gsl/gsl_eigen.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const double two_pi = 6.283185307179586476925287;

// GSL's workspace allocators report a failed allocation to GSL's error handler, whose default
// aborts the process (and the handler is process-wide, so the library leaves it alone). The
// workspaces are plain structs of gsl_eigen.h: symmv's holds four arrays of n doubles (diagonal,
// subdiagonal, Givens cosines and sines) and gensymmv's one symmv workspace. They are allocated
// here instead (gensymmv's in modes_lanczos.c), a failure returned as NULL. Behind symmv's arrays
// lie n row indices for symmetric_eigenpairs (row_places).
gsl_eigen_symmv_workspace* sm_modes_symmv_workspace_create(size_t n)
{
	gsl_eigen_symmv_workspace* w = malloc(sizeof *w);
	double* arrays =
	    n <= SIZE_MAX / 5 / sizeof(double) ? malloc(4 * n * sizeof(double) + n * sizeof(size_t)) : NULL;
	if (w == NULL || arrays == NULL) {
		free(w);
		free(arrays);
		return NULL;
	}
	*w = (gsl_eigen_symmv_workspace){n, arrays, arrays + n, arrays + 2 * n, arrays + 3 * n};
	return w;
}

// The n row indices behind the arrays of a workspace of sm_modes_symmv_workspace_create.
static size_t* row_places(gsl_eigen_symmv_workspace* w)
{
	return (size_t*)(void*)(w->d + 4 * w->size);
}

void sm_modes_symmv_workspace_destroy(gsl_eigen_symmv_workspace* w)
{
	if (w != NULL) {
		free(w->d);
		free(w);
	}
}

// All eigenpairs of the symmetric n x n matrix (destroyed), eigenvalues ascending, eigenvectors
// as the columns of vectors; ws is a workspace for n. False if the eigensolver fails.
//
// A row of zeros (a degree of freedom that no spring holds, such as a particle without springs
// or one on an unstressed spring along x in y and z; a mode that no spring damps) is an
// eigenvector by itself, e_i with eigenvalue exactly 0, and is taken out before GSL's solver
// sees the matrix. Left in, such rows let the Householder reduction pass the round-off of the
// other rows on from row to row, shrinking by about the machine epsilon at each, down to
// subnormal numbers, where gsl_eigen_symmv's implicit QR never meets its convergence test
// (eps (|d_i| + |d_i+1|) underflows) and loops for ever: a spring along (2, 3, 6) among 20
// particles without springs, or a damper alone among 40 particles, never returned. The other
// rows and columns, in their order, form the matrix solved; a matrix without zero rows is solved
// as it is.
//
// The matrix is solved scaled by a power of two that brings its largest entry to [1, 2), the
// eigenvalues scaled back: exact, so the eigenpairs are those of the matrix as it is. Entries of
// the size of DBL_MIN make that test underflow just the same, and the implicit QR never returned:
// springs of 1e-307 N/m between particles of 1 kg, or 1 N/m between particles of 1e307 kg.
static bool symmetric_eigenpairs(double* matrix, size_t n, double* values, double* vectors,
                                 gsl_eigen_symmv_workspace* ws)
{
	// place[i]: where row i goes, the rows kept first in their order, then the zero rows.
	size_t* place = row_places(ws);
	size_t kept = 0;
	for (size_t i = 0; i < n; i++) {
		size_t j = 0;
		while (j < n && matrix[i * n + j] == 0.0)
			j++;
		place[i] = j < n ? kept++ : SIZE_MAX;
	}
	for (size_t i = 0, zero = kept; i < n; i++)
		if (place[i] == SIZE_MAX)
			place[i] = zero++;
	double largest = 0.0;
	for (size_t k = 0; k < n * n; k++)
		largest = fmax(largest, fabs(matrix[k]));
	const int exponent = largest > 0.0 ? ilogb(largest) : 0;
	if (exponent != 0)
		for (size_t k = 0; k < n * n; k++)
			matrix[k] = scalbn(matrix[k], -exponent);
	gsl_vector_view L = gsl_vector_view_array(values, n);
	gsl_matrix_view V = gsl_matrix_view_array(vectors, n, n);
	bool solved;
	if (kept == n) {
		gsl_matrix_view A = gsl_matrix_view_array(matrix, n, n);
		solved = gsl_eigen_symmv(&A.matrix, &L.vector, &V.matrix, ws) == GSL_SUCCESS;
	} else {
		// The rows kept, kept x kept, into vectors; their eigenvectors into matrix (both hold
		// n x n), then spread back, and a unit vector with eigenvalue 0 for each zero row.
		for (size_t i = 0; i < n; i++)
			for (size_t j = 0; j < n; j++)
				if (place[i] < kept && place[j] < kept)
					vectors[place[i] * kept + place[j]] = matrix[i * n + j];
		gsl_eigen_symmv_workspace part = *ws;  // its arrays have room for n
		part.size = kept;
		gsl_matrix_view A = gsl_matrix_view_array(vectors, kept, kept);
		gsl_matrix_view Y = gsl_matrix_view_array(matrix, kept, kept);
		gsl_vector_view T = gsl_vector_view_array(values, kept);
		solved = kept == 0 || gsl_eigen_symmv(&A.matrix, &T.vector, &Y.matrix, &part) == GSL_SUCCESS;
		for (size_t i = 0; i < n && solved; i++)
			for (size_t k = 0; k < n; k++)
				vectors[i * n + k] = place[i] < kept ? (k < kept ? matrix[place[i] * kept + k] : 0.0)
				                                     : (k == place[i] ? 1.0 : 0.0);
		for (size_t k = kept; k < n; k++)
			values[k] = 0.0;
	}
	for (size_t k = 0; k < kept && exponent != 0; k++)
		values[k] = scalbn(values[k], exponent);
	return solved && gsl_eigen_symmv_sort(&L.vector, &V.matrix, GSL_EIGEN_SORT_VAL_ASC) == GSL_SUCCESS;
}

sm_modes_def sm_default_modes_def(void)
{
	sm_modes_def def;
	memset(&def, 0, sizeof def);
	def.configuration = NULL;
	def.mode_count = 0;
	def.zero_tolerance = 1e-12;
	def.proportional_tolerance = 1e-6;
	def.solver = SM_MODES_AUTO;
	def.residual_tolerance = 1e-9;
	return def;
}

void sm_modes_release(sm_modes* modes)
{
	if (modes == NULL)
		return;
	free(modes->omega_squared);
	free(modes->frequency);
	free(modes->modal_damping);
	free(modes->damping_ratio);
	free(modes->shapes);
	memset(modes, 0, sizeof *modes);
}
// Writes the free-dof vector y (scaled by scale[r], or 1 if scale is NULL) as a shape over all
// particles (constrained particles 0).
void sm_modes_scatter_shape(const modes_problem* p, const double* y, size_t stride, const double* scale,
                            double* shape)
{
	for (int32_t q = 0; q < p->particle_count; q++) {
		const int32_t fi = p->free_index[q];
		if (fi < 0)
			continue;
		for (int c = 0; c < 3; c++) {
			const size_t r = 3 * (size_t)fi + c;
			shape[3 * (size_t)q + c] = y[r * stride] * (scale != NULL ? scale[r] : 1.0);
		}
	}
}

// Error for an omega^2 beyond the doubles: row r of M^(-1/2) K M^(-1/2) (entries K_rc /
// sqrt(m_r m_c) [1/s^2]) overflowed, e.g. ks = 1e200 N/m on m = 1e-200 kg (omega^2 = 1e400).
// Left alone, the infinities came out of the eigensolver as rigid-body modes.
sm_status sm_modes_overflow_error(const modes_problem* p, size_t r, sm_error* err)
{
	int32_t particle = -1;
	for (int32_t q = 0; q < p->particle_count && particle < 0; q++)
		if (p->free_index[q] == (int32_t)(r / 3))
			particle = q;
	return sm_error_set(err, SM_ERROR_NOT_FINITE,
	                    "modes: omega^2 overflows at particle %d (mass %g kg): its stiffness over its mass "
	                    "exceeds %g 1/s^2; the stiffnesses are out of range for the masses",
	                    (int)particle, p->dof_mass[r], DBL_MAX);
}

// The sum of the squares of x[0, n) times 2^(-2 k), k (into *exponent) the binary exponent of
// the largest |x_i|, so that the squares neither overflow nor underflow to 0 where the entries lie
// near the largest or the smallest doubles (as BLAS dnrm2 scales its sum): a shape's entries of
// 1e150 or 1e-150 (1 / sqrt(m), m = 1e-300 or 1e300 kg), a residual's of 1e-170. The scaling is
// exact, so that the sum is the plain one times 2^(-2 k) wherever that one is finite and normal.
static double scaled_squares(const double* x, size_t n, int* exponent)
{
	double largest = 0.0;
	for (size_t i = 0; i < n; i++)
		largest = fmax(largest, fabs(x[i]));
	*exponent = largest > 0.0 && isfinite(largest) ? ilogb(largest) : 0;
	double sum = 0.0;
	for (size_t i = 0; i < n; i++) {
		const double y = scalbn(x[i], -*exponent);
		sum += y * y;
	}
	return sum;
}

// ||r|| / (norm ||phi||) over n entries, the residual of a mode phi (r = K phi - omega^2 M phi)
// relative to the bound norm on ||K||; 0 if norm or phi is 0. Computed from scaled sums of
// squares: sqrt(r2 / phi2) / norm, to the bit, wherever those plain sums are finite and normal.
double sm_modes_relative_residual(const double* r, const double* phi, size_t n, double norm)
{
	int r_exponent, phi_exponent;
	const double r2 = scaled_squares(r, n, &r_exponent);
	const double phi2 = scaled_squares(phi, n, &phi_exponent);
	if (!(norm > 0.0 && phi2 > 0.0))
		return 0.0;
	return sqrt(r2 / phi2) / scalbn(norm, phi_exponent - r_exponent);
}

// Sets eigenvalues within zero_level of 0 to exactly 0 and counts the zero and unstable ones.
void sm_modes_classify(double* omega_squared, size_t count, double zero_level, sm_modes* modes)
{
	for (size_t i = 0; i < count; i++) {
		if (fabs(omega_squared[i]) <= zero_level) {
			omega_squared[i] = 0.0;
			modes->zero_count++;
		} else if (omega_squared[i] < 0.0) {
			modes->unstable_count++;
		}
	}
}

// ---------------------------------------------------------------------------------------------
// Dense path: all eigenpairs of A = M^(-1/2) K M^(-1/2).

static sm_status dense_modes(modes_problem* p, sm_modes* modes, sm_error* err)
{
	const size_t dof = p->dof;
	if (dof > SIZE_MAX / sizeof(double) / dof)
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: %zu degrees of freedom are too many", dof);
	sm_status st = SM_OK;
	double* K = malloc(dof * dof * sizeof(double));
	double* evec = malloc(dof * dof * sizeof(double));
	double* eval = malloc(dof * sizeof(double));
	double* scale = malloc(dof * sizeof(double));
	gsl_eigen_symmv_workspace* ws = NULL;
	if (K == NULL || evec == NULL || eval == NULL || scale == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		                  "modes: out of memory for a dense eigenproblem of %zu degrees of freedom", dof);
		goto done;
	}
	sm_analysis_dense_stiffness(p->model, p->free_index, p->x0, dof, SM_JACOBIAN_EXACT, K);
	if (!sm_analysis_all_finite(K, dof * dof)) {
		st = sm_error_set(err, SM_ERROR_NOT_FINITE, "modes: the stiffness matrix is not finite");
		goto done;
	}
	// The bound on ||K|| (sm_block_row_bound), block row by block row.
	for (size_t r = 0; r < dof; r += 3) {
		const sm_block_row row = {K + r * dof, dof, dof / 3, r / 3, NULL};
		p->stiffness_norm = fmax(p->stiffness_norm, sm_block_row_bound(&row, NULL));
	}
	for (size_t i = 0; i < dof; i++)
		scale[i] = 1.0 / sqrt(p->dof_mass[i]);
	// A = M^(-1/2) K M^(-1/2), symmetrised against round-off in the assembly.
	for (size_t i = 0; i < dof; i++)
		for (size_t j = 0; j <= i; j++) {
			const double a = 0.5 * (K[i * dof + j] + K[j * dof + i]) * scale[i] * scale[j];
			K[i * dof + j] = K[j * dof + i] = a;
		}
	// Every eigenvalue is bounded by a row sum of |A| (Gershgorin): finite sums, finite omega^2.
	for (size_t i = 0; i < dof; i++) {
		double row = 0.0;
		for (size_t j = 0; j < dof; j++)
			row += fabs(K[i * dof + j]);
		if (!isfinite(row)) {
			st = sm_modes_overflow_error(p, i, err);
			goto done;
		}
	}
	ws = sm_modes_symmv_workspace_create(dof);
	if (ws == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the eigensolver");
		goto done;
	}
	if (!symmetric_eigenpairs(K, dof, eval, evec, ws)) {
		st = sm_error_set(err, SM_ERROR_SOLVER, "modes: the symmetric eigensolver failed");
		goto done;
	}
	double largest = 0.0;
	for (size_t i = 0; i < dof; i++)
		largest = fmax(largest, fabs(eval[i]));
	sm_modes_classify(eval, dof, p->def->zero_tolerance * largest, modes);
	modes->omega_max = eval[dof - 1] > 0.0 ? sqrt(eval[dof - 1]) : 0.0;
	// Mode shapes phi = M^(-1/2) y.
	const size_t n3 = 3 * (size_t)p->particle_count;
	for (size_t m = 0; m < p->kept; m++) {
		sm_modes_scatter_shape(p, evec + m, dof, scale, modes->shapes + m * n3);
		modes->omega_squared[m] = eval[m];
	}
	p->next_omega_squared = p->kept < dof ? eval[p->kept] : NAN;
done:
	sm_modes_symmv_workspace_destroy(ws);
	free(K);
	free(evec);
	free(eval);
	free(scale);
	return st;
}
// ---------------------------------------------------------------------------------------------
// Both paths: frequencies, residuals and the modal damping matrix of the kept modes.

// Within a repeated frequency any orthonormal basis of the eigenspace is a set of modes, and the
// eigensolver returns whichever its round-off leads to; with non-proportional damping the modal
// damping block of the group, Phi_g^T C Phi_g, then depends on that basis. Rotating the group's
// shapes by the eigenvectors Q of that block (phi'_a = sum_b Q_ba phi_b: still M-orthonormal
// and still modes of that frequency) makes the block diagonal, with its eigenvalues, which do
// not depend on the basis, as the modes' damping: the only choice in which the group's modes
// decay independently of each other. Modes are one group when their omega^2 differ by at most
// repeated_tolerance times the largest |omega^2|, the eigensolvers' round-off (about 1e-15 of
// it, dense or sparse), and they are all zero, all unstable or all positive. The rotation
// applies to the rows and columns of the modal damping matrix as well (modal' = Q^T modal Q on
// the group). repeated_tolerance: SM_MODES_REPEATED_TOLERANCE (modes_internal.h).
static const double repeated_tolerance = SM_MODES_REPEATED_TOLERANCE;

// How far apart the omega^2 of one repeated frequency may lie: repeated_tolerance times the
// largest |omega^2| [1/s^2].
static double repeated_level(const sm_modes* modes, size_t kept)
{
	double scale = modes->omega_max * modes->omega_max;
	for (size_t i = 0; i < kept; i++)
		scale = fmax(scale, fabs(modes->omega_squared[i]));
	return repeated_tolerance * scale;
}

// The end of the group of modes that starts at start (ascending omega^2).
static size_t group_end(const double* w2, size_t count, size_t start, double tolerance)
{
	size_t end = start + 1;
	while (end < count && (w2[end] == 0.0) == (w2[start] == 0.0) && (w2[end] < 0.0) == (w2[start] < 0.0) &&
	       w2[end] - w2[end - 1] <= tolerance)
		end++;
	return end;
}

static sm_status diagonalise_repeated_groups(const modes_problem* p, sm_modes* modes, double* modal,
                                             sm_error* err)
{
	const size_t kept = p->kept;
	const size_t n3 = 3 * (size_t)p->particle_count;
	const double* w2 = modes->omega_squared;
	const double tolerance = repeated_level(modes, kept);
	size_t largest_group = 1;
	for (size_t start = 0, end; start < kept; start = end) {
		end = group_end(w2, kept, start, tolerance);
		largest_group = end - start > largest_group ? end - start : largest_group;
	}
	if (largest_group == 1)
		return SM_OK;

	const size_t g = largest_group;
	const size_t row = kept > n3 ? kept : n3;
	double* block = malloc(g * g * sizeof(double));
	double* rotation = malloc(g * g * sizeof(double));
	double* damping = malloc(g * sizeof(double));
	double* rows = malloc(g * row * sizeof(double));
	sm_status st = SM_OK;
	if (block == NULL || rotation == NULL || damping == NULL || rows == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the modal damping");
		goto done;
	}
	for (size_t start = 0, end; start < kept; start = end) {
		end = group_end(w2, kept, start, tolerance);
		const size_t s = end - start;
		if (s == 1)
			continue;
		// The group's block, symmetrised (C is symmetric up to round-off at zero velocity).
		for (size_t a = 0; a < s; a++)
			for (size_t b = 0; b < s; b++)
				block[a * s + b] =
				    0.5 * (modal[(start + a) * kept + start + b] + modal[(start + b) * kept + start + a]);
		gsl_eigen_symmv_workspace* ws = sm_modes_symmv_workspace_create(s);
		if (ws == NULL) {
			st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the modal damping");
			goto done;
		}
		const bool solved = symmetric_eigenpairs(block, s, damping, rotation, ws);
		sm_modes_symmv_workspace_destroy(ws);
		if (!solved) {
			st = sm_error_set(err, SM_ERROR_SOLVER,
			                  "modes: the eigensolver of a repeated frequency's damping failed");
			goto done;
		}
		// Shapes: phi'_a = sum_b Q_ba phi_b.
		double* shapes = modes->shapes + start * n3;
		for (size_t a = 0; a < s; a++)
			for (size_t k = 0; k < n3; k++) {
				double sum = 0.0;
				for (size_t b = 0; b < s; b++)
					sum += rotation[b * s + a] * shapes[b * n3 + k];
				rows[a * n3 + k] = sum;
			}
		memcpy(shapes, rows, s * n3 * sizeof(double));
		// Rows of the modal damping matrix, then its columns.
		for (size_t a = 0; a < s; a++)
			for (size_t j = 0; j < kept; j++) {
				double sum = 0.0;
				for (size_t b = 0; b < s; b++)
					sum += rotation[b * s + a] * modal[(start + b) * kept + j];
				rows[a * kept + j] = sum;
			}
		memcpy(modal + start * kept, rows, s * kept * sizeof(double));
		for (size_t i = 0; i < kept; i++) {
			for (size_t a = 0; a < s; a++) {
				double sum = 0.0;
				for (size_t b = 0; b < s; b++)
					sum += modal[i * kept + start + b] * rotation[b * s + a];
				rows[a] = sum;
			}
			memcpy(modal + i * kept + start, rows, s * sizeof(double));
		}
	}
done:
	free(block);
	free(rotation);
	free(damping);
	free(rows);
	return st;
}

static sm_status finish_modes(const modes_problem* p, sm_modes* modes, sm_error* err)
{
	const size_t kept = p->kept;
	const size_t n3 = 3 * (size_t)p->particle_count;
	double* product = malloc((n3 + 1) * sizeof(double));
	double* modal = malloc(kept * kept * sizeof(double));
	if (product == NULL || modal == NULL) {
		free(product);
		free(modal);
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the modal damping");
	}
	// The bounds of sm_model_explicit_limit: on every mode's damping rate, the largest eigenvalue of
	// M^-1/2 C M^-1/2, C = -df/dv over the free degrees of freedom, and with it the step limit.
	sm_explicit_limit limit;
	if (sm_model_explicit_limit(p->model, &limit) != SM_OK) {
		free(product);
		free(modal);
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the modal damping");
	}
	// What round-off leaves in an entry of Phi^T C Phi: each is a sum over the n3 components of
	// phi_i times C phi_j, with phi M-normalised, so its error is below about n3 eps times that
	// largest eigenvalue. Entries within it are zero: those of a free body's rigid modes, which
	// spring damping does not act on, come out as 1e-14 or so.
	const double damping_round_off = limit.damping_rate * 4.0 * (double)n3 * DBL_EPSILON;
	// Modal damping matrix Phi^T C Phi over the kept modes; C phi = -(df/dv) phi.
	for (size_t j = 0; j < kept; j++) {
		sm_model_jacobian_product(p->model, p->x0, NULL, SM_JACOBIAN_EXACT, NULL, modes->shapes + j * n3,
		                          product);
		for (size_t i = 0; i < kept; i++) {
			const double* phi = modes->shapes + i * n3;
			double s = 0.0;
			for (size_t k = 0; k < n3; k++)
				s -= phi[k] * product[k];
			modal[i * kept + j] = s;
		}
	}
	sm_status st = diagonalise_repeated_groups(p, modes, modal, err);
	if (st != SM_OK) {
		free(product);
		free(modal);
		return st;
	}
	// Residual ||K phi - omega^2 M phi|| / (||K|| ||phi||), K phi = -(df/dx) phi, over the free
	// degrees of freedom (phi is 0 on the others).
	modes->residual = 0.0;
	for (size_t a = 0; a < kept; a++) {
		const double* phi = modes->shapes + a * n3;
		const double w2 = modes->omega_squared[a];
		modes->frequency[a] = w2 > 0.0 ? sqrt(w2) / two_pi : 0.0;
		sm_model_jacobian_product(p->model, p->x0, NULL, SM_JACOBIAN_EXACT, phi, NULL, product);
		for (int32_t q = 0; q < p->particle_count; q++) {
			const int32_t fi = p->free_index[q];
			for (int c = 0; c < 3; c++) {
				const size_t k = 3 * (size_t)q + c;
				product[k] = fi < 0 ? 0.0 : -product[k] - w2 * p->dof_mass[3 * (size_t)fi + c] * phi[k];
			}
		}
		modes->residual =
		    fmax(modes->residual, sm_modes_relative_residual(product, phi, n3, p->stiffness_norm));
	}

	double largest_damping = 0.0;
	for (size_t i = 0; i < kept; i++)
		largest_damping = fmax(largest_damping, fabs(modal[i * kept + i]));
	for (size_t i = 0; i < kept; i++) {
		// A mode the damping does not act on (the transverse modes of a taut string whose springs
		// damp only along themselves) is undamped, whatever round-off its entry picked up.
		const double ci = fabs(modal[i * kept + i]) <= damping_round_off ? 0.0 : modal[i * kept + i];
		modes->modal_damping[i] = ci;
		const double omega = modes->omega_squared[i] > 0.0 ? sqrt(modes->omega_squared[i]) : 0.0;
		// An unstable mode grows (or, damped, creeps away) whatever its damping: it has no ratio.
		if (omega > 0.0)
			modes->damping_ratio[i] = ci / (2.0 * omega);
		else if (modes->omega_squared[i] < 0.0)
			modes->damping_ratio[i] = NAN;
		else
			modes->damping_ratio[i] = ci > fmax(1e-12 * largest_damping, damping_round_off) ? INFINITY : 0.0;
	}
	// Coupling between blocks of modes: a block is modes alike in frequency and in damping (within
	// round-off), which stay any basis of their span after diagonalise_repeated_groups (the two modes
	// of a symmetric pair, damped alike). The coupling of two blocks is the Frobenius norm of their
	// entries of Phi^T C Phi, which no rotation within either changes, over the geometric mean of
	// their damping; for single modes, |c_ij| / sqrt(c_ii c_jj).
	size_t* first = malloc((kept + 1) * sizeof *first);
	if (first == NULL) {
		free(product);
		free(modal);
		return sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the modal damping");
	}
	const double level = repeated_level(modes, kept);
	const double damping_level = fmax(damping_round_off, 1e-10 * largest_damping);
	size_t blocks = 0;
	for (size_t start = 0, end; start < kept; start = end) {
		end = group_end(modes->omega_squared, kept, start, level);
		for (size_t a = start; a < end; a++)
			if (a == start || modes->modal_damping[a] - modes->modal_damping[a - 1] > damping_level)
				first[blocks++] = a;
	}
	first[blocks] = kept;
	modes->damping_coupling = 0.0;
	for (size_t b = 0; b < blocks; b++)
		for (size_t c = 0; c < b; c++) {
			double sum = 0.0;
			for (size_t i = first[b]; i < first[b + 1]; i++)
				for (size_t j = first[c]; j < first[c + 1]; j++) {
					// Symmetrised: C is symmetric up to round-off at zero velocity.
					const double cij = 0.5 * (modal[i * kept + j] + modal[j * kept + i]);
					if (fabs(cij) > damping_round_off)
						sum += cij * cij;
				}
			// Floor of the normalisation: entries below 1e-12 of the largest damping are round-off.
			const double scale = fmax(
			    sqrt(fmax(modes->modal_damping[first[b]], 0.0) * fmax(modes->modal_damping[first[c]], 0.0)),
			    1e-12 * largest_damping);
			if (sum > 0.0 && scale > 0.0)
				modes->damping_coupling = fmax(modes->damping_coupling, sqrt(sum) / scale);
		}
	free(first);
	modes->proportional = modes->damping_coupling <= p->def->proportional_tolerance;
	modes->damping_rate_max = limit.damping_rate;
	modes->explicit_step = sm_symplectic_euler_step(modes->omega_max, modes->damping_rate_max);
	// With every mode at hand (the dense path, all kept), the smallest of their own limits, each
	// mode's omega with its damping rate phi^T C phi: exact for proportional damping, and above
	// the bound, which pairs the largest rate with the largest frequency.
	if (kept > 0 && kept == (size_t)modes->dof) {
		double step = INFINITY;
		for (size_t i = 0; i < kept; i++)
			step = fmin(step, sm_symplectic_euler_step(sqrt(fmax(modes->omega_squared[i], 0.0)),
			                                           fmax(modes->modal_damping[i], 0.0)));
		modes->explicit_step = step;
	}
	free(product);
	free(modal);
	return SM_OK;
}

sm_status sm_modes_compute(const sm_model* model, const sm_modes_def* def, sm_modes* modes, sm_error* err)
{
	if (modes == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: result pointer must not be NULL");
	memset(modes, 0, sizeof *modes);  // zeroed on every error (sm_modes_release zeroes the later ones)
	if (model == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: model must not be NULL");
	const sm_modes_def d = def != NULL ? *def : sm_default_modes_def();
	if (d.mode_count < 0)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: mode_count must be >= 0, got %d",
		                    (int)d.mode_count);
	if (!(d.zero_tolerance >= 0.0 && d.zero_tolerance < 1.0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "modes: zero_tolerance must lie in [0, 1), got %g", d.zero_tolerance);
	if (!(d.proportional_tolerance >= 0.0) || !isfinite(d.proportional_tolerance))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "modes: proportional_tolerance must be finite and >= 0, got %g",
		                    d.proportional_tolerance);
	if (d.solver != SM_MODES_AUTO && d.solver != SM_MODES_DENSE && d.solver != SM_MODES_SPARSE)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: unknown solver %d", (int)d.solver);
	if (!(d.residual_tolerance > 0.0 && d.residual_tolerance < 1.0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "modes: residual_tolerance must lie in (0, 1), got %g", d.residual_tolerance);
	modes->next_omega_squared = NAN;  // every mode kept until a solver says otherwise

	const int32_t n = sm_model_particle_count(model);
	const size_t n3 = 3 * (size_t)n;
	sm_status st = SM_OK;
	double* x0 = malloc((n3 + 1) * sizeof(double));
	int32_t* free_index = malloc(((size_t)n + 1) * sizeof(int32_t));
	double* dof_mass = malloc((n3 + 1) * sizeof(double));
	if (x0 == NULL || free_index == NULL || dof_mass == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for %d particles", (int)n);
		goto done;
	}
	if (d.configuration != NULL)
		memcpy(x0, d.configuration, n3 * sizeof(double));
	else
		sm_model_initial_state(model, x0, NULL);
	for (size_t k = 0; k < n3; k++)
		if (!isfinite(x0[k])) {
			st = sm_error_set(err, SM_ERROR_NOT_FINITE, "modes: position of particle %zu is not finite",
			                  k / 3);
			goto done;
		}
	// A spring's length that overflows leaves its direction 0 (model.h): its Jacobian blocks would
	// not be the configuration's, and the check below would take it for two coincident particles.
	const int32_t overflowing = sm_analysis_overflowing_spring(model, x0);
	if (overflowing >= 0) {
		st = sm_error_set(
		    err, SM_ERROR_NOT_FINITE,
		    "modes: spring %d between particles %d and %d is too long in the configuration (its squared "
		    "length overflows: particles joined by springs must be less than 1.3e154 m apart)",
		    (int)overflowing, (int)model->spring_a[overflowing], (int)model->spring_b[overflowing]);
		goto done;
	}
	const int32_t coincident = sm_analysis_coincident_spring(model, x0);
	if (coincident >= 0) {
		st = sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "modes: spring %d (rest length %g m) has its particles %d and %d at one point, where its force "
		    "has no derivative (its energy is a maximum there): the configuration has no modes",
		    (int)coincident, model->rest_length[coincident], (int)model->spring_a[coincident],
		    (int)model->spring_b[coincident]);
		goto done;
	}
	const int32_t damper = sm_analysis_coincident_damper(model, x0);
	if (damper >= 0) {
		st = sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "modes: spring %d (damping %g N s/m) has its particles %d and %d at one point, where its "
		    "damping force has no derivative (a motion through the point is damped in full, the "
		    "linearisation would have no damping): the configuration has no modes; take one with the "
		    "particles apart",
		    (int)damper, model->damping[damper], (int)model->spring_a[damper], (int)model->spring_b[damper]);
		goto done;
	}
	const int32_t nf = sm_analysis_free_map(model, free_index, dof_mass);
	const size_t dof = 3 * (size_t)nf;
	modes->dof = (int32_t)dof;
	modes->particle_count = n;
	modes->proportional = true;
	modes->explicit_step = INFINITY;  // no free particle: nothing to integrate

	// The sparse path needs 4 degrees of freedom per mode beyond a margin: room for the Krylov
	// space (2 per mode + 20) next to the locked modes. Without free particles there is nothing to
	// solve and no solver to refuse: no modes, whichever solver was asked for.
	const size_t wanted = (size_t)d.mode_count;
	const int sparse_fits =
	    wanted > 0 && dof >= SM_MODES_SPARSE_MARGIN && wanted <= (dof - SM_MODES_SPARSE_MARGIN) / 4;
	sm_modes_solver solver = d.solver;
	if (solver == SM_MODES_AUTO)
		solver = dof > SM_MODES_DENSE_LIMIT && sparse_fits ? SM_MODES_SPARSE : SM_MODES_DENSE;
	if (solver == SM_MODES_SPARSE && !sparse_fits && dof > 0) {
		if (dof < SM_MODES_SPARSE_MARGIN + 4)
			st = sm_error_set(
			    err, SM_ERROR_INVALID_ARGUMENT,
			    "modes: the sparse solver needs at least %d free degrees of freedom, the model has %zu: "
			    "use the dense solver",
			    SM_MODES_SPARSE_MARGIN + 4, dof);
		else if (d.mode_count == 0)
			st = sm_error_set(
			    err, SM_ERROR_INVALID_ARGUMENT,
			    "modes: the sparse solver gives the lowest modes, 1 to (dof - %d) / 4 = %zu of this "
			    "model's %zu, not all (mode_count = 0): use the dense solver for all",
			    SM_MODES_SPARSE_MARGIN, (dof - SM_MODES_SPARSE_MARGIN) / 4, dof);
		else
			st = sm_error_set(
			    err, SM_ERROR_INVALID_ARGUMENT,
			    "modes: the sparse solver gives 1 to (dof - %d) / 4 = %zu modes of this model (%zu free "
			    "degrees of freedom), not %d: use the dense solver for more",
			    SM_MODES_SPARSE_MARGIN, (dof - SM_MODES_SPARSE_MARGIN) / 4, dof, (int)d.mode_count);
		goto done;
	}
#ifndef SPRINGMASS_HAVE_CHOLMOD
	solver = SM_MODES_DENSE;
#endif
	modes->solver = solver;
	if (dof == 0)
		goto done;

	modes_problem p;
	memset(&p, 0, sizeof p);
	p.next_omega_squared = NAN;
	p.model = model;
	p.def = &d;
	p.x0 = x0;
	p.free_index = free_index;
	p.dof_mass = dof_mass;
	p.particle_count = n;
	p.dof = dof;
	p.kept = wanted == 0 || wanted > dof ? dof : wanted;
	const size_t kept = p.kept;
	modes->omega_squared = malloc(kept * sizeof(double));
	modes->frequency = malloc(kept * sizeof(double));
	modes->modal_damping = malloc(kept * sizeof(double));
	modes->damping_ratio = malloc(kept * sizeof(double));
	modes->shapes = kept <= SIZE_MAX / sizeof(double) / (n3 + 1) ? calloc(kept * n3, sizeof(double)) : NULL;
	if (modes->omega_squared == NULL || modes->frequency == NULL || modes->modal_damping == NULL ||
	    modes->damping_ratio == NULL || modes->shapes == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for %zu modes of %d particles",
		                  kept, (int)n);
		goto done;
	}
#ifdef SPRINGMASS_HAVE_CHOLMOD
	if (solver == SM_MODES_SPARSE)
		st = sm_modes_sparse(&p, modes, err);
	else
#endif
		st = dense_modes(&p, modes, err);
	if (st != SM_OK)
		goto done;
	modes->count = (int32_t)kept;
	st = finish_modes(&p, modes, err);
	modes->next_omega_squared = p.next_omega_squared;
	if (kept > 0 && !isnan(p.next_omega_squared)) {
		const double w2[2] = {modes->omega_squared[kept - 1], p.next_omega_squared};
		modes->group_cut = group_end(w2, 2, 0, repeated_level(modes, kept)) == 2;
	}
	if (st == SM_OK && solver == SM_MODES_SPARSE && !(modes->residual <= d.residual_tolerance))
		st = sm_error_set(err, SM_ERROR_NOT_CONVERGED,
		                  "modes: the Lanczos modes miss the residual test: %.3g > residual_tolerance %.3g",
		                  modes->residual, d.residual_tolerance);

done:
	free(x0);
	free(free_index);
	free(dof_mass);
	if (st != SM_OK)
		sm_modes_release(modes);
	else if (err != NULL) {
		err->status = SM_OK;
		err->message[0] = '\0';
	}
	return st;
}
