// The sparse Jacobian over the free particles' degrees of freedom: pattern built once, values
// refilled in place.
//
// Layout: compressed sparse rows with 64-bit indices, columns sorted within each row, the
// diagonal blocks always present (SUNMatrix_Sparse CSR_MAT with 64-bit sunindextype). The
// pattern is made of 3x3 blocks: block row p (free particle p) holds one block per distinct
// free neighbour q (a spring between p and q) plus its own diagonal block, in increasing q.
// If block row p holds `blocks` blocks, each of its three scalar rows holds 3 * blocks entries,
// so the entry (i, j) of the k-th block of the row is at base_p + i * 3 * blocks + 3 * k + j,
// where base_p is the row's first value.
//
// The fill works block row by block row, so that the values are written in storage order (a
// stream, which is what the memory system does fastest; the values are the bulk of the data
// for large models). For each free particle it visits its incident springs, precomputed with
// the block each one lands in: d f_p / d x_q = +K of the spring for the neighbour q (for p = a
// that is K; for p = b it is d f_b / d x_a = K too), and -K summed on the diagonal. The blocks
// K and D of a spring do not change when its ends are swapped, so both rows read the same
// record: each spring is evaluated once, in spring order, into factored records (forces.c,
// sm_model_forces_and_jacobians), and the rows are assembled from them. That takes about 60 %
// of the time of evaluating each spring from both of its ends in the row loop, as an earlier
// version did (bench/README.md).
#include "law_body_forces.h"
#include "model_internal.h"

#include <stdlib.h>
#include <string.h>

struct sm_sparse_jacobian {
	int64_t dimension;
	int64_t nonzeros;
	int64_t* row_pointers;    // dimension + 1
	int64_t* column_indices;  // nonzeros

	// Topology the pattern was built from, checked on every fill.
	int32_t particle_count;
	int32_t spring_count;
	int32_t* free_index;  // per particle
	int32_t* spring_a;
	int32_t* spring_b;

	// Per free particle p: its particle index, its first block (values start at 9 * block_start),
	// its block count, and the position of its diagonal block in the row.
	int32_t* row_particle;
	int64_t* block_start;  // F + 1
	int32_t* diagonal_block;
	// Incident springs of each free particle (CSR over free particles): spring index and the
	// block of the other end in this row, or -1 if the other end is constrained.
	int64_t* incident_start;  // F + 1
	int32_t* incident_spring;
	int32_t* incident_block;
};

void sm_sparse_jacobian_destroy(sm_sparse_jacobian* jacobian)
{
	if (jacobian == NULL)
		return;
	free(jacobian->row_pointers);
	free(jacobian->column_indices);
	free(jacobian->free_index);
	free(jacobian->spring_a);
	free(jacobian->spring_b);
	free(jacobian->row_particle);
	free(jacobian->block_start);
	free(jacobian->diagonal_block);
	free(jacobian->incident_start);
	free(jacobian->incident_spring);
	free(jacobian->incident_block);
	free(jacobian);
}

static int compare_int32(const void* p, const void* q)
{
	const int32_t a = *(const int32_t*)p, b = *(const int32_t*)q;
	return (a > b) - (a < b);
}

// Position of `column` in the sorted list of `count` entries (-1 if absent).
static int32_t find_block(const int32_t* list, int32_t count, int32_t column)
{
	int32_t lo = 0, hi = count - 1;
	while (lo <= hi) {
		const int32_t mid = lo + (hi - lo) / 2;
		if (list[mid] < column)
			lo = mid + 1;
		else if (list[mid] > column)
			hi = mid - 1;
		else
			return mid;
	}
	return -1;
}

