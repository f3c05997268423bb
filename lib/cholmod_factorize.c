// CHOLMOD's numeric factorisation on the calling thread alone.
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
