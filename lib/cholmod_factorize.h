// CHOLMOD's numeric factorisation, run on the calling thread alone (cholmod_factorize.c).
#pragma once

#include <cholmod.h>

/// cholmod_l_factorize(A, L, common) with CHOLMOD's OpenMP loops kept to the calling thread; the
/// same return value, status and factor.
int sm_cholmod_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common);
