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
// round-off, of either sign: eigenvalues within zero_tolerance * max|omega^2| are set to 0.
// An eigenvalue below that is a true instability (x0 is not a stable rest shape).
//
// Damping: with mass-normalised phi, the modal damping matrix is Phi^T C Phi. When it is
// diagonal (proportional or "classical" damping, e.g. C = a M + b K) each mode decays
// independently as exp(-zeta omega t) with 2 zeta_i omega_i = phi_i^T C phi_i. The largest
// off-diagonal entry, normalised by the geometric mean of the two diagonal ones, measures how far
// the damping is from proportional; C phi is computed without assembling C through the model's
// Jacobian-vector product (df/dv times phi).
#include "analysis_internal.h"
#include "model_internal.h"

#include <gsl/gsl_eigen.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double two_pi = 6.283185307179586476925287;

sm_modes_def sm_default_modes_def(void)
{
	sm_modes_def def;
	memset(&def, 0, sizeof def);
	def.configuration = NULL;
	def.mode_count = 0;
	def.zero_tolerance = 1e-9;
	def.proportional_tolerance = 1e-6;
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

sm_status sm_modes_compute(const sm_model* model, const sm_modes_def* def, sm_modes* modes, sm_error* err)
{
	if (modes == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: result pointer must not be NULL");
	memset(modes, 0, sizeof *modes);
	if (model == NULL)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: model must not be NULL");
	const sm_modes_def d = def != NULL ? *def : sm_default_modes_def();
	if (d.mode_count < 0)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: mode_count must be >= 0, got %d",
		                    (int)d.mode_count);
	if (!(d.zero_tolerance >= 0.0 && d.zero_tolerance < 1.0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "modes: zero_tolerance must lie in [0, 1), got %g",
		                    d.zero_tolerance);
	if (!(d.proportional_tolerance >= 0.0) || !isfinite(d.proportional_tolerance))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "modes: proportional_tolerance must be finite and >= 0, got %g", d.proportional_tolerance);

	const int32_t n = sm_model_particle_count(model);
	const size_t n3 = 3 * (size_t)n;
	sm_status st = SM_OK;
	double* x0 = malloc((n3 + 1) * sizeof(double));
	int32_t* free_index = malloc(((size_t)n + 1) * sizeof(int32_t));
	double* dof_mass = malloc((n3 + 1) * sizeof(double));
	double* K = NULL;
	double* evec = NULL;
	double* eval = NULL;
	double* c_phi = NULL;
	double* modal = NULL;
	gsl_eigen_symmv_workspace* ws = NULL;
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
			st = sm_error_set(err, SM_ERROR_NOT_FINITE, "modes: position of particle %zu is not finite", k / 3);
			goto done;
		}
	const int32_t nf = analysis_free_map(model, free_index, dof_mass);
	const size_t dof = 3 * (size_t)nf;
	modes->dof = (int32_t)dof;
	modes->particle_count = n;
	modes->proportional = true;
	if (dof == 0)
		goto done;
	if (dof > SIZE_MAX / sizeof(double) / dof) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: %zu degrees of freedom are too many", dof);
		goto done;
	}
	const size_t kept = d.mode_count == 0 || (size_t)d.mode_count > dof ? dof : (size_t)d.mode_count;
	K = malloc(dof * dof * sizeof(double));
	evec = malloc(dof * dof * sizeof(double));
	eval = malloc(dof * sizeof(double));
	c_phi = malloc((n3 + 1) * sizeof(double));
	modal = malloc(kept * kept * sizeof(double));
	modes->omega_squared = malloc(kept * sizeof(double));
	modes->frequency = malloc(kept * sizeof(double));
	modes->modal_damping = malloc(kept * sizeof(double));
	modes->damping_ratio = malloc(kept * sizeof(double));
	modes->shapes = calloc(kept * n3, sizeof(double));
	if (K == NULL || evec == NULL || eval == NULL || c_phi == NULL || modal == NULL || modes->omega_squared == NULL ||
	    modes->frequency == NULL || modes->modal_damping == NULL || modes->damping_ratio == NULL ||
	    modes->shapes == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY,
		                  "modes: out of memory for a dense eigenproblem of %zu degrees of freedom", dof);
		goto done;
	}

	// A = M^(-1/2) K M^(-1/2), symmetrised against round-off in the assembly.
	analysis_dense_stiffness(model, free_index, x0, dof, SM_JACOBIAN_EXACT, K);
	for (size_t i = 0; i < dof; i++)
		for (size_t j = 0; j <= i; j++) {
			const double a = 0.5 * (K[i * dof + j] + K[j * dof + i]) / sqrt(dof_mass[i] * dof_mass[j]);
			K[i * dof + j] = K[j * dof + i] = a;
		}
	if (!analysis_all_finite(K, dof * dof)) {
		st = sm_error_set(err, SM_ERROR_NOT_FINITE, "modes: the stiffness matrix is not finite");
		goto done;
	}
	ws = gsl_eigen_symmv_alloc(dof);
	if (ws == NULL) {
		st = sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "modes: out of memory for the eigensolver");
		goto done;
	}
	gsl_matrix_view A = gsl_matrix_view_array(K, dof, dof);
	gsl_matrix_view V = gsl_matrix_view_array(evec, dof, dof);
	gsl_vector_view L = gsl_vector_view_array(eval, dof);
	if (gsl_eigen_symmv(&A.matrix, &L.vector, &V.matrix, ws) != GSL_SUCCESS ||
	    gsl_eigen_symmv_sort(&L.vector, &V.matrix, GSL_EIGEN_SORT_VAL_ASC) != GSL_SUCCESS) {
		st = sm_error_set(err, SM_ERROR_SOLVER, "modes: the symmetric eigensolver failed");
		goto done;
	}

	double largest = 0.0;
	for (size_t i = 0; i < dof; i++)
		largest = fmax(largest, fabs(eval[i]));
	const double zero_level = d.zero_tolerance * largest;
	for (size_t i = 0; i < dof; i++) {
		if (fabs(eval[i]) <= zero_level) {
			eval[i] = 0.0;
			modes->zero_count++;
		} else if (eval[i] < 0.0) {
			modes->unstable_count++;
		}
	}
	modes->omega_max = eval[dof - 1] > 0.0 ? sqrt(eval[dof - 1]) : 0.0;
	modes->count = (int32_t)kept;

	// Mode shapes phi = M^(-1/2) y over all particles (constrained ones stay 0).
	for (size_t m = 0; m < kept; m++) {
		double* shape = modes->shapes + m * n3;
		for (int32_t p = 0; p < n; p++) {
			const int32_t fi = free_index[p];
			if (fi < 0)
				continue;
			for (int c = 0; c < 3; c++) {
				const size_t r = 3 * (size_t)fi + c;
				shape[3 * (size_t)p + c] = evec[r * dof + m] / sqrt(dof_mass[r]);
			}
		}
		modes->omega_squared[m] = eval[m];
		modes->frequency[m] = eval[m] > 0.0 ? sqrt(eval[m]) / two_pi : 0.0;
	}

	// Modal damping matrix Phi^T C Phi over the kept modes; C phi = -(df/dv) phi.
	for (size_t j = 0; j < kept; j++) {
		sm_model_jacobian_product(model, x0, NULL, SM_JACOBIAN_EXACT, NULL, modes->shapes + j * n3, c_phi);
		for (size_t i = 0; i < kept; i++) {
			const double* phi = modes->shapes + i * n3;
			double s = 0.0;
			for (size_t k = 0; k < n3; k++)
				s -= phi[k] * c_phi[k];
			modal[i * kept + j] = s;
		}
	}
	double largest_damping = 0.0;
	for (size_t i = 0; i < kept; i++)
		largest_damping = fmax(largest_damping, fabs(modal[i * kept + i]));
	modes->damping_coupling = 0.0;
	for (size_t i = 0; i < kept; i++) {
		const double ci = modal[i * kept + i];
		modes->modal_damping[i] = ci;
		const double omega = modes->omega_squared[i] > 0.0 ? sqrt(modes->omega_squared[i]) : 0.0;
		if (omega > 0.0)
			modes->damping_ratio[i] = ci / (2.0 * omega);
		else
			modes->damping_ratio[i] = ci > 1e-12 * largest_damping && ci > 0.0 ? INFINITY : 0.0;
		for (size_t j = 0; j < i; j++) {
			// Symmetrised: C is symmetric up to round-off at zero velocity.
			const double cij = 0.5 * (modal[i * kept + j] + modal[j * kept + i]);
			const double cj = modal[j * kept + j];
			// Floor of the normalisation: entries below 1e-12 of the largest damping are round-off.
			const double scale = fmax(sqrt(fmax(ci, 0.0) * fmax(cj, 0.0)), 1e-12 * largest_damping);
			if (scale > 0.0)
				modes->damping_coupling = fmax(modes->damping_coupling, fabs(cij) / scale);
		}
	}
	modes->proportional = modes->damping_coupling <= d.proportional_tolerance;

done:
	if (ws != NULL)
		gsl_eigen_symmv_free(ws);
	free(x0);
	free(free_index);
	free(dof_mass);
	free(K);
	free(evec);
	free(eval);
	free(c_phi);
	free(modal);
	if (st != SM_OK)
		sm_modes_release(modes);
	else if (err != NULL) {
		err->status = SM_OK;
		err->message[0] = '\0';
	}
	return st;
}
