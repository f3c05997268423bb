// The coarse matrix of the two-level preconditioner factorised so that its triangular solves
// split into two halves that run at once (reduced_preconditioner.c, chunked models).
//
// Derivation. Number the unknowns as two halves H0, H1 with no entry of the matrix between them,
// then a separator S (the unknowns that join them). Then no column of H0 has a row of H1 in its
// Cholesky factor L, nor the reverse, since fill only links neighbours of eliminated unknowns:
//     L = [[L00, 0, 0], [0, L11, 0], [L20, L21, L22]].
// The forward solve L y = b is y0 = L00^-1 b0 and y1 = L11^-1 b1, independent, then
// y2 = L22^-1 (b2 - L20 y0 - L21 y1); the backward solve L^T x = y is x2 = L22^-T y2, then
// x0 = L00^-T (y0 - L20^T x2) and x1 = L11^-T (y1 - L21^T x2), independent again. CHOLMOD's
// constrained ordering (CAMD) orders each half for little fill and the separator last; its
// supernodal factor is then solved here supernode by supernode, those of each half on their own
// thread, the updates a half makes to separator rows summed apart and added in a fixed order, so
// that the bits do not depend on the number of threads.
#ifndef SPRINGMASS_COARSE_HALVES_H
#define SPRINGMASS_COARSE_HALVES_H

#include "workers.h"

#include <stdbool.h>
#include <stdint.h>
#include <suitesparse/cholmod.h>

typedef struct sm_coarse_halves sm_coarse_halves;

// Analyses A (symmetric, upper triangle stored) with its unknowns in parts part[i] = 0 or 1 (the
// halves, with no entry of A between them) or 2 (the separator): the symbolic supernodal factor
// in *factor (numerical factorisation by cholmod_l_factorize, as usual) and what the solves need.
// NULL if out of memory or CHOLMOD fails (*factor then NULL).
sm_coarse_halves* sm_coarse_halves_create(cholmod_sparse* A, const int8_t* part, cholmod_factor** factor,
                                          cholmod_common* common);

// x = A^-1 b with the numerical factor L made from *factor, the halves' supernodes in two chunks
// of `workers` (NULL: in turn on the caller's thread, with the same bits).
void sm_coarse_halves_solve(sm_coarse_halves* halves, const cholmod_factor* L, const double* b, double* x,
                            sm_workers* workers);

void sm_coarse_halves_destroy(sm_coarse_halves* halves);

#endif
