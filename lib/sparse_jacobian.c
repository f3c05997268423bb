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

#include <math.h>
#include <stdlib.h>
#include <string.h>

// Where one spring's four blocks go.
typedef struct spring_slots {
	int64_t block[4];  // value offsets of blocks (a,a), (a,b), (b,a), (b,b); -1 if absent
	int32_t stride_a;  // row stride of a's block row (0 if a is constrained)
	int32_t stride_b;  // likewise for b
	int32_t assign;    // 1: first spring of its pair, assigns the off-diagonal blocks; 0: adds
	int32_t unused;
} spring_slots;

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
	spring_slots* slots;       // per spring
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
	free(jacobian->slots);
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
		J->slots = malloc(((size_t)S + 1) * sizeof(spring_slots));
		J->row_pointers = malloc(((size_t)J->dimension + 1) * sizeof(int64_t));
		ok = J->free_index && J->spring_a && J->spring_b && J->row_stride && J->diagonal_offset &&
		     J->slots && J->row_pointers;
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
		// The first spring of each free pair assigns its off-diagonal blocks, later ones add:
		// every stored value is then written without clearing the arrays first.
		uint8_t* claimed = calloc((size_t)block_start[F] + 1, 1);
		ok = claimed != NULL;
		for (int32_t s = 0; ok && s < S; s++) {
			const int32_t fa = model->free_index[model->spring_a[s]], fb = model->free_index[model->spring_b[s]];
			spring_slots* slot = J->slots + s;
			int64_t* o = slot->block;
			o[0] = o[1] = o[2] = o[3] = -1;
			slot->stride_a = fa >= 0 ? (int32_t)J->row_stride[fa] : 0;
			slot->stride_b = fb >= 0 ? (int32_t)J->row_stride[fb] : 0;
			slot->assign = 0;
			slot->unused = 0;
			if (fa >= 0)
				o[0] = J->diagonal_offset[fa];
			if (fb >= 0)
				o[3] = J->diagonal_offset[fb];
			if (fa >= 0 && fb >= 0) {
				const int64_t ka = find_block(neighbours + start[fa], count[fa], fb);
				const int64_t kb = find_block(neighbours + start[fb], count[fb], fa);
				o[1] = 9 * block_start[fa] + 3 * ka;
				o[2] = 9 * block_start[fb] + 3 * kb;
				// Claim both blocks: a later spring may join the pair in the other direction.
				slot->assign = !claimed[block_start[fa] + ka];
				claimed[block_start[fa] + ka] = 1;
				claimed[block_start[fb] + kb] = 1;
			}
		}
		free(claimed);
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

// Block writers: the three rows of a block are `stride` values apart.
static inline void block_set(double* restrict values, int64_t offset, int64_t stride, const double b[9])
{
	double* row = values + offset;
	for (int i = 0; i < 3; i++, row += stride) {
		row[0] = b[3 * i];
		row[1] = b[3 * i + 1];
		row[2] = b[3 * i + 2];
	}
}

static inline void block_add(double* restrict values, int64_t offset, int64_t stride, const double b[9])
{
	double* row = values + offset;
	for (int i = 0; i < 3; i++, row += stride) {
		row[0] += b[3 * i];
		row[1] += b[3 * i + 1];
		row[2] += b[3 * i + 2];
	}
}

static inline void block_subtract(double* restrict values, int64_t offset, int64_t stride, const double b[9])
{
	double* row = values + offset;
	for (int i = 0; i < 3; i++, row += stride) {
		row[0] -= b[3 * i];
		row[1] -= b[3 * i + 1];
		row[2] -= b[3 * i + 2];
	}
}

// Scatters one spring's block into the four places of one matrix: -B on the diagonal blocks,
// +B on the off-diagonal ones.
static inline void scatter_spring(double* restrict values, const spring_slots* slot, const double B[9])
{
	const int64_t* o = slot->block;
	if (o[0] >= 0)
		block_subtract(values, o[0], slot->stride_a, B);
	if (o[3] >= 0)
		block_subtract(values, o[3], slot->stride_b, B);
	if (o[1] >= 0) {
		if (slot->assign) {
			block_set(values, o[1], slot->stride_a, B);
			block_set(values, o[2], slot->stride_b, B);
		} else {
			block_add(values, o[1], slot->stride_a, B);
			block_add(values, o[2], slot->stride_b, B);
		}
	}
}