sm_sparse_jacobian* sm_sparse_jacobian_create(const sm_model* model)
{
	if (model == NULL)
		return NULL;
	const int32_t n = model->particle_count, S = model->spring_count, F = model->free_count;
	const int32_t* fi = model->free_index;
	sm_sparse_jacobian* J = calloc(1, sizeof *J);
	int32_t* count = calloc((size_t)F + 1, sizeof(int32_t));  // neighbours per free particle
	int64_t* start = calloc((size_t)F + 1, sizeof(int64_t));  // neighbour list start
	int32_t* neighbours = malloc(((size_t)2 * S + (size_t)F + 1) * sizeof(int32_t));
	int ok = J != NULL && count != NULL && start != NULL && neighbours != NULL;
	if (ok) {
		J->particle_count = n;
		J->spring_count = S;
		J->dimension = 3 * (int64_t)F;
		J->free_index = malloc(((size_t)n + 1) * sizeof(int32_t));
		J->spring_a = malloc(((size_t)S + 1) * sizeof(int32_t));
		J->spring_b = malloc(((size_t)S + 1) * sizeof(int32_t));
		J->row_particle = malloc(((size_t)F + 1) * sizeof(int32_t));
		J->block_start = calloc((size_t)F + 1, sizeof(int64_t));
		J->diagonal_block = malloc(((size_t)F + 1) * sizeof(int32_t));
		J->incident_start = calloc((size_t)F + 1, sizeof(int64_t));
		J->incident_spring = malloc(((size_t)2 * S + 1) * sizeof(int32_t));
		J->incident_block = malloc(((size_t)2 * S + 1) * sizeof(int32_t));
		J->row_pointers = malloc(((size_t)J->dimension + 1) * sizeof(int64_t));
		ok = J->free_index && J->spring_a && J->spring_b && J->row_particle && J->block_start &&
		     J->diagonal_block && J->incident_start && J->incident_spring && J->incident_block &&
		     J->row_pointers;
	}
	if (ok) {
		if (n > 0)
			memcpy(J->free_index, fi, (size_t)n * sizeof(int32_t));
		if (S > 0) {
			memcpy(J->spring_a, model->spring_a, (size_t)S * sizeof(int32_t));
			memcpy(J->spring_b, model->spring_b, (size_t)S * sizeof(int32_t));
		}
		for (int32_t i = 0; i < n; i++)
			if (fi[i] >= 0)
				J->row_particle[fi[i]] = i;
		// Neighbour lists (self included) and incident springs, by counting sort on the row.
		int64_t* incident_count = J->incident_start;  // counts first, turned into starts below
		for (int32_t p = 0; p < F; p++)
			count[p] = 1;
		for (int32_t s = 0; s < S; s++) {
			const int32_t fa = fi[model->spring_a[s]], fb = fi[model->spring_b[s]];
			if (fa >= 0 && fb >= 0) {
				count[fa]++;
				count[fb]++;
			}
			if (fa >= 0)
				incident_count[fa + 1]++;
			if (fb >= 0)
				incident_count[fb + 1]++;
		}
		for (int32_t p = 0; p < F; p++) {
			start[p + 1] = start[p] + count[p];
			J->incident_start[p + 1] += J->incident_start[p];
		}
		for (int32_t p = 0; p < F; p++) {
			neighbours[start[p]] = p;
			count[p] = 1;
		}
		for (int32_t s = 0; s < S; s++) {
			const int32_t fa = fi[model->spring_a[s]], fb = fi[model->spring_b[s]];
			if (fa >= 0 && fb >= 0) {
				neighbours[start[fa] + count[fa]++] = fb;
				neighbours[start[fb] + count[fb]++] = fa;
			}
		}
		// Sort and remove duplicates (two springs between the same pair share their blocks).
		for (int32_t p = 0; p < F; p++) {
			int32_t* list = neighbours + start[p];
			qsort(list, (size_t)count[p], sizeof(int32_t), compare_int32);
			int32_t unique = 0;
			for (int32_t k = 0; k < count[p]; k++)
				if (unique == 0 || list[k] != list[unique - 1])
					list[unique++] = list[k];
			count[p] = unique;
			J->block_start[p + 1] = J->block_start[p] + unique;
			J->diagonal_block[p] = find_block(list, unique, p);
		}
		// Incident springs in spring order within each row, with their blocks.
		int64_t* fill = malloc(((size_t)F + 1) * sizeof(int64_t));
		ok = fill != NULL;
		if (ok) {
			memcpy(fill, J->incident_start, ((size_t)F + 1) * sizeof(int64_t));
			for (int32_t s = 0; s < S; s++) {
				const int32_t fa = fi[model->spring_a[s]], fb = fi[model->spring_b[s]];
				if (fa >= 0) {
					J->incident_spring[fill[fa]] = s;
					J->incident_block[fill[fa]++] =
					    fb >= 0 ? find_block(neighbours + start[fa], count[fa], fb) : -1;
				}
				if (fb >= 0) {
					J->incident_spring[fill[fb]] = s;
					J->incident_block[fill[fb]++] =
					    fa >= 0 ? find_block(neighbours + start[fb], count[fb], fa) : -1;
				}
			}
			free(fill);
		}
		J->nonzeros = 9 * J->block_start[F];
		J->column_indices = malloc(((size_t)J->nonzeros + 1) * sizeof(int64_t));
		ok = ok && J->column_indices != NULL;
	}
	if (ok) {
		for (int32_t p = 0; p < F; p++) {
			const int32_t* list = neighbours + start[p];
			const int64_t blocks = count[p], base = 9 * J->block_start[p];
			for (int i = 0; i < 3; i++) {
				const int64_t row = 3 * (int64_t)p + i, first = base + i * 3 * blocks;
				J->row_pointers[row] = first;
				for (int64_t k = 0; k < blocks; k++)
					for (int j = 0; j < 3; j++)
						J->column_indices[first + 3 * k + j] = 3 * (int64_t)list[k] + j;
			}
		}
		J->row_pointers[J->dimension] = J->nonzeros;
	}
	free(count);
	free(start);
	free(neighbours);
	if (!ok) {
		sm_sparse_jacobian_destroy(J);
		return NULL;
	}
	return J;
}

