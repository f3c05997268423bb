// The sparse Jacobian over the free particles' degrees of freedom: pattern built once, values
// refilled in place.
//
// Layout: compressed sparse rows with 64-bit indices, columns sorted within each row, the
// diagonal blocks always present (SUNMatrix_Sparse CSR_MAT with 64-bit sunindextype). The
// pattern is made of 3x3 blocks: block row p (free particle p) holds one block per distinct
// free neighbour q (a spring between p and q) plus its own diagonal block, in increasing q.
// If block row p holds `blocks` blocks, each of its three scalar rows holds 3 * blocks entries,
// so the entry (i, j) of the block whose (0, 0) entry sits at value offset o is at
// o + i * 3 * blocks + j. For every spring the offsets of its four blocks (a,a), (a,b), (b,a),
// (b,b) are precomputed (-1 where an endpoint is constrained), which makes the fill a
// streaming loop over springs with no search.
#include "law_body_forces.h"
#include "law_rest_length.h"
#include "law_spring_damping.h"
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

	int64_t* row_stride;       // per free particle: 3 * blocks in its block row
	int64_t* diagonal_offset;  // per free particle: value offset of its diagonal block
	int64_t* spring_offset;    // 4 per spring: blocks (a,a), (a,b), (b,a), (b,b); -1 if absent
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
	free(jacobian->row_stride);
	free(jacobian->diagonal_offset);
	free(jacobian->spring_offset);
	free(jacobian);
}

static int compare_int32(const void* p, const void* q)
{
	const int32_t a = *(const int32_t*)p, b = *(const int32_t*)q;
	return (a > b) - (a < b);
}

// Position of `column` in the sorted list [begin, begin + count).
static int64_t find_block(const int32_t* list, int64_t count, int32_t column)
{
	int64_t lo = 0, hi = count - 1;
	while (lo <= hi) {
		const int64_t mid = lo + (hi - lo) / 2;
		if (list[mid] < column)
			lo = mid + 1;
		else if (list[mid] > column)
			hi = mid - 1;
		else
			return mid;
	}
	return -1;  // not reached for a consistent pattern
}

