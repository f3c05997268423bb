// CHOLMOD's symbolic analysis, ordered by AMD alone, and its numeric factorisation, run on the
// calling thread alone (cholmod_factorize.c).
#pragma once

#include <cholmod.h>

/// cholmod_l_factorize(A, L, common) with CHOLMOD's OpenMP loops kept to the calling thread; the
/// same return value, status and factor.
int sm_cholmod_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common);

/// cholmod_l_analyze(A, common) with the fill-reducing ordering AMD's alone (cholmod_factorize.c);
/// common's ordering settings are as they were after the call.
cholmod_factor* sm_cholmod_analyze(cholmod_sparse* A, cholmod_common* common);
