// The two-level preconditioner's coarse space (reduced_preconditioner.c applies it): the free
// particles grouped into aggregates, the coarse matrix's block pattern, where each spring's share
// lands in it, and, for a model in chunks, the coarse unknowns in two halves.
//
// Aggregation. Each aggregate is a particle and its spring neighbours, formed greedily in
// particle order; the prolongation P moves an aggregate as one rigid translation, so the coarse
// space holds the long, smooth waves that block Jacobi cannot damp. For the multilevel path the aggregates
// follow the strong springs only (stiffness at least STRONG_FRACTION of the stiffest at either end):
// neighbours across soft springs (bending) are then not drawn in, which makes the aggregates smaller (9
// particles instead of 15 on the cloth) and the coarse space larger. The coarse pattern follows all springs.
#define _POSIX_C_SOURCE 200809L

#include "linear_solver_reduced.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

// The share of the stiffest spring at either end from which a spring counts as strong when the
// aggregates follow the strong springs only (the multilevel path; measurements with
// MULTILEVEL_MIN_PARTICLES, linear_solver_reduced.c).
#define STRONG_FRACTION 0.25

// Coarse unknowns from which CHOLMOD's supernodal factorisation is used for the coarse matrix
// (simplicial below). The coarse matrix of a model in chunks is factorised supernodally at any
// size: its solves in two halves (coarse_halves.c) work on the supernodes (858 unknowns on the
// 64 x 64 benchmark cloth).
#define COARSE_SUPERNODAL_MIN_DOFS 1000

