// Analytic Jacobians: per-spring blocks, dense matrices and the Jacobian-vector product.
//
// Every spring force depends only on d = x_b - x_a and dv = v_b - v_a, and f_b = -f_a, so one
// pair of 3x3 blocks K = d f_a / d x_b and D = d f_a / d v_b describes a spring completely:
//
//   d f_a / d x_a = -K,  d f_a / d x_b = K,  d f_b / d x_a = K,  d f_b / d x_b = -K
//
// and likewise for D. K is the sum of the elastic block (law_rest_length.h; zero-length
// springs are the case l0 = 0, see law_zero_length.h) and the position-derivative of the
// damping (law_spring_damping.h); D is the damping block. Mass damping adds -alpha m I to the
// diagonal of df/dv (law_body_forces.h).
#include "law_body_forces.h"
#include "law_rest_length.h"
#include "law_spring_damping.h"
#include "model_internal.h"

#include <string.h>

void sm_spring_blocks(const sm_model* model, int32_t spring, const double* x, const double* v,
                      sm_jacobian_variant variant, double K[9], double D[9])
{
	spring_geometry g;
	spring_geometry_eval(x, v, model->spring_a[spring], model->spring_b[spring], model->rest_length[spring],
	                     &g);
	for (int k = 0; k < 9; k++)
		K[k] = D[k] = 0.0;
	rest_length_add_block(model->stiffness[spring], model->rest_length[spring], &g, variant, K);
	spring_damping_add_blocks(model->damping[spring], &g, variant, K, D);
}

static bool known_variant(sm_jacobian_variant variant)
{
	return variant == SM_JACOBIAN_EXACT || variant == SM_JACOBIAN_DEFINITE;
}

sm_status sm_model_spring_jacobian(const sm_model* model, int32_t spring, const double* x, const double* v,
                                   sm_jacobian_variant variant, double K[9], double D[9])
{
	if (K != NULL)
		memset(K, 0, 9 * sizeof(double));
	if (D != NULL)
		memset(D, 0, 9 * sizeof(double));
	if (model == NULL || x == NULL || !known_variant(variant))
		return SM_ERROR_INVALID_ARGUMENT;
	if (spring < 0 || spring >= model->spring_count)
		return SM_ERROR_SPRING_INDEX;
	double k[9], d[9];
	sm_spring_blocks(model, spring, x, v, variant, k, d);
	if (K != NULL)
		memcpy(K, k, sizeof k);
	if (D != NULL)
		memcpy(D, d, sizeof d);
	return SM_OK;
}

// Adds sign * block to the 3x3 block (row particle p, column particle q) of a dense
// row-major matrix with `columns` columns.
static void add_dense_block(double* matrix, size_t columns, int32_t p, int32_t q, double sign,
                            const double block[9])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			matrix[(3 * (size_t)p + i) * columns + 3 * (size_t)q + j] += sign * block[3 * i + j];
}

sm_status sm_model_jacobian_dense(const sm_model* model, const double* x, const double* v,
                                  sm_jacobian_variant variant, double* dfdx, double* dfdv)
{
	if (model == NULL || x == NULL || !known_variant(variant))
		return SM_ERROR_INVALID_ARGUMENT;
	const size_t dim = 3 * (size_t)model->particle_count;
	if (dfdx != NULL)
		memset(dfdx, 0, dim * dim * sizeof(double));
	if (dfdv != NULL) {
		memset(dfdv, 0, dim * dim * sizeof(double));
		for (size_t r = 0; r < dim; r++)
			dfdv[r * dim + r] = mass_damping_derivative(model->mass[r / 3], model->def.mass_damping);
	}
	for (int32_t s = 0; s < model->spring_count; s++) {
		double K[9], D[9];
		sm_spring_blocks(model, s, x, v, variant, K, D);
		const int32_t a = model->spring_a[s], b = model->spring_b[s];
		if (dfdx != NULL) {
			add_dense_block(dfdx, dim, a, b, 1.0, K);
			add_dense_block(dfdx, dim, a, a, -1.0, K);
			add_dense_block(dfdx, dim, b, a, 1.0, K);
			add_dense_block(dfdx, dim, b, b, -1.0, K);
		}
		if (dfdv != NULL) {
			add_dense_block(dfdv, dim, a, b, 1.0, D);
			add_dense_block(dfdv, dim, a, a, -1.0, D);
			add_dense_block(dfdv, dim, b, a, 1.0, D);
			add_dense_block(dfdv, dim, b, b, -1.0, D);
		}
	}
	return SM_OK;
}