int64_t sm_sparse_jacobian_dimension(const sm_sparse_jacobian* jacobian)
{
	return jacobian != NULL ? jacobian->dimension : 0;
}

int64_t sm_sparse_jacobian_nonzeros(const sm_sparse_jacobian* jacobian)
{
	return jacobian != NULL ? jacobian->nonzeros : 0;
}

const int64_t* sm_sparse_jacobian_row_pointers(const sm_sparse_jacobian* jacobian)
{
	return jacobian != NULL ? jacobian->row_pointers : NULL;
}

const int64_t* sm_sparse_jacobian_column_indices(const sm_sparse_jacobian* jacobian)
{
	return jacobian != NULL ? jacobian->column_indices : NULL;
}

static int same_topology(const sm_sparse_jacobian* J, const sm_model* model)
{
	if (J->particle_count != model->particle_count || J->spring_count != model->spring_count ||
	    3 * (int64_t)model->free_count != J->dimension)
		return 0;
	const size_t n = (size_t)J->particle_count, S = (size_t)J->spring_count;
	return (n == 0 || memcmp(J->free_index, model->free_index, n * sizeof(int32_t)) == 0) &&
	       (S == 0 || (memcmp(J->spring_a, model->spring_a, S * sizeof(int32_t)) == 0 &&
	                   memcmp(J->spring_b, model->spring_b, S * sizeof(int32_t)) == 0));
}

// Adds sign * B to the block at `block` (row stride `stride`).
static inline void block_add(double* restrict block, int64_t stride, double sign, const double B[9])
{
	for (int i = 0; i < 3; i++, block += stride) {
		block[0] += sign * B[3 * i];
		block[1] += sign * B[3 * i + 1];
		block[2] += sign * B[3 * i + 2];
	}
}

