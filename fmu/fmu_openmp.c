// Keeps the OpenMP runtime loaded for the rest of the process.
//
// CHOLMOD's supernodal factorisation runs in an OpenMP team whose threads outlive the instance
// that used it: they wait in libgomp for the next parallel region. An importer that unloads the
// FMU after fmi2FreeInstance (fmpy does) would unload libgomp with it, under those threads, which
// then crash the importer's process when they wake. The runtime, once loaded, is marked never to
// be unloaded (RTLD_NODELETE); the FMU binary and its other libraries still are, so that loading
// FMUs again and again (a sweep in one process, each extracted to a new folder) keeps no copies.
// libgomp is one library per process (the loader loads a name once), so it is kept once.
#define _GNU_SOURCE  // RTLD_NOLOAD, RTLD_NODELETE

#include "fmu_instance.h"

#include <dlfcn.h>

void fmu_keep_openmp_loaded(void)
{
	void* gomp = dlopen("libgomp.so.1", RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
	if (gomp != NULL)
		dlclose(gomp);  // the mark stays; the reference is given back
}
