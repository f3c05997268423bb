// Helpers shared by the static equilibrium (statics.c) and the modal analysis (modes.c,
// modes_lanczos.c): the free degrees of freedom and their masses, the springs an analysis cannot
// linearise about a state (coincident ends, overflowing forces), the dense stiffness K = -df/dx,
// and the CHOLMOD factorisation of a sparse symmetric matrix.
#include "analysis_internal.h"
#include "model_internal.h"

#include <math.h>
#include <string.h>

#ifdef SPRINGMASS_HAVE_CHOLMOD
#include <cholmod.h>

#include "cholmod_factorize.h"
#endif

int32_t sm_analysis_free_map(const sm_model* model, int32_t* free_index, double* dof_mass)
{
	const int32_t n = sm_model_particle_count(model);
	int32_t nf = 0;
	for (int32_t p = 0; p < n; p++) {
		sm_particle_def def;
		sm_model_get_particle(model, p, &def);
		if (def.motion == SM_PARTICLE_FREE) {
			if (dof_mass != NULL)
				dof_mass[3 * (size_t)nf] = dof_mass[3 * (size_t)nf + 1] = dof_mass[3 * (size_t)nf + 2] =
				    def.mass;
			free_index[p] = nf++;
		} else {
			free_index[p] = -1;
		}
	}
	return nf;
}

// What first_spring looks for.
typedef enum spring_question {
	COINCIDENT_SPRING,   // a rest-length spring of l0 > 0 and ks > 0 whose particles coincide at x
	COINCIDENT_DAMPER,   // a damped spring whose particles coincide at x
	OVERFLOWING_SPRING,  // a rest-length or damped spring whose length at x is not a double
} spring_question;

// The first intact spring with a free end that answers the question at x, or -1. A spring between
// two held particles acts on no free degree of freedom: it has nothing to linearise. 1 / L is 0
// both where the particles coincide and where L overflows (about 1e154 m): the length tells
// which. An undamped zero-length spring's blocks, ks I and 0, need no direction, so its length
// may overflow.
static int32_t first_spring(const sm_model* model, const double* x, spring_question question)
{
	for (int32_t s = 0; s < model->spring_count; s++) {
		const bool zero_length = model->zero_length[s], damped = model->damping[s] > 0.0;
		const bool concerned = question == COINCIDENT_SPRING
		                           ? !zero_length && model->rest_length[s] > 0.0 && model->stiffness[s] > 0.0
		                       : question == COINCIDENT_DAMPER ? damped
		                                                       : !zero_length || damped;
		const bool held =
		    model->free_index[model->spring_a[s]] < 0 && model->free_index[model->spring_b[s]] < 0;
		if (!model->enabled[s] || !concerned || held)
			continue;
		spring_geometry g;
		spring_geometry_eval(x, NULL, model->spring_a[s], model->spring_b[s], model->rest_length[s], &g);
		const bool overflows = !isfinite(g.length);
		if (question == OVERFLOWING_SPRING ? overflows : g.inv_length == 0.0 && !overflows)
			return s;
	}
	return -1;
}

int32_t sm_analysis_overflowing_spring(const sm_model* model, const double* x)
{
	return first_spring(model, x, OVERFLOWING_SPRING);
}

int32_t sm_analysis_coincident_spring(const sm_model* model, const double* x)
{
	return first_spring(model, x, COINCIDENT_SPRING);
}

int32_t sm_analysis_coincident_damper(const sm_model* model, const double* x)
{
	return first_spring(model, x, COINCIDENT_DAMPER);
}

int sm_analysis_all_finite(const double* values, size_t count)
{
	for (size_t k = 0; k < count; k++)
		if (!isfinite(values[k]))
			return 0;
	return 1;
}

#ifdef SPRINGMASS_HAVE_CHOLMOD
cholmod_sparse sm_analysis_cholmod_view(const sm_sparse_jacobian* pattern, size_t dof, double* values)
{
	cholmod_sparse A;
	memset(&A, 0, sizeof A);
	A.nrow = A.ncol = dof;
	A.nzmax = (size_t)sm_sparse_jacobian_nonzeros(pattern);
	A.p = (void*)sm_sparse_jacobian_row_pointers(pattern);
	A.i = (void*)sm_sparse_jacobian_column_indices(pattern);
	A.x = values;
	A.stype = 1;
	A.itype = CHOLMOD_LONG;
	A.xtype = CHOLMOD_REAL;
	A.dtype = CHOLMOD_DOUBLE;
	A.sorted = 1;
	A.packed = 1;
	return A;
}

int sm_analysis_cholmod_factor(cholmod_sparse* A, cholmod_factor** factor, cholmod_common* common)
{
	if (*factor == NULL) {
		*factor = sm_cholmod_analyze(A, common);
		if (*factor == NULL)
			return -1;
	}
	sm_cholmod_factorize(A, *factor, common);
	if (common->status == CHOLMOD_NOT_POSDEF || (*factor)->minor < (*factor)->n)
		return 0;
	return common->status < CHOLMOD_OK ? -1 : 1;
}

int sm_analysis_cholmod_solve(cholmod_factor* factor, cholmod_common* common, size_t dof, const double* rhs,
                              double* out)
{
	cholmod_dense b;
	memset(&b, 0, sizeof b);
	b.nrow = b.d = b.nzmax = dof;
	b.ncol = 1;
	b.x = (void*)rhs;
	b.xtype = CHOLMOD_REAL;
	b.dtype = CHOLMOD_DOUBLE;
	cholmod_dense* s = cholmod_l_solve(CHOLMOD_A, factor, &b, common);
	if (s == NULL)
		return -1;
	memcpy(out, s->x, dof * sizeof(double));
	cholmod_l_free_dense(&s, common);
	return 0;
}
#endif

// K = -df/dx: the block K_s = d f_a / d x_b of spring s enters as
//   K[a][a] += K_s, K[b][b] += K_s, K[a][b] -= K_s, K[b][a] -= K_s
// (since d f_a / d x_a = -K_s, see model.h), rows and columns of constrained particles dropped.
void sm_analysis_dense_stiffness(const sm_model* model, const int32_t* free_index, const double* x,
                                 size_t dof, sm_jacobian_variant variant, double* K)
{
	memset(K, 0, dof * dof * sizeof(double));
	const int32_t ns = sm_model_spring_count(model);
	for (int32_t s = 0; s < ns; s++) {
		if (!sm_model_spring_enabled(model, s))
			continue;
		sm_spring_def sd;
		sm_model_get_spring(model, s, &sd);
		const int32_t fa = free_index[sd.a], fb = free_index[sd.b];
		if (fa < 0 && fb < 0)
			continue;
		double block[9];
		sm_model_spring_jacobian(model, s, x, NULL, variant, block, NULL);
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				const double k = block[3 * i + j];
				if (fa >= 0)
					K[(3 * (size_t)fa + i) * dof + 3 * (size_t)fa + j] += k;
				if (fb >= 0)
					K[(3 * (size_t)fb + i) * dof + 3 * (size_t)fb + j] += k;
				if (fa >= 0 && fb >= 0) {
					K[(3 * (size_t)fa + i) * dof + 3 * (size_t)fb + j] -= k;
					K[(3 * (size_t)fb + i) * dof + 3 * (size_t)fa + j] -= k;
				}
			}
	}
}