// Without storage, each spring's factored form (forces.c: K = beta I + u z^T, D = kd u u^T) is
// computed on the fly and applied at once, instead of building its two 3x3 blocks:
// d f_a = K rx + D rv = u (z . rx + kd u . rv) + beta rx, d f_b = -d f_a.
sm_status sm_model_jacobian_product(const sm_model* model, const double* x, const double* v,
                                    sm_jacobian_variant variant, const double* dx, const double* dv,
                                    double* out)
{
	if (model == NULL || x == NULL || out == NULL || !known_variant(variant))
		return SM_ERROR_INVALID_ARGUMENT;
	// out is written before the springs read dx and dv, and x and v at every spring.
	if (out == x || out == v || out == dx || out == dv)
		return SM_ERROR_INVALID_ARGUMENT;
	const int32_t n = model->particle_count;
	for (int32_t i = 0; i < n; i++) {
		const double c = mass_damping_derivative(model->mass[i], model->def.mass_damping);
		for (int k = 0; k < 3; k++)
			out[3 * (size_t)i + k] = dv != NULL ? c * dv[3 * (size_t)i + k] : 0.0;
	}
	const int exact = variant != SM_JACOBIAN_DEFINITE;
	for (int32_t s = 0; s < model->spring_count; s++) {
		spring_geometry g;
		const double l0 = model->rest_length[s], ks = model->stiffness[s], kd = model->damping[s];
		spring_geometry_eval(x, v, model->spring_a[s], model->spring_b[s], l0, &g);
		double geometric = 1.0 - l0 * g.inv_length;
		if (!exact && geometric < 0.0)
			geometric = 0.0;
		const double c = exact ? kd * g.inv_length : 0.0;
		const double cr = c * g.rate;
		const double beta = ks * geometric + cr;
		const double axial = ks - beta - cr;
		const size_t a = 3 * (size_t)model->spring_a[s], b = 3 * (size_t)model->spring_b[s];
		double rx[3] = {0.0, 0.0, 0.0}, coefficient = 0.0;
		for (int k = 0; k < 3; k++) {
			if (dx != NULL) {
				rx[k] = dx[b + k] - dx[a + k];
				coefficient += (axial * g.u[k] + c * g.dv[k]) * rx[k];
			}
			if (dv != NULL)
				coefficient += kd * g.u[k] * (dv[b + k] - dv[a + k]);
		}
		for (int k = 0; k < 3; k++) {
			const double df = g.u[k] * coefficient + beta * rx[k];
			out[a + k] += df;
			out[b + k] -= df;
		}
	}
	return SM_OK;
}

// From the factored records (model_internal.h; derivation in forces.c):
// K = u z^T + beta I, D = kd u u^T.
sm_status sm_spring_jacobians_block(const sm_spring_jacobians* jacobians, int32_t spring, double K[9],
                                    double D[9])
{
	if (jacobians == NULL || !jacobians->evaluated)
		return SM_ERROR_INVALID_ARGUMENT;
	if (spring < 0 || spring >= jacobians->spring_count)
		return SM_ERROR_SPRING_INDEX;
	const double* q = jacobians->data + SPRING_JACOBIAN_STRIDE * (size_t)spring;
	const double *u = q, *z = q + 3, beta = q[6], kd = q[7];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) {
			if (K != NULL)
				K[3 * i + j] = u[i] * z[j] + (i == j ? beta : 0.0);
			if (D != NULL)
				D[3 * i + j] = kd * u[i] * u[j];
		}
	return SM_OK;
}

// The product of one spring: d f_a = K rx + D rv = u (z . rx + kd u . rv) + beta rx, with
// rx = dx_b - dx_a, rv = dv_b - dv_a; d f_b = -d f_a. Specialised for the NULL cases.
static inline void factored_product(const sm_spring_jacobians* J, const sm_model* model,
                                    const double* restrict dx, const double* restrict dv,
                                    double* restrict out, const int with_x, const int with_v)
{
	const int32_t* restrict first = model->spring_a;
	const int32_t* restrict second = model->spring_b;
	const double* restrict data = J->data;
	for (int32_t s = 0; s < J->spring_count; s++) {
		const double* restrict q = data + SPRING_JACOBIAN_STRIDE * (size_t)s;
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		double rx[3] = {0.0, 0.0, 0.0}, coefficient = 0.0;
		if (with_x) {
			rx[0] = dx[b] - dx[a];
			rx[1] = dx[b + 1] - dx[a + 1];
			rx[2] = dx[b + 2] - dx[a + 2];
			coefficient = q[3] * rx[0] + q[4] * rx[1] + q[5] * rx[2];
		}
		if (with_v)
			coefficient += q[7] * (q[0] * (dv[b] - dv[a]) + q[1] * (dv[b + 1] - dv[a + 1]) +
			                       q[2] * (dv[b + 2] - dv[a + 2]));
		for (int k = 0; k < 3; k++) {
			const double df = q[k] * coefficient + (with_x ? q[6] * rx[k] : 0.0);
			out[a + k] += df;
			out[b + k] -= df;
		}
	}
}