// Groups the free particles into aggregates (each a particle and its spring neighbours not yet
// taken, over the strong springs only if strong_only; particles left over join a neighbouring
// aggregate) and builds the coarse pattern (over all springs). Returns false on out of memory.
bool sm_reduced_build_two_level(sm_reduced* r, bool strong_only)
{
	sm_simulation* sim = r->sim;
	const sm_model* m = sim->model;
	const int32_t nf = sim->free_count;
	bool ok = false;
	// Neighbours of every free particle among the free particles (CSR, duplicates allowed).
	int64_t* first = calloc((size_t)nf + 1, sizeof(int64_t));
	int32_t* neighbour = malloc(2 * (size_t)m->spring_count * sizeof(int32_t) + sizeof(int32_t));
	int64_t* fill = malloc(((size_t)nf + 1) * sizeof(int64_t));
	int32_t* mark = malloc(((size_t)nf + 1) * sizeof(int32_t));
	int32_t* group = malloc(((size_t)nf + 1) * sizeof(int32_t));            // aggregate per free particle
	bool* strong = malloc(2 * (size_t)m->spring_count * sizeof(bool) + 1);  // per neighbour entry
	double* strongest = calloc((size_t)nf + 1, sizeof(double));
	r->aggregate = malloc(((size_t)m->particle_count + 1) * sizeof(int32_t));
	r->spring_coarse = malloc(4 * (size_t)m->spring_count * sizeof(int64_t) + sizeof(int64_t));
	if (!first || !neighbour || !fill || !mark || !group || !r->aggregate || !r->spring_coarse || !strong ||
	    !strongest)
		goto done;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			strongest[a] = fmax(strongest[a], m->stiffness[s]);
			strongest[b] = fmax(strongest[b], m->stiffness[s]);
		}
	}
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			first[a + 1]++;
			first[b + 1]++;
		}
	}
	for (int32_t q = 0; q < nf; q++)
		first[q + 1] += first[q];
	memcpy(fill, first, ((size_t)nf + 1) * sizeof(int64_t));
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t a = m->free_index[m->spring_a[s]], b = m->free_index[m->spring_b[s]];
		if (a >= 0 && b >= 0) {
			const double stiffest = fmax(strongest[a], strongest[b]);
			strong[fill[a]] = strong[fill[b]] = !strong_only || m->stiffness[s] >= STRONG_FRACTION * stiffest;
			neighbour[fill[a]++] = b;
			neighbour[fill[b]++] = a;
		}
	}
	// Pass 1: a particle whose neighbours are all free of aggregates starts one with them.
	int32_t count = 0;
	for (int32_t q = 0; q < nf; q++)
		group[q] = -1;
	for (int32_t q = 0; q < nf; q++) {
		if (group[q] >= 0)
			continue;
		bool all_free = true;
		for (int64_t e = first[q]; e < first[q + 1] && all_free; e++)
			all_free = !strong[e] || group[neighbour[e]] < 0;
		if (!all_free)
			continue;
		group[q] = count;
		for (int64_t e = first[q]; e < first[q + 1]; e++)
			if (strong[e])
				group[neighbour[e]] = count;
		count++;
	}
	// Pass 2: the others join a neighbour's aggregate (from pass 1: mark holds pass 1's groups, so
	// that a particle never joins an aggregate another particle of pass 2 started), or start their
	// own.
	for (int32_t q = 0; q < nf; q++)
		mark[q] = group[q];
	for (int32_t q = 0; q < nf; q++) {
		if (group[q] >= 0)
			continue;
		for (int64_t e = first[q]; e < first[q + 1] && group[q] < 0; e++)
			if (strong[e] && mark[neighbour[e]] >= 0)
				group[q] = mark[neighbour[e]];
		if (group[q] < 0)
			group[q] = count++;
	}
	r->aggregate_count = count;
	// Coarse pattern: the aggregates linked by springs, each list sorted, itself included.
	r->coarse_first = calloc((size_t)count + 1, sizeof(int64_t));
	r->coarse_self = malloc(((size_t)count + 1) * sizeof(int32_t));
	r->coarse_mass = calloc((size_t)count + 1, sizeof(double));
	if (!r->coarse_first || !r->coarse_self || !r->coarse_mass)
		goto done;
	// Members of each aggregate (fill reused as each aggregate's next position in member).
	int64_t* member_first = calloc((size_t)count + 1, sizeof(int64_t));
	int32_t* member = malloc(((size_t)nf + 1) * sizeof(int32_t));
	int32_t* seen = malloc(((size_t)count + 1) * sizeof(int32_t));
	int32_t* list = malloc(((size_t)count + 1) * sizeof(int32_t));
	if (!member_first || !member || !seen || !list) {
		free(member_first), free(member), free(seen), free(list);
		goto done;
	}
	for (int32_t q = 0; q < nf; q++)
		member_first[group[q] + 1]++;
	for (int32_t I = 0; I < count; I++)
		member_first[I + 1] += member_first[I];
	for (int32_t I = 0; I <= count; I++)
		fill[I] = member_first[I];
	for (int32_t q = 0; q < nf; q++)
		member[fill[group[q]]++] = q;
	for (int32_t I = 0; I < count; I++)
		seen[I] = -1;
	// Two passes over the aggregates: count the neighbour lists, then fill them.
	int32_t* lists = NULL;
	for (int pass = 0; pass < 2; pass++) {
		int64_t total = 0;
		for (int32_t I = 0; I < count; I++) {
			int32_t degree = 0;
			list[degree++] = I;
			seen[I] = I;
			for (int64_t k = member_first[I]; k < member_first[I + 1]; k++) {
				const int32_t q = member[k];
				for (int64_t e = first[q]; e < first[q + 1]; e++) {
					const int32_t J = group[neighbour[e]];
					if (seen[J] != I) {
						seen[J] = I;
						list[degree++] = J;
					}
				}
			}
			// Insertion sort: the lists are short.
			for (int32_t i = 1; i < degree; i++)
				for (int32_t j = i; j > 0 && list[j - 1] > list[j]; j--) {
					const int32_t t = list[j];
					list[j] = list[j - 1];
					list[j - 1] = t;
				}
			if (pass == 0) {
				r->coarse_first[I + 1] = degree;
			} else {
				for (int32_t i = 0; i < degree; i++) {
					lists[total + i] = list[i];
					if (list[i] == I)
						r->coarse_self[I] = i;
				}
			}
			total += degree;
		}
		for (int32_t I = 0; I < count; I++)
			seen[I] = -1;
		if (pass == 0) {
			for (int32_t I = 0; I < count; I++)
				r->coarse_first[I + 1] += r->coarse_first[I];
			lists = malloc(((size_t)total + 1) * sizeof(int32_t));
			if (!lists)
				break;
		}
	}
	free(member_first), free(member), free(seen), free(list);
	r->coarse_neighbour = lists;
	if (!lists)
		goto done;
	// Per particle: its aggregate (-1 if constrained). Per spring between aggregates I != J:
	// the first entries of its blocks (I, I), (J, J) (-1 for a constrained end), (I, J), (J, I)
	// (-1 unless both ends are free).
	for (int32_t i = 0; i < m->particle_count; i++)
		r->aggregate[i] = m->free_index[i] >= 0 ? group[m->free_index[i]] : -1;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t I = r->aggregate[m->spring_a[s]], J = r->aggregate[m->spring_b[s]];
		int64_t* entry = r->spring_coarse + 4 * (size_t)s;
		entry[0] = entry[1] = entry[2] = entry[3] = -1;
		if (I == J)
			continue;  // inside an aggregate (or between two constrained particles)
		if (I >= 0)
			entry[0] = sm_reduced_coarse_entry(r, I, r->coarse_self[I], 0, 0);
		if (J >= 0)
			entry[1] = sm_reduced_coarse_entry(r, J, r->coarse_self[J], 0, 0);
		if (I < 0 || J < 0)
			continue;
		for (int64_t k = r->coarse_first[I]; k < r->coarse_first[I + 1]; k++)
			if (lists[k] == J)
				entry[2] = sm_reduced_coarse_entry(r, I, (int32_t)(k - r->coarse_first[I]), 0, 0);
		for (int64_t k = r->coarse_first[J]; k < r->coarse_first[J + 1]; k++)
			if (lists[k] == I)
				entry[3] = sm_reduced_coarse_entry(r, J, (int32_t)(k - r->coarse_first[J]), 0, 0);
	}
	// The coarse matrix: 3 rows per aggregate, 3 deg(I) entries each, symmetric storage.
	const size_t nc = 3 * (size_t)count;
	if (nc < COARSE_SUPERNODAL_MIN_DOFS)
		r->common.supernodal = CHOLMOD_SIMPLICIAL;
	const size_t nonzeros = 9 * (size_t)r->coarse_first[count];
	r->coarse = cholmod_l_allocate_sparse(nc, nc, nonzeros, 1, 1, 1, CHOLMOD_REAL, &r->common);
	r->coarse_b = cholmod_l_allocate_dense(nc, 1, nc, CHOLMOD_REAL, &r->common);
	if (!r->coarse || !r->coarse_b)
		goto done;
	sm_block_pattern_fill(count, r->coarse_first, lists, r->coarse->p, r->coarse->i);
	ok = true;