// The fill from the factored records (model_internal.h; derivation in forces.c), block row by
// block row as the file's header describes, with K = u z^T + beta I and D = kd u u^T rebuilt
// from each incident spring's record. Both ends of a spring read the same record (K and D do
// not depend on the order of the ends).
static inline void fill_from_records(const sm_sparse_jacobian* J, const sm_model* model,
                                     const double* restrict records, double* restrict dfdx,
                                     double* restrict dfdv, const int want_x, const int want_v)
{
	const int32_t F = model->free_count;
	for (int32_t p = 0; p < F; p++) {
		const int64_t base = 9 * J->block_start[p];
		const int64_t blocks = J->block_start[p + 1] - J->block_start[p], stride = 3 * blocks;
		double* restrict row_x = want_x ? dfdx + base : NULL;
		double* restrict row_v = want_v ? dfdv + base : NULL;
		if (want_x)
			memset(row_x, 0, 9 * (size_t)blocks * sizeof(double));
		if (want_v)
			memset(row_v, 0, 9 * (size_t)blocks * sizeof(double));
		double diag_x[9] = {0}, diag_v[9] = {0};
		if (want_v) {
			const int32_t i = J->row_particle[p];
			const double c = mass_damping_derivative(model->mass[i], model->def.mass_damping);
			diag_v[0] = diag_v[4] = diag_v[8] = c;
		}
		for (int64_t e = J->incident_start[p]; e < J->incident_start[p + 1]; e++) {
			const int32_t other = J->incident_block[e];
			const double* restrict q = records + SPRING_JACOBIAN_STRIDE * (size_t)J->incident_spring[e];
			if (want_x) {
				double K[9];
				for (int i = 0; i < 3; i++)
					for (int j = 0; j < 3; j++)
						K[3 * i + j] = q[i] * q[3 + j];
				K[0] += q[6];
				K[4] += q[6];
				K[8] += q[6];
				for (int k = 0; k < 9; k++)
					diag_x[k] -= K[k];
				if (other >= 0)
					block_add(row_x + 3 * (int64_t)other, stride, 1.0, K);
			}
			if (want_v) {
				double D[9];
				for (int i = 0; i < 3; i++)
					for (int j = 0; j < 3; j++) {
						D[3 * i + j] = q[7] * q[i] * q[j];
						diag_v[3 * i + j] -= D[3 * i + j];
					}
				if (other >= 0)
					block_add(row_v + 3 * (int64_t)other, stride, 1.0, D);
			}
		}
		const int64_t diagonal = 3 * (int64_t)J->diagonal_block[p];
		if (want_x)
			block_add(row_x + diagonal, stride, 1.0, diag_x);
		if (want_v)
			block_add(row_v + diagonal, stride, 1.0, diag_v);
	}
}

sm_status sm_sparse_jacobian_fill_from_springs(const sm_sparse_jacobian* jacobian, const sm_model* model,
                                               const sm_spring_jacobians* jacobians, double* dfdx,
                                               double* dfdv)
{
	if (jacobian == NULL || model == NULL || jacobians == NULL || !jacobians->evaluated)
		return SM_ERROR_INVALID_ARGUMENT;
	if (!same_topology(jacobian, model) || jacobians->particle_count != model->particle_count ||
	    jacobians->spring_count != model->spring_count)
		return SM_ERROR_TOPOLOGY;
	if (dfdx != NULL && dfdv != NULL)
		fill_from_records(jacobian, model, jacobians->data, dfdx, dfdv, 1, 1);
	else if (dfdx != NULL)
		fill_from_records(jacobian, model, jacobians->data, dfdx, NULL, 1, 0);
	else if (dfdv != NULL)
		fill_from_records(jacobian, model, jacobians->data, NULL, dfdv, 0, 1);
	return SM_OK;
}

sm_status sm_sparse_jacobian_fill(const sm_sparse_jacobian* jacobian, const sm_model* model, const double* x,
                                  const double* v, sm_jacobian_variant variant, double* dfdx, double* dfdv)
{
	if (jacobian == NULL || model == NULL || x == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (variant != SM_JACOBIAN_EXACT && variant != SM_JACOBIAN_DEFINITE)
		return SM_ERROR_INVALID_ARGUMENT;
	if (!same_topology(jacobian, model))
		return SM_ERROR_TOPOLOGY;  // springs or free particles changed since the pattern was built
	// Every spring evaluated once, in spring order, into scratch records (the fused force pass,
	// whose forces are not needed here), then the block rows filled from the records. The
	// scratch is the caller's own for the call, so concurrent fills stay independent.
	sm_spring_jacobians* records = sm_spring_jacobians_create(model);
	double* forces = malloc((3 * (size_t)model->particle_count + 1) * sizeof(double));
	sm_status status = SM_ERROR_OUT_OF_MEMORY;
	if (records != NULL && forces != NULL) {
		status = sm_model_forces_and_jacobians(model, x, v, NULL, variant, forces, records);
		if (status == SM_OK)
			status = sm_sparse_jacobian_fill_from_springs(jacobian, model, records, dfdx, dfdv);
	}
	free(forces);
	sm_spring_jacobians_destroy(records);
	return status;
}
