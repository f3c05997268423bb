// CHOLMOD's symbolic analysis with AMD's ordering alone, and its numeric factorisation on the
// calling thread alone.
//
// CHOLMOD 3 (SuiteSparse 5) assembles every update of its supernodal factorisation into the
// supernode in OpenMP parallel loops of 4 threads (an explicit num_threads(4), whatever
// OMP_NUM_THREADS says): thousands of parallel regions per factorisation, each a few microseconds
// of scattering (the dense work is BLAS's). On 2 cores the team of 4 spent more time waiting on
// its barriers than working (three alternating runs on a quiet machine): the sparse statics of
// the 40 x 40 benchmark cloth took 5.7 - 6.4 s with it, with 540 000 context switches, and 1.1 -
// 1.3 s on the calling thread alone (the same iterations; the loops only scatter, so the factor
// is the same either way); the 64 x 64 cloth's 52 s against 12 s; the ten lowest modes of the
// 129 x 129 trampoline 5.1 - 5.5 s against 3.2 - 3.6 s. The team also outlived the call, as
// threads waiting in the program's OpenMP runtime.
//
// OpenMP's max-active-levels setting belongs to the thread (a data-environment setting since
// OpenMP 5.0, and so in GCC's libgomp from GCC 11 on): 0 makes every parallel region the thread
// starts run on that thread alone. It is set for the call and put back after it, so other threads
// and the program's own OpenMP are untouched. (An older libgomp, loaded by a program before
// springmass, keeps one setting for the whole process: its other threads' parallel regions run on
// one thread while a factorisation lasts, and two factorisations at once in two threads may leave
// it at 0, a program's OpenMP then running on one thread: slower, never wrong.) The runtime's
// functions are looked up in the process (dlopen with RTLD_NOLOAD): springmass does not link
// OpenMP itself, and without an OpenMP runtime loaded (a CHOLMOD built without OpenMP) there is
// nothing to keep to one thread.
#define _GNU_SOURCE  // RTLD_NOLOAD

#include "cholmod_factorize.h"

#include <dlfcn.h>

int sm_cholmod_factorize(cholmod_sparse* A, cholmod_factor* L, cholmod_common* common)
{
	void* openmp = dlopen("libgomp.so.1", RTLD_LAZY | RTLD_NOLOAD);
	int (*get_levels)(void) = NULL;
	void (*set_levels)(int) = NULL;
	if (openmp != NULL) {
		// POSIX's way from an object pointer to a function pointer (dlsym's rationale).
		*(void**)&get_levels = dlsym(openmp, "omp_get_max_active_levels");
		*(void**)&set_levels = dlsym(openmp, "omp_set_max_active_levels");
	}
	const int keep = get_levels != NULL && set_levels != NULL;
	const int levels = keep ? get_levels() : 0;
	if (keep)
		set_levels(0);
	const int ok = cholmod_l_factorize(A, L, common);
	if (keep)
		set_levels(levels);
	if (openmp != NULL)
		dlclose(openmp);
	return ok;
}

// CHOLMOD's default choice of ordering tries METIS after AMD where AMD's leaves much fill (on a
// sheet of 129 x 129 particles or a block of 13 x 13 x 13, not on a sheet of 100 x 100 or a block
// of 12 x 12 x 12), and METIS draws its random numbers from the C library's one generator of the
// process: it seeds it with srand() and takes them with rand(). The statics of a 14 x 14 x 14
// block in three concurrent threads took each other's numbers, orderings other than alone and so
// other bits in each thread, where include/springmass/analysis.h promises the same; and every
// analysis reset the program's own sequence of rand(). Where AMD's ordering won anyway (sheets
// up to 160 x 160 at least) the factor is the same, without the time METIS took: the first Newton
// iteration of a 160 x 160 sheet's statics 1.2 s instead of 1.6 s. Where METIS's nested
// dissection won (large blocks), AMD's ordering fills more: an 18 x 18 x 18 block's sparse
// statics took 4.8 - 5.5 s instead of 3.1 - 3.3 s, its five lowest modes 4.5 - 5.7 s instead of
// 3.5 - 3.9 s (three alternating runs on a busy 2-core machine).
cholmod_factor* sm_cholmod_analyze(cholmod_sparse* A, cholmod_common* common)
{
	const int methods = common->nmethods, ordering = common->method[0].ordering;
	common->nmethods = 1;
	common->method[0].ordering = CHOLMOD_AMD;
	cholmod_factor* L = cholmod_l_analyze(A, common);
	common->nmethods = methods;
	common->method[0].ordering = ordering;
	return L;
}

// CHOLMOD's simplicial solve asks for its workspace y as 4 rows by n columns (it solves up to four
// right-hand sides at a time: cholmod_l_ensure_dense(y, 4, n, 4)), but leaves it shaped as the
// right-hand sides it last held (1 by n, leading dimension 1): every later call found another shape,
// freed the workspace and allocated it again, two allocations at each solve and so at each
// iteration of conjugate gradients preconditioned by such a factor (the reduced solvers' coarse
// correction and Cholesky preconditioner, the multilevel cycle's coarsest level: 2006 allocations
// in the 1003 iterations of 0.05 s of the 32 x 32 benchmark cloth with pcg). Its storage holds 4 n entries
// either way: given back the shape it asks for, the workspace is used again. The supernodal solve keeps its
// workspaces' shapes.
int sm_cholmod_solve(cholmod_factor* L, cholmod_dense* b, cholmod_dense** x, cholmod_dense** y,
                     cholmod_dense** e, cholmod_common* common)
{
	cholmod_dense* w = *y;
	if (w != NULL && !L->is_super && w->ncol == L->n && w->nzmax >= 4 * L->n) {
		w->nrow = 4;
		w->d = 4;
	}
	return cholmod_l_solve2(CHOLMOD_A, L, b, NULL, x, NULL, y, e, common);
}