done:
	free(first);
	free(neighbour);
	free(fill);
	free(mark);
	free(group);
	free(strong);
	free(strongest);
	return ok;
}

// For the exact coarse solve of a chunked model: the aggregates in two halves, those whose first
// member lies in the first two chunks and the others, and a separator, the aggregates of the
// second half that neighbour the first (so that no coarse entry joins the two halves left). The
// coarse factor's triangular solves then run in two at once (coarse_halves.h). Returns false on
// out of memory.
bool sm_reduced_split_coarse(sm_reduced* r)
{
	const int32_t count = r->aggregate_count;
	r->coarse_part = malloc(3 * ((size_t)count + 1) * sizeof(int8_t));
	r->coarse_solution = malloc(3 * ((size_t)count + 1) * sizeof(double));
	if (r->coarse_part == NULL || r->coarse_solution == NULL)
		return false;
	for (int32_t I = 0; I < count; I++)
		r->coarse_part[3 * (size_t)I] = r->member[r->member_first[I]] < r->chunk_particle[2] ? 0 : 1;
	for (int32_t I = 0; I < count; I++) {
		if (r->coarse_part[3 * (size_t)I] != 1)
			continue;
		for (int64_t k = r->coarse_first[I]; k < r->coarse_first[I + 1]; k++)
			if (r->coarse_part[3 * (size_t)r->coarse_neighbour[k]] == 0) {
				r->coarse_part[3 * (size_t)I] = 2;
				break;
			}
	}
	for (int32_t I = 0; I < count; I++)
		r->coarse_part[3 * (size_t)I + 1] = r->coarse_part[3 * (size_t)I + 2] = r->coarse_part[3 * (size_t)I];
	return true;
}