// The fill loop, specialised by the compiler for each combination of the constant flags.
//
// The blocks of law_rest_length.h and law_spring_damping.h are expanded here into
//   K = (ks g + c r) I + (ks (1 - g) - c r) u u^T + c u (P dv)^T,   D = kd u u^T,
// with g = 1 - l0/L (clamped at 0 for the definite variant) and c = kd / L (0 for the
// definite variant), using P = I - u u^T.
static inline void fill_loop(const sm_sparse_jacobian* J, const sm_model* model, const double* restrict x,
                             const double* restrict v, double* restrict dfdx, double* restrict dfdv,
                             const int want_x, const int want_v, const int clamp, const int damping_position)
{
	// Diagonal blocks first: zero for df/dx, mass damping for df/dv.
	for (int32_t i = 0; i < model->particle_count; i++) {
		const int32_t p = model->free_index[i];
		if (p < 0)
			continue;
		const int64_t o = J->diagonal_offset[p], stride = J->row_stride[p];
		const double c = mass_damping_derivative(model->mass[i], model->def.mass_damping);
		for (int r = 0; r < 3; r++)
			for (int k = 0; k < 3; k++) {
				if (want_x)
					dfdx[o + r * stride + k] = 0.0;
				if (want_v)
					dfdv[o + r * stride + k] = r == k ? c : 0.0;
			}
	}
	const int32_t* restrict first = J->spring_a;
	const int32_t* restrict second = J->spring_b;
	const double* restrict rest_length = model->rest_length;
	const double* restrict stiffness = model->stiffness;
	const double* restrict damping = model->damping;
	for (int32_t s = 0; s < J->spring_count; s++) {
		const spring_slots* slot = J->slots + s;
		if (slot->block[0] < 0 && slot->block[3] < 0)
			continue;  // both ends constrained: no free degree of freedom involved
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		const double d0 = x[b] - x[a], d1 = x[b + 1] - x[a + 1], d2 = x[b + 2] - x[a + 2];
		const double l0 = rest_length[s], ks = stiffness[s], kd = damping[s];
		const double length = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
		const int regular = length > 0.0 && length >= SM_DEGENERATE_LENGTH_RATIO * l0;
		const double inv = 1.0 / (regular ? length : 1.0);
		const double inv_length = regular ? inv : 0.0;
		const double u[3] = {d0 * inv_length, d1 * inv_length, d2 * inv_length};
		double uu[9];
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++)
				uu[3 * i + j] = u[i] * u[j];
		if (want_x) {
			double g = 1.0 - l0 * inv_length;
			if (clamp)
				g = g < 0.0 ? 0.0 : g;
			double K[9];
			double diagonal = ks * g, axial = ks - ks * g;
			if (damping_position) {
				const double dv[3] = {v[b] - v[a], v[b + 1] - v[a + 1], v[b + 2] - v[a + 2]};
				const double r = u[0] * dv[0] + u[1] * dv[1] + u[2] * dv[2];
				const double c = kd * inv_length;
				const double cp[3] = {c * (dv[0] - r * u[0]), c * (dv[1] - r * u[1]), c * (dv[2] - r * u[2])};
				diagonal += c * r;
				axial -= c * r;
				for (int i = 0; i < 3; i++)
					for (int j = 0; j < 3; j++)
						K[3 * i + j] = axial * uu[3 * i + j] + u[i] * cp[j];
			} else {
				for (int k = 0; k < 9; k++)
					K[k] = axial * uu[k];
			}
			K[0] += diagonal;
			K[4] += diagonal;
			K[8] += diagonal;
			scatter_spring(dfdx, slot, K);
		}
		if (want_v) {
			double D[9];
			for (int k = 0; k < 9; k++)
				D[k] = kd * uu[k];
			scatter_spring(dfdv, slot, D);
		}
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
	// Exact: no clamp, with the damping-position term (which needs v; without v it is zero).
	const int clamp = variant == SM_JACOBIAN_DEFINITE;
	const int damping_position = !clamp && v != NULL;
	if (dfdx != NULL && dfdv != NULL) {
		if (damping_position)
			fill_loop(jacobian, model, x, v, dfdx, dfdv, 1, 1, 0, 1);
		else
			fill_loop(jacobian, model, x, v, dfdx, dfdv, 1, 1, clamp, 0);
	} else if (dfdx != NULL) {
		if (damping_position)
			fill_loop(jacobian, model, x, v, dfdx, NULL, 1, 0, 0, 1);
		else
			fill_loop(jacobian, model, x, v, dfdx, NULL, 1, 0, clamp, 0);
	} else if (dfdv != NULL) {
		fill_loop(jacobian, model, x, v, NULL, dfdv, 0, 1, 0, 0);
	}
	return SM_OK;
}