sm_status sm_spring_jacobians_product(const sm_spring_jacobians* jacobians, const sm_model* model,
                                      const double* dx, const double* dv, double* out)
{
	if (jacobians == NULL || model == NULL || out == NULL || !jacobians->evaluated || out == dx || out == dv)
		return SM_ERROR_INVALID_ARGUMENT;
	if (jacobians->particle_count != model->particle_count || jacobians->spring_count != model->spring_count)
		return SM_ERROR_TOPOLOGY;
	const int32_t n = model->particle_count;
	for (int32_t i = 0; i < n; i++) {
		const double c = mass_damping_derivative(model->mass[i], model->def.mass_damping);
		for (int k = 0; k < 3; k++)
			out[3 * (size_t)i + k] = dv != NULL ? c * dv[3 * (size_t)i + k] : 0.0;
	}
	if (dx != NULL && dv != NULL)
		factored_product(jacobians, model, dx, dv, out, 1, 1);
	else if (dx != NULL)
		factored_product(jacobians, model, dx, NULL, out, 1, 0);
	else if (dv != NULL)
		factored_product(jacobians, model, NULL, dv, out, 0, 1);
	return SM_OK;
}

// One spring of the combined product: with r = p_b - p_a,
//   (a K + b D) r = u (a z . r + b kd u . r) + a beta r = u (w . r) + a beta r,
// w = a z + b kd u, added to out at a and subtracted at b.
sm_status sm_spring_jacobians_combined_product(const sm_spring_jacobians* jacobians, const sm_model* model,
                                               double scale_k, double scale_d, const double* restrict p,
                                               double* restrict out)
{
	if (jacobians == NULL || model == NULL || p == NULL || out == NULL || !jacobians->evaluated || out == p)
		return SM_ERROR_INVALID_ARGUMENT;
	if (jacobians->particle_count != model->particle_count || jacobians->spring_count != model->spring_count)
		return SM_ERROR_TOPOLOGY;
	const int32_t n = model->particle_count;
	const double alpha = model->def.mass_damping;
	for (int32_t i = 0; i < n; i++) {
		const double c = scale_d * mass_damping_derivative(model->mass[i], alpha);
		const size_t k = 3 * (size_t)i;
		out[k] = c * p[k];
		out[k + 1] = c * p[k + 1];
		out[k + 2] = c * p[k + 2];
	}
	const int32_t* restrict first = model->spring_a;
	const int32_t* restrict second = model->spring_b;
	const double* restrict data = jacobians->data;
	const int32_t count = jacobians->spring_count;
	// Structures list their springs particle by particle, so consecutive springs often share
	// their first particle: its sum is kept in registers until the particle changes, which
	// spares a chain of additions through memory.
	size_t held = count > 0 ? 3 * (size_t)first[0] : 0;
	double hx = 0.0, hy = 0.0, hz = 0.0;
	for (int32_t s = 0; s < count; s++) {
		const double* restrict q = data + SPRING_JACOBIAN_STRIDE * (size_t)s;
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		if (a != held) {
			out[held] += hx;
			out[held + 1] += hy;
			out[held + 2] += hz;
			hx = hy = hz = 0.0;
			held = a;
		}
		const double rx = p[b] - p[a], ry = p[b + 1] - p[a + 1], rz = p[b + 2] - p[a + 2];
		const double along = q[0] * rx + q[1] * ry + q[2] * rz;
		const double coefficient = scale_k * (q[3] * rx + q[4] * ry + q[5] * rz) + scale_d * q[7] * along;
		const double diagonal = scale_k * q[6];
		const double fx = q[0] * coefficient + diagonal * rx;
		const double fy = q[1] * coefficient + diagonal * ry;
		const double fz = q[2] * coefficient + diagonal * rz;
		hx += fx;
		hy += fy;
		hz += fz;
		out[b] -= fx;
		out[b + 1] -= fy;
		out[b + 2] -= fz;
	}
	if (count > 0) {
		out[held] += hx;
		out[held + 1] += hy;
		out[held + 2] += hz;
	}
	return SM_OK;
}

const char* sm_jacobian_variant_name(sm_jacobian_variant variant)
{
	switch (variant) {
	case SM_JACOBIAN_EXACT: return "exact";
	case SM_JACOBIAN_DEFINITE: return "definite";
	}
	return "unknown";
}

sm_status sm_jacobian_variant_from_name(const char* name, sm_jacobian_variant* variant)
{
	if (name == NULL || variant == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (strcmp(name, "exact") == 0)
		*variant = SM_JACOBIAN_EXACT;
	else if (strcmp(name, "definite") == 0)
		*variant = SM_JACOBIAN_DEFINITE;
	else
		return SM_ERROR_INVALID_ARGUMENT;
	return SM_OK;
}