sm_sparse_jacobian* sm_sparse_jacobian_create(const sm_model* model)
{
	if (model == NULL)
		return NULL;
	const int32_t n = model->particle_count, S = model->spring_count, F = model->free_count;
	sm_sparse_jacobian* J = calloc(1, sizeof *J);
	int32_t* count = calloc((size_t)F + 1, sizeof(int32_t));        // neighbours per free particle
	int64_t* start = calloc((size_t)F + 1, sizeof(int64_t));        // list start per free particle
	int32_t* neighbours = malloc(((size_t)2 * S + (size_t)F + 1) * sizeof(int32_t));
	int64_t* block_start = calloc((size_t)F + 1, sizeof(int64_t));  // first block of each row
	int ok = J != NULL && count != NULL && start != NULL && neighbours != NULL && block_start != NULL;
	if (ok) {
		J->particle_count = n;
		J->spring_count = S;
		J->dimension = 3 * (int64_t)F;
		J->free_index = malloc(((size_t)n + 1) * sizeof(int32_t));
		J->spring_a = malloc(((size_t)S + 1) * sizeof(int32_t));
		J->spring_b = malloc(((size_t)S + 1) * sizeof(int32_t));
		J->row_stride = malloc(((size_t)F + 1) * sizeof(int64_t));
		J->diagonal_offset = malloc(((size_t)F + 1) * sizeof(int64_t));
		J->spring_offset = malloc((4 * (size_t)S + 1) * sizeof(int64_t));
		J->row_pointers = malloc(((size_t)J->dimension + 1) * sizeof(int64_t));
		ok = J->free_index && J->spring_a && J->spring_b && J->row_stride && J->diagonal_offset &&
		     J->spring_offset && J->row_pointers;
	}
	if (ok) {
		if (n > 0)
			memcpy(J->free_index, model->free_index, (size_t)n * sizeof(int32_t));
		if (S > 0) {
			memcpy(J->spring_a, model->spring_a, (size_t)S * sizeof(int32_t));
			memcpy(J->spring_b, model->spring_b, (size_t)S * sizeof(int32_t));
		}
		// Neighbour lists (self included), by counting sort on the row.
		for (int32_t p = 0; p < F; p++)
			count[p] = 1;
		for (int32_t s = 0; s < S; s++) {
			const int32_t fa = model->free_index[model->spring_a[s]], fb = model->free_index[model->spring_b[s]];
			if (fa >= 0 && fb >= 0) {
				count[fa]++;
				count[fb]++;
			}
		}
		for (int32_t p = 0; p < F; p++)
			start[p + 1] = start[p] + count[p];
		for (int32_t p = 0; p < F; p++) {
			neighbours[start[p]] = p;
			count[p] = 1;
		}
		for (int32_t s = 0; s < S; s++) {
			const int32_t fa = model->free_index[model->spring_a[s]], fb = model->free_index[model->spring_b[s]];
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
			block_start[p + 1] = block_start[p] + unique;
		}
		J->nonzeros = 9 * block_start[F];
		J->column_indices = malloc(((size_t)J->nonzeros + 1) * sizeof(int64_t));
		ok = J->column_indices != NULL;
	}
	if (ok) {
		for (int32_t p = 0; p < F; p++) {
			const int32_t* list = neighbours + start[p];
			const int64_t blocks = count[p], base = 9 * block_start[p];
			J->row_stride[p] = 3 * blocks;
			J->diagonal_offset[p] = base + 3 * find_block(list, blocks, p);
			for (int i = 0; i < 3; i++) {
				const int64_t row = 3 * (int64_t)p + i, first = base + i * 3 * blocks;
				J->row_pointers[row] = first;
				for (int64_t k = 0; k < blocks; k++)
					for (int j = 0; j < 3; j++)
						J->column_indices[first + 3 * k + j] = 3 * (int64_t)list[k] + j;
			}
		}
		J->row_pointers[J->dimension] = J->nonzeros;
		for (int32_t s = 0; s < S; s++) {
			const int32_t fa = model->free_index[model->spring_a[s]], fb = model->free_index[model->spring_b[s]];
			int64_t* o = J->spring_offset + 4 * (size_t)s;
			o[0] = o[1] = o[2] = o[3] = -1;
			if (fa >= 0) {
				o[0] = J->diagonal_offset[fa];
				if (fb >= 0)
					o[1] = 9 * block_start[fa] + 3 * find_block(neighbours + start[fa], count[fa], fb);
			}
			if (fb >= 0) {
				o[3] = J->diagonal_offset[fb];
				if (fa >= 0)
					o[2] = 9 * block_start[fb] + 3 * find_block(neighbours + start[fb], count[fb], fa);
			}
		}
	}
	free(count);
	free(start);
	free(neighbours);
	free(block_start);
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

// Adds sign * block into the values at block offset `offset` with row stride `stride`.
static inline void scatter(double* restrict values, int64_t offset, int64_t stride, double sign,
                           const double block[9])
{
	double* row = values + offset;
	for (int i = 0; i < 3; i++, row += stride) {
		row[0] += sign * block[3 * i];
		row[1] += sign * block[3 * i + 1];
		row[2] += sign * block[3 * i + 2];
	}
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

sm_status sm_sparse_jacobian_fill(const sm_sparse_jacobian* jacobian, const sm_model* model, const double* x,
                                  const double* v, sm_jacobian_variant variant, double* dfdx, double* dfdv)
{
	if (jacobian == NULL || model == NULL || x == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (variant != SM_JACOBIAN_EXACT && variant != SM_JACOBIAN_DEFINITE)
		return SM_ERROR_INVALID_ARGUMENT;
	if (!same_topology(jacobian, model))
		return SM_ERROR_TOPOLOGY;  // springs or free particles changed since the pattern was built
	const sm_sparse_jacobian* J = jacobian;
	const size_t nnz = (size_t)J->nonzeros;
	if (dfdx != NULL && nnz > 0)
		memset(dfdx, 0, nnz * sizeof(double));
	if (dfdv != NULL) {
		if (nnz > 0)
			memset(dfdv, 0, nnz * sizeof(double));
		for (int32_t i = 0; i < model->particle_count; i++) {
			const int32_t p = model->free_index[i];
			if (p < 0)
				continue;
			const double c = mass_damping_derivative(model->mass[i], model->def.mass_damping);
			const int64_t o = J->diagonal_offset[p], stride = J->row_stride[p];
			for (int k = 0; k < 3; k++)
				dfdv[o + k * stride + k] += c;
		}
	}
	for (int32_t s = 0; s < J->spring_count; s++) {
		const int64_t* o = J->spring_offset + 4 * (size_t)s;
		if (o[0] < 0 && o[3] < 0)
			continue;  // both ends constrained: no free degree of freedom involved
		spring_geometry g;
		spring_geometry_eval(x, v, model->spring_a[s], model->spring_b[s], model->rest_length[s], &g);
		double K[9] = {0}, D[9] = {0};
		rest_length_add_block(model->stiffness[s], model->rest_length[s], &g, variant, K);
		spring_damping_add_blocks(model->damping[s], &g, variant, K, D);
		const int32_t fa = model->free_index[model->spring_a[s]], fb = model->free_index[model->spring_b[s]];
		const int64_t sa = fa >= 0 ? J->row_stride[fa] : 0, sb = fb >= 0 ? J->row_stride[fb] : 0;
		if (dfdx != NULL) {
			if (o[0] >= 0)
				scatter(dfdx, o[0], sa, -1.0, K);
			if (o[1] >= 0)
				scatter(dfdx, o[1], sa, 1.0, K);
			if (o[2] >= 0)
				scatter(dfdx, o[2], sb, 1.0, K);
			if (o[3] >= 0)
				scatter(dfdx, o[3], sb, -1.0, K);
		}
		if (dfdv != NULL) {
			if (o[0] >= 0)
				scatter(dfdv, o[0], sa, -1.0, D);
			if (o[1] >= 0)
				scatter(dfdv, o[1], sa, 1.0, D);
			if (o[2] >= 0)
				scatter(dfdv, o[2], sb, 1.0, D);
			if (o[3] >= 0)
				scatter(dfdv, o[3], sb, -1.0, D);
		}
	}
	return SM_OK;
}
