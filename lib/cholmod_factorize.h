// CHOLMOD's symbolic analysis, ordered by AMD alone, its numeric factorisation, run on the
// calling thread alone, and its solves with a workspace kept between calls (cholmod_factorize.c).
#pragma once

#include <cholmod.h>

/// cholmod_l_factorize(A, L, common) with CHOLMOD's OpenMP loops kept to the calling thread; the
/// same return value, status and factor.
int sm_cholmod_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common);

/// cholmod_l_analyze(A, common) with the fill-reducing ordering AMD's alone (cholmod_factorize.c);
/// common's ordering settings are as they were after the call.
cholmod_factor* sm_cholmod_analyze(cholmod_sparse* A, cholmod_common* common);

/// cholmod_l_solve2(CHOLMOD_A, L, b, NULL, x, NULL, y, e, common): x = A^-1 b by the factor L,
/// into *x, with the workspaces *y and *e, all three kept by the caller from one call to the next
/// (NULL at the first: allocated then, freed by the caller with cholmod_l_free_dense). Once they
/// are allocated, a solve with a factor of the same kind allocates nothing. The same return value
/// and solution as cholmod_l_solve2.
int sm_cholmod_solve(cholmod_factor* L, cholmod_dense* b, cholmod_dense** x, cholmod_dense** y,
                     cholmod_dense** e, cholmod_common* common);
