// Multilevel approximate inverse of a symmetric positive definite matrix in 3x3 blocks (the
// coarse matrix of the reduced solver's two-level preconditioner), internal.
//
// Block layout shared with reduced_aggregates.c and reduced_preconditioner.c: block row I has
// the neighbours neighbour[first[I] .. first[I + 1]) (sorted, I itself included), deg(I) of them,
// and its entry (3 I + i, 3 J_k + j), J_k its k-th neighbour, is values[9 first[I] + 3 deg(I) i + 3 k + j]:
// the 3 rows of a block row one after the other, each holding its deg(I) blocks' rows.
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <suitesparse/cholmod.h>

#include "workers.h"

typedef struct sm_multilevel sm_multilevel;

// Index of entry (3 I + i, 3 J_k + j) in the block layout.
static inline int64_t sm_block_entry(const int64_t* first, int32_t I, int32_t k, int i, int j)
{
	const int64_t degree = first[I + 1] - first[I];
	return 9 * first[I] + 3 * degree * i + 3 * k + j;
}

// Fills a CHOLMOD matrix's column pointers p (3 count + 1) and row indices (9 first[count]) for
// the block layout: its rows are the columns of the symmetric matrix CHOLMOD reads.
void sm_block_pattern_fill(int32_t count, const int64_t* first, const int32_t* neighbour, int64_t* p,
                           int64_t* index);

// Inverts the 3x3 block a (row-major) into inv; false if it is singular.
bool sm_invert3(const double* a, double* inv);

// Builds the levels below the matrix of `count` block rows (pattern first, neighbour; copied)
// by aggregation, down to at most coarsest_dofs unknowns, where CHOLMOD factorises. NULL on out
// of memory.
sm_multilevel* sm_multilevel_create(int32_t count, const int64_t* first, const int32_t* neighbour,
                                    int32_t coarsest_dofs, cholmod_common* common);

// Sums the coarse levels from values (the top matrix in the block layout, read again by every
// solve until the next refresh), inverts the smoother's blocks and factorises the coarsest level.
// False if a block is singular or the coarsest matrix is not positive definite.
bool sm_multilevel_refresh(sm_multilevel* ml, const double* values, cholmod_common* common);

// x ~ A^-1 b: one V-cycle from x = 0 (symmetric positive definite as a function of b), or with
// iterations > 1 that many conjugate-gradient iterations preconditioned by it (then x depends
// on b non-linearly: the outer solver must be flexible). The products of levels of
// MULTILEVEL_PARALLEL_ROWS block rows or more run on the team `workers` (NULL: on the caller's
// thread), row by row, so the result does not depend on it. Returns x (3 count entries, owned by
// ml, stale at the next call), NULL on failure.
const double* sm_multilevel_solve(sm_multilevel* ml, const double* b, int iterations, sm_workers* workers,
                                  cholmod_common* common);

// Accepts NULL.
void sm_multilevel_destroy(sm_multilevel* ml, cholmod_common* common);
